"""A second publisher where the graph expects one (rev_e 5): another node on a joint's effort topic beside its
joint controller. The plant would apply whichever answer came first, so the run's numbers would not be its
controller's alone (nor, in lockstep, the in-process run's); the plant counts the publishers and warns, the
launcher's report and stderr say so and it exits 1 (docs/graph.md). One short lockstep run (3 s)."""
import json
import sys
from pathlib import Path

import pytest

from graph_harness import Launcher, Proc, assert_no_leftovers
from pa10_dnbs.ros.shm_cleanup import remove_stale, shm_files

pytestmark = pytest.mark.graph  # starts ROS processes

HERE = Path(__file__).resolve().parent


def test_a_second_publisher_on_an_effort_topic_is_reported_and_fails_the_run(tmp_path, domain):
    shm_before = shm_files()
    out = tmp_path / "run"
    rival = Proc([sys.executable, HERE / "rival_publisher.py", domain, "/pa10/s1/effort"], domain)
    rival.wait_for("RIVAL READY", 60)
    # 3 s: the plant must match the rival's publisher while it runs (a 1 s run once ended first in a loaded CI)
    rc, la, pids, _ = Launcher.beside(rival, "--mode", "lockstep", "--duration", 3.0, "--out", out, domain_id=domain)
    assert rc == 1, la.output
    stats = json.loads((out / "plant_stats.json").read_text())
    assert [j["effort_publishers"] for j in stats["joints"]] == [2, 1, 1, 1, 1, 1, 1], stats["joints"]
    m = json.loads((out / "metrics.json").read_text())
    assert m["faults"]["joints"][0]["plant"]["effort_publishers"] == 2, m["faults"]["joints"][0]
    says = "a second publisher on an effort topic: s1: 2 publishers, 0 efforts for steps already applied"
    assert f"- {says} (" in (out / "report.md").read_text()
    assert f"pa10-dnbs launch: warning: {says} (" in la.output, la.output
    assert "SECOND EFFORT PUBLISHER at step " in (out / "logs" / "plant.log").read_text()
    assert "/pa10/joint_controller_s1, /rival" in (out / "logs" / "plant.log").read_text()
    remove_stale(shm_files() - shm_before)  # the rival's own files (no node of the launcher)
    assert_no_leftovers(list(pids.values()) + [rival.proc.pid], shm_before)

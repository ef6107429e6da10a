"""The graph under another namespace: `launch --namespace /arm2 --record BAG` runs 1 s in lockstep, the bag
holds /arm2/... (nothing under /pa10), `analyse BAG` works, and the run equals the in-process simulation."""
import json

import numpy as np
import pytest

from cli_runner import run_cli
from graph_harness import Launcher, exit_codes
from pa10_dnbs.bag.bag_reader import Bag
from pa10_dnbs.report.metrics_file import metrics_dict, metrics_settings
from pa10_dnbs.run_data import RunData
from pa10_dnbs.sim.closed_loop import simulate

pytestmark = pytest.mark.graph  # starts ROS processes

DURATION_S = 1.0
GLOBAL = {"/clock", "/tf", "/tf_static", "/diagnostics"}


def test_graph_in_namespace_arm2_records_arm2_topics_and_equals_in_process(tmp_path, domain, _default_cfg):
    out, bag = tmp_path / "run", tmp_path / "bag"
    la = Launcher("--namespace", "/arm2", "--duration", DURATION_S, "--out", out, "--record", bag, domain_id=domain)
    try:
        rc = la.wait(timeout=180)
    finally:
        la.kill()
    assert rc == 0, la.output
    assert all(c == 0 for c in exit_codes(la.output).values()), la.output
    with Bag(bag) as b:
        topics = set(b.topics)
        counts = {t: i.count for t, i in b.topics.items()}
    assert not [t for t in topics if t.startswith("/pa10/")], topics
    assert {t for t in topics if not t.startswith("/arm2/")} <= GLOBAL, topics
    assert {"/arm2/joint_states", "/arm2/robot_description", "/arm2/s1/state", "/arm2/w2/effort",
            "/arm2/e1/reference"} <= topics
    assert counts["/arm2/joint_states"] == int(DURATION_S * 1000) + 1

    r = run_cli("analyse", bag, "--out", tmp_path / "again", "--no-progress", "--no-figures")
    assert r.returncode == 0, r.stderr
    analysed = json.loads((tmp_path / "again" / "metrics.json").read_text())

    local = simulate(_default_cfg, "dnbs", DURATION_S)
    wire = RunData.load_npz(out / "timeseries.npz")
    for field in ("position_rad", "velocity_rad_s", "reference_rad", "torque_nm"):
        assert np.array_equal(getattr(local, field), getattr(wire, field)), field
    expected = metrics_dict(local, metrics_settings(_default_cfg, DURATION_S))
    launched = json.loads((out / "metrics.json").read_text())
    for key in ("joints", "worst_rms_error_rad", "worst_max_abs_error_run_rad", "all_finite",
                "torques_within_limits", "duration_s", "window_s"):
        assert analysed[key] == expected[key] == launched[key], key

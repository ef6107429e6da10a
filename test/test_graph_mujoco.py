"""`pa10-dnbs launch --plant mujoco`: the MuJoCo robot node behind the joint bus, in the launcher's domain. The run
reports, every node ends, and the lockstep graph equals the in-process MuJoCo run bit for bit."""
import json

import numpy as np
import pytest

from cli_runner import run_cli
from graph_harness import Launcher, assert_no_leftovers


@pytest.mark.graph
def test_launch_plant_mujoco_runs_reports_and_equals_the_in_process_engine(domain, tmp_path):
    from pa10_dnbs.ros.shm_cleanup import shm_files

    shm_before = shm_files()
    out = tmp_path / "graph"
    launcher = Launcher("--arm", "iiwa", "--plant", "mujoco", "--duration", "2", "--out", out, domain_id=domain)
    pids = launcher.node_pids()
    assert launcher.wait(240) == 0, launcher.output
    assert "mujoco_robot=0" in launcher.output and "joint_bus=0" in launcher.output
    assert "plant: the arm in MuJoCo" in (out / "report.md").read_text()
    m = json.loads((out / "metrics.json").read_text())
    assert m["all_finite"] and m["worst_rms_error_rad"] < 1e-3
    assert_no_leftovers(list(pids.values()) + [launcher.proc.pid], shm_before)

    ref = tmp_path / "in_process"
    r = run_cli("simulate", "--engine", "mujoco", "--arm", "iiwa", "--controller", "dnbs", "--duration", "2",
                "--out", ref, "--no-figures")
    assert r.returncode == 0, r.stderr
    a, b = np.load(out / "timeseries.npz"), np.load(ref / "timeseries.npz")
    for key in ("position_rad", "velocity_rad_s", "torque_nm"):
        assert np.array_equal(a[key], b[key]), key


@pytest.mark.parametrize("flags, message", [
    (["--robot", "external"], "--plant mujoco: not with an external robot (--robot external"),
    (["--mode", "realtime"], "--plant mujoco: only in lockstep mode so far (--mode lockstep"),
])
def test_launch_plant_mujoco_refuses_what_it_cannot_run_in_one_line(tmp_path, flags, message):
    r = run_cli("launch", "--arm", "iiwa", "--plant", "mujoco", "--duration", "1", "--out", tmp_path / "x", *flags)
    assert r.returncode == 2 and message in r.stderr and "Traceback" not in r.stderr, r.stderr
    assert not (tmp_path / "x").exists()


@pytest.mark.graph
def test_relative_topic_names_meet_in_the_arms_namespace(domain, tmp_path):
    """rev_e 7: the same relative names given to `pa10-dnbs robot` and to `launch --robot external` meet: both
    resolve them in the arm's namespace (the robot resolved them at /, the bus in /pa10: nothing connected)."""
    import sys

    from graph_harness import Proc
    from pa10_dnbs.ros.shm_cleanup import remove_stale, shm_files

    shm_before = shm_files()
    robot = Proc([sys.executable, "-m", "pa10_dnbs.cli", "robot", "--engine", "mujoco", "--duration", "0.3",
                  "--state-topic", "js", "--command-topic", "cmd"], domain)
    launcher = None
    try:
        robot.wait_for("READY mujoco_robot", 60)
        assert "state /pa10/js, commands /pa10/cmd" in robot.output, robot.output
        launcher = Launcher("--robot", "external", "--robot-state-topic", "js", "--robot-command-topic", "cmd",
                            "--duration", "0.3", "--out", tmp_path / "run", domain_id=domain)
        pids = launcher.node_pids()
        assert launcher.wait(120) == 0, launcher.output
        assert robot.wait(30) == 0, robot.output
    finally:
        robot.kill()
        if launcher is not None:
            launcher.kill()
    assert "JOINT BUS /pa10/js -> /pa10/cmd" in (tmp_path / "run" / "logs" / "joint_bus.log").read_text()
    remove_stale(shm_files() - shm_before)  # the robot's own files (it is no node of the launcher)
    assert_no_leftovers(list(pids.values()) + [robot.proc.pid], shm_before)

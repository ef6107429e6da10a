"""`pa10-dnbs robot --engine mujoco`: the MuJoCo arm as an external robot on the standard interface, a ROS 2 node.

Lockstep against a minimal client (test/robot_interface_probe.py): every state equals the in-process MuJoCo
plant's under the same efforts, bit for bit; /clock goes out from time 0; SIGINT ends it cleanly.
"""
import json
import sys

import numpy as np
import pytest

from graph_harness import REPO, Proc, assert_no_leftovers
from pa10_dnbs.arm import load_arm
from pa10_dnbs.loop.robot_stepper import RobotStepper
from pa10_dnbs.config import default_config_path
from pa10_dnbs.plant.engines import open_plant
from pa10_dnbs.run_settings import build_settings
from robot_interface_probe import effort

STEPS = 300


def _probe_beside_robot(domain: int, robot_args: tuple, probe_args: tuple, probe_timeout_s: float):
    """``pa10-dnbs robot --engine mujoco ROBOT_ARGS`` until ready, then ``python PROBE_ARGS`` against it to its
    end (exit 0), then the robot stopped by SIGINT (exit 0); both killed whatever happens. (robot, probe)."""
    robot = Proc([sys.executable, "-m", "pa10_dnbs.cli", "robot", "--engine", "mujoco", *robot_args], domain)
    probe = None
    try:
        robot.wait_for(r"READY mujoco_robot", 60)
        probe = Proc([sys.executable, *probe_args], domain)
        assert probe.wait(probe_timeout_s) == 0, probe.output
        robot.interrupt()
        assert robot.wait(30) == 0, robot.output
    finally:
        robot.kill()
        if probe is not None:
            probe.kill()
    return robot, probe


class _Recorder:
    """A plant stand-in that records what it is stepped with (the stepper's unit test)."""

    n_joints = 2

    def __init__(self):
        self.steps = []

    def step(self, u):
        self.steps.append(list(u))


def test_lockstep_steps_once_on_the_command_for_the_current_state():
    s = RobotStepper(_Recorder(), "lockstep", 1e-3)
    assert not s.offer(1_000_000, [1.0, 2.0]) and s.stale == 1  # a command for state 1 while state 0 is out
    assert s.offer(0, [1.0, 2.0]) and s.step == 1 and s.stamp_ns == 1_000_000
    assert not s.offer(0, [3.0, 4.0]) and s.stale == 2  # state 0's answer again: ignored
    assert not s.offer(1_000_000, [float("nan"), 0.0]) and s.refused == 1 and s.step == 1
    assert s.plant.steps == [[1.0, 2.0]]
    with pytest.raises(RuntimeError):
        s.tick()


def test_paced_steps_every_tick_with_the_latest_command():
    s = RobotStepper(_Recorder(), "paced", 1e-3)
    s.tick()
    s.offer(123, [1.0, 1.0])
    s.offer(456, [2.0, 2.0])
    s.tick()
    s.tick()
    assert s.plant.steps == [[0.0, 0.0], [2.0, 2.0], [2.0, 2.0]] and s.step == 3 and s.commands == 2
    with pytest.raises(ValueError, match="mode"):
        RobotStepper(_Recorder(), "realtime", 1e-3)


@pytest.mark.graph
def test_the_robot_node_answers_lockstep_bit_for_bit_and_stops_on_sigint(domain, tmp_path):
    from pa10_dnbs.ros.shm_cleanup import shm_files

    shm_before = shm_files()
    arm = load_arm("iiwa")
    out = tmp_path / "probe.json"
    probe_args = (str(REPO / "test" / "robot_interface_probe.py"), ",".join(arm.joint_names), STEPS, out)
    robot, probe = _probe_beside_robot(domain, ("--arm", "iiwa", "--clock-hz", "1000"), probe_args, 120)
    assert "Traceback" not in robot.output
    summary = robot.wait_for(r"mujoco_robot: (\d+) steps", 1)
    assert int(summary.group(1)) == STEPS, robot.output
    got = json.loads(out.read_text())
    plant, _ = open_plant(build_settings(default_config_path(), arm="iiwa"), "mujoco")  # the configured start
    for k in range(STEPS + 1):
        state = got["states"][str(k)]
        q, qd = plant.state
        assert state["position"] == q.tolist() and state["velocity"] == qd.tolist(), k
        assert state["effort"] == plant.applied_torque_nm.tolist(), k
        if k < STEPS:
            plant.step(np.array([effort(k, j) for j in range(arm.n_joints)]))
    assert got["clock_ns"][0] == 0 and got["clock_ns"] == sorted(got["clock_ns"])
    assert_no_leftovers([robot.proc.pid, probe.proc.pid], shm_before)


@pytest.mark.parametrize("flags, message", [
    (["--arm", "nope"], "arm: no arm called 'nope'"),
    (["--duration", "-1"], "--duration: must be a positive number of seconds"),
    (["--clock-hz", "5000"], "--clock-hz: must be in [0, 1000]"),
    (["--mode", "realtime"], "invalid choice: 'realtime'"),
])
def test_robot_refuses_bad_arguments_in_one_line_before_starting(flags, message):
    from cli_runner import run_cli

    r = run_cli("robot", "--engine", "mujoco", *flags)
    assert r.returncode == 2 and message in r.stderr and "Traceback" not in r.stderr, r.stderr


@pytest.mark.graph
def test_a_paced_robot_holds_state_0_until_the_first_command(domain):
    """rev_e 17: matched by a silent commander (as by the joint bus during the graph's start handshake), the paced
    robot re-sends state 0 and does not step (it stepped at once: its time ran seconds ahead of the graph's); the
    first command starts it."""
    from pa10_dnbs.ros.shm_cleanup import remove_stale, shm_files

    shm_before = shm_files()
    robot, probe = _probe_beside_robot(domain, ("--mode", "paced", "--duration", "20"),
                                       (str(REPO / "test" / "paced_start_probe.py"), domain, 2.0), 60)
    before = json.loads(probe.wait_for(r"BEFORE (.*)", 1).group(1))
    after = int(probe.wait_for(r"AFTER (\d+)", 1).group(1))
    assert before == [0], before  # state 0 only, re-sent
    assert after > 100, after     # stepping every 1 ms once a command came
    remove_stale(shm_files() - shm_before)
    assert_no_leftovers([robot.proc.pid, probe.proc.pid], shm_before)

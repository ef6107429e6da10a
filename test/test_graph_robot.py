"""``launch --robot external``: the joint bus in front of a robot speaking the standard interface.

The project's PyBullet plant as that robot (``interface:=standard``): the recorded lockstep run equals the
in-process run bit for bit, the bag holds the graph's topics as before, every process ends; paced
(``--mode realtime``), the bus follows the robot's own ticks. A small probe robot
(test/robot_probe.py, no /clock, stamps not starting at 0) for the faults: it stops publishing, a joint goes
missing from its state, a position turns NaN, a joint is named twice. Each: one ``ROBOT FAULT`` line, the
zero-effort safe command answering the last state, no traceback, every process ends (docs/your_robot.md).
"""
import json
import re
import sys
from pathlib import Path

import numpy as np
import pytest

from graph_harness import Launcher, Proc, assert_no_leftovers, exit_codes
from pa10_dnbs.ros.shm_cleanup import remove_stale, shm_files
from pa10_dnbs.run_data import RunData
from pa10_dnbs.sim.closed_loop import simulate

pytestmark = pytest.mark.graph  # starts ROS processes

HERE = Path(__file__).resolve().parent


def _no_leftovers(pids, shm_before) -> None:
    """Every process gone; the robot's own shared-memory files (it is no node of the launcher, which cleans up
    only after its nodes) removed as the launcher does, then nothing new may be left."""
    remove_stale(shm_files() - shm_before)
    assert_no_leftovers(pids, shm_before)


def _plant_robot(domain: int, duration_s: float, *params: str) -> Proc:
    """The PyBullet plant speaking the standard interface, waiting for the bus (lockstep)."""
    args = [sys.executable, "-m", "pa10_dnbs.ros.plant.node", "--ros-args", "-r", "__node:=robot",
            "-p", "interface:=standard", "-p", f"duration_s:={duration_s}", "-p", "start_timeout_s:=120.0"]
    for p in params:
        args += ["-p", p]
    return Proc(args, domain)


@pytest.mark.parametrize("form", ["joint_state", "forward:effort_controller"])
def test_the_pybullet_robot_behind_the_bus_is_the_in_process_run(form, tmp_path, domain, _default_cfg):
    """Either command form; the JointState one recorded (the Float64MultiArray one on /joint_states and
    /effort_controller/commands, as beside a JointGroupEffortController)."""
    shm_before = shm_files()
    out, bag = tmp_path / "run", tmp_path / "bag"
    robot = _plant_robot(domain, 1.0, f"robot_command:={form}")
    record = ("--record", bag) if form == "joint_state" else ()
    la = Launcher("--robot", "external", "--robot-command", form, "--duration", 1.0, "--out", out, *record,
                  domain_id=domain)
    try:
        pids = la.node_pids()
        rc = la.wait(timeout=300)
        robot_rc = robot.wait(timeout=60)
    finally:
        la.kill()
        robot.kill()
    assert rc == 0, la.output
    assert robot_rc == 0, robot.output
    # its /clock's readers (the graph's reference) were stopped by their launcher before they acknowledged the last
    # ticks: the robot waited for them 10 s at every run's end
    assert "not every subscriber acknowledged" not in robot.output, robot.output
    assert "joint_bus" in pids and "plant" not in pids
    bus_log = (out / "logs" / "joint_bus.log").read_text()
    assert "graph time from the robot's /clock" in bus_log, bus_log
    wire = RunData.load_npz(out / "timeseries.npz")
    local = simulate(_default_cfg, "dnbs", 1.0)
    for field in ("position_rad", "velocity_rad_s", "reference_rad", "torque_nm"):
        a, b = getattr(local, field), getattr(wire, field)
        assert np.array_equal(a, b), f"{field}: first (step, joint) that differs {np.argwhere(a != b)[:3].tolist()}"
    m = json.loads((out / "metrics.json").read_text())
    assert all(j["effort_timeouts"] == 0 for j in m["timing"]["joints"]), m["timing"]["joints"]
    if record:
        from pa10_dnbs.bag.bag_reader import Bag

        with Bag(bag) as b:
            assert {"/pa10/s1/state", "/pa10/s1/effort", "/pa10/joint_states", "/clock"} <= set(b.topics)
    else:
        assert "JOINT BUS /joint_states -> /effort_controller/commands (forward)" in bus_log, bus_log
    codes = exit_codes(la.output)
    assert len(codes) == 10 and all(c == 0 for c in codes.values()), codes  # 9 nodes and the observer
    _no_leftovers(list(pids.values()) + [robot.proc.pid], shm_before)


def test_a_paced_robot_is_followed(tmp_path, domain):
    """--mode realtime: the plant as a robot on its own wall-clock ticks (R = 0.5), not waiting for the bus; the
    bus forwards each state as it comes and answers it as soon as every controller has. The run converges; the
    robot outlasts the run (it is the user's: the test stops it)."""
    shm_before = shm_files()
    out = tmp_path / "run"
    robot = _plant_robot(domain, 3.0, "mode:=realtime", "real_time_factor:=0.5")
    la = Launcher("--robot", "external", "--mode", "realtime", "--duration", 1.0, "--out", out, domain_id=domain)
    try:
        pids = la.node_pids()
        rc = la.wait(timeout=300)
    finally:
        la.kill()
        robot.kill()
    assert rc == 0, la.output
    m = json.loads((out / "metrics.json").read_text())
    assert m["mode"] == "realtime" and m["all_finite"] and m["torques_within_limits"], m
    assert m["worst_rms_error_rad"] < 1e-2, m["worst_rms_error_rad"]
    assert 0 < m["timing"]["on_time_fraction"] <= 1, m["timing"]
    # rev_e 8: no tick schedule of the graph's own is reported (it said "target real-time factor 1 (tick 1.00 ms")
    assert m["timing"]["paced_by"] == "robot" and m["timing"]["target_real_time_factor"] is None, m["timing"]
    report = (out / "report.md").read_text()
    assert "paced by the robot (its next state is each state's deadline)" in report and "tick 1.00 ms" not in report
    assert "realtime, paced by the robot: every effort before the robot's next state on " in la.output, la.output
    stats = json.loads((out / "plant_stats.json").read_text())
    assert stats["steps"] == 1000 and stats["robot"]["robot_commands"] >= 1000, stats["robot"]
    _no_leftovers(list(pids.values()) + [robot.proc.pid], shm_before)


FAULTS = [  # (fault, mode, what the one line says): each fault in lockstep, the paced loop's own stale check
    ("stop", "lockstep", "(stale robot)"),
    ("missing", "lockstep", "joint_states lacks s3"),
    ("nan", "lockstep", "non-finite state of joint s2: position nan"),
    ("dup", "lockstep", "joint_states names s1 more than once"),
    ("frozen", "lockstep", "(stale robot); meanwhile "),  # rev_e 12: the count of copies follows
    ("back", "lockstep", "states stamped earlier (the robot's time went back"),
    ("skip", "lockstep", "comes 2 ms after the previous one, not simulation.dt_s = 1 ms"),  # rev_e 10
    ("nowait", "lockstep", "before the command answering the previous one: it does not wait for commands"),
    ("stop", "realtime", "(stale robot)"),
]


@pytest.mark.parametrize("fault,mode,says", FAULTS, ids=[f"{f}-{m}" for f, m, _ in FAULTS])
def test_a_robot_fault_is_one_line_and_the_safe_command(fault, mode, says, tmp_path, domain):
    shm_before = shm_files()
    at = 300
    robot = Proc([sys.executable, HERE / "robot_probe.py", domain, fault, at], domain)
    robot.wait_for("PROBE READY", 60)
    rc, la, pids, robot_rc = Launcher.beside(robot, "--robot", "external", "--mode", mode, "--duration", 3.0, "--out",
                                             tmp_path / "run", domain_id=domain)
    assert rc == 1, la.output
    assert robot_rc == 0 and "PROBE END" in robot.output, robot.output
    lines = [x for x in la.output.splitlines() if "ROBOT FAULT:" in x]
    assert len(lines) == 1 and says in lines[0], la.output
    assert "joint_bus exited early with code 1" in la.output, la.output
    logs = tmp_path / "run.failed" / "logs"
    for log in [la.output] + [p.read_text() for p in logs.glob("*.log")]:
        assert "Traceback" not in log, log
    # the safe command: zero effort on every joint, answering the last state the robot sent
    commands = [x.split(" ", 3) for x in robot.output.splitlines() if x.startswith("COMMAND ")]
    step, _, efforts = int(commands[-1][1]), commands[-1][2], json.loads(commands[-1][3])
    assert efforts == [0.0] * 7, commands[-3:]
    # the state it answers: the last new one (stop, back), the bad one (skip: stamped as step at + 1), the latest
    # unanswered one (nowait)
    expected = {"stop": at - 1, "back": at - 1, "skip": at + 1}.get(fault, at)
    assert step >= at if fault == "nowait" else step == expected, commands[-3:]
    assert all(any(v != 0.0 for v in json.loads(c[3])) for c in commands[:-1]), "a zero command before the fault"
    codes = exit_codes(la.output)
    assert codes["joint_bus"] == 1 and all(c == 0 for n, c in codes.items() if n != "joint_bus"), codes
    _no_leftovers(list(pids.values()) + [robot.proc.pid], shm_before)


def test_states_the_guard_refuses_without_an_injected_fault_are_reported(tmp_path, domain):
    """rev_e 1: a robot whose s1 is 0.2 rad beyond its URDF limit on every state (a wrong zero or offset): the
    joint controller's guard refuses each one (its torque held at 0). No fault was injected, yet the report's
    faults line names the counter (it was written only under injection), metrics.json has it, and the launcher
    warns on stderr. The run itself ends as |e| > 1 rad makes it: diverged, exit 1."""
    shm_before = shm_files()
    out = tmp_path / "run"
    robot = Proc([sys.executable, HERE / "robot_probe.py", domain, "beyond", 0], domain)
    robot.wait_for("PROBE READY", 60)
    rc, la, pids, _ = Launcher.beside(robot, "--robot", "external", "--duration", 0.3, "--out", out, domain_id=domain)
    assert rc == 1 and "DIVERGED" in la.output, la.output
    m = json.loads((out / "metrics.json").read_text())
    s1 = m["faults"]["joints"][0]
    assert s1["name"] == "s1" and s1["controller"]["bad_states_position"] == s1["controller"]["states"] == 301, s1
    assert all(j["controller"]["bad_states_position"] == 0 for j in m["faults"]["joints"][1:]), m["faults"]
    report = (out / "report.md").read_text()
    assert "- faults: s1: bad_states_position 301\n" in report, report
    warning = [x for x in la.output.splitlines() if x.startswith("pa10-dnbs launch: warning: faults detected")]
    assert len(warning) == 1 and "s1: bad_states_position 301" in warning[0], la.output
    _no_leftovers(list(pids.values()) + [robot.proc.pid], shm_before)


def test_a_second_commander_of_the_robot_is_a_robot_fault(tmp_path, domain):
    """rev_e 2: another publisher on the robot's command topic (the probe's own, silent: as a forgotten second
    graph would be) is a second commander; the robot would take whichever command came first. The bus sees it
    (``get_publishers_info_by_topic``), sends the safe command and exits 1 with one ROBOT FAULT line naming it."""
    line, la = _one_robot_fault(tmp_path, domain, "rival")
    # the rival named once discovery has its node's name (under load it may not yet)
    assert re.search(r"another publisher on the robot's command topic /robot_joint_command besides this bus "
                     r"\(publishers: /pa10/joint_bus, (/robot_probe|a node not known by name yet)\)", line), line
    assert exit_codes(la.output)["joint_bus"] == 1


def _one_robot_fault(tmp_path, domain, fault: str):
    """``launch --robot external`` (3 s) beside a probe injecting ``fault`` from the start: exit 1 with one
    ROBOT FAULT line, the safe command the last the robot took, nothing left behind. (that line, the launcher)"""
    shm_before = shm_files()
    robot = Proc([sys.executable, HERE / "robot_probe.py", domain, fault, 0], domain)
    robot.wait_for("PROBE READY", 60)
    rc, la, pids, _ = Launcher.beside(robot, "--robot", "external", "--duration", 3.0, "--out", tmp_path / "run",
                                      domain_id=domain)
    assert rc == 1, la.output
    lines = [x for x in la.output.splitlines() if "ROBOT FAULT:" in x]
    assert len(lines) == 1, la.output
    commands = [json.loads(x.split(" ", 3)[3]) for x in robot.output.splitlines() if x.startswith("COMMAND ")]
    assert commands and commands[-1] == [0.0] * 7, commands[-3:]  # the safe command last
    _no_leftovers(list(pids.values()) + [robot.proc.pid], shm_before)
    return lines[0], la


def test_a_second_robot_on_the_state_topic_is_a_robot_fault(tmp_path, domain):
    """Two robots publishing on one state topic: the bus would take both's states as one robot's and drive both
    (the run ended 0 with 20x the error before, its counters alone showing duplicate and old states). One more
    publisher on the state topic (the probe's own, silent) is a ROBOT FAULT naming them, after the safe command."""
    line, _ = _one_robot_fault(tmp_path, domain, "twin")
    assert re.search(r"more than one publisher on the robot's state topic /robot_joint_states \(publishers: "
                     r"(/robot_probe|a node not known by name yet), (/robot_probe|a node not known by name yet)\)",
                     line), line


def test_the_last_command_to_a_paced_robot_is_zero_effort(tmp_path, domain):
    """rev_e 18: a paced robot (the probe, not waiting for commands) goes on applying the last command it got once
    the run is over; the bus's last act is the zero-effort command, as on a fault."""
    shm_before = shm_files()
    robot = Proc([sys.executable, HERE / "robot_probe.py", domain, "nowait", 0], domain)
    robot.wait_for("PROBE READY", 60)
    rc, la, pids, _ = Launcher.beside(
        robot, "--robot", "external", "--mode", "realtime", "--duration", 0.3, "--out", tmp_path / "run",
        domain_id=domain, then=lambda: robot.wait_for("COMMAND .* \\[0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0\\]", 10))
    assert rc == 0, la.output
    commands = [json.loads(x.split(" ", 3)[3]) for x in robot.output.splitlines() if x.startswith("COMMAND ")]
    assert len(commands) > 100 and commands[-1] == [0.0] * 7 and any(v != 0.0 for v in commands[-2]), commands[-3:]
    # the bus's own line about it is not asserted: CI once had the zero command last without it (not understood,
    # noted in the stop's closing note); what the robot got, above, is the behaviour
    _no_leftovers(list(pids.values()) + [robot.proc.pid], shm_before)

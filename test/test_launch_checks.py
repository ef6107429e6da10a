"""Checks made before any ROS node starts (one line, exit 2, nothing written, no process left): joint names the
graph cannot name nodes and topics after, robot topic names, --rtf and --effort-timeout out of range; and the
compiled kernel's cache: a cached library that does not load is rebuilt once, else ``auto`` falls back to numpy.

No ROS graph is started here: every launch below is refused before its first node.
"""
from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from cli_runner import run_cli
from test_arms import three_link_urdf, write_arm

from pa10_dnbs.wire.topics import check_joint_name, check_topic_name

REPO = Path(__file__).resolve().parent.parent


def _refused(r, words) -> str:
    """Exit 2, one error line on stderr (the last; an arm file's gains table may come before it) containing every
    one of ``words``, no traceback."""
    lines = [line for line in r.stderr.strip().splitlines() if "error" in line]
    assert r.returncode == 2, (r.returncode, r.stderr)
    assert len(lines) == 1 and r.stderr.strip().endswith(lines[0]), r.stderr
    assert "Traceback" not in r.stderr + r.stdout
    for w in words:
        assert w in lines[0], (w, lines[0])
    return lines[0]


def _no_pa10_children() -> None:
    """No node of ours was started (the checks run before the first one)."""
    ps = subprocess.run(["ps", "-o", "pid=,args=", "--ppid", str(os.getpid())], capture_output=True, text=True)
    assert "pa10_dnbs.ros" not in ps.stdout, ps.stdout


@pytest.mark.parametrize("bad", ["関節2", "j.2", "j 1", "2j", "j-1"])   # "j/2": refused at intake (test_arm_intake_edges)
def test_a_joint_name_the_graph_cannot_use_is_refused_before_any_node(tmp_path, bad):
    arm_dir = tmp_path / "arm"
    arm_dir.mkdir()
    arm = write_arm(arm_dir, three_link_urdf().replace('name="j2"', f'name="{bad}"'))
    out = tmp_path / "out"
    line = _refused(run_cli("launch", "--arm", arm, "--duration", "0.1", "--out", out), [repr(bad), "ROS"])
    assert "--arm" in line
    assert not out.exists() and not list(tmp_path.glob("*.failed")) and not list(tmp_path.glob("out*"))
    _no_pa10_children()


def test_the_in_process_simulation_still_takes_such_an_arm(tmp_path):
    arm_dir = tmp_path / "arm"
    arm_dir.mkdir()
    arm = write_arm(arm_dir, three_link_urdf().replace('name="j2"', 'name="関節2"'))
    r = run_cli("simulate", "--arm", arm, "--controller", "pid", "--duration", "0.05", "--out", tmp_path / "o",
                "--no-figures")
    assert r.returncode == 0, r.stderr


def test_the_name_rules():
    for good in ("s1", "panda_joint1", "a_", "A9"):
        assert check_joint_name(good) == good
    for bad in ("", "1a", "a b", "a/b", "é", "a-b", "_a", "a__b"):   # '__' (joint_controller__a): no remap rule
        with pytest.raises(ValueError):
            check_joint_name(bad)
    for good in ("/robot_joint_states", "a/b", "/a/b_2"):
        assert check_topic_name(good) == good
    for bad in ("", "/", "//a", "/a/", "/関節", "/a b", "/1a", "a//b"):
        with pytest.raises(ValueError):
            check_topic_name(bad)


@pytest.mark.parametrize("args,words", [
    (("--state-topic", "/関節"), ["--state-topic", "'/関節'"]),
    (("--command-topic", "/a//b"), ["--command-topic"]),
    (("--state-topic", "/x", "--command-topic", "/x"), ["--command-topic", "--state-topic", "'/x'"]),
    (("--state-topic", "x", "--command-topic", "/pa10/x"), ["--command-topic", "--state-topic", "/pa10/x in /pa10"]),
    # the graph's /clock (rosgraph_msgs): an RCLError traceback from the robot node ('incompatible type', 'invalid
    # allocator'); every node's /rosout too
    (("--state-topic", "/clock"), ["--state-topic: '/clock' is /clock, which carries rosgraph_msgs/msg/Clock"]),
    (("--command-topic", "/clock"), ["--command-topic: '/clock' is /clock"]),
    (("--state-topic", "/rosout"), ["--state-topic: '/rosout' is /rosout, which carries rcl_interfaces/msg/Log"]),
    # the arm's graph's own topics: the joint bus publishes /pa10/joint_states itself
    (("--state-topic", "joint_states"), ["--state-topic: 'joint_states' is the graph's own joint states "
                                         "(/pa10/joint_states in the namespace /pa10)"]),
    (("--command-topic", "/pa10/s1/effort"), ["--command-topic: '/pa10/s1/effort' is joint s1's effort topic"]),
])
def test_robot_topics_are_checked(args, words):
    _refused(run_cli("robot", "--duration", "0.1", *args), words)
    _no_pa10_children()


@pytest.mark.parametrize("args,words", [
    (("--robot-state-topic", "/関節"), ["--robot-state-topic", "'/関節'"]),
    (("--robot-command-topic", "/a/"), ["--robot-command-topic"]),
    (("--robot-state-topic", "/a", "--robot-command-topic", "/a"), ["--robot-state-topic", "'/a'"]),
    (("--robot-state-topic", "/robot_joint_command"), ["--robot-state-topic", "/robot_joint_command"]),
    # relative names resolve in the arm's namespace, where the joint bus runs (were compared as written)
    (("--robot-state-topic", "x", "--robot-command-topic", "/pa10/x"), ["--robot-state-topic", "'x'", "/pa10/x"]),
    (("--namespace", "/arm2", "--robot-state-topic", "/arm2/y", "--robot-command-topic", "y"),
     ["--robot-state-topic", "both /arm2/y in the namespace /arm2"]),
    # accepted, then the joint bus waited 30 s for joint states on the graph's /clock
    (("--robot-state-topic", "/clock"), ["--robot-state-topic: '/clock' is /clock, which carries rosgraph_msgs"]),
    (("--robot-command-topic", "/clock"), ["--robot-command-topic: '/clock' is /clock"]),
    # the graph's own joint states: accepted, then reported at run time as "a second robot" on the state topic
    (("--robot-state-topic", "/pa10/joint_states"), ["--robot-state-topic: '/pa10/joint_states' is the graph's "
                                                     "own joint states: the robot's joint states and commands"]),
    (("--robot-state-topic", "w2/reference"), ["--robot-state-topic: 'w2/reference' is joint w2's reference topic"]),
    (("--namespace", "/arm2", "--robot-command-topic", "trajectory"), ["--robot-command-topic", "/arm2/trajectory",
                                                                       "the graph's trajectory input"]),
])
def test_launch_robot_external_topics_are_checked(tmp_path, args, words):
    out = tmp_path / "out"
    _refused(run_cli("launch", "--robot", "external", *args, "--duration", "0.1", "--out", out), words)
    assert not list(tmp_path.iterdir())
    _no_pa10_children()


def test_robot_topics_are_compared_as_resolved_in_the_arms_namespace():
    """``x`` in /pa10 is /pa10/x: it differs from /x (accepted) and equals /pa10/x (refused above)."""
    from pa10_dnbs.supervisor.robot_options import RobotOptions, check_robot_options
    for ns in ("/pa10", "/lab/arm2"):
        fields = check_robot_options(RobotOptions(state_topic="x", command_topic="/x"), "lockstep", ns)
        assert (fields["robot_state_topic"], fields["robot_command_topic"]) == ("x", "/x")
    with pytest.raises(ValueError, match="both /lab/arm2/x in the namespace /lab/arm2"):
        check_robot_options(RobotOptions(state_topic="/lab/arm2/x", command_topic="x"), "lockstep", "/lab/arm2")
    # another arm's graph topics are a robot's like any other: only the arm's own namespace is the graph's
    assert check_robot_options(RobotOptions(state_topic="/pa10/joint_states"), "lockstep", "/arm2")[
        "robot_state_topic"] == "/pa10/joint_states"
    with pytest.raises(ValueError, match="'joint_states' is the graph's own joint states"):
        check_robot_options(RobotOptions(state_topic="joint_states"), "lockstep", "/arm2")


@pytest.mark.parametrize("args,words", [
    (("--mode", "realtime", "--rtf", "1e-300"), ["--rtf", "1e-300"]),
    (("--mode", "realtime", "--rtf", "0.0009"), ["--rtf"]),
    (("--mode", "realtime", "--rtf", "101"), ["--rtf"]),
    (("--effort-timeout", "1e308"), ["--effort-timeout", "1e308"]),
    (("--effort-timeout", "3601"), ["--effort-timeout"]),
    (("--effort-timeout", "0"), ["--effort-timeout"]),
])
def test_rtf_and_effort_timeout_are_bounded(tmp_path, args, words):
    out = tmp_path / "out"
    _refused(run_cli("launch", *args, "--duration", "0.2", "--out", out), words)
    assert not list(tmp_path.iterdir())
    _no_pa10_children()


_PROBE = """
import numpy as np
from pa10_dnbs.accel.choice import auto_kernel
print(auto_kernel().kernel)
"""


def _truncated_cache(tmp_path: Path, env: dict) -> Path:
    """A cache directory whose library (for $CC as ``env`` sets it) is a truncated copy of a real build (made by
    this shell's compiler)."""
    cache = tmp_path / "cache"
    good = subprocess.run([sys.executable, "-m", "pa10_dnbs.accel.build"], capture_output=True, text=True,
                          env={**os.environ, "PA10_DNBS_CACHE": str(tmp_path / "good")}, cwd=REPO)
    assert good.returncode == 0, good.stderr
    data = Path(good.stdout.strip()).read_bytes()
    probe = "from pa10_dnbs.accel.build import library_target; print(library_target())"
    where = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True,
                           env={**env, "PA10_DNBS_CACHE": str(cache)}, cwd=REPO)
    target = Path(where.stdout.strip())
    target.parent.mkdir(parents=True)
    target.write_bytes(data[:100])
    return target


def test_a_truncated_cached_kernel_is_rebuilt_once_and_says_so(tmp_path):
    env = dict(os.environ)
    target = _truncated_cache(tmp_path, env)
    env["PA10_DNBS_CACHE"] = str(target.parent)
    r = subprocess.run([sys.executable, "-c", _PROBE], capture_output=True, text=True, env=env, cwd=REPO)
    assert r.returncode == 0 and r.stdout.strip() == "c", r.stderr
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and "rebuilding" in lines[0] and str(target) in lines[0], r.stderr
    assert target.stat().st_size > 1000 and not list(target.parent.glob(".*.tmp"))
    again = subprocess.run([sys.executable, "-c", _PROBE], capture_output=True, text=True, env=env, cwd=REPO)
    assert again.stdout.strip() == "c" and again.stderr == "", again.stderr  # the rebuilt one loads as is


def test_a_failed_rebuild_falls_back_to_numpy_under_auto_and_fails_in_one_line_under_c(tmp_path):
    """A compiler that fails (``false``): auto says numpy in one line and the run goes on; kernel c: exit 2."""
    env = {**os.environ, "CC": "false"}
    target = _truncated_cache(tmp_path, env)
    env["PA10_DNBS_CACHE"] = str(target.parent)
    r = subprocess.run([sys.executable, "-m", "pa10_dnbs.cli", "simulate", "--controller", "dnbs", "--duration",
                        "0.05", "--out", str(tmp_path / "o"), "--no-figures"], capture_output=True, text=True,
                       env=env, cwd=REPO)
    assert r.returncode == 0, r.stderr
    assert "rebuilding" in r.stderr and "auto -> numpy" in r.stdout and "Traceback" not in r.stderr
    c = subprocess.run([sys.executable, "-m", "pa10_dnbs.cli", "simulate", "--config", "config/compiled.yaml",
                        "--controller", "dnbs", "--duration", "0.05", "--out", str(tmp_path / "c"), "--no-figures"],
                       capture_output=True, text=True, env=env, cwd=REPO)
    assert c.returncode == 2 and "Traceback" not in c.stderr, c.stderr
    assert "compiling" in c.stderr and not (tmp_path / "c").exists()


def test_a_failed_launch_says_whose_bag_lies_at_record(tmp_path):
    """``--record BAG --force`` over an earlier run's bag, the run failing before its recorder opened BAG: the
    bag there is the earlier run's, and a user told "the bag recorded so far" would analyse it as this run's."""
    from pa10_dnbs.commands.launch_record import bag_stamp, failed_run_bag_note

    bag = tmp_path / "bag"
    assert failed_run_bag_note(bag, bag_stamp(bag)) is None   # no bag there at all
    bag.mkdir()
    (bag / "metadata.yaml").write_text("rosbag2_bagfile_information: {}\n")
    before = bag_stamp(bag)
    assert failed_run_bag_note(bag, before) == f"this run recorded nothing: {bag} is still the earlier run's bag, untouched"
    (bag / "metadata.yaml").unlink()   # the recorder replaced it, then finished what it had
    (bag / "metadata.yaml").write_text("rosbag2_bagfile_information: {}\n")
    later = before[1] + 10**9   # written a second later (the inode number may be the same one again)
    os.utime(bag / "metadata.yaml", ns=(later, later))
    assert failed_run_bag_note(bag, before) == f"the bag recorded so far is closed and readable: {bag}"
    assert failed_run_bag_note(tmp_path / "new", None) is None


@pytest.mark.parametrize("value", ["-5", "300", "x"])
def test_robot_refuses_a_domain_ros_2_does_not_accept(monkeypatch, value):
    """``robot`` joins this shell's ROS_DOMAIN_ID: a negative one ran silently on some domain, 300 ended in the
    DDS's colored "Calculated port number is too high" and exit 1."""
    monkeypatch.setenv("ROS_DOMAIN_ID", value)
    r = run_cli("robot", "--duration", "0.1")
    assert r.returncode == 2 and r.stderr.startswith("pa10-dnbs: error: ROS_DOMAIN_ID: ") and r.stderr.count("\n") == 1, r


@pytest.mark.parametrize("args", [
    ("launch", "--arm", "iiwa", "--duration", "0.2", "--no-figures", "--kill", "s1@0.1"),   # a PA10 joint
    ("launch", "--arm", "panda", "--duration", "0.2", "--no-figures", "--fault-joints", "zz"),
    ("robot", "--arm", "iiwa", "--state-topic", "bad//t"),
    ("simulate", "--arm", "iiwa", "--init-from", "/nonexistent"),
    ("study", "--arm", "iiwa", "--scenarios", "nominal", "--duration", "0.1", "--out", "/"),
    ("tune", "--arm", "iiwa", "--controller", "pid", "--trials", "1", "--duration", "0.1", "--out", "/"),
])
def test_a_refused_input_on_an_arm_the_rule_derives_is_one_line_without_its_table(tmp_path, args):
    """The gain rule's table is said once the inputs are accepted: a refusal is its one line alone."""
    out = () if "--out" in args or args[0] == "robot" else ("--out", tmp_path / "out")
    r = run_cli(*args, *out)
    assert r.returncode == 2, (r.returncode, r.stderr)
    assert len(r.stderr.strip().splitlines()) == 1, r.stderr
    assert r.stderr.startswith("pa10-dnbs: error: ") and "gains by the rule" not in r.stderr + r.stdout
    assert not (tmp_path / "out").exists()
    _no_pa10_children()


def test_an_accepted_run_on_such_an_arm_still_says_the_rules_table(tmp_path):
    r = run_cli("simulate", "--arm", "iiwa", "--controller", "pid", "--duration", "0.05", "--out", tmp_path / "o",
                "--no-figures")
    assert r.returncode == 0, r.stderr
    assert "arm iiwa: 7 joints" in r.stderr and "gains by the rule of docs/arms.md" in r.stderr
    assert len([line for line in r.stderr.splitlines() if line.startswith("  a")]) == 7, r.stderr


@pytest.mark.parametrize("command", [("launch", "--duration", "1", "--no-figures"), ("robot", "--duration", "1")])
def test_a_config_step_the_default_clock_rate_does_not_fit_names_the_step_not_the_flag(tmp_path, command):
    """simulation.dt_s: 0.1 takes at most 10 /clock a second: without --clock-hz the config's step is the cause;
    with it, the flag."""
    config = tmp_path / "dt.yaml"
    config.write_text(f"extends: {REPO / 'config' / 'default.yaml'}\nsimulation: {{dt_s: 0.1}}\n")
    out = ("--out", tmp_path / "out") if command[0] == "launch" else ()
    line = _refused(run_cli(*command, "--config", config, *out), ["default --clock-hz 100", "--clock-hz 10 or less"])
    assert line.startswith("pa10-dnbs: error: simulation.dt_s: a step of 0.1 s"), line
    line = _refused(run_cli(*command, "--config", config, *out, "--clock-hz", "100"), ["got 100.0"])
    assert line.startswith("pa10-dnbs: error: --clock-hz: must be in"), line
    assert not (tmp_path / "out").exists()
    _no_pa10_children()


@pytest.mark.parametrize("value", [",", "", " , "])
def test_an_empty_fault_joints_list_is_said_to_be_empty(tmp_path, value):
    """',' said "--fault-joints: unknown joint '(none)'"; '' silently meant every joint."""
    line = _refused(run_cli("launch", "--duration", "0.1", "--out", tmp_path / "out", "--drop-states", "0.1",
                            "--fault-joints", value), ["--fault-joints: the list names no joint", repr(value)])
    assert "(none)" not in line
    assert not (tmp_path / "out").exists()
    _no_pa10_children()


def test_a_joint_given_twice_in_fault_joints_is_refused(tmp_path):
    """It was taken silently, while --kill refuses a joint given twice."""
    line = _refused(run_cli("launch", "--duration", "0.1", "--out", tmp_path / "out", "--drop-states", "0.1",
                            "--fault-joints", "s1,s2,s1"), ["--fault-joints: joint s1 given twice"])
    assert line.startswith("pa10-dnbs: error: --fault-joints"), line
    assert not (tmp_path / "out").exists()
    _no_pa10_children()


def test_a_clock_so_slow_that_a_reference_message_would_be_too_large_is_refused(tmp_path):
    """A /clock hours apart made the launcher give the reference node more points per message than its
    batch_steps takes: the run failed inside the node, naming a parameter the user never set."""
    line = _refused(run_cli("launch", "--duration", "0.1", "--out", tmp_path / "out", "--clock-hz", "0.00005"),
                    ["--clock-hz: 5e-05 Hz is one /clock per 20,000,000 steps", "(at most 1,000,000)"])
    assert line.startswith("pa10-dnbs: error: --clock-hz"), line
    assert not (tmp_path / "out").exists()
    _no_pa10_children()

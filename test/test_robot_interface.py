"""The standard robot interface without ROS (pa10_dnbs/wire/robot_interface.py, supervisor/robot_options.py):
command forms, joint matching by name, the faults a robot's state can carry, the robot's time line."""
import math

import pytest

from cli_runner import run_cli
from pa10_dnbs.config import ConfigError
from pa10_dnbs.supervisor.domain_ids import shell_domain
from pa10_dnbs.supervisor.robot_options import RobotOptions, check_robot_options
from pa10_dnbs.wire import joint_state_cdr
from pa10_dnbs.wire.robot_interface import (JointMatcher, RobotCommand, RobotFault, RobotTimeline,
                                            default_state_topic, parse_robot_command)

PA10 = ("s1", "s2", "s3", "e1", "e2", "w1", "w2")


def test_command_forms_and_their_default_topics():
    assert parse_robot_command("joint_state") == RobotCommand("joint_state", "/robot_joint_command")
    assert parse_robot_command("joint_state", "/arm/cmd") == RobotCommand("joint_state", "/arm/cmd")
    fwd = parse_robot_command("forward:effort_controller")
    assert fwd == RobotCommand("forward", "/effort_controller/commands")
    assert default_state_topic(fwd) == "/joint_states"
    assert default_state_topic(parse_robot_command("joint_state")) == "/robot_joint_states"
    for bad in ("position", "forward:", "forward:1abc", "forward:a b", "JointState"):
        with pytest.raises(ValueError):
            parse_robot_command(bad)
    with pytest.raises(ValueError, match="only the JointState form takes a command topic"):
        parse_robot_command("forward:effort_controller", "/x")


def test_a_command_topic_beside_the_forward_form_is_said_of_its_own_flag():
    """It was '--robot-command: robot_command_topic is the JointState form's': a parameter's name, under the
    other flag."""
    r = run_cli("launch", "--out", "unused", "--robot", "external", "--robot-command", "forward:ctl",
                "--robot-command-topic", "/cmd")
    assert r.returncode == 2 and r.stderr == ("pa10-dnbs: error: --robot-command-topic: only the JointState form takes "
                                              "a command topic; the forward form publishes on /ctl/commands\n"), r.stderr


def test_joints_are_matched_by_name_not_order():
    m = JointMatcher(PA10)
    names = list(reversed(PA10)) + ["gripper"]
    pos = [float(i) for i in range(8)]
    q, qd = m.read(names, pos, [10 * p for p in pos])
    assert q == [6.0, 5.0, 4.0, 3.0, 2.0, 1.0, 0.0] and qd == [60.0, 50.0, 40.0, 30.0, 20.0, 10.0, 0.0]
    assert m.efforts(names, pos) == q


@pytest.mark.parametrize("names,pos,vel,says", [
    (PA10[:2] + PA10[3:], [0.0] * 6, [0.0] * 6, "joint_states lacks s3"),
    (PA10, [0.0, math.nan, 0, 0, 0, 0, 0], [0.0] * 7, "non-finite state of joint s2: position nan"),
    (PA10, [0.0] * 7, [0, 0, 0, 0, 0, 0, math.inf], "non-finite state of joint w2"),
    (PA10, [0.0] * 7, [], "7 names but 7 positions and 0 velocities"),
    (PA10 + ("s1",), [0.0] * 7 + [5.0], [0.0] * 8, "joint_states names s1 more than once"),
    (("s2",) + PA10 + ("gripper", "gripper"), [0.0] * 10, [0.0] * 10, "joint_states names s2 more than once"),
])
def test_a_bad_state_is_a_robot_fault_naming_it(names, pos, vel, says):
    with pytest.raises(RobotFault, match=says.replace("(", r"\(")):
        JointMatcher(PA10).read(names, pos, vel)


def test_a_state_decoded_from_cdr_reads_the_same():
    data = joint_state_cdr.encode(3, 5, list(reversed(PA10)), [0.1 * i for i in range(7)], [0.0] * 7, [])
    sec, nanosec, names, pos, vel, eff = joint_state_cdr.decode(data)
    assert (sec, nanosec) == (3, 5) and eff == ()
    q, _ = JointMatcher(PA10).read(names, pos, vel)
    assert q[0] == pytest.approx(0.6) and q[6] == 0.0


def test_the_robot_time_line():
    t = RobotTimeline(1_000_000)
    base = 1_700_000_000_000_000_000
    assert t.classify(base) == "new" and t.graph_ns(base) == 0
    assert t.classify(base) == "duplicate"
    assert t.classify(base - 1) == "old"
    assert t.classify(base + 1_000_000) == "new" and t.off_grid == 0
    assert t.classify(base + 3_000_000) == "new" and t.off_grid == 1  # a step of 2 ms on a 1 ms graph
    assert t.graph_ns(base + 3_000_000) == 3_000_000


def test_launch_flags_are_checked_with_one_line_naming_the_flag(monkeypatch):
    ok = check_robot_options(RobotOptions(), "lockstep")
    assert ok == {"robot": "external", "robot_command": "joint_state", "robot_state_topic": "",
                  "robot_command_topic": "", "robot_timeout_s": 1.0}
    assert check_robot_options(RobotOptions(command="forward:arm_effort"), "lockstep")["robot_command"] \
        == "forward:arm_effort"
    assert check_robot_options(RobotOptions(), "realtime")["robot"] == "external"  # paced: the bus follows
    cases = [(RobotOptions(command="torque"), "lockstep", "robot_command"),
             (RobotOptions(state_topic="/bad topic"), "lockstep", "robot_state_topic"),
             (RobotOptions(command_topic="//x"), "lockstep", "robot_command_topic"),
             (RobotOptions(timeout_s=0.0), "lockstep", "robot_timeout"),
             (RobotOptions(timeout_s=math.nan), "lockstep", "robot_timeout")]
    for opt, mode, setting in cases:  # the library names the setting; the command line, its flag (cli.py)
        with pytest.raises(ConfigError, match=f"^{setting}: ") as err:
            check_robot_options(opt, mode)
        flag = "--" + setting.replace("_", "-")
        assert err.value.setting == setting and err.value.named({setting: flag}).startswith(f"{flag}: ")
    monkeypatch.setenv("ROS_DOMAIN_ID", "42")
    assert shell_domain("the robot's domain") == 42
    monkeypatch.delenv("ROS_DOMAIN_ID")
    assert shell_domain("the robot's domain") == 0
    monkeypatch.setenv("ROS_DOMAIN_ID", "232")
    assert shell_domain("the robot's domain") == 232
    for bad in ("x", "300", "233", "-1"):  # rev_e 11: 300 started every node to fail, -1 ran on domain 0
        monkeypatch.setenv("ROS_DOMAIN_ID", bad)
        with pytest.raises(ConfigError, match="^ROS_DOMAIN_ID"):
            shell_domain("the robot's domain")


def test_the_launcher_starts_the_joint_bus_in_the_plants_place(tmp_path):
    """node_specs: with --robot external the last process is the joint bus with the robot's flags, no plant."""
    from pa10_dnbs.supervisor.graph_options import GraphOptions
    from pa10_dnbs.supervisor.node_specs import node_commands, node_group

    fields = check_robot_options(RobotOptions(command="forward:arm", state_topic="/arm/states"), "lockstep")
    opt = GraphOptions(config_path=tmp_path / "c.yaml", joint_names=PA10, **fields)
    cmds = node_commands(opt, tmp_path / "plant_stats.json", tmp_path / "wire.npz")
    names = [n for n, _ in cmds]
    assert names[-1] == "joint_bus" and "plant" not in names and node_group("joint_bus") == "plant"
    argv = cmds[-1][1]
    assert "pa10_dnbs.ros.joint_bus_node" in argv
    for param in ("robot_command:=forward:arm", "robot_state_topic:=/arm/states", "robot_command_topic:=''",
                  "robot_timeout_s:=1.0", f'stats_file:="{tmp_path / "plant_stats.json"}"'):
        assert param in argv, (param, argv)
    ready = next(a for a in argv if a.startswith("ready_nodes:="))
    assert "joint_controller_s1" in ready and "reference" in ready and "joint_bus" not in ready
    plain = node_commands(GraphOptions(config_path=tmp_path / "c.yaml", joint_names=PA10), tmp_path / "s.json",
                          tmp_path / "w.npz")
    assert plain[-1][0] == "plant" and not any("robot_" in a for a in plain[-1][1])


def test_the_bus_looks_for_the_robots_clock_until_discovery_has_had_its_time():
    """The bus took a robot for one without /clock when discovery had not yet matched its /clock publisher at
    the first state (1 launch in 13 of a second graph on a robot past time 0 drove it; review rev_g, 2)."""
    from pa10_dnbs.ros.joint_bus_node import CLOCK_DISCOVERY_S, publisher_seen

    t = [0.0]
    def later(answers):   # noqa: E306 - count() answers in turn; each sleep advances the fake wall clock
        it = iter(answers)
        return lambda: next(it, answers[-1])
    tick = dict(now=lambda: t[0], sleep=lambda s: t.__setitem__(0, t[0] + s))
    assert publisher_seen(later([0, 0, 0, 1]), CLOCK_DISCOVERY_S, **tick)   # matched 60 ms after the state
    t[0] = 0.0
    assert not publisher_seen(later([0]), CLOCK_DISCOVERY_S, **tick) and t[0] >= CLOCK_DISCOVERY_S   # hardware
    t[0] = 0.0
    assert publisher_seen(later([1]), CLOCK_DISCOVERY_S, **tick) and t[0] == 0.0   # seen at once: no wait


def test_the_robots_warning_of_a_command_lacking_joints_names_the_arms_and_the_commands():
    """robot --arm iiwa fed PA10 commands said 'a command without every joint of the arm (s1, ..., w2)': the
    command's joints, as if they were the arm's."""
    from types import SimpleNamespace

    from pa10_dnbs.ros.mujoco_robot_node import MuJoCoRobotNode

    said = []
    node = SimpleNamespace(_index_of={}, joint_names=("a1", "a2", "a3"),
                           get_logger=lambda: SimpleNamespace(warning=said.append))
    assert MuJoCoRobotNode._efforts(node, ["s1", "a2"], [0.0, 1.0]) is None
    assert said == ["a command without every joint of the arm: the arm's joints are a1, a2, a3; the command names "
                    "s1, a2 (missing a1, a3): ignored"]
    assert MuJoCoRobotNode._efforts(node, ["a3", "a1", "a2"], [3.0, 1.0, 2.0]) == [1.0, 2.0, 3.0]
    assert MuJoCoRobotNode._efforts(node, [], []) is None
    assert said[-1].endswith("the command names none (missing a1, a2, a3): ignored")

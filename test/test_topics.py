"""Topic names for a namespace (wire/topics.py): validation, resolution, the arm of a bag, replay renaming."""
import pytest

from pa10_dnbs.arm import load_arm

JOINT_NAMES = load_arm("pa10").joint_names
from pa10_dnbs.wire.topics import (ArmTopics, arm_topics, check_namespace, find_arm, legacy_topics, renamed,
                                   resolve)


def test_default_namespace_keeps_the_per_joint_names():
    arm = ArmTopics()
    assert (arm.state("s1"), arm.effort("w2"), arm.reference("e1")) == ("/pa10/s1/state", "/pa10/w2/effort",
                                                                         "/pa10/e1/reference")
    assert (arm.joint_states, arm.robot_description, arm.tracking) == ("/pa10/joint_states",
                                                                        "/pa10/robot_description", "/pa10/tracking")
    assert resolve("/clock", "/arm2") == "/clock" and resolve("s1/state", "/lab/arm2") == "/lab/arm2/s1/state"


@pytest.mark.parametrize("ns", ["/pa10", "/arm2", "/lab/arm_2", "/A"])
def test_valid_namespaces(ns):
    assert check_namespace(ns) == ns and arm_topics(ns).state("s1") == f"{ns}/s1/state"


@pytest.mark.parametrize("ns", ["", "/", "pa10", "/pa10/", "//pa10", "/pa10//x", "/pa-10", "/pa 10", "/2arm", "/a/1b",
                                "/a__b", "/lab/__arm"])   # '__': rcl cannot parse the remap rule (it started the graph)
def test_invalid_namespaces(ns):
    with pytest.raises(ValueError, match="ROS namespace"):
        check_namespace(ns)


@pytest.mark.parametrize("name,ns", [("pa10", "/pa10"), ("PA10 - lab copy", "/PA10_lab_copy"), ("__x_", "/x"),
                                     ("7dof", "/arm_7dof"), ("--", "/arm")])
def test_an_arm_s_name_gives_a_namespace_rcl_can_take(name, ns):
    """'PA10 - lab copy' gave /PA10___lab_copy, which every node of the graph then failed to take."""
    from pa10_dnbs.wire.topics import default_namespace

    assert default_namespace(name) == ns and check_namespace(ns) == ns


def test_a_joint_name_with_a_double_underscore_is_refused_before_any_node_starts():
    from pa10_dnbs.wire.topics import check_joint_name

    assert check_joint_name("arm_left_1") == "arm_left_1"
    for joint in ("arm__1", "_j1"):   # joint_controller__j1: the same '__'
        with pytest.raises(ValueError, match="without '__'"):
            check_joint_name(joint)


def test_find_arm_new_old_and_none():
    def topics(arm):
        return {arm.joint_states, arm.robot_description, "/clock", "/tf"} | {arm.reference(j) for j in JOINT_NAMES}

    assert find_arm(topics(ArmTopics("/lab/arm2")), "s1") == ArmTopics("/lab/arm2")
    assert find_arm(topics(legacy_topics()), "s1") == legacy_topics()
    both = topics(ArmTopics("/arm2")) | topics(ArmTopics())
    assert find_arm(both, "s1") == ArmTopics()  # the default arm first
    assert find_arm({"/arm2/joint_states", "/pa10/s1/reference"}, "s1") is None


def test_renamed_moves_only_the_arms_topics():
    old, new = legacy_topics(), ArmTopics()
    assert renamed("/joint_states", old, "/arm2") == "/arm2/joint_states"
    assert renamed("/pa10/s1/effort", new, "/x/y") == "/x/y/s1/effort"
    assert renamed("/clock", new, "/arm2") == "/clock" and renamed("/tf", old, "/arm2") == "/tf"
    assert renamed("/pa10/s1/effort", new, None) == "/pa10/s1/effort"


def test_cli_parameter_reads_ros_args_only():
    pytest.importorskip("rclpy")
    from pa10_dnbs.ros.params import cli_parameter

    argv = ["node", "-p", "joint:=s9", "--ros-args", "-r", "__ns:=/a", "-p", "joint:=e1", "--param", "x:='y'", "--"]
    assert cli_parameter(argv, "joint") == "e1" and cli_parameter(argv, "x") == "y"
    assert cli_parameter(["node", "--ros-args", "-p", "other:=1"], "joint") is None


@pytest.mark.parametrize("args,word", [(("launch", "--namespace", "/pa10/"), "--namespace"),
                                       (("launch", "--namespace", "arm2"), "--namespace"),
                                       (("launch", "--clock-hz", "0"), "--clock-hz"),
                                       (("launch", "--clock-hz", "2000"), "--clock-hz")])
def test_launcher_refuses_a_bad_namespace_or_clock_rate_in_one_line(tmp_path, args, word):
    from cli_runner import run_cli

    r = run_cli(*args, "--duration", "1", "--out", tmp_path / "out")
    assert r.returncode == 2 and word in r.stderr and len(r.stderr.strip().splitlines()) == 1, r.stderr
    assert not (tmp_path / "out").exists()


def test_replay_refuses_a_bad_namespace(tmp_path):
    from cli_runner import run_cli

    r = run_cli("replay", tmp_path / "no_bag", "--namespace", "/a//b")
    assert r.returncode == 2 and "--namespace" in r.stderr and len(r.stderr.strip().splitlines()) == 1, r.stderr

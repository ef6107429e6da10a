"""Bags other programs wrote, or a hand-damaged run description: one line on stderr naming the topic, key or
flag, exit 2, nothing written, never a traceback."""
import json
import os
import subprocess
import sys

from cli_runner import run_cli
from rosbags.typesys import Stores, get_typestore
from test_bag_files import QOS, REPO, _assert_clear_error, _write_run_bag

from pa10_dnbs.bag.bag_writer import BagWriter
from pa10_dnbs.config import default_config_path
from pa10_dnbs.run_settings import build_settings
from pa10_dnbs.wire import joint_state_cdr


def test_a_reference_point_without_a_position_is_named(tmp_path):
    """Reference points with empty positions (another program's bag) gave an IndexError traceback."""
    bag = _write_run_bag(tmp_path / "b", n=20, ref_positions=())
    r = run_cli("analyse", bag, "--out", tmp_path / "out")
    _assert_clear_error(r, f"{bag}: /pa10/s1/reference: a reference point holds no position")
    assert len(r.stderr.strip().splitlines()) == 1 and not (tmp_path / "out").exists(), r.stderr


def _replay(domain, *args, timeout=60):
    """``pa10-dnbs replay ARGS`` in its own process, on the test's ROS domain."""
    return subprocess.run([sys.executable, "-m", "pa10_dnbs.cli", "replay", *map(str, args)], cwd=REPO,
                          capture_output=True, text=True, timeout=timeout,
                          env={**os.environ, "ROS_DOMAIN_ID": str(domain), "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST"})


def _string_bag(path, topic):
    """A bag another program could write: five std_msgs/String messages on ``topic``, 10 ms apart."""
    store = get_typestore(Stores.ROS2_JAZZY)
    data = bytes(store.serialize_cdr(store.types["std_msgs/msg/String"](data="x"), "std_msgs/msg/String"))
    w = BagWriter(path)
    w.add_topic(topic, "std_msgs/msg/String", [QOS])
    for k in range(5):
        w.write(topic, k * 10_000_000, data)
    w.close()
    return path


def test_replay_of_a_topic_name_ros_refuses_is_refused_before_playing(tmp_path, domain):
    """A topic named /9bad-name gave rclpy's InvalidTopicNameException traceback from the player."""
    bag = _string_bag(tmp_path / "b", "/9bad-name")
    r = _replay(domain, bag)
    _assert_clear_error(r, f"{bag}: cannot play topic '/9bad-name': expected a ROS topic name")
    assert r.stdout == "" and len(r.stderr.strip().splitlines()) == 1, r.stdout + r.stderr


def _two_joint_bag(path, custom_data=None):
    """A 2-joint arm's joint states (joints a, b) in /pa10, as another program writes them: no reference topics."""
    w = BagWriter(path, custom_data=custom_data)
    w.add_topic("/pa10/joint_states", "sensor_msgs/msg/JointState", [QOS])
    for k in range(5):
        w.write("/pa10/joint_states", k * 1_000_000,
                joint_state_cdr.encode(0, k * 1_000_000, ["a", "b"], [0.0, 0.1], [0.0, 0.0], [0.0, 0.0]))
    w.close()
    return path


def _stored(**changes) -> str:
    """The default config as the recorder stores it (JSON), with ``changes`` ({"section.key": value}) made."""
    cfg = build_settings(default_config_path(), report=False).to_config()
    for dotted, value in changes.items():
        section, key = dotted.split(".")
        cfg[section][key] = value
    return json.dumps(cfg)


def test_replay_live_of_a_bag_whose_arm_is_not_the_configs_is_refused(tmp_path, domain):
    """A 2-joint bag without a stored config gave LiveView's ValueError traceback ('torque_limit_nm needs one value
    per joint'): now analyse's joint-count check (bag/run_config.py), one line, before the live view starts."""
    bag = _two_joint_bag(tmp_path / "b")
    r = _replay(domain, bag, "--live", 0)
    _assert_clear_error(r, f"{bag}: the bag's arm has 2 joints (a, b), the shipped default config's")
    assert "LIVE" not in r.stdout and len(r.stderr.strip().splitlines()) == 1, r.stdout + r.stderr


def test_replay_live_of_a_damaged_stored_config_is_refused(tmp_path, domain):
    """A stored simulation.dt_s of 0 gave a ValueError traceback ('dt_s must be at least 1 ns')."""
    bag = _write_run_bag(tmp_path / "b", n=20, ns="/pa10", custom_data={"pa10_dnbs.config": _stored(**{"simulation.dt_s": 0})})
    r = _replay(domain, bag, "--live", 0)
    _assert_clear_error(r, f"{bag}: the config stored in the bag (pa10_dnbs.config): simulation.dt_s: must be >= ")
    assert "LIVE" not in r.stdout and len(r.stderr.strip().splitlines()) == 1, r.stdout + r.stderr

"""Bags other programs wrote, or a hand-damaged run description: one line on stderr naming the topic, key or
flag, exit 2, nothing written, never a traceback."""
import json
import os
import subprocess
import sys

import pytest
from cli_runner import run_cli
from rosbags.typesys import Stores, get_typestore
from test_bag_files import QOS, REPO, _assert_clear_error, _write_run_bag, tf_message_or_skip

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
    _assert_clear_error(r, f"{bag}: the bag's arm has 2 joints (a, b), the shipped default config (")
    assert "LIVE" not in r.stdout and len(r.stderr.strip().splitlines()) == 1, r.stdout + r.stderr


def test_replay_live_of_a_damaged_stored_config_is_refused(tmp_path, domain):
    """A stored simulation.dt_s of 0 gave a ValueError traceback ('dt_s must be at least 1 ns')."""
    bag = _write_run_bag(tmp_path / "b", n=20, ns="/pa10", custom_data={"pa10_dnbs.config": _stored(**{"simulation.dt_s": 0})})
    r = _replay(domain, bag, "--live", 0)
    _assert_clear_error(r, f"{bag}: the config stored in the bag (pa10_dnbs.config): simulation.dt_s: must be >= ")
    assert "LIVE" not in r.stdout and len(r.stderr.strip().splitlines()) == 1, r.stdout + r.stderr


@pytest.mark.parametrize("custom,words", [
    # the duration the launcher stored: OverflowError, or a negative step count blamed on the stamps
    ({"duration_s": "inf"}, "custom_data pa10_dnbs.duration_s: must be finite, got inf"),
    ({"duration_s": "-1"}, "custom_data pa10_dnbs.duration_s: must be > 0, got -1"),
    ({"duration_s": "x"}, "custom_data pa10_dnbs.duration_s: not a number: 'x'"),
    # a duration no memory holds: blamed on the stamps ('stamped by a wall clock instead of the sim clock?')
    ({"duration_s": "1e9"}, "custom_data pa10_dnbs.duration_s: 1e+09 s is 1,000,000,000,000 steps of 0.001 s"),
    # the stored config: ZeroDivisionError, ValueError from wire/steps.py, IndexError, TypeError, ValueError, KeyError
    ({"simulation.dt_s": 0}, "the config stored in the bag (pa10_dnbs.config): simulation.dt_s: must be >= 1e-05, got 0"),
    ({"simulation.dt_s": -0.001}, "simulation.dt_s: must be >= 1e-05, got -0.001"),
    ({"simulation.window_s": [5]}, "simulation.window_s: expected [t0, t1], got [5]"),
    ({"simulation.window_s": "ab"}, "simulation.window_s: expected [t0, t1], got 'ab'"),
    ({"plant.torque_limit_nm": ["a"] * 7}, "plant.torque_limit_nm[0]: expected a number, got str 'a'"),
    ({"metrics.x": 1}, "metrics.x: unknown key (allowed: settle_band_rad, startup_s)"),
])
def test_analyse_of_a_hand_damaged_run_description_names_the_key(tmp_path, custom, words):
    """Each of these gave a traceback (the brief's list in the commit); now one line naming the bag and the stored
    key, checked by the config schema where the description is read (bag/run_config.py), nothing written."""
    duration = custom.pop("duration_s", "0.02")
    cfg = json.loads(_stored(**{k: v for k, v in custom.items() if k != "metrics.x"}))
    if "metrics.x" in custom:
        cfg["metrics"] = {"x": 1}
    bag = _write_run_bag(tmp_path / "b", n=20, ns="/pa10",
                         custom_data={"pa10_dnbs.config": json.dumps(cfg), "pa10_dnbs.duration_s": duration})
    r = run_cli("analyse", bag, "--out", tmp_path / "out")
    _assert_clear_error(r, f"{bag}: ", words)
    assert len(r.stderr.strip().splitlines()) == 1 and not (tmp_path / "out").exists(), r.stderr


def test_analyse_of_an_intact_run_description_still_reads(tmp_path):
    """The checks pass a run's own description: 20 steps of 1 ms, exit 0."""
    bag = _write_run_bag(tmp_path / "b", n=20, ns="/pa10",
                         custom_data={"pa10_dnbs.config": _stored(), "pa10_dnbs.duration_s": "0.02"})
    r = run_cli("analyse", bag, "--out", tmp_path / "out", "--no-figures")
    assert r.returncode == 0, r.stderr
    assert "(20 steps from" in r.stdout, r.stdout


def test_replay_of_a_bag_without_messages_says_so(tmp_path, domain):
    """It said '--start-offset: 0.0 s is past the bag's end (-9223372036.855 s)' though no --start-offset was given."""
    w = BagWriter(tmp_path / "b")
    w.add_topic("/pa10/joint_states", "sensor_msgs/msg/JointState", [QOS])
    w.close()
    r = _replay(domain, tmp_path / "b")
    _assert_clear_error(r, f"{tmp_path / 'b'}: the bag holds no messages: nothing to play")
    assert "--start-offset" not in r.stderr and len(r.stderr.strip().splitlines()) == 1, r.stderr


def test_replay_of_a_bag_with_nothing_playable_is_refused_as_with_topics(tmp_path, domain):
    """A bag of /tf only (no Python package for tf2_msgs here) printed 'PLAYING 0 topics' and exited 0; with
    --topics /tf the same was refused: now both, one line, before ROS."""
    tf = tf_message_or_skip()
    w = BagWriter(tmp_path / "b")
    w.add_topic("/tf", "tf2_msgs/msg/TFMessage", [QOS])
    for k in range(3):
        w.write("/tf", k * 1_000_000, tf)
    w.close()
    r = _replay(domain, tmp_path / "b")
    _assert_clear_error(r, f"{tmp_path / 'b'}: nothing to play: /tf (tf2_msgs/msg/TFMessage: ")
    assert r.stdout == "" and len(r.stderr.strip().splitlines()) == 1, r.stdout + r.stderr



@pytest.mark.parametrize("bad", ["999", "233", "-1", "x"])
def test_replay_on_a_domain_ros_refuses_is_refused_before_joining(tmp_path, bad):
    """ROS_DOMAIN_ID=999 gave Fast DDS's 'Calculated port number is too high' twice, exit 1 and a file left in
    /dev/shm; -1 played on domain 0: now one line naming ROS_DOMAIN_ID, exit 2, before ROS is loaded."""
    from pa10_dnbs.ros.shm_cleanup import shm_files, unused

    before = shm_files()
    r = _replay(bad, _string_bag(tmp_path / "b", "/chatter"))
    _assert_clear_error(r, "ROS_DOMAIN_ID: ")
    assert "the domain the bag is played on" in r.stderr and len(r.stderr.strip().splitlines()) == 1, r.stderr
    assert r.stdout == "" and unused(shm_files() - before, frozenset({os.getpid()})) == set()

@pytest.mark.graph  # plays on a ROS domain
@pytest.mark.parametrize("case", ["played", "refused"])
def test_replay_leaves_nothing_in_dev_shm(tmp_path, domain, case):
    """No launcher sweeps after a replay: its Fast DDS files (a played bag: 39 were left) and LTTng's wait file
    (even a refusal, made once rclpy loaded) are its own to remove as it ends (commands/replay.py)."""
    from pa10_dnbs.ros.shm_cleanup import shm_files, unused

    before = shm_files()
    if case == "played":
        r = _replay(domain, _string_bag(tmp_path / "b", "/chatter"))
        assert r.returncode == 0 and "PLAYED 5 messages" in r.stdout, r.stdout + r.stderr
    else:
        r = _replay(domain, _string_bag(tmp_path / "b", "/9bad-name"))
        assert r.returncode == 2, r.stderr
    # this test's process may map LTTng's file too (rclpy loaded by another test): its mapping does not count
    assert unused(shm_files() - before, frozenset({os.getpid()})) == set()


@pytest.mark.parametrize("offset, where", [("0.04", "at"), ("0.040000000001", "at"), ("0.05", "past")])
def test_replay_from_the_bags_end_is_refused_not_looped_without_pause(tmp_path, domain, offset, where):
    """--start-offset exactly the bag's length with --loop replayed its last instant in a tight loop (250k
    messages in 20 s): an offset at or past the last message is one line naming --start-offset, before ROS."""
    bag = _string_bag(tmp_path / "b", "/s")   # 0, 10, ..., 40 ms
    r = _replay(domain, bag, "--start-offset", offset, "--loop", timeout=20)
    _assert_clear_error(r, f"--start-offset: {float(offset):g} s is {where} the bag's end (its messages span 0.04 s)")
    assert r.stdout == "" and len(r.stderr.strip().splitlines()) == 1, r.stdout + r.stderr


def test_replay_loop_of_a_bag_at_one_instant_is_refused(tmp_path, domain):
    store = get_typestore(Stores.ROS2_JAZZY)
    w = BagWriter(tmp_path / "b")
    w.add_topic("/s", "std_msgs/msg/String", [QOS])
    w.write("/s", 0, bytes(store.serialize_cdr(store.types["std_msgs/msg/String"](data="x"), "std_msgs/msg/String")))
    w.close()
    r = _replay(domain, tmp_path / "b", "--loop", timeout=20)
    _assert_clear_error(r, "--loop: the bag's messages are all at one instant")


def test_replay_loop_of_topics_ending_early_waits_for_the_bags_end(tmp_path, domain):
    """--topics of a message at t = 0 only, --loop: each pass lasts the bag's 40 ms (it started the next at once:
    hundreds of thousands of messages a second)."""
    import signal
    import time

    store = get_typestore(Stores.ROS2_JAZZY)
    data = bytes(store.serialize_cdr(store.types["std_msgs/msg/String"](data="x"), "std_msgs/msg/String"))
    w = BagWriter(tmp_path / "b")
    for topic in ("/once", "/s"):
        w.add_topic(topic, "std_msgs/msg/String", [QOS])
    w.write("/once", 0, data)
    for k in range(5):
        w.write("/s", k * 10_000_000, data)
    w.close()
    p = subprocess.Popen([sys.executable, "-m", "pa10_dnbs.cli", "replay", str(tmp_path / "b"), "--topics", "/once",
                          "--loop"], cwd=REPO, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                         env={**os.environ, "ROS_DOMAIN_ID": str(domain), "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST"})
    try:
        assert "PLAYING" in p.stdout.readline() + p.stdout.readline(), "no PLAYING line"
        time.sleep(2.0)
        p.send_signal(signal.SIGINT)
        out, err = p.communicate(timeout=30)
    finally:
        if p.poll() is None:
            p.kill()
            p.wait()
    assert p.returncode == 0, err
    played = int(out.split("PLAYED ")[1].split()[0])
    assert 10 <= played <= 2.0 / 0.04 * 2, out   # about 50 passes of one message

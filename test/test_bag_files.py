"""Bag files without ROS: what the writer produces, and a clear error (exit 2, no traceback) for each broken bag."""
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import yaml
from cli_runner import run_cli
from rosbags.interfaces import Qos, QosDurability, QosHistory, QosLiveliness, QosReliability, QosTime

from pa10_dnbs.arm import load_arm

JOINT_NAMES = load_arm("pa10").joint_names
from pa10_dnbs.bag.bag_reader import Bag
from pa10_dnbs.bag.bag_writer import BagExistsError, BagWriter
from pa10_dnbs.wire import joint_state_cdr

REPO = Path(__file__).resolve().parent.parent
ZERO = QosTime(0, 0)
QOS = Qos(QosHistory.KEEP_LAST, 10, QosReliability.RELIABLE, QosDurability.VOLATILE, ZERO, ZERO,
          QosLiveliness.AUTOMATIC, ZERO, False)


def _write_bag(path, n=200, topic="/joint_states"):
    w = BagWriter(path, custom_data={"pa10_dnbs.controller": "dnbs"})
    w.add_topic(topic, "sensor_msgs/msg/JointState", [QOS])
    for k in range(n):
        w.write(topic, k * 1_000_000, joint_state_cdr.encode(0, k * 1_000_000, ["s1"], [0.1 * k], [1.0], [2.0]))
    w.close()
    return path


def _write_run_bag(path, n=300, compression="zstd", ns=None, custom_data=None, ref_positions=(0.0,)):
    """A complete little run: joint_states (7 joints) and one reference batch per joint, as the graph sends them.

    ``ns`` None: the old layout (/joint_states at the root, /pa10/<joint>/reference); else every topic in ``ns``.
    ``ref_positions``: each reference point's positions [rad] (the graph sends one).
    """
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS2_JAZZY)
    T = store.types
    w = BagWriter(path, compression=compression, custom_data=custom_data)
    js = "/joint_states" if ns is None else f"{ns}/joint_states"
    prefix = "/pa10" if ns is None else ns
    w.add_topic(js, "sensor_msgs/msg/JointState", [QOS])
    for k in range(n + 1):
        w.write(js, k * 1_000_000, joint_state_cdr.encode(
            0, k * 1_000_000, list(JOINT_NAMES), [0.001 * k] * 7, [1.0] * 7, [2.0] * 7))
    for j in JOINT_NAMES:
        pts = [T["trajectory_msgs/msg/JointTrajectoryPoint"](
            positions=np.array(ref_positions, dtype=float), velocities=np.array([0.0]), accelerations=np.array([], dtype=float),
            effort=np.array([], dtype=float), time_from_start=T["builtin_interfaces/msg/Duration"](sec=0, nanosec=i * 1_000_000))
            for i in range(n + 10)]
        msg = T["trajectory_msgs/msg/JointTrajectory"](
            header=T["std_msgs/msg/Header"](stamp=T["builtin_interfaces/msg/Time"](sec=0, nanosec=0), frame_id=""),
            joint_names=[j], points=pts)
        w.add_topic(f"{prefix}/{j}/reference", "trajectory_msgs/msg/JointTrajectory", [QOS])
        w.write(f"{prefix}/{j}/reference", 0, bytes(store.serialize_cdr(msg, "trajectory_msgs/msg/JointTrajectory")))
    w.close()
    return path


def _analyse(bag, tmp_path):
    return run_cli("analyse", bag, "--out", tmp_path / "out")


def _assert_clear_error(r, *words):
    assert r.returncode == 2, r.stderr
    assert "Traceback" not in r.stderr, r.stderr
    for w in words:
        assert w in r.stderr, r.stderr


def test_written_bag_reads_back(tmp_path):
    bag = _write_bag(tmp_path / "b")
    with Bag(bag) as b:
        assert b.topics["/joint_states"].count == 200 and b.message_count == 200
        assert b.custom_data["pa10_dnbs.controller"] == "dnbs"
        stamps = [joint_state_cdr.decode(bytes(d))[1] for _, _, _, d in b.messages()]
        assert stamps == [k * 1_000_000 for k in range(200)]
    meta = yaml.safe_load((bag / "metadata.yaml").read_text())["rosbag2_bagfile_information"]
    assert meta["version"] == 9 and meta["storage_identifier"] == "mcap"


def test_writer_refuses_an_existing_path_without_force(tmp_path):
    bag = _write_bag(tmp_path / "b")
    with pytest.raises(BagExistsError, match="pass `force` to replace it"):
        BagWriter(bag)
    w = BagWriter(bag, force=True)
    w.close()
    with Bag(bag) as b:
        assert b.message_count == 0


def test_force_replaces_only_an_empty_folder_or_a_bag_of_ours(tmp_path):
    """A bag carries OUTPUT_MARK (rosbag2 readers ignore the extra file: it opens as before); ``force`` replaces
    such a bag or an empty folder, never a folder of other files nor a file."""
    from pa10_dnbs.output_mark import OUTPUT_MARK

    bag = _write_bag(tmp_path / "b")
    assert (bag / OUTPUT_MARK).is_file()
    with Bag(bag) as b:
        assert b.message_count == 200
    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / "keep.txt").write_text("mine")
    with pytest.raises(BagExistsError, match="not a pa10-dnbs bag"):
        BagWriter(mine, force=True)
    (tmp_path / "file").write_text("mine")
    with pytest.raises(BagExistsError, match="not a folder"):
        BagWriter(tmp_path / "file", force=True)
    assert (mine / "keep.txt").read_text() == "mine" and (tmp_path / "file").read_text() == "mine"
    (tmp_path / "empty").mkdir()
    BagWriter(tmp_path / "empty", force=True).close()
    assert (tmp_path / "empty" / "metadata.yaml").is_file()


def test_force_replaces_a_bag_of_ours_recorded_before_bags_were_marked(tmp_path):
    """runs/main_bag of an earlier scripts/run_main.sh has no mark: known by its two files and its MCAP header
    (library pa10_dnbs), it is replaced as before; the same two files written by another tool are not."""
    from pa10_dnbs.output_mark import OUTPUT_MARK

    bag = _write_bag(tmp_path / "b")
    (bag / OUTPUT_MARK).unlink()
    BagWriter(bag, force=True).close()
    assert (bag / OUTPUT_MARK).is_file()
    other = tmp_path / "other"
    other.mkdir()
    (other / "metadata.yaml").write_text("rosbag2_bagfile_information: {}\n")
    profile, library = b"ros2", b"ros2 bag record"
    header = len(profile).to_bytes(4, "little") + profile + len(library).to_bytes(4, "little") + library
    (other / "other.mcap").write_bytes(b"\x89MCAP0\r\n" + bytes([1]) + len(header).to_bytes(8, "little") + header)
    with pytest.raises(BagExistsError, match="not a pa10-dnbs bag"):
        BagWriter(other, force=True)
    assert sorted(f.name for f in other.iterdir()) == ["metadata.yaml", "other.mcap"]


def test_a_complete_run_bag_analyses(tmp_path):
    """The baseline for the corruption tests below: undamaged, the same bag analyses with exit 0 (the current
    layout, /pa10/joint_states; the corruption tests use old bags)."""
    r = _analyse(_write_run_bag(tmp_path / "b", ns="/pa10"), tmp_path)
    assert r.returncode == 0, r.stderr
    m = json.loads((tmp_path / "out" / "metrics.json").read_text(), parse_constant=_not_json)
    assert m["wall_time_s"] is None and m["real_time_factor"] is None   # a bag holds no wall time: null, not NaN


def test_analyse_with_another_arms_config_is_refused_and_an_exit_1_says_why(tmp_path):
    """--config of another arm with as many joints reported the bag against that arm's limits and ended with
    exit 1 and no word, and one of another step misread the run's steps (metrics 34x off, exit 0); an exit 1
    (torques beyond the config's limits) now says why. A reader of a bag does not print the rules' table."""
    bag = _write_run_bag(tmp_path / "b", ns="/pa10")
    default = Path(__file__).resolve().parent.parent / "config" / "default.yaml"
    iiwa = tmp_path / "iiwa.yaml"
    iiwa.write_text(f"extends: {default}\narm: iiwa\n")
    r = run_cli("analyse", bag, "--out", tmp_path / "out", "--config", iiwa)
    _assert_clear_error(r, f"--config {iiwa}: its arm iiwa (joints a1, ", "is not the bag's (joints s1, ")
    assert len(r.stderr.strip().splitlines()) == 1, r.stderr   # was the rules' gain table (9 lines), then the error
    assert not (tmp_path / "out").exists()
    from pa10_dnbs.run_settings import build_settings
    stored = build_settings(default).to_config()   # a bag whose stored config gives its step, 1 ms
    stepped = _write_run_bag(tmp_path / "b1ms", ns="/pa10", custom_data={"pa10_dnbs.config": json.dumps(stored)})
    coarse = tmp_path / "coarse.yaml"
    coarse.write_text(f"extends: {default}\nsimulation:\n  dt_s: 0.002\n")
    r = run_cli("analyse", stepped, "--out", tmp_path / "out", "--config", coarse)
    _assert_clear_error(r, f"--config {coarse}: its simulation.dt_s 0.002 s is not the bag's step 0.001 s")
    assert not (tmp_path / "out").exists()
    weak = tmp_path / "weak.yaml"   # the bag's torques are 2 N m
    weak.write_text(f"extends: {default}\nplant:\n  torque_limit_nm: 1.0\n")
    r = run_cli("analyse", bag, "--out", tmp_path / "out", "--config", weak, "--no-figures")
    assert r.returncode == 1 and r.stderr.strip() == ("analyse: exit 1: the recorded run holds torques beyond the "
                                                      f"limits ({tmp_path / 'out'}/report.md)"), r.stderr


def _not_json(name):
    raise AssertionError(f"{name} in metrics.json: strict readers refuse it")


def test_a_stopped_runs_bag_analyses_its_recorded_part(tmp_path):
    """A bag whose run was stopped (Ctrl-C: 301 of the 1001 states of a 1 s run): analysed up to its last state,
    saying where it ends; a record with a gap is not taken for a stopped run."""
    bag = _write_run_bag(tmp_path / "b", n=300, ns="/pa10", custom_data={"pa10_dnbs.duration_s": "1.0"})
    r = _analyse(bag, tmp_path)
    assert r.returncode == 0, r.stderr
    assert "the bag ends at step 300 (0.3 s) of the 1000-step run (1 s)" in r.stdout
    assert "analysed the recorded part, [0, 0.3] s" in (tmp_path / "out" / "report.md").read_text()
    from pa10_dnbs.commands.analyse import _recorded_prefix_end
    from pa10_dnbs.wire.wire_record import WireRecord

    rec = WireRecord(200, 1e-3, 7)
    rec.got_state[:] = True
    rec.got_state[50:60] = False
    assert _recorded_prefix_end(rec) is None  # a gap: not a stopped run
    rec.got_state[50:] = False
    assert _recorded_prefix_end(rec) == 49



def test_missing_path_and_not_a_bag(tmp_path):
    _assert_clear_error(_analyse(tmp_path / "nothing", tmp_path), "does not exist")
    (tmp_path / "plain").mkdir()
    (tmp_path / "plain" / "x.txt").write_text("hello")
    _assert_clear_error(_analyse(tmp_path / "plain", tmp_path), "not a rosbag2 bag directory")
    _assert_clear_error(_analyse(tmp_path / "plain" / "x.txt", tmp_path), "not a rosbag2 bag")


def test_a_bag_cut_off_before_its_metadata_is_named_unfinished(tmp_path):
    """A second Ctrl-C (or a kill) while recording leaves the .mcap without metadata.yaml: said so, with the way
    back, not only "not a rosbag2 bag directory"."""
    bag = _write_bag(tmp_path / "b")
    (bag / "metadata.yaml").unlink()
    _assert_clear_error(_analyse(bag, tmp_path), f"{bag}: an unfinished bag: b.mcap but no metadata.yaml",
                        "ros2 bag reindex")


def test_truncated_bag(tmp_path):
    bag = _write_bag(tmp_path / "b")
    mcap = bag / "b.mcap"
    data = mcap.read_bytes()
    mcap.write_bytes(data[: len(data) // 2])
    _assert_clear_error(_analyse(bag, tmp_path), "truncated")
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("compression,where", [("none", 0.02), ("none", 0.5), ("none", 0.9),
                                               ("zstd", 0.02), ("zstd", 0.2), ("zstd", 0.45), ("zstd", 0.9)])
def test_corrupt_bag(tmp_path, compression, where):
    """Garbage over part of the file (record headers, payloads or compressed chunk data, message indexes,
    summary): a clear error. (In the small zstd bag the message indexes span 36-58 % of the file: only the
    data section CRC sees damage there; test_bag_crc.py has single flipped bytes.)
    """
    bag = _write_run_bag(tmp_path / "b", compression=compression)
    mcap = bag / "b.mcap"
    data = bytearray(mcap.read_bytes())
    at = int(len(data) * where)
    data[at:at + 64] = b"\xff" * 64
    mcap.write_bytes(bytes(data))
    r = _analyse(bag, tmp_path)
    _assert_clear_error(r, "pa10-dnbs: error:", str(bag))
    assert not (tmp_path / "out").exists()


def test_inconsistent_metadata(tmp_path):
    bag = _write_bag(tmp_path / "b")
    meta_path = bag / "metadata.yaml"
    meta = yaml.safe_load(meta_path.read_text())
    meta["rosbag2_bagfile_information"]["message_count"] = 999
    meta_path.write_text(yaml.safe_dump(meta))
    _assert_clear_error(_analyse(bag, tmp_path), "metadata.yaml counts 999")
    meta_path.write_text("rosbag2_bagfile_information: [unclosed")
    _assert_clear_error(_analyse(bag, tmp_path), "not valid YAML")


def test_bag_missing_the_needed_topics(tmp_path):
    bag = _write_bag(tmp_path / "b", topic="/other")
    _assert_clear_error(_analyse(bag, tmp_path), "needs topics", "/pa10/joint_states")  # it names the joints


def test_analysis_finds_the_arm_under_any_namespace_and_in_old_bags(tmp_path):
    """The same run recorded under /lab/arm2 and in the old layout (/joint_states at the root) reads back the
    same; a bag whose joint_states and references are in different namespaces is refused."""
    from pa10_dnbs.bag.analysis import bag_arm, wire_record_from_bag

    runs = []
    for name, ns in (("old", None), ("new", "/lab/arm2")):
        with Bag(_write_run_bag(tmp_path / name, n=100, ns=ns)) as b:
            assert bag_arm(b).joint_states == ("/joint_states" if ns is None else f"{ns}/joint_states")
            runs.append(wire_record_from_bag(b, 1e-3, None).run_data("dnbs", JOINT_NAMES, [1.0] * 7, 1.0))
    for field in ("position_rad", "velocity_rad_s", "reference_rad", "torque_nm"):
        assert np.array_equal(getattr(runs[0], field), getattr(runs[1], field)), field
    w = BagWriter(tmp_path / "mixed")
    w.add_topic("/arm3/joint_states", "sensor_msgs/msg/JointState", [QOS])
    w.write("/arm3/joint_states", 0, joint_state_cdr.encode(0, 0, list(JOINT_NAMES), [0.0] * 7, [0.0] * 7, [0.0] * 7))
    w.close()
    _assert_clear_error(_analyse(tmp_path / "mixed", tmp_path), "needs topics", "/pa10/joint_states")


def test_replay_rejects_unknown_topics_before_joining_ros(tmp_path):
    bag = _write_bag(tmp_path / "b")
    _assert_clear_error(run_cli("replay", bag, "--topics", "/nope"), "no such topic in the bag: /nope")
    _assert_clear_error(run_cli("replay", bag, "--topics", ""), "no such topic in the bag: (an empty name) (it has")
    _assert_clear_error(run_cli("replay", bag, "--rate", "0"), "--rate")


def _recorder(domain, *params):
    env = {**os.environ, "ROS_DOMAIN_ID": str(domain), "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST"}
    args = [a for p in params for a in ("-p", p)]
    return subprocess.run([sys.executable, "-m", "pa10_dnbs.ros.recorder_node", "--ros-args", *args],
                          cwd=REPO, env=env, capture_output=True, text=True, timeout=60)


@pytest.mark.graph
def test_standalone_recorder_rejects_bad_parameters(tmp_path, domain):
    _assert_clear_error(_recorder(domain), "parameter bag is required")
    _assert_clear_error(_recorder(domain, f"bag:={tmp_path / 'b'}"), "all_topics")
    _assert_clear_error(_recorder(domain, f"bag:={tmp_path / 'b'}", "topics:=['/pa10//joint_states']"),
                        "parameter topics: Invalid topic name: topic name must not contain repeated '/'")
    # a space: a ValueError traceback from making the subscription, an empty bag left behind
    _assert_clear_error(_recorder(domain, f"bag:={tmp_path / 'b'}", "topics:=['bad topic']"),
                        "parameter topics: topic name 'bad topic' is invalid")
    existing = _write_bag(tmp_path / "old")
    before = sorted(p.name for p in existing.iterdir())
    _assert_clear_error(_recorder(domain, f"bag:={existing}", "all_topics:=true"), "exists", "pass force:=true")
    assert sorted(p.name for p in existing.iterdir()) == before
    assert not (tmp_path / "b").exists()


def test_launcher_rejects_a_lockstep_bag_that_lost_messages(tmp_path, cfg):
    """A lockstep recording must hold one message per step on every per-step topic, or the run fails."""
    from pa10_dnbs.commands.launch_record import bag_run as _bag_run

    bag = _write_run_bag(tmp_path / "b", n=300)
    run, missing = _bag_run(bag, 1e-3, 300, "dnbs", cfg, 1.0, lockstep_stats=None)
    assert missing is None and run.n_steps == 300
    stats = {"joints": [{"timeout_ranges": []} for _ in JOINT_NAMES]}
    _, missing = _bag_run(bag, 1e-3, 300, "dnbs", cfg, 1.0, lockstep_stats=stats)
    assert "/pa10/s1/effort lacks 300 steps (first 0)" in missing and "/clock lacks 31 steps" in missing  # 100 Hz: steps 0, 10, ..., 300
    assert "/joint_states" not in missing  # that one is complete
    new = _write_run_bag(tmp_path / "new", n=300, ns="/arm2")
    _, missing = _bag_run(new, 1e-3, 300, "dnbs", cfg, 1.0, lockstep_stats=stats)
    assert "/arm2/s1/effort lacks 300 steps (first 0)" in missing and "/arm2/joint_states" not in missing


@pytest.mark.parametrize("compression,chunk_compression", [("zstd", "zstd"), ("none", "")])
def test_compression_option_every_reader_gets_every_message(tmp_path, compression, chunk_compression):
    """zstd: compressed MCAP chunks, as `ros2 bag record -s mcap` writes (metadata.yaml names no compression,
    the chunks say it); rosbags, mcap and the analysis read every message of either kind, the same bytes."""
    from mcap.reader import make_reader
    from rosbags.highlevel import AnyReader

    from pa10_dnbs.bag.analysis import wire_record_from_bag

    bag = _write_run_bag(tmp_path / "b", compression=compression)
    plain = _write_run_bag(tmp_path / "plain", compression="none")
    meta = yaml.safe_load((bag / "metadata.yaml").read_text())["rosbag2_bagfile_information"]
    assert meta["compression_mode"] == "" and meta["compression_format"] == ""
    with open(bag / "b.mcap", "rb") as f:
        reader = make_reader(f)
        summary = reader.get_summary()
        assert summary.chunk_indexes and {c.compression for c in summary.chunk_indexes} == {chunk_compression}
        via_mcap = [(ch.topic, m.log_time, m.data) for _, ch, m in reader.iter_messages(log_time_order=False)]
    with AnyReader([bag]) as r:
        via_rosbags = [(c.topic, t, bytes(d)) for c, t, d in r.messages()]
    with AnyReader([plain]) as r:
        expected = [(c.topic, t, bytes(d)) for c, t, d in r.messages()]
    assert len(expected) == meta["message_count"] == 301 + 7
    assert sorted(via_mcap) == sorted(expected) and sorted(via_rosbags) == sorted(expected)
    with Bag(bag) as b, Bag(plain) as p:
        a, c = wire_record_from_bag(b, 1e-3, 300), wire_record_from_bag(p, 1e-3, 300)
    for field in ("pos", "vel", "eff", "ref"):
        assert np.array_equal(getattr(a, field), getattr(c, field), equal_nan=True), field


def test_zstd_bag_is_smaller_and_a_bad_compression_is_refused(tmp_path):
    zstd = _write_run_bag(tmp_path / "z", n=3000)
    none = _write_run_bag(tmp_path / "n", n=3000, compression="none")
    assert (zstd / "z.mcap").stat().st_size < (none / "n.mcap").stat().st_size / 3
    with pytest.raises(ValueError, match="compression"):
        BagWriter(tmp_path / "x", compression="lz4")
    assert not (tmp_path / "x").exists()


def test_analysis_progress_reports_steps_and_the_worst_error(tmp_path):
    """The progress callback of the analysis sees the steps and the worst |x_d - x|; the result is unchanged."""
    from pa10_dnbs.bag.analysis import wire_record_from_bag

    bag = _write_run_bag(tmp_path / "b", n=1200)
    calls = []
    with Bag(bag) as b:
        with_progress = wire_record_from_bag(b, 1e-3, 1200, progress=lambda k, e: calls.append((k, e)))
        without = wire_record_from_bag(b, 1e-3, 1200)
    assert [k for k, _ in calls] == [499, 999, 1200]
    # x_d = 0 and x(k) = 0.001 k on every joint: |e| grows with k; x_d ends at step 1209
    assert [e for _, e in calls] == pytest.approx([0.499, 0.999, 1.2])
    for field in ("pos", "vel", "eff", "ref"):
        assert np.array_equal(getattr(with_progress, field), getattr(without, field), equal_nan=True)


def test_launch_rejects_bad_live_and_compression_options_before_starting(tmp_path):
    for args, words in ((["--live", "70000"], "--live: port must be in 0..65535"),
                        (["--live", "0", "--live-hz", "0"], "--live-hz"),
                        (["--live", "0", "--live-host", "no-such-host.invalid"], "--live-host")):
        r = run_cli("launch", "--duration", "1", "--out", tmp_path / "run", *args)
        _assert_clear_error(r, words)
        assert "launch: domain" not in r.stdout and not (tmp_path / "run").exists()
    r = run_cli("launch", "--duration", "1", "--out", tmp_path / "run", "--record", tmp_path / "bag",
                "--bag-compression", "lz4")
    assert r.returncode == 2 and "--bag-compression" in r.stderr and not (tmp_path / "bag").exists()


def test_the_player_counts_what_it_publishes_to_nobody():
    """A message published while its topic has no matched subscriber is counted, and the player's last line says
    that nothing received it (the re-drive a newcomer tries without a plant listening)."""
    from types import SimpleNamespace

    from pa10_dnbs.ros.player_node import HEARD_RECHECK_S, PlayerNode, unheard_warning

    subs = {"/pa10/s1/effort": 0, "/pa10/s2/effort": 1}
    player = SimpleNamespace(unheard={}, _heard_at={},
                             pubs={t: SimpleNamespace(get_subscription_count=lambda t=t: subs[t]) for t in subs})
    for i in range(3):
        for t in subs:
            PlayerNode._count_unheard(player, t, now=i * HEARD_RECHECK_S / 2)
    assert player.unheard == {"/pa10/s1/effort": 3}
    subs["/pa10/s2/effort"] = 0  # its subscriber went away: noticed once the recheck period has passed
    PlayerNode._count_unheard(player, "/pa10/s2/effort", now=2 * HEARD_RECHECK_S)
    assert player.unheard == {"/pa10/s1/effort": 3, "/pa10/s2/effort": 1}
    line = unheard_warning(player.unheard, 6)
    assert line.startswith("WARNING replay: 4 of 6 messages went out with no subscriber matched on "
                           "/pa10/s1/effort, /pa10/s2/effort: nothing received them")
    assert "--wait-for-subscribers" in line


def _edit_metadata(bag, edit):
    """Apply ``edit`` to the bag's rosbag2_bagfile_information and write metadata.yaml back."""
    meta_path = bag / "metadata.yaml"
    meta = yaml.safe_load(meta_path.read_text())
    edit(meta["rosbag2_bagfile_information"])
    meta_path.write_text(yaml.safe_dump(meta))
    return bag


def _topic_entry(info, topic):
    return next(e for e in info["topics_with_message_count"] if e["topic_metadata"]["name"] == topic)


def _drop_topic(info, topic):
    """Leave ``topic`` out (the total lessened by its count: only the per-topic check can see it)."""
    entry = _topic_entry(info, topic)
    info["topics_with_message_count"].remove(entry)
    info["message_count"] -= entry["message_count"]


METADATA_DISAGREEMENTS = {
    "type": (lambda i: _topic_entry(i, "/pa10/joint_states")["topic_metadata"].__setitem__("type", "std_msgs/msg/String"),
             "topic /pa10/joint_states has type std_msgs/msg/String but the MCAP file holds it as "
             "sensor_msgs/msg/JointState"),
    "left out": (lambda i: _drop_topic(i, "/pa10/s1/reference"),
                 "leaves out topic /pa10/s1/reference, of which the MCAP file holds 1 messages"),
    "added": (lambda i: i["topics_with_message_count"].append(
        {"topic_metadata": {"name": "/extra", "type": "std_msgs/msg/String", "serialization_format": "cdr"},
         "message_count": 0}), "lists topic /extra (std_msgs/msg/String, 0 messages), which the MCAP file"),
    "count": (lambda i: _topic_entry(i, "/pa10/joint_states").__setitem__("message_count", 5),
              "topic /pa10/joint_states counts 5 messages but the MCAP summary holds 51"),
    "negative duration": (lambda i: i.__setitem__("duration", {"nanoseconds": -1}),
                          "duration.nanoseconds: expected a whole number >= 0, got -1"),
    "absurd duration": (lambda i: i.__setitem__("duration", {"nanoseconds": 10 ** 18}),
                        "duration 1000000000000000000 ns ends the bag at 1000000000000000000 ns but its last "
                        "message in the MCAP file is at 50000000 ns"),
    "start": (lambda i: i.__setitem__("starting_time", {"nanoseconds_since_epoch": 7}),
              "starting_time is 7 ns but the first message in the MCAP file is at 0 ns"),
    "malformed count": (lambda i: i["topics_with_message_count"][0].__setitem__("message_count", "many"),
                        "topics_with_message_count[0].message_count (/pa10/joint_states): expected a whole number"),
}


@pytest.mark.parametrize("case", sorted(METADATA_DISAGREEMENTS))
def test_metadata_that_disagrees_with_the_mcap_is_refused(tmp_path, case):
    """rosbags reads a bag's topics, types, counts and times from metadata.yaml: a type that is not its channel's
    played 0 messages of the topic (exit 0), a topic left out was 'no such topic', wrong counts and durations were
    taken as they stood. Each is now one line naming metadata.yaml and the topic or field, exit 2, for analyse
    and replay alike (replay opens the bag before it joins ROS)."""
    from pa10_dnbs.bag.bag_reader import BagError

    edit, words = METADATA_DISAGREEMENTS[case]
    bag = _edit_metadata(_write_run_bag(tmp_path / "b", n=50, ns="/pa10"), edit)
    with pytest.raises(BagError) as err:
        Bag(bag)
    assert f"{bag}/metadata.yaml: " in str(err.value) and words in str(err.value), str(err.value)
    r = _analyse(bag, tmp_path)
    _assert_clear_error(r, f"{bag}/metadata.yaml: ", words)
    assert len(r.stderr.strip().splitlines()) == 1 and not (tmp_path / "out").exists()


def test_replay_of_a_bag_whose_metadata_names_another_type_is_refused_before_ros(tmp_path):
    """The reviewer's case: replay played 0 of the topic's messages and exited 0."""
    edit, words = METADATA_DISAGREEMENTS["type"]
    bag = _edit_metadata(_write_run_bag(tmp_path / "b", n=50, ns="/pa10"), edit)
    r = subprocess.run([sys.executable, "-m", "pa10_dnbs.cli", "replay", str(bag), "--rate", "10", "--topics",
                        "/pa10/joint_states"], cwd=REPO, capture_output=True, text=True, timeout=120,
                       env={**os.environ, "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST"})
    _assert_clear_error(r, f"{bag}/metadata.yaml: ", words)
    assert r.stdout == "" and len(r.stderr.strip().splitlines()) == 1, r.stdout + r.stderr


def test_metadata_within_rosbag2s_own_slack_is_accepted(tmp_path):
    """rosbag2 writes the duration as a running maximum, short of the span when receive stamps came out of order:
    an end a little before the last message is how rosbag2 writes it, not a disagreement."""
    bag = _edit_metadata(_write_run_bag(tmp_path / "b", n=50, ns="/pa10"),
                         lambda i: i.__setitem__("duration", {"nanoseconds": i["duration"]["nanoseconds"] - 1_000_000}))
    with Bag(bag) as b:
        assert b.message_count == 51 + 7


def test_the_unheard_warning_names_the_topics_as_published():
    """replay --namespace /arm3 of a bag recorded in /arm2: the warning named /arm2/joint_states, where nothing
    was published; it names /arm3/joint_states, where a subscriber must be started."""
    import contextlib
    import io
    from types import SimpleNamespace

    from pa10_dnbs.ros.player_node import PlayerNode

    player = SimpleNamespace(published=301, skipped=[], interrupted=False, unheard={"/arm2/joint_states": 301},
                             out_name={"/arm2/joint_states": "/arm3/joint_states", "/clock": "/clock"})
    err = io.StringIO()
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(err):
        PlayerNode.close(player)
    assert err.getvalue().startswith("WARNING replay: 301 of 301 messages went out with no subscriber matched on "
                                     "/arm3/joint_states: nothing received them"), err.getvalue()
    assert "/arm2" not in err.getvalue()


def tf_message_or_skip() -> bytes:
    """An empty tf2_msgs/TFMessage (CDR) for a bag; the test is skipped where tf2_msgs has a Python package (/tf is
    then playable)."""
    from rosbags.typesys import Stores, get_typestore

    from pa10_dnbs.ros.msg_types import message_class

    try:
        message_class("tf2_msgs/msg/TFMessage")
        pytest.skip("tf2_msgs is installed here: /tf is playable")
    except LookupError:
        pass
    store = get_typestore(Stores.ROS2_JAZZY)
    return bytes(store.serialize_cdr(store.types["tf2_msgs/msg/TFMessage"](transforms=[]), "tf2_msgs/msg/TFMessage"))


def test_replay_of_only_unplayable_topics_is_refused_before_ros(tmp_path):
    """--topics /tf (tf2_msgs has no Python package here) played nothing and exited 0: now one line naming
    --topics and why, exit 2, before ROS; a mix of playable and unplayable topics is played as before (the player
    skips and names the others)."""
    from pa10_dnbs.commands.replay import unplayable_topics

    tf = tf_message_or_skip()
    w = BagWriter(tmp_path / "b")
    w.add_topic("/tf", "tf2_msgs/msg/TFMessage", [QOS])
    w.add_topic("/tf_static", "tf2_msgs/msg/TFMessage", [QOS])
    w.add_topic("/joint_states", "sensor_msgs/msg/JointState", [QOS])
    for k in range(3):
        w.write("/tf", k * 1_000_000, tf)
        w.write("/joint_states", k * 1_000_000, joint_state_cdr.encode(0, k * 1_000_000, ["s1"], [0.0], [0.0], [0.0]))
    w.write("/tf_static", 0, tf)
    w.close()
    bag = tmp_path / "b"
    with Bag(bag) as b:
        assert set(unplayable_topics(b, ["/tf", "/joint_states", "/tf"])) == {"/tf"}
        assert unplayable_topics(b, ["/joint_states"]) == {}
    r = subprocess.run([sys.executable, "-m", "pa10_dnbs.cli", "replay", str(bag), "--topics", "/tf", "/tf_static"],
                       cwd=REPO, capture_output=True, text=True, timeout=120,
                       env={**os.environ, "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST"})
    _assert_clear_error(r, "--topics: nothing to play: /tf (tf2_msgs/msg/TFMessage: no Python message package "
                           "installed for it); /tf_static (")
    assert r.stdout == "" and len(r.stderr.strip().splitlines()) == 1, r.stdout + r.stderr


def test_a_yaml_alias_bomb_in_metadata_is_refused_before_it_is_built(tmp_path):
    """A "billion laughs" relative_file_paths was expanded by its error message's repr; now one line."""
    from yaml_bomb import alias_bomb
    bag = tmp_path / "bag"
    bag.mkdir()
    (bag / "metadata.yaml").write_text("rosbag2_bagfile_information:\n  relative_file_paths:\n"
                                       + alias_bomb(indent="    "))
    r = _analyse(bag, tmp_path)
    _assert_clear_error(r, f"{bag}/metadata.yaml: refused: its aliases (*name) expand it to 1.23e+07 nodes")
    assert len(r.stderr) < 300, r.stderr[:300]

"""Bags of the node graph: recorded in lockstep, read back by standard readers, analysed, replayed, re-driven.

The recorded run is the session fixture ``lockstep_run`` (conftest.py): 3 s of lockstep DNBS with --record.
"""
import json
import pickle
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
import yaml
from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory
from rosbags.highlevel import AnyReader

from conftest import LOCKSTEP_DURATION_S
from graph_harness import REPO, Launcher, Proc
from mcap_crc_probe import assert_every_crc_written_and_valid, assert_jazzy_fields, mcap_file, rosidl_type_hash
from pa10_dnbs.arm import load_arm
JOINT_NAMES = load_arm("pa10").joint_names
from pa10_dnbs.bag.bag_reader import Bag
from pa10_dnbs.sim.closed_loop import simulate
from pa10_dnbs.run_data import RunData

pytestmark = pytest.mark.graph  # starts ROS processes

N_STEPS = int(LOCKSTEP_DURATION_S * 1000)
PER_JOINT = [f"/pa10/{j}/{kind}" for j in JOINT_NAMES for kind in ("state", "effort")]


def _stamp_ns(data: bytes) -> int:
    sec, nanosec = np.frombuffer(bytes(data[4:12]), dtype="<i4,<u4")[0]
    return int(sec) * 1_000_000_000 + int(nanosec)


@pytest.fixture(scope="module")
def bag(lockstep_run):
    assert lockstep_run["rc"] == 0, lockstep_run["output"]
    return lockstep_run["bag"]


def test_metadata_counts_equal_the_messages_in_the_file(bag):
    meta = yaml.safe_load((bag / "metadata.yaml").read_text())["rosbag2_bagfile_information"]
    assert meta["version"] == 9 and meta["storage_identifier"] == "mcap"
    counted = {}
    with open(bag / meta["relative_file_paths"][0], "rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        header = reader.get_header()
        assert header.profile == "ros2"
        summary = reader.get_summary()
        assert {s.encoding for s in summary.schemas.values()} == {"ros2msg"}
        assert {c.message_encoding for c in summary.channels.values()} == {"cdr"}
        assert all("offered_qos_profiles" in c.metadata for c in summary.channels.values())
        assert "rosbag2" in {m.name for m in reader.iter_metadata()}
        for _, channel, _, decoded in reader.iter_decoded_messages():  # every payload decodes with mcap_ros2
            counted[channel.topic] = counted.get(channel.topic, 0) + 1
            assert decoded is not None
    per_topic = {t["topic_metadata"]["name"]: t["message_count"] for t in meta["topics_with_message_count"]}
    assert per_topic == counted
    assert meta["message_count"] == sum(counted.values())
    for t in per_topic:
        qos = next(x for x in meta["topics_with_message_count"] if x["topic_metadata"]["name"] == t)
        assert all(p["history"] == "keep_last" for p in qos["topic_metadata"]["offered_qos_profiles"])


def test_every_mcap_crc_is_valid_and_channels_carry_what_jazzy_writes(bag):
    """The mcap library with CRC validation reads every chunk (each CRC present and right), the data section and
    summary CRCs are right; each channel's topic_type_hash is metadata.yaml's and rosidl's; ros_distro jazzy."""
    assert assert_every_crc_written_and_valid(mcap_file(bag)) >= 1
    hashes = assert_jazzy_fields(bag)
    meta = yaml.safe_load((bag / "metadata.yaml").read_text())["rosbag2_bagfile_information"]
    types = {t["topic_metadata"]["name"]: t["topic_metadata"]["type"] for t in meta["topics_with_message_count"]}
    checked = [t for t in hashes if rosidl_type_hash(types[t]) is not None]
    assert "/pa10/joint_states" in checked and "/clock" in checked  # tf2_msgs has no wheel: not checkable
    assert all(hashes[t] == rosidl_type_hash(types[t]) for t in checked)


def test_anyreader_reads_every_topic(bag):
    with AnyReader([bag]) as reader:
        topics = {c.topic: c for c in reader.connections}
        assert set(PER_JOINT) | {"/clock", "/pa10/joint_states", "/pa10/robot_description", "/tf", "/tf_static"} <= set(topics)
        seen = set()
        for conn, t_ns, raw in reader.messages():
            if conn.topic not in seen:
                msg = reader.deserialize(raw, conn.msgtype)
                seen.add(conn.topic)
                if conn.topic == "/pa10/joint_states":
                    assert list(msg.name) == list(JOINT_NAMES) and len(msg.position) == 7
        assert seen == set(topics)


def test_one_message_per_step_on_every_per_joint_topic(bag, lockstep_run):
    """Every step once; a state the plant sent again (it counts them: a controller that had not answered
    within resend_s of wall time) adds exactly one copy, and the controller's answer to it at most one."""
    joints = json.loads((lockstep_run["out"] / "metrics.json").read_text())["faults"]["joints"]
    resent = {j["name"]: j["plant"]["resent_states"] for j in joints}
    with Bag(bag) as b:
        for topic in PER_JOINT + ["/pa10/joint_states"]:
            stamps = sorted(_stamp_ns(d) for _, _, _, d in b.messages([topic]))
            assert sorted(set(stamps)) == [k * 1_000_000 for k in range(N_STEPS + 1)], topic
            copies = len(stamps) - len(set(stamps))
            joint, kind = topic.split("/")[2:4] if topic.count("/") == 3 else (None, "joint_states")
            if kind == "state":
                assert copies == resent[joint], topic
            else:
                assert copies <= (resent[joint] if joint else 0), topic
        clock = sorted(_stamp_ns(d) for _, _, _, d in b.messages(["/clock"]))
    assert clock == [k * 1_000_000 for k in range(0, N_STEPS + 1, 10)]  # 100 Hz of simulated time, the default


def test_robot_description_and_tf_for_foxglove(bag, _default_cfg):
    with AnyReader([bag]) as reader:
        conns = {c.topic: c for c in reader.connections}
        assert conns["/pa10/robot_description"].ext.offered_qos_profiles[0].durability.name == "TRANSIENT_LOCAL"
        msgs = {t: [reader.deserialize(raw, c.msgtype) for c, _, raw in reader.messages(connections=[conns[t]])]
                for t in ("/pa10/robot_description", "/tf_static", "/tf", "/pa10/joint_states")}
    assert msgs["/pa10/robot_description"][0].data == load_arm("pa10").urdf_text()
    static = msgs["/tf_static"][0].transforms
    assert [(t.header.frame_id, t.child_frame_id) for t in static] == [("link7", "flange")]
    tf = msgs["/tf"]
    assert len(tf) == N_STEPS // 10 + 1  # 100 Hz of simulated time
    chain = load_arm("pa10").chain
    states = {(m.header.stamp.sec, m.header.stamp.nanosec): m for m in msgs["/pa10/joint_states"]}
    for m in (tf[0], tf[len(tf) // 2], tf[-1]):
        stamp = (m.transforms[0].header.stamp.sec, m.transforms[0].header.stamp.nanosec)
        js = states[stamp]
        expected = chain.moving_transforms(dict(zip(js.name, js.position)))
        assert [t.child_frame_id for t in m.transforms] == [f"link{i}" for i in range(1, 8)]
        for got, exp in zip(m.transforms, expected):
            r = got.transform.rotation
            assert (r.x, r.y, r.z, r.w) == pytest.approx(exp.rotation_xyzw, abs=1e-12)
            assert got.header.frame_id == exp.parent


def test_analysis_of_the_bag_equals_the_live_run(lockstep_run, bag, tmp_path, _default_cfg):
    """``analyse`` gives the launcher's metrics, and time series equal to the in-process run bit for bit."""
    out = tmp_path / "analysis"
    r = subprocess.run([sys.executable, "-m", "pa10_dnbs.cli", "analyse", bag, "--out", out], cwd=REPO,
                       capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    live = json.loads((lockstep_run["out"] / "metrics.json").read_text())
    offline = json.loads((out / "metrics.json").read_text())
    assert offline["source"] == "bag" and offline["mode"] == "lockstep" and offline["controller"] == "dnbs"
    for key in ("joints", "worst_rms_error_rad", "all_finite", "torques_within_limits", "duration_s", "dt_s",
                "window_s"):
        assert offline[key] == live[key], key
    b = RunData.load_npz(out / "timeseries.npz")
    for a in (RunData.load_npz(lockstep_run["out"] / "timeseries.npz"),
              simulate(_default_cfg, "dnbs", LOCKSTEP_DURATION_S)):
        for field in ("position_rad", "velocity_rad_s", "reference_rad", "torque_nm"):
            assert np.array_equal(getattr(a, field), getattr(b, field)), field
    assert (out / "report.md").is_file() and (out / "tracking.png").is_file()


def _stop(p: Proc, sig=signal.SIGINT, timeout=20) -> int:
    if p.proc.poll() is None:
        p.proc.send_signal(sig)
    try:
        return p.wait(timeout)
    finally:
        p.kill()


def test_faithful_replay(bag, tmp_path, domain):
    """A subscriber receives exactly the recorded messages: count, order and payload bytes."""
    specs = {"/pa10/s1/state": "sensor_msgs/msg/JointState", "/pa10/w2/effort": "sensor_msgs/msg/JointState",
             "/pa10/e1/reference": "trajectory_msgs/msg/JointTrajectory", "/clock": "rosgraph_msgs/msg/Clock",
             "/pa10/robot_description": "std_msgs/msg/String"}
    with Bag(bag) as b:
        recorded = {t: [bytes(d) for _, _, _, d in b.messages([t])] for t in specs}
    total = sum(map(len, recorded.values()))
    dump = tmp_path / "probe.pkl"
    probe = Proc([sys.executable, REPO / "test" / "bag_probe.py", dump, total, 90]
                 + [f"{t}:{ty}" for t, ty in specs.items()], domain_id=domain)
    player = None
    try:
        probe.wait_for("READY bag_probe", 60)
        player = Proc([sys.executable, "-m", "pa10_dnbs.cli", "replay", bag, "--topics", *specs,
                       "--wait-for-subscribers", 30], domain_id=domain)
        assert player.wait(120) == 0, player.output
        assert probe.wait(120) == 0, probe.output
    finally:
        for p in (probe, player):
            if p is not None:
                p.kill()
    assert f"PLAYED {total} messages" in player.output
    got = pickle.loads(dump.read_bytes())
    for t in specs:
        assert len(got[t]) == len(recorded[t]), t
        assert got[t] == recorded[t], t


def test_replay_stopped_by_ctrl_c_says_so_and_exits_130(bag, domain):
    """Playback cut short by a Ctrl-C exited 0 with the same PLAYED line as a whole bag; now one line says how far
    it got, and the exit code is 130 as for every command (with --loop a Ctrl-C is how it ends: 0)."""
    player = Proc([sys.executable, "-m", "pa10_dnbs.cli", "replay", bag, "--rate", 0.05], domain_id=domain)
    try:
        player.wait_for("PLAYING", 60)
        time.sleep(0.5)
        assert _stop(player) == 130, player.output
    finally:
        player.kill()
    assert "pa10-dnbs replay: interrupted: played " in player.output and " of the bag's " in player.output


def test_redrive_reproduces_the_recorded_states_bit_for_bit(bag, tmp_path, domain):
    """Only the recorded efforts, replayed into a fresh lockstep plant (no controllers): same states, same bytes."""
    new_bag = tmp_path / "redriven"
    efforts = [f"/pa10/{j}/effort" for j in JOINT_NAMES]
    topics = ["/pa10/joint_states:sensor_msgs/msg/JointState"] + [f"/pa10/{j}/state:sensor_msgs/msg/JointState"
                                                                   for j in JOINT_NAMES]
    ros = ["--ros-args", "-r", "__ns:=/pa10", "-p"]  # the arm's namespace, as the launcher starts them
    recorder = Proc([sys.executable, "-m", "pa10_dnbs.ros.recorder_node", *ros, f"bag:={new_bag}", "-p",
                     "topics:=[" + ",".join(f"'{t}'" for t in topics) + "]", "-p", f"end_stamp_ns:={N_STEPS * 10**6}",
                     "-p", "tf_rate_hz:=0.0"], domain_id=domain)
    plant = Proc([sys.executable, "-m", "pa10_dnbs.ros.plant.node", *ros, "mode:=lockstep", "-p",
                  f"duration_s:={LOCKSTEP_DURATION_S}", "-p", "state_subscribers:=1", "-p", "clock_subscribers:=0",
                  "-p", "min_joint_states_subscribers:=1"], domain_id=domain)
    player = None
    try:
        recorder.wait_for("READY recorder", 60)
        plant.wait_for("READY plant", 60)
        player = Proc([sys.executable, "-m", "pa10_dnbs.cli", "replay", bag, "--topics", *efforts,
                       "--wait-for-subscribers", 30], domain_id=domain)
        assert plant.wait(180) == 0, plant.output
        recorder.wait_for("COMPLETE", 30)
        assert player.wait(60) == 0, player.output
        assert _stop(recorder, signal.SIGTERM) == 0, recorder.output   # SIGTERM closes the bag too
    finally:
        for p in (recorder, plant, player):
            if p is not None:
                p.kill()
    assert "WARN" not in plant.output, plant.output  # no effort timeout
    with Bag(bag) as old, Bag(new_bag) as new:
        for t in [s.split(":")[0] for s in topics]:
            a = {_stamp_ns(d): bytes(d) for _, _, _, d in old.messages([t])}
            b = {_stamp_ns(d): bytes(d) for _, _, _, d in new.messages([t])}
            assert len(b) == N_STEPS + 1 and a.keys() == b.keys(), t
            differ = [k for k in a if a[k] != b[k]]
            assert not differ, f"{t}: {len(differ)} states differ, first at {differ[0]} ns"


def test_interrupted_recording_leaves_a_complete_bag(tmp_path, domain):
    """Ctrl-C of the launcher mid-run: exit 130, and the bag so far is closed, consistent and readable."""
    bag = tmp_path / "bag"
    la = Launcher("--duration", 60, "--out", tmp_path / "run", "--record", bag, domain_id=domain)
    try:
        la.wait_running()
        time.sleep(3.0)
        la.interrupt()
        rc = la.wait(60)
    finally:
        la.kill()
    assert rc == 130, la.output
    assert not (tmp_path / "run").exists()
    with Bag(bag) as b:  # Bag checks the footer, the summary and metadata.yaml against each other
        counts = {t: i.count for t, i in b.topics.items()}
        assert counts["/pa10/joint_states"] > 100
        states = sorted(_stamp_ns(d) for _, _, _, d in b.messages(["/pa10/joint_states"]))
    assert states == [k * 1_000_000 for k in range(len(states))]  # a prefix of the run, without gaps


def test_existing_bag_is_not_overwritten_without_force(tmp_path, domain):
    bag = tmp_path / "bag"
    bag.mkdir()
    (bag / "keep.txt").write_text("mine")
    r = subprocess.run([sys.executable, "-m", "pa10_dnbs.cli", "launch", "--duration", "1", "--out", tmp_path / "run",
                        "--record", bag, "--domain-id", str(domain)], cwd=REPO, capture_output=True, text=True, timeout=60)
    assert r.returncode == 2 and "--force" in r.stderr and "Traceback" not in r.stderr
    assert (bag / "keep.txt").read_text() == "mine" and not (tmp_path / "run").exists()


def test_the_bag_names_the_config_where_the_run_left_it(lockstep_run, bag):
    """rev_e 9: the bag's (and so analyse's) config path is <out>/config_used.yaml, which exists after the run; it
    named the run's temporary output folder (.<out>.partial-XXXX), renamed at the end."""
    meta = yaml.safe_load((bag / "metadata.yaml").read_text())["rosbag2_bagfile_information"]
    named = meta["custom_data"]["pa10_dnbs.config_file"]
    assert named == str(lockstep_run["out"] / "config_used.yaml") and Path(named).is_file(), named

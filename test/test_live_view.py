"""The live view without ROS: decimation, reference buffer, tracking frames, the Foxglove server and a real
WebSocket client, option checks."""
import json
import math
import socket
import time
from pathlib import Path

import numpy as np
import pytest
from rosbags.typesys import Stores, get_typestore

from foxglove_client import FoxgloveClient
from pa10_dnbs.arm import load_arm
JOINT_NAMES = load_arm("pa10").joint_names
from pa10_dnbs.config import ConfigError
from pa10_dnbs.kinematics.urdf_chain import UrdfChain
from pa10_dnbs.live import tracking
from pa10_dnbs.live.decimator import Decimator
from pa10_dnbs.live.options import check_live_options
from pa10_dnbs.live.schemas import live_channels
from pa10_dnbs.wire.topics import ArmTopics
from pa10_dnbs.live.server import LiveServer
from pa10_dnbs.live.view import LiveView, string_cdr
from pa10_dnbs.wire import joint_state_cdr
from pa10_dnbs.wire.reference_buffer import ReferenceBuffer
from pa10_dnbs.wire.steps import StepClock

STORE = get_typestore(Stores.ROS2_JAZZY)
T = STORE.types
LIMITS = [232.0, 232.0, 100.0, 100.0, 14.5, 14.5, 14.5]
URDF = Path(__file__).resolve().parent.parent / "urdf" / "pa10" / "pa10_7ce.urdf"


def reference_cdr(joint: str, first_step: int, positions) -> bytes:
    """A reference batch as the reference node sends it (1 ms steps), serialized by rosbags."""
    pts = [T["trajectory_msgs/msg/JointTrajectoryPoint"](
        positions=np.array([x]), velocities=np.array([0.0]), accelerations=np.array([], dtype=float),
        effort=np.array([], dtype=float), time_from_start=T["builtin_interfaces/msg/Duration"](sec=0, nanosec=i * 10**6))
        for i, x in enumerate(positions)]
    sec, nsec = divmod(first_step * 10**6, 10**9)
    msg = T["trajectory_msgs/msg/JointTrajectory"](
        header=T["std_msgs/msg/Header"](stamp=T["builtin_interfaces/msg/Time"](sec=sec, nanosec=nsec), frame_id=""),
        joint_names=[joint], points=pts)
    return bytes(STORE.serialize_cdr(msg, "trajectory_msgs/msg/JointTrajectory"))


def string_msg(text: str) -> bytes:
    return bytes(STORE.serialize_cdr(T["std_msgs/msg/String"](data=text), "std_msgs/msg/String"))


def state(k: int, q) -> bytes:
    sec, nsec = divmod(k * 10**6, 10**9)
    return joint_state_cdr.encode(sec, nsec, list(JOINT_NAMES), list(q), [0.0] * 7, [float(j + 1) for j in range(7)])


# ------------------------------------------------------------------ decimation
def test_decimator_hands_out_the_newest_sample_once_per_period():
    d = Decimator(0.02)
    taken = []
    for k in range(1000):  # 1 kHz of samples over 1 s of (fake) wall time
        now = k * 1e-3
        d.offer(k)
        got = d.take(now)
        if got is not None:
            taken.append((now, got))
    assert 49 <= len(taken) <= 51
    assert all(got == round(now * 1000) for now, got in taken)  # always the newest
    gaps = np.diff([t for t, _ in taken])
    assert gaps.min() >= 0.019 - 1e-9 and gaps.mean() == pytest.approx(0.02, abs=1e-4)  # the cadence holds
    assert d.take(10.0) == 999  # the last one, not yet due at 0.999 s
    assert d.take(20.0) is None  # nothing new since the last take
    d.offer("late")
    assert d.take(20.0) == "late"  # after a pause: at once


def test_decimator_rejects_a_bad_period():
    with pytest.raises(ValueError):
        Decimator(0.0)


# ------------------------------------------------------------------ reference buffer
def test_reference_buffer_reads_batches_and_tracks_the_worst_error():
    buf = ReferenceBuffer(7, StepClock(1e-3))
    for j, name in enumerate(JOINT_NAMES):
        assert buf.add_cdr(j, reference_cdr(name, 100, [0.01 * j + 0.001 * i for i in range(100)]))
    assert buf.at(150) == pytest.approx([0.01 * j + 0.05 for j in range(7)], abs=1e-15)
    assert all(math.isnan(v) for v in buf.at(99)) and all(math.isnan(v) for v in buf.at(200))
    e = buf.error(150, [0.0] * 7)
    assert e == buf.at(150)
    assert buf.worst_abs_error == pytest.approx(0.11)
    buf.error(151, [x + 0.001 for x in buf.at(151)])  # small errors do not lower the worst
    assert buf.worst_abs_error == pytest.approx(0.11)
    buf.forget_before(180)
    assert len(buf) == 7 * 20 and math.isnan(buf.at(150)[0])
    assert not buf.add_cdr(0, b"\x00\x01\x00\x00garbage") and buf.malformed == 1


# ------------------------------------------------------------------ tracking frame
def test_tracking_message_error_torque_and_nulls():
    m = tracking.tracking_message(1_234_000_000, 1234, JOINT_NAMES, [0.1] * 7, [0.3] + [math.nan] * 6,
                                  [116.0, -232.0, 0, 0, 14.5, 0, 0], LIMITS, 0.25)
    assert m["timestamp"] == {"sec": 1, "nsec": 234_000_000} and m["step"] == 1234
    assert m["error_rad"][0] == pytest.approx(0.2) and m["error_rad"][1:] == [None] * 6
    assert m["torque_over_limit"][:2] == [0.5, -1.0] and m["torque_over_limit"][4] == 1.0
    assert m["worst_abs_error_rad"] == 0.25
    json.loads(tracking.encode(m))  # strict JSON (NaN would raise in encode)
    assert set(m) == set(tracking.SCHEMA["properties"])


def test_channels_use_schemas_foxglove_decodes():
    chans = {c.topic: c for c in live_channels()}
    assert set(chans) == {"/pa10/robot_description", "/pa10/joint_states", "/tf", "/tf_static", "/pa10/tracking", "/diagnostics"}
    for c in chans.values():
        if c.topic == "/pa10/tracking":
            assert (c.schema_encoding, c.message_encoding) == ("jsonschema", "json")
        else:
            assert (c.schema_encoding, c.message_encoding) == ("ros2msg", "cdr")
    assert chans["/pa10/joint_states"].schema.startswith(b"std_msgs/Header header\nstring[] name\nfloat64[] position")
    assert b"MSG: geometry_msgs/TransformStamped" in chans["/tf"].schema
    assert chans["/pa10/robot_description"].latched and chans["/tf_static"].latched and not chans["/tf"].latched
    other = {c.topic for c in live_channels(ArmTopics("/arm2"))}
    assert other == {"/arm2/robot_description", "/arm2/joint_states", "/tf", "/tf_static", "/arm2/tracking",
                     "/diagnostics"}


def test_string_cdr():
    assert string_cdr(string_msg("<robot name='x'/>")) == "<robot name='x'/>"
    with pytest.raises(ValueError):
        string_cdr(b"\x00\x01\x00\x00\xff\xff\x00\x00abc")


# ------------------------------------------------------------------ server + view + a real client
def _pump_ticking(client, view, until, seconds=10.0) -> bool:
    """Receive while ticking the view (what the node's timer does: latched messages go to new subscribers)."""
    deadline = time.monotonic() + seconds
    while not until() and time.monotonic() < deadline:
        view.tick(-1.0)  # no new state: only the latched re-sends
        client.pump(0.1)
    return bool(until())


@pytest.fixture
def live():
    server = LiveServer(live_channels(), port=0)
    view = LiveView(server, LIMITS, 1e-3, display_hz=64.0, joint_names=JOINT_NAMES)  # 1/64 s: exact in binary, like the fake clock below
    yield server, view
    server.stop()


def test_a_client_sees_the_arm_and_the_tracking_frames(live):
    server, view = live
    view.on_message("/pa10/robot_description", string_msg(URDF.read_text()))
    for j, name in enumerate(JOINT_NAMES):
        view.on_message(f"/pa10/{name}/reference", reference_cdr(name, 0, [0.5] * 200))
    client = FoxgloveClient(server.url)
    try:
        assert client.subprotocol == "foxglove.sdk.v1"
        assert client.wait_for_channels([c.topic for c in live_channels()], 10)
        assert client.channels["/pa10/joint_states"]["schemaName"] == "sensor_msgs/msg/JointState"
        client.subscribe(*client.channels)
        assert _pump_ticking(client, view, lambda: client.count("/pa10/robot_description") and client.count("/tf_static"))
        sent = {}
        for k in range(150):  # one state per 1/1024 s of (fake) wall time: a frame every 16th state
            data = state(k, [0.01 * k + 0.001 * j for j in range(7)])
            sent[k] = data
            view.on_message("/pa10/joint_states", data)
            view.tick(k / 1024)
        assert view.frames == 10
        # the SDK sends time broadcasts and channel messages on separate paths: wait for the last of both
        assert client.pump(10, lambda: client.count("/pa10/tracking") == 10 and client.times[-1:] == [144 * 10**6])
    finally:
        client.close()
    got = client.messages["/pa10/joint_states"]
    steps = [t // 10**6 for t, _ in got]
    assert steps == list(range(0, 150, 16))
    assert all(payload == sent[t // 10**6] for t, payload in got)  # forwarded byte for byte
    assert client.times[-1] == 144 * 10**6  # the simulated time of the last frame
    frames = [json.loads(p) for _, p in client.messages["/pa10/tracking"]]
    for f in frames:
        q = [0.01 * f["step"] + 0.001 * j for j in range(7)]
        assert f["error_rad"] == [0.5 - x for x in q]
        assert f["torque_nm"] == [float(j + 1) for j in range(7)]
    assert frames[-1]["worst_abs_error_rad"] == max(abs(e) for f in frames for e in f["error_rad"])
    chain = UrdfChain(URDF.read_text())
    tf = STORE.deserialize_cdr(client.messages["/tf"][-1][1], "tf2_msgs/msg/TFMessage")
    expected = chain.moving_transforms(dict(zip(JOINT_NAMES, [0.01 * 144 + 0.001 * j for j in range(7)])))
    assert [t.child_frame_id for t in tf.transforms] == [e.child for e in expected]
    for got_t, exp in zip(tf.transforms, expected):
        r = got_t.transform.rotation
        assert (r.x, r.y, r.z, r.w) == pytest.approx(exp.rotation_xyzw, abs=1e-12)
    static = STORE.deserialize_cdr(client.messages["/tf_static"][0][1], "tf2_msgs/msg/TFMessage")
    assert [(t.header.frame_id, t.child_frame_id) for t in static.transforms] == [("link7", "flange")]


def test_a_late_subscriber_gets_the_latched_urdf(live):
    server, view = live
    view.on_message("/pa10/robot_description", string_msg(URDF.read_text()))
    client = FoxgloveClient(server.url)
    try:
        client.wait_for_channels(["/pa10/robot_description"], 10)
        client.subscribe("/pa10/robot_description", "/tf_static")
        assert _pump_ticking(client, view, lambda: client.count("/pa10/robot_description") and client.count("/tf_static"))
    finally:
        client.close()
    assert string_cdr(client.messages["/pa10/robot_description"][0][1]) == URDF.read_text()


def test_a_stalled_client_does_not_block_logging(live):
    """A client that subscribes and then never reads: every log() returns, and another client still gets frames."""
    server, view = live
    stalled = FoxgloveClient(server.url)
    reader = FoxgloveClient(server.url)
    try:
        for c in (stalled, reader):
            c.wait_for_channels(["/pa10/joint_states"], 10)
            c.subscribe("/pa10/joint_states")
        time.sleep(0.5)
        payload = state(1, [0.1] * 7)
        blob = b"\x00\x01\x00\x00" + bytes(200_000)  # large messages fill the stalled client's socket fast
        for i in range(600):  # 60 MB: far more than the stalled client's socket and queue hold
            server.log("/pa10/joint_states", blob if i % 2 else payload, i)
        server.log("/pa10/joint_states", payload, 10**9)  # the newest message reaches the client that reads
        assert reader.pump(20, lambda: any(t == 10**9 for t, _ in reader.messages.get("/pa10/joint_states", [])))
    finally:
        reader.close()
        stalled.close()


# ------------------------------------------------------------------ options
def test_live_options_are_checked_before_anything_starts():
    with pytest.raises(ConfigError, match="^live_port: port must be in 0..65535") as err:
        check_live_options("127.0.0.1", 70000)
    assert err.value.named({"live_port": "--live"}).startswith("--live: port must be in 0..65535")  # as the command line says it
    with pytest.raises(ConfigError, match="^live_hz"):
        check_live_options("127.0.0.1", 0, 0.0)
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        s.listen()
        with pytest.raises(ConfigError, match=r"^live_port: cannot serve on 127.0.0.1:\d+ \(in use\)"):
            check_live_options("127.0.0.1", s.getsockname()[1])
    with pytest.raises(ConfigError, match="^live_host"):
        check_live_options("no-such-host.invalid", 0)
    check_live_options("127.0.0.1", 0)


def _ipv6_loopback() -> bool:
    try:
        with socket.socket(socket.AF_INET6) as s:
            s.bind(("::1", 0))
        return True
    except OSError:
        return False


@pytest.mark.skipif(not _ipv6_loopback(), reason="no IPv6 loopback here")
def test_an_ipv6_host_is_bracketed_in_the_url_and_its_port_taken_named_so():
    """--live-host ::1 printed 'LIVE ws://::1:PORT', which no client parses: now ws://[::1]:PORT."""
    server = LiveServer(live_channels(), host="::1", port=0)
    try:
        assert server.url == f"ws://[::1]:{server.port}"
    finally:
        server.stop()
    with socket.socket(socket.AF_INET6) as s:
        s.bind(("::1", 0))
        s.listen()
        with pytest.raises(ConfigError, match=r"^live_port: cannot serve on \[::1\]:\d+ \(in use\)"):
            check_live_options("::1", s.getsockname()[1])


@pytest.mark.parametrize("host", ["fe80::1", "192.0.2.1"])   # link-local without its interface; not this machine's
def test_a_host_that_cannot_be_bound_is_named_live_host_not_live(tmp_path, host):
    """'--live: cannot serve on fe80::1:0 (Invalid argument)' named the port's flag for the address's fault."""
    from cli_runner import run_cli

    with pytest.raises(ConfigError, match=f"^live_host: cannot serve on {host} ") as err:
        check_live_options(host, 0)
    assert err.value.setting == "live_host"
    (tmp_path / "bag").mkdir()
    for command in (("replay", tmp_path / "bag"), ("launch", "--duration", "0.1", "--out", tmp_path / "out")):
        r = run_cli(*command, "--live", "0", "--live-host", host)
        assert r.returncode == 2 and r.stderr.startswith(f"pa10-dnbs: error: --live-host: cannot serve on {host} "), \
            r.stderr
        assert len(r.stderr.strip().splitlines()) == 1 and not (tmp_path / "out").exists(), r.stderr



# ------------------------------------------------------------------ the layout file
def _leaves(tree):
    if isinstance(tree, str):
        return [tree]
    return _leaves(tree["first"]) + _leaves(tree["second"])


def test_layout_file_is_current_and_uses_only_served_channels(_default_cfg):
    from pa10_dnbs.live.layout import layout_json

    path = Path(__file__).resolve().parents[1] / "config" / "foxglove_layout.json"
    chain = UrdfChain(URDF.read_text())
    title = load_arm("pa10").description
    assert path.read_text() == layout_json(JOINT_NAMES, _default_cfg.plant.torque_limit_nm, title, chain.root_link), \
        "config/foxglove_layout.json is stale: run scripts/make_foxglove_layout.py"
    lay = json.loads(path.read_text())
    assert sorted(_leaves(lay["layout"])) == sorted(lay["configById"])
    served = {c.topic for c in live_channels()}
    three_d = lay["configById"]["3D!arm"]
    assert three_d["topics"]["/pa10/robot_description"]["visible"] and three_d["followTf"] == "base_link"
    assert lay["configById"]["DiagnosticSummary!diagnostics"]["topicToRender"] == "/diagnostics"
    plotted = []
    for pid, cfg in lay["configById"].items():
        if pid.startswith("Plot!"):
            for p in cfg["paths"]:
                topic, _, rest = p["value"].partition(".")
                field, index = rest.rstrip("]").split("[")
                assert topic in served and field in tracking.SCHEMA["properties"], p["value"]
                plotted.append((pid, field, int(index)))
    assert [(f, i) for pid, f, i in plotted if pid == "Plot!errors"] == [("error_rad", j) for j in range(7)]
    assert [(f, i) for pid, f, i in plotted if pid == "Plot!torques"] == \
        [("torque_over_limit", j) for j in range(7)] + [("torque_fraction_limits", 0), ("torque_fraction_limits", 1)]

"""The live view of the node graph and of a replayed bag, watched by a Foxglove WebSocket client.

In one lockstep run with --record and --live: a client connects (offering subprotocol
foxglove.websocket.v1 and its current name foxglove.sdk.v1), sees the channels advertised, subscribes and
gets /joint_states whose decoded positions are the run's time series at the same stamps, while other
clients drop mid-run or stall, and the run is the session's recorded lockstep run bit for bit;
``replay --live`` shows a bag at its recorded timing.
"""
import json
import socket
import sys

import numpy as np
import pytest
from rosbags.typesys import Stores, get_typestore

from conftest import LOCKSTEP_DURATION_S
from foxglove_client import FoxgloveClient
from graph_harness import Launcher, Proc, alive, exit_codes
from pa10_dnbs.bag.bag_reader import Bag
from pa10_dnbs.run_data import RunData

pytestmark = pytest.mark.graph  # starts ROS processes

STORE = get_typestore(Stores.ROS2_JAZZY)
CHANNELS = {"/pa10/robot_description": "std_msgs/msg/String", "/pa10/joint_states": "sensor_msgs/msg/JointState",
            "/tf": "tf2_msgs/msg/TFMessage", "/tf_static": "tf2_msgs/msg/TFMessage",
            "/pa10/tracking": "pa10_dnbs/Tracking", "/diagnostics": "diagnostic_msgs/msg/DiagnosticArray"}
LIVE_URL = r"launch: live view at (ws://\S+)"


def _step(stamp_ns: int) -> int:
    assert stamp_ns % 1_000_000 == 0
    return stamp_ns // 1_000_000


def _check_joint_states(messages, run: RunData) -> int:
    """Each message's log time is its stamp and its decoded positions are the run's x(k); returns how many."""
    matched = 0
    for log_time, payload in messages:
        m = STORE.deserialize_cdr(payload, "sensor_msgs/msg/JointState")
        stamp = m.header.stamp.sec * 1_000_000_000 + m.header.stamp.nanosec
        assert log_time == stamp
        k = _step(stamp)
        if k < run.n_steps:  # the state after the last step is not in the time series
            assert np.array_equal(m.position, run.position_rad[k]), k
            matched += 1
    return matched


def _check_tracking(messages, run: RunData) -> int:
    """e = x_d - x and the torque applied over the previous step, as in the run's time series; returns how
    many frames had every error."""
    full = 0
    for _, payload in messages:
        f = json.loads(payload)
        k = f["step"]
        if not 1 <= k < run.n_steps:
            continue
        assert f["position_rad"] == run.position_rad[k].tolist()
        assert f["torque_nm"] == run.torque_nm[k - 1].tolist()
        if None not in f["error_rad"]:
            assert f["error_rad"] == (run.reference_rad[k] - run.position_rad[k]).tolist()
            full += 1
    return full


def test_clients_watch_drop_or_stall_and_change_nothing(lockstep_run, tmp_path, domain):
    """One run with --record and --live, four clients. One watches: it sees the channels advertised, and the
    /joint_states and tracking frames it gets are the run's time series at the same stamps. One subscribes
    and never reads again, one drops its connection mid-run without a closing handshake, one says goodbye
    politely. The run equals the session's recorded lockstep run (same duration, no --live) bit for bit,
    and every process exits 0."""
    assert lockstep_run["rc"] == 0, lockstep_run["output"]
    out, bag = tmp_path / "run", tmp_path / "bag"
    la = Launcher("--duration", LOCKSTEP_DURATION_S, "--out", out, "--record", bag, "--live", 0, domain_id=domain)
    clients = []
    try:
        url = la.wait_for(LIVE_URL, 120).group(1)
        m = la.wait_for(r"; live view live_view=(\d+)", 10)
        live_pid = int(m.group(1))
        watcher, stalled, dropped, polite = (FoxgloveClient(url) for _ in range(4))
        clients = [watcher, stalled, dropped, polite]
        assert watcher.subprotocol == "foxglove.sdk.v1"
        for c in clients:
            assert c.wait_for_channels(CHANNELS, 30), c.channels
        for topic, schema in CHANNELS.items():
            ch = watcher.channels[topic]
            assert ch["schemaName"] == schema
            assert (ch["encoding"], ch["schemaEncoding"]) == (("json", "jsonschema") if topic == "/pa10/tracking"
                                                              else ("cdr", "ros2msg"))
        watcher.subscribe("/pa10/joint_states", "/pa10/tracking", "/pa10/robot_description")
        for c in (stalled, dropped, polite):
            c.subscribe(*CHANNELS)
        la.wait_for("launch: plant running", 120)
        assert dropped.pump(60, lambda: dropped.count("/pa10/joint_states") >= 5)
        dropped.ws.socket.shutdown(socket.SHUT_RDWR)  # gone without a closing handshake
        dropped.ws.socket.close()
        assert polite.pump(60, lambda: polite.count("/pa10/joint_states") >= 10)
        polite.close()
        watcher.pump(300, until=lambda: la.proc.poll() is not None)
        rc = la.wait(300)
    finally:
        for c in clients:
            try:
                c.close()
            except OSError:
                pass
        la.kill()
    assert rc == 0, la.output
    codes = exit_codes(la.output)
    assert codes["live_view"] == 0 and all(c == 0 for c in codes.values()), codes
    assert not alive(live_pid)
    assert "frames shown in" in (out / "logs" / "live_view.log").read_text()
    run = RunData.load_npz(out / "timeseries.npz")
    assert _check_joint_states(watcher.messages["/pa10/joint_states"], run) >= 20
    assert _check_tracking(watcher.messages["/pa10/tracking"], run) >= 10
    assert watcher.count("/pa10/robot_description") >= 1
    base = json.loads((lockstep_run["out"] / "metrics.json").read_text())
    watched = json.loads((out / "metrics.json").read_text())
    for key in ("joints", "worst_rms_error_rad", "all_finite", "torques_within_limits", "duration_s", "dt_s",
                "window_s", "limit_hits"):
        assert watched[key] == base[key], key
    a = RunData.load_npz(lockstep_run["out"] / "timeseries.npz")
    for field in ("position_rad", "velocity_rad_s", "reference_rad", "torque_nm"):
        assert np.array_equal(getattr(a, field), getattr(run, field)), field


def test_replay_live_shows_the_bag_at_its_timing(lockstep_run, domain):
    """``replay BAG --live`` waits for a client, then shows the recorded states (the same bytes) in order."""
    assert lockstep_run["rc"] == 0, lockstep_run["output"]
    bag = lockstep_run["bag"]
    player = Proc([sys.executable, "-m", "pa10_dnbs.cli", "replay", bag, "--live", 0, "--rate", 2, "--topics",
                   "/pa10/joint_states"], domain_id=domain)
    client = None
    try:
        url = player.wait_for(r"LIVE waiting for a Foxglove client on (ws://\S+)", 60).group(1)
        client = FoxgloveClient(url)
        assert client.wait_for_channels(CHANNELS, 30)
        client.subscribe("/pa10/joint_states", "/pa10/tracking", "/tf", "/pa10/robot_description")
        client.pump(120, until=lambda: player.proc.poll() is not None)
        rc = player.wait(60)
    finally:
        if client is not None:
            client.close()
        player.kill()
    assert rc == 0, player.output
    assert f"PLAYED {int(LOCKSTEP_DURATION_S * 1000) + 1} messages" in player.output
    run = RunData.load_npz(lockstep_run["out"] / "timeseries.npz")
    shown = client.messages["/pa10/joint_states"]
    assert _check_joint_states(shown, run) >= 20
    with Bag(bag) as b:
        recorded = {bytes(d) for _, _, _, d in b.messages(["/pa10/joint_states"])}
    assert all(p in recorded for _, p in shown)
    stamps = [t for t, _ in shown]
    assert stamps == sorted(stamps) and stamps[-1] == int(LOCKSTEP_DURATION_S * 1e9)  # the last state too
    assert _check_tracking(client.messages["/pa10/tracking"], run) >= 10
    assert client.count("/tf") == len(shown) and client.count("/pa10/robot_description") >= 1

"""live_observer node: the running graph, live in Foxglove (a Foxglove WebSocket server; see live/view.py).

An observer only: it publishes nothing on ROS and answers nothing, so the
loop never waits for it. Subscribes raw to /joint_states with best effort and
depth 1 (only the newest state is ever shown; a best-effort reader sends no
acknowledgements the plant's writer would have to track), and reliably to
the seven reference topics and /robot_description (transient-local, so
batches and the URDF sent before it matched still arrive) and /diagnostics.
Serves the live view on ``host``:``port`` (0: a free port), one frame per
1 / ``display_hz`` s of wall time. Prints ``LIVE ws://host:port``, then READY.
"""
from __future__ import annotations

import sys
import time

from diagnostic_msgs.msg import DiagnosticArray
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import JointState
from std_msgs.msg import String
from trajectory_msgs.msg import JointTrajectory

from .. import JOINT_NAMES
from ..live.schemas import live_channels
from ..live.server import LiveServer, LiveServerError
from ..live.view import LiveView
from .diagnostics import diagnostics_qos
from .params import ParameterError, declare, load_node_config
from .runtime import announce_ready, run_node
from ..wire.topics import DIAGNOSTICS, JOINT_STATES, ROBOT_DESCRIPTION, reference_topic
from .wire import description_qos, reference_qos


def newest_only_qos() -> QoSProfile:
    """/joint_states for display: best effort, depth 1."""
    return QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=1, reliability=ReliabilityPolicy.BEST_EFFORT,
                      durability=DurabilityPolicy.VOLATILE)


class LiveObserverNode(Node):
    def __init__(self):
        super().__init__("live_view")
        p = declare(self, {"config_file": "", "host": "127.0.0.1", "port": 8765, "display_hz": 50.0})
        if not 0 <= p["port"] <= 65535:
            raise ParameterError(f"parameter port must be in 0..65535, got {p['port']}")
        if not 0 < p["display_hz"] <= 1000:
            raise ParameterError(f"parameter display_hz must be in (0, 1000] frames per second, got {p['display_hz']}")
        cfg = load_node_config(p["config_file"])
        try:
            self.server = LiveServer(live_channels(), host=p["host"], port=p["port"])
        except LiveServerError as exc:
            raise ParameterError(str(exc)) from None
        self.view = LiveView(self.server, cfg["plant"]["torque_limit_nm"], cfg["simulation"]["dt_s"],
                             display_hz=p["display_hz"])
        feed = self.view.on_message
        self.create_subscription(JointState, JOINT_STATES, lambda d: feed(JOINT_STATES, d), newest_only_qos(),
                                 raw=True)
        self.create_subscription(String, ROBOT_DESCRIPTION, lambda d: feed(ROBOT_DESCRIPTION, d), description_qos(),
                                 raw=True)
        self.create_subscription(DiagnosticArray, DIAGNOSTICS, lambda d: feed(DIAGNOSTICS, d), diagnostics_qos(),
                                 raw=True)
        for j in JOINT_NAMES:
            t = reference_topic(j)
            self.create_subscription(JointTrajectory, t, lambda d, t=t: feed(t, d), reference_qos(), raw=True)
        self.create_timer(1.0 / p["display_hz"], lambda: self.view.tick(time.monotonic()))
        print(f"LIVE {self.server.url}", flush=True)
        announce_ready("live_view")

    def close(self) -> None:
        self.server.stop()
        d = self.view.decimator
        print(f"LIVE_VIEW {self.view.frames} frames shown of {d.offered} states received; "
              f"{self.server.subscriptions} subscriptions; {self.view.malformed} malformed messages", flush=True)


def main(args=None) -> int:
    return run_node(LiveObserverNode, args)


if __name__ == "__main__":
    sys.exit(main())

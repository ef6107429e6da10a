"""live_observer node: the running graph, live in Foxglove (a Foxglove WebSocket server; see live/view.py).

An observer only: it publishes nothing on ROS and answers nothing, so the
loop never waits for it. It reads the arm of its namespace (/pa10 by
default, also when it runs at the root), and the Foxglove channels carry the resolved names
(/pa10/joint_states, /pa10/robot_description, /tf, ...). joint_states is read with best effort and depth 1
(a best-effort reader sends no acknowledgements the plant's writer would have
to track) on a subscription that no executor spins: DDS keeps the newest
state and the display timer takes it, so the 1 kHz messages cost no Python
callback. Every joint's reference topic and /robot_description are subscribed
reliably (transient-local, so batches and the URDF sent before it matched
still arrive), /diagnostics too. Serves the live view on ``host``:``port``
(0: a free port), one frame per 1 / ``display_hz`` s of wall time. Prints
``LIVE ws://host:port``, then READY; at exit, what it showed and its CPU time.
"""
from __future__ import annotations

import resource
import time
from typing import NoReturn

from diagnostic_msgs.msg import DiagnosticArray
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import JointState
from std_msgs.msg import String
from trajectory_msgs.msg import JointTrajectory

from ..live.schemas import live_channels
from ..live.server import LiveServer, LiveServerError
from ..live.view import LiveView
from .diagnostics import diagnostics_qos
from ..loop.scheduling import apply_batch, apply_fifo
from .params import RT_PRIORITY, SCHED_BATCH, SETTINGS_DEFAULTS, Param, ParameterError, declare, declare_settings
from .settings_params import NODE_SECTIONS
from .runtime import announce_ready, exit_process, run_node
from ..wire.topics import DEFAULT_NS, DIAGNOSTICS, ArmTopics
from .endpoints import description_qos, reference_qos
from .wall_timer import wall_timer


def newest_only_qos() -> QoSProfile:
    """/joint_states for display: best effort, depth 1."""
    return QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=1, reliability=ReliabilityPolicy.BEST_EFFORT,
                      durability=DurabilityPolicy.VOLATILE)


PARAMS = {
    "config_file": SETTINGS_DEFAULTS,
    "sched_batch": SCHED_BATCH,
    "rt_priority": RT_PRIORITY,
    "host": Param("127.0.0.1", "address the Foxglove WebSocket server listens on"),
    "port": Param(8765, "its TCP port; 0 = any free port", 0, 65535),
    "display_hz": Param(50.0, "frames per second of wall time, at most [Hz], in (0, 1000]", 0.0, 1000.0),
}


class LiveObserverNode(Node):
    def __init__(self):
        super().__init__("live_view")
        p = declare(self, PARAMS)
        if not 0 <= p["port"] <= 65535:
            raise ParameterError(f"parameter port must be in 0..65535, got {p['port']}")
        if not 0 < p["display_hz"] <= 1000:
            raise ParameterError(f"parameter display_hz must be in (0, 1000] frames per second, got {p['display_hz']}")
        settings = declare_settings(self, NODE_SECTIONS["live_view"], p["config_file"])
        ns = self.get_namespace()
        arm = ArmTopics(ns if ns != "/" else DEFAULT_NS)
        try:
            self.server = LiveServer(live_channels(arm), host=p["host"], port=p["port"])
        except LiveServerError as exc:
            raise ParameterError(str(exc)) from None
        self.view = LiveView(self.server, settings.plant.torque_limit_nm, settings.simulation.dt_s,
                             display_hz=p["display_hz"], joint_names=settings.arm.joint_names, arm=arm)
        self.arm = arm
        feed = self.view.on_message
        # a node of its own, never added to the executor (and free of the launcher's name remapping)
        self._poll_node = Node("live_view_states", namespace=arm.ns, use_global_arguments=False)
        self._states = self._poll_node.create_subscription(JointState, arm.joint_states, lambda d: None,
                                                           newest_only_qos(), raw=True)
        self.states_taken = 0
        self.create_subscription(String, arm.robot_description, lambda d: feed(arm.robot_description, d),
                                 description_qos(),
                                 raw=True)
        self.create_subscription(DiagnosticArray, DIAGNOSTICS, lambda d: feed(DIAGNOSTICS, d), diagnostics_qos(),
                                 raw=True)
        for j in settings.arm.joint_names:
            t = arm.reference(j)
            self.create_subscription(JointTrajectory, t, lambda d, t=t: feed(t, d), reference_qos(),
                                     raw=True)
        wall_timer(self, 1.0 / p["display_hz"], self._frame)
        self._t0 = time.monotonic()
        print(f"LIVE {self.server.url}", flush=True)
        if p["sched_batch"]:
            print(apply_batch()[1], flush=True)
        if p["rt_priority"]:  # after SCHED_BATCH: a granted priority replaces it
            print(apply_fifo(p["rt_priority"])[1], flush=True)
        announce_ready("live_view")

    def _frame(self) -> None:
        """Take the newest /joint_states DDS holds (if a new one came) and show a frame."""
        with self._states.handle:
            taken = self._states.handle.take_message(JointState, True)
        if taken is not None:
            self.states_taken += 1
            self.view.on_message(self.arm.joint_states, taken[0])
        self.view.tick(time.monotonic())

    def close(self) -> None:
        self.server.stop()  # its subscriptions and nodes go with the process (ros/runtime.py: no rclpy teardown)
        use = resource.getrusage(resource.RUSAGE_SELF)
        wall = time.monotonic() - self._t0
        print(f"LIVE_VIEW {self.view.frames} frames shown in {wall:.1f} s; {self.server.subscriptions} subscriptions; "
              f"{self.view.malformed} malformed messages; CPU {use.ru_utime + use.ru_stime:.1f} s", flush=True)


def main(args=None) -> NoReturn:
    exit_process(run_node(LiveObserverNode, args, params=PARAMS))


if __name__ == "__main__":
    main()

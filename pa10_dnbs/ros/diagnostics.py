"""Fault counters on /diagnostics (diagnostic_msgs/DiagnosticArray), as ROS nodes report health.

One DiagnosticStatus per joint a node is responsible for: name
``<ns>/<role>/<joint>`` (``pa10/plant/s1``, ``pa10/joint_controller/s1``,
``pa10/reference``: <ns> is the arm's namespace without its leading '/'),
hardware_id the node's name, level OK, or WARN once any fault counter is non-zero,
and every counter as a KeyValue. Published on a wall-clock timer, stamped
with the node's latest simulated time.
"""
from __future__ import annotations

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy

from ..wire.topics import DIAGNOSTICS
from .wall_timer import wall_timer

PERIOD_S = 1.0  # wall seconds between reports


def diagnostics_qos() -> QoSProfile:
    return QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=10, reliability=ReliabilityPolicy.RELIABLE,
                      durability=DurabilityPolicy.VOLATILE)


def status_name(node, *parts: str) -> str:
    """``<ns>/<part>/<part>...``: the node's namespace (without the leading '/') and ``parts``."""
    ns = node.get_namespace().strip("/")
    return "/".join(([ns] if ns else []) + list(parts))


def status(name: str, hardware_id: str, counters: dict, fault_keys) -> DiagnosticStatus:
    """WARN with the faulty counters named in the message when any of ``fault_keys`` is non-zero."""
    faulty = [k for k in fault_keys if counters.get(k)]
    return DiagnosticStatus(
        level=DiagnosticStatus.WARN if faulty else DiagnosticStatus.OK, name=name, hardware_id=hardware_id,
        message=("faults: " + ", ".join(f"{k} {counters[k]}" for k in faulty)) if faulty else "OK",
        values=[KeyValue(key=k, value=str(v)) for k, v in counters.items()])


class DiagnosticsReporter:
    """Publishes ``report()`` (a list of DiagnosticStatus) every PERIOD_S of wall time."""

    def __init__(self, node, report, stamp):
        """``report()`` -> list[DiagnosticStatus]; ``stamp()`` -> builtin_interfaces Time (simulated)."""
        self._pub = node.create_publisher(DiagnosticArray, DIAGNOSTICS, diagnostics_qos())
        self._report, self._stamp = report, stamp
        self.timer = wall_timer(node, PERIOD_S, self.publish)

    def publish(self) -> None:
        msg = DiagnosticArray(status=self._report())
        msg.header.stamp = self._stamp()
        self._pub.publish(msg)

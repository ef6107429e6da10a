"""Topic names (relative to the node's namespace, see wire/topics.py), QoS profiles and message conversions shared by the nodes.

Step k is carried as the stamp k * T (integer nanoseconds), so step and
simulated time are the same thing on the wire.
"""
from __future__ import annotations

from builtin_interfaces.msg import Time
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy

from ..wire import steps
from ..wire.topics import (CLOCK, JOINT_STATES, ROBOT_DESCRIPTION, TF, TF_STATIC,  # noqa: F401 (re-exported)
                          effort_topic, reference_topic, state_topic)


def loop_qos(reliability: str, depth: int = 10) -> QoSProfile:
    """Per-joint 1 kHz state/effort and /clock: KEEP_LAST, volatile."""
    rel = {"reliable": ReliabilityPolicy.RELIABLE, "best_effort": ReliabilityPolicy.BEST_EFFORT}[reliability]
    return QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=depth, reliability=rel,
                      durability=DurabilityPolicy.VOLATILE)


def reference_qos(depth: int = 20) -> QoSProfile:
    """Reference batches: reliable and transient-local, so a late subscriber gets the recent ones."""
    return QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=depth, reliability=ReliabilityPolicy.RELIABLE,
                      durability=DurabilityPolicy.TRANSIENT_LOCAL)


def record_qos(depth: int = 2000) -> QoSProfile:
    """Monitoring /joint_states: reliable with a deep queue so nothing is lost."""
    return QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=depth, reliability=ReliabilityPolicy.RELIABLE,
                      durability=DurabilityPolicy.VOLATILE)


def description_qos() -> QoSProfile:
    """/robot_description: reliable, transient-local, depth 1 (latched), as robot_state_publisher offers it."""
    return QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=1, reliability=ReliabilityPolicy.RELIABLE,
                      durability=DurabilityPolicy.TRANSIENT_LOCAL)


class StepClock(steps.StepClock):
    """Step arithmetic of ``wire/steps.py`` plus the ``builtin_interfaces`` Time of a step (diagnostics stamps)."""

    def stamp(self, step: int, out: Time | None = None) -> Time:
        t = out if out is not None else Time()
        t.sec, t.nanosec = self.sec_nanosec(step)
        return t

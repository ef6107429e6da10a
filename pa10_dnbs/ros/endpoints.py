"""Topic names (relative to the node's namespace, see wire/topics.py), QoS profiles and message conversions shared by the nodes.

Step k is carried as the stamp k * T (integer nanoseconds), so step and
simulated time are the same thing on the wire.
"""
from __future__ import annotations

from builtin_interfaces.msg import Time
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy

from ..wire import steps
from ..wire.topics import (CLOCK, JOINT_STATES, REFERENCE_DEPTH, ROBOT_DESCRIPTION, TF,  # noqa: F401 (re-exported)
                          TF_STATIC, effort_topic, reference_topic, state_topic)


def loop_qos(reliability: str, depth: int = 10) -> QoSProfile:
    """Per-joint 1 kHz state/effort: KEEP_LAST, volatile."""
    rel = {"reliable": ReliabilityPolicy.RELIABLE, "best_effort": ReliabilityPolicy.BEST_EFFORT}[reliability]
    return QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=depth, reliability=rel,
                      durability=DurabilityPolicy.VOLATILE)


def reference_qos(depth: int = REFERENCE_DEPTH) -> QoSProfile:
    """Reference batches: reliable and transient-local, so a late subscriber gets the recent ones."""
    return QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=depth, reliability=ReliabilityPolicy.RELIABLE,
                      durability=DurabilityPolicy.TRANSIENT_LOCAL)


def record_qos(depth: int = 2000) -> QoSProfile:
    """/joint_states and /clock: reliable, a deep queue, transient-local, so nothing is lost, not even to a
    late match. DDS discovery is two-sided: the plant's writer can count a reader as matched (and send to it)
    before that reader has matched the writer back, and a volatile reader drops what came before (the
    reference node once saw no /clock for the first 200 steps and the graph stalled for 2 s). A transient-local
    reader asks for the writer's history when its side of the match completes. That alone did not close the race
    (a lost first send waits for the next heartbeat): the start handshake (ros/ready.py) does."""
    return QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=depth, reliability=ReliabilityPolicy.RELIABLE,
                      durability=DurabilityPolicy.TRANSIENT_LOCAL)


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

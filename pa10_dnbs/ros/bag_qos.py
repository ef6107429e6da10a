"""QoS between rclpy and the bag (rosbags Qos, written to metadata.yaml as rosbag2 v9 expects).

DDS discovery does not carry a publisher's history and depth, so a discovered
profile's history is written as an explicit keep_last (Jazzy bags need it)
with ``fallback_depth`` when the depth is unknown.
"""
from __future__ import annotations

from rclpy.duration import Duration
from rclpy.qos import DurabilityPolicy, HistoryPolicy, LivelinessPolicy, QoSProfile, ReliabilityPolicy
from rosbags.interfaces import Qos, QosDurability, QosHistory, QosLiveliness, QosReliability, QosTime
from ..wire.steps import NS_PER_S


def _time(d: Duration) -> QosTime:
    sec, nsec = divmod(int(d.nanoseconds), NS_PER_S)
    return QosTime(sec, nsec)


def to_bag_qos(p: QoSProfile, fallback_depth: int) -> Qos:
    """A discovered (or our own) rclpy profile as the bag records it."""
    known = p.history in (HistoryPolicy.KEEP_LAST, HistoryPolicy.KEEP_ALL) and p.depth > 0
    return Qos(history=QosHistory[p.history.name] if known else QosHistory.KEEP_LAST,
               depth=int(p.depth) if known else fallback_depth,
               reliability=QosReliability[p.reliability.name], durability=QosDurability[p.durability.name],
               deadline=_time(p.deadline), lifespan=_time(p.lifespan), liveliness=QosLiveliness[p.liveliness.name],
               liveliness_lease_duration=_time(p.liveliness_lease_duration),
               avoid_ros_namespace_conventions=bool(p.avoid_ros_namespace_conventions))


def bag_qos(reliable: bool, transient_local: bool, depth: int) -> Qos:
    """A plain keep_last profile for topics the recorder writes itself (/tf, /tf_static)."""
    zero = QosTime(0, 0)
    return Qos(history=QosHistory.KEEP_LAST, depth=depth,
               reliability=QosReliability.RELIABLE if reliable else QosReliability.BEST_EFFORT,
               durability=QosDurability.TRANSIENT_LOCAL if transient_local else QosDurability.VOLATILE,
               deadline=zero, lifespan=zero, liveliness=QosLiveliness.AUTOMATIC, liveliness_lease_duration=zero,
               avoid_ros_namespace_conventions=False)


def from_bag_qos(profiles: list[Qos], min_depth: int) -> QoSProfile:
    """The profile a player publishes with: reliable / transient-local only if every recorded publisher was,
    keep_last with at least ``min_depth`` (so a slow subscriber is not overrun during playback)."""
    reliable = bool(profiles) and all(p.reliability == QosReliability.RELIABLE for p in profiles)
    transient = bool(profiles) and all(p.durability == QosDurability.TRANSIENT_LOCAL for p in profiles)
    depth = max([min_depth] + [p.depth for p in profiles])
    return QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=depth,
                      reliability=ReliabilityPolicy.RELIABLE if reliable else ReliabilityPolicy.BEST_EFFORT,
                      durability=DurabilityPolicy.TRANSIENT_LOCAL if transient else DurabilityPolicy.VOLATILE,
                      liveliness=LivelinessPolicy.AUTOMATIC)


def subscription_qos(publishers: list[QoSProfile], depth: int) -> QoSProfile:
    """What ``ros2 bag record`` does: reliable / transient-local only if every publisher offers it."""
    reliable = bool(publishers) and all(p.reliability == ReliabilityPolicy.RELIABLE for p in publishers)
    transient = bool(publishers) and all(p.durability == DurabilityPolicy.TRANSIENT_LOCAL for p in publishers)
    return QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=depth,
                      reliability=ReliabilityPolicy.RELIABLE if reliable else ReliabilityPolicy.BEST_EFFORT,
                      durability=DurabilityPolicy.TRANSIENT_LOCAL if transient else DurabilityPolicy.VOLATILE)

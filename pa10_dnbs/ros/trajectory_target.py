"""Which graph a trajectory goes to when no namespace is given: the one on the wire that takes trajectories.

A graph's reference node subscribes to ``<ns>/trajectory`` (trajectory_msgs/JointTrajectory). The sender
(trajectory_sender.py) waits until its discovery has seen such a subscriber and no other has shown up for
SETTLE_S. Discovery is gradual (a second graph's endpoints can come seconds after the first's on a busy host),
so two graphs are told apart only when both are seen: ``--namespace`` names the one meant for certain.
"""
from __future__ import annotations

import sys
import time

import rclpy

from ..wire.topics import TRAJECTORY

TRAJECTORY_TYPE = "trajectory_msgs/msg/JointTrajectory"
SETTLE_S = 1.0       # a graph found is taken once the set of graphs seen has not changed for this long [s]
SAY_WAITING_S = 1.0  # a wait longer than this is said in one line (stderr) [s]


class SeveralGraphs(Exception):
    """More than one graph takes trajectories and no namespace says which (the topics, comma-separated)."""


def trajectory_topics(node) -> list[str]:
    """The ``<ns>/trajectory`` topics of JointTrajectory that some node subscribes to (a graph's reference
    node), sorted; what this node's discovery has seen so far."""
    tail = "/" + TRAJECTORY
    return sorted(name for name, types in node.get_topic_names_and_types()
                  if name.endswith(tail) and len(name) > len(tail) and TRAJECTORY_TYPE in types
                  and node.count_subscribers(name) > 0)


def found_topic(node, deadline: float) -> str | None:
    """The one graph's trajectory topic, once discovery has shown the same single one for SETTLE_S, before
    ``deadline`` (time.monotonic()); None if none was seen by then; SeveralGraphs as soon as two are seen."""
    say_at = time.monotonic() + SAY_WAITING_S
    seen, since = [], time.monotonic()
    while time.monotonic() < deadline:
        found = trajectory_topics(node)
        if len(found) > 1:
            raise SeveralGraphs(", ".join(found))
        if found != seen:
            seen, since = found, time.monotonic()
        elif found and time.monotonic() - since >= SETTLE_S:
            return found[0]
        if say_at is not None and time.monotonic() > say_at:
            print("trajectory_sender: waiting for a graph that takes trajectories (a <ns>/trajectory subscriber)",
                  file=sys.stderr, flush=True)
            say_at = None
        rclpy.spin_once(node, timeout_sec=0.05)
    found = trajectory_topics(node)
    return found[0] if len(found) == 1 else None

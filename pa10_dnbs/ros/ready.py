"""The start handshake on the wire: the latched ``ready`` topic (``loop/start_handshake.py`` says what is said).

``ready`` (relative: ``/pa10/ready`` by default) is ``std_msgs/String``,
reliable and transient-local with depth 1 per writer, as a latched topic: the
plant reads every node's latest status whenever its reader matches, before
or after the node said it. A node announces with ``announce_when_ready``
(a wall timer polls its check every ``POLL_S`` until it is ready); the plant
reads with ``ReadyListener``. Not recorded: the recorder records the graph's
topics by name, and ``ready`` is not one of them.
"""
from __future__ import annotations

import sys
from typing import Callable

from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy
from std_msgs.msg import String

from ..loop.start_handshake import READY, ReadyAnnouncer, ReadyBoard
from .wall_timer import wall_timer

POLL_S = 0.01  # wall seconds between two checks of a node's readiness
READER_DEPTH = 100  # the plant's reader: one instance (an unkeyed topic), the latest status of every node


class GraphNotReady(RuntimeError):
    """The graph a node waits for did not match within its ``start_timeout_s``; the message says what was lacking.
    A node ends on it with one line (``runtime.run_node``: ``FAILED <message>``, exit 1), no traceback."""


def ready_qos(depth: int = 1) -> QoSProfile:
    """Latched: reliable, transient-local, keep-last ``depth``."""
    return QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=depth, reliability=ReliabilityPolicy.RELIABLE,
                      durability=DurabilityPolicy.TRANSIENT_LOCAL)


def announce_when_ready(node, check: Callable[[], str | None]) -> ReadyAnnouncer:
    """Publish ``node``'s status on ``ready`` until ``check()`` (None when ready for the first steps, else what
    it still waits for) says ready; prints ``HANDSHAKE <name> ready after <s> s`` then."""
    pub = node.create_publisher(String, READY, ready_qos())
    announcer = ReadyAnnouncer(node.get_name(), check, lambda text: pub.publish(String(data=text)))

    def poll() -> None:
        if announcer.poll():
            node.destroy_timer(timer)
            print(f"HANDSHAKE {announcer.name} ready after {announcer.ready_after_s:.3f} s", file=sys.stdout,
                  flush=True)

    timer = wall_timer(node, POLL_S, poll)
    return announcer


class ReadyListener:
    """The plant's reader of ``ready``: fills a ``ReadyBoard`` of ``expected`` node names (served by the
    executor: the plant spins it while it waits). Never destroyed: a destroyed endpoint is a graph update to
    every node, and the run's first steps would go out in the middle of it."""

    def __init__(self, node, expected: list[str]):
        self.board = ReadyBoard(expected)
        self._sub = node.create_subscription(String, READY, lambda msg: self.board.offer(msg.data),
                                             ready_qos(READER_DEPTH))

"""Waiting for reliable subscribers to acknowledge what a node published, in slices a stop can end."""
from __future__ import annotations

import time

from rclpy.duration import Duration

SLICE_S = 0.1   # wall seconds of one wait: how soon a stop (SIGINT, SIGTERM) ends a flush


def wait_acked(publishers, timeout_s: float, stop=None) -> bool:
    """Until every publisher's messages are acknowledged by its reliable subscribers, at most ``timeout_s`` [s of
    wall time] in all, or until ``stop`` (a Future) is done; True when all were. One long wait in rclpy's C code
    would hold off the node's signal handler: a Ctrl-C that stops the subscribers too then left the node waiting
    out the whole timeout, past the launcher's grace, to SIGKILL."""
    end = time.monotonic() + timeout_s
    pending = list(publishers)
    while True:
        left = end - time.monotonic()
        wait = Duration(nanoseconds=int(max(0.0, min(SLICE_S, left)) * 1e9))
        pending = [p for p in pending if not p.wait_for_all_acked(wait)]
        if not pending:
            return True
        if left <= SLICE_S or (stop is not None and stop.done()):
            return False

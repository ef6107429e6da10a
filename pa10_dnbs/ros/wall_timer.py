"""Timers that tick in wall time whatever the node's clock: every node but the plant runs with
``use_sim_time:=true``, and a timer on the node's (simulated) clock would stall whenever /clock does.

Housekeeping (draining polled subscriptions, /diagnostics, discovery, the live view's frames) is plumbing:
it must go on in wall time. The 1 kHz loop never uses a timer; it takes its time from the messages' stamps.
"""
from __future__ import annotations

from typing import Callable

from rclpy.clock import Clock, ClockType

STEADY = Clock(clock_type=ClockType.STEADY_TIME)


def wall_timer(node, period_s: float, callback: Callable[[], None]):
    """``node.create_timer`` on the steady clock: ``callback`` every ``period_s`` [s] of wall time."""
    return node.create_timer(period_s, callback, clock=STEADY)

"""Step k <-> stamp k T, in integer nanoseconds, and the stamp at the start of a stamped CDR message.

Step k travels as the stamp k * T, so step and simulated time are the same
thing on the wire. No ROS types here: ``ros/endpoints.py`` adds the conversions
to and from ``builtin_interfaces`` messages on top.
"""
from __future__ import annotations

import struct

NS_PER_S = 1_000_000_000
# header.stamp (or Clock.clock): int32 sec, uint32 nanosec, right after the 4-byte CDR encapsulation
STAMP = struct.Struct("<iI")


def to_ns(sec: int, nanosec: int) -> int:
    """(sec, nanosec) -> integer nanoseconds."""
    return sec * NS_PER_S + nanosec


def cdr_stamp_ns(data: bytes) -> int:
    """The stamp [ns] at the start of a stamped message's CDR body (JointState, JointTrajectory, Clock, Header).

    Raises struct.error when ``data`` is shorter than the stamp.
    """
    sec, nanosec = STAMP.unpack_from(data, 4)
    return sec * NS_PER_S + nanosec


class StepClock:
    """Conversions between step k and time for a fixed step T = ``dt_ns`` nanoseconds."""

    def __init__(self, dt_s: float):
        self.dt_ns = int(round(dt_s * 1e9))
        if self.dt_ns <= 0:
            raise ValueError("dt_s must be at least 1 ns")

    def ns(self, step: int) -> int:
        """Stamp of step ``step`` [ns]."""
        return step * self.dt_ns

    def sec_nanosec(self, step: int) -> tuple[int, int]:
        """Stamp of step ``step`` as (sec, nanosec)."""
        return divmod(step * self.dt_ns, NS_PER_S)

    def step_of_ns(self, ns: int) -> int:
        """The step nearest to a stamp [ns]."""
        return round(ns / self.dt_ns)

    def step_of_sec_nanosec(self, sec: int, nanosec: int) -> int:
        """The step nearest to a stamp (sec, nanosec)."""
        return round((sec * NS_PER_S + nanosec) / self.dt_ns)

    def step_of_cdr(self, data: bytes) -> int:
        """The step of a stamped message's CDR bytes (see :func:`cdr_stamp_ns`)."""
        return round(cdr_stamp_ns(data) / self.dt_ns)

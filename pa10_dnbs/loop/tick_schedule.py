"""Wall-clock pacing of the realtime plant: when each tick starts, its deadline, late starts.

Like Gazebo's ``real_time_factor``: a step of T simulated seconds takes
``period_s = T / real_time_factor`` of wall time. Tick k is scheduled at
``s_k``; the efforts answering state k must arrive before its deadline
``s_k + deadline_fraction * period_s``. A tick that starts more than
``late_tolerance * period_s`` after ``s_k`` is late: it is counted, and the
schedule shifts (``s_k`` becomes the actual start, later ticks follow from it;
lost time is not caught up, as in gz-sim and ros2_control). A start within
the tolerance keeps the grid, so wake-up jitter does not slow the run down.
Times are seconds of any monotonic clock; nothing here reads a clock.
"""
from __future__ import annotations

import math


class TickSchedule:
    def __init__(self, period_s: float, deadline_fraction: float = 0.9, late_tolerance: float = 0.1):
        """``period_s`` [s] of wall time per tick; fractions of the period for the deadline and lateness."""
        if not (math.isfinite(period_s) and period_s > 0):
            raise ValueError(f"period_s must be a positive number of seconds, got {period_s}")
        if not 0 < deadline_fraction <= 1:
            raise ValueError(f"deadline_fraction must be in (0, 1], got {deadline_fraction}")
        if not 0 <= late_tolerance < 1:
            raise ValueError(f"late_tolerance must be in [0, 1), got {late_tolerance}")
        self.period_s = period_s
        self.deadline_fraction = deadline_fraction
        self.late_tolerance = late_tolerance
        self.tick = -1               # the tick in progress (-1: not started)
        self.scheduled = math.nan    # s_k of the tick in progress [s]
        self.started = math.nan      # when it actually started [s]
        self.first_start = math.nan
        self.late_starts = 0
        self.max_lateness_s = 0.0     # largest start - s_k seen, within tolerance or not [s]

    @property
    def next_start(self) -> float:
        """When the next tick is scheduled [s]."""
        return self.scheduled + self.period_s

    @property
    def deadline(self) -> float:
        """Deadline of the tick in progress [s]."""
        return self.scheduled + self.deadline_fraction * self.period_s

    def begin(self, now: float) -> bool:
        """Start the next tick at ``now``; True when it started late (counted; the schedule shifts)."""
        if self.tick < 0:
            self.tick, self.scheduled, self.started, self.first_start = 0, now, now, now
            return False
        self.tick += 1
        self.scheduled += self.period_s
        self.started = now
        lateness = now - self.scheduled
        self.max_lateness_s = max(self.max_lateness_s, lateness)
        if lateness > self.late_tolerance * self.period_s:
            self.late_starts += 1
            self.scheduled = now  # no catch-up: the schedule follows the late start
            return True
        return False

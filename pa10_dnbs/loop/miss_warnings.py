"""Throttled deadline-miss warnings: at most one line per period, naming the joints that missed.

Like ros2_control's "Overrun detected! ... (missed cycles: N)", printed at
most once a second however many ticks miss: the misses since the last line
are summed per joint, with the range of ticks they fell in and the late
starts of the plant's own ticks. Times are seconds of any monotonic clock.
"""
from __future__ import annotations

from collections import Counter


class MissWarnings:
    def __init__(self, joint_names, period_s: float = 1.0):
        if period_s <= 0:
            raise ValueError(f"period_s must be > 0, got {period_s}")
        self.names = list(joint_names)
        self.period_s = period_s
        self._missed: Counter = Counter()
        self._late = 0
        self._first = self._last = None
        self._next_s = None   # earliest time the next line may go out
        self.lines = 0

    def missed(self, step: int, joints) -> None:
        """Joints (indices) whose effort for ``step`` missed its deadline."""
        if len(joints):
            self._missed.update(int(j) for j in joints)
            self._note(step)

    def late_start(self, step: int) -> None:
        """The tick of ``step`` started late."""
        self._late += 1
        self._note(step)

    def _note(self, step: int) -> None:
        self._first = step if self._first is None else self._first
        self._last = step

    def poll(self, now: float) -> str | None:
        """The warning to print now, or None (nothing new, or one went out less than ``period_s`` ago)."""
        if self._first is None or (self._next_s is not None and now < self._next_s):
            return None
        parts = [f"{self.names[j]} {n}" for j, n in sorted(self._missed.items())]
        text = (f"steps {self._first}-{self._last}: " + (f"efforts missed the deadline: {', '.join(parts)}"
                                                          if parts else "no effort missed")
                + (f"; {self._late} ticks started late" if self._late else ""))
        self._missed.clear()
        self._late = 0
        self._first = self._last = None
        self._next_s = now + self.period_s
        self.lines += 1
        return text

"""Keep only the newest of many samples and hand one out per display period (wall time).

The 1 kHz loop sends far more states than a screen can draw: the live view
stores the newest /joint_states as it comes (cheap) and takes one per
``period_s`` of wall time. Time comes from the caller, so tests use a fake clock.
"""
from __future__ import annotations

from typing import Any


class Decimator:
    def __init__(self, period_s: float):
        if not period_s > 0:
            raise ValueError(f"period_s must be > 0, got {period_s}")
        self.period_s = period_s
        self._latest: Any = None
        self._fresh = False
        self._next_s = float("-inf")
        self.offered = 0
        self.taken = 0

    def offer(self, sample: Any) -> None:
        """Remember ``sample`` as the newest (the older one, if not taken, is dropped)."""
        self._latest = sample
        self._fresh = True
        self.offered += 1

    def take(self, now_s: float) -> Any | None:
        """The newest sample if one came since the last take and a period has passed since then; else None."""
        if not self._fresh or now_s < self._next_s:
            return None
        self._fresh = False
        # keep the cadence; the first take, or one after a pause, starts it anew from now
        self._next_s += self.period_s
        if self._next_s < now_s:
            self._next_s = now_s + self.period_s
        self.taken += 1
        return self._latest

"""The lockstep plant's patience, without ROS: when to resend a state, when to give up on an effort.

State k went out at ``published_s``. While some joint has not answered it,
the plant re-sends state k to the joints that owe (every ``resend_s``), and
once ``timeout_s`` has passed since the first send it steps without them
(hold or zero, counted by the effort gate). Times are seconds of any
monotonic clock.
"""
from __future__ import annotations

import math


class LockstepPolicy:
    def __init__(self, resend_s: float = 0.25, timeout_s: float = 1.0):
        if not (resend_s > 0 and timeout_s > 0):
            raise ValueError(f"resend_s and timeout_s must be > 0 s, got {resend_s}, {timeout_s}")
        self.resend_s = resend_s
        self.timeout_s = timeout_s
        self._step = -1
        self._published_s = math.nan
        self._last_resend_s = math.nan

    def published(self, step: int, now: float) -> None:
        """State ``step`` went out at ``now`` (its first send)."""
        self._step, self._published_s, self._last_resend_s = step, now, math.nan

    def action(self, now: float) -> str | None:
        """'timeout' (step without the missing joints), 'resend' (send the state again to them) or None."""
        waited = now - self._published_s
        if waited > self.timeout_s:
            return "timeout"
        if waited > self.resend_s and not (now - self._last_resend_s <= self.resend_s):
            self._last_resend_s = now
            return "resend"
        return None

    def next_check_s(self, now: float) -> float:
        """Seconds until ``action`` could change its answer (>= 0)."""
        due = [self._published_s + self.timeout_s]
        first_resend = self._published_s + self.resend_s
        due.append(first_resend if math.isnan(self._last_resend_s) else self._last_resend_s + self.resend_s)
        return max(0.0, min(due) - now)

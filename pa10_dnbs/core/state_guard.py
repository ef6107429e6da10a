"""Plausibility of one joint's measured state, checked before it reaches the controller.

A state is rejected when x1 [rad] or x2 [rad/s] is not finite, when x1 lies
beyond the joint's limits by more than ``margin_rad``, or when |x2| exceeds
``max_speed_rad_s``. numpy-free: scalars only.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

REASONS = ("nonfinite", "position", "speed")


@dataclass(frozen=True)
class StateGuard:
    lower_rad: float
    upper_rad: float
    margin_rad: float
    max_speed_rad_s: float

    def check(self, x1: float, x2: float) -> str | None:
        """None for a plausible state, else the reason: 'nonfinite', 'position' or 'speed'."""
        if not (math.isfinite(x1) and math.isfinite(x2)):
            return "nonfinite"
        if x1 < self.lower_rad - self.margin_rad or x1 > self.upper_rad + self.margin_rad:
            return "position"
        if abs(x2) > self.max_speed_rad_s:
            return "speed"
        return None

"""Plausibility of the joints' measured states, checked before they reach the controllers.

A state is rejected when x1 [rad] or x2 [rad/s] is not finite, when x1 lies
beyond the joint's limits by more than ``margin_rad``, or when |x2| exceeds
``max_speed_rad_s``. One row per joint: arrays of shape (n,).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

REASONS = ("nonfinite", "position", "speed")
OK = -1  # check() code of a plausible state; otherwise the index into REASONS


@dataclass(frozen=True)
class StateGuard:
    """Limits per joint (arrays (n,) or numbers): lower_rad, upper_rad, max_speed_rad_s; margin_rad [rad]."""

    lower_rad: np.ndarray
    upper_rad: np.ndarray
    margin_rad: float
    max_speed_rad_s: np.ndarray

    def __post_init__(self) -> None:
        object.__setattr__(self, "_low", np.asarray(self.lower_rad, dtype=float) - self.margin_rad)
        object.__setattr__(self, "_high", np.asarray(self.upper_rad, dtype=float) + self.margin_rad)

    def all_plausible(self, x1: np.ndarray, x2: np.ndarray) -> bool:
        """True when every joint's state, x1 (n,) [rad] and x2 (n,) [rad/s], passes (one expression: NaN and +-inf
        fail every comparison)."""
        ok = (x1 >= self._low) & (x1 <= self._high) & (np.abs(x2) <= self.max_speed_rad_s)
        return bool(np.logical_and.reduce(ok))

    def check(self, x1: np.ndarray, x2: np.ndarray) -> np.ndarray:
        """int (n,): OK for a plausible state x1 (n,) [rad], x2 (n,) [rad/s], else the index of the reason in
        REASONS (the first that applies)."""
        with np.errstate(invalid="ignore"):
            code = np.where(np.abs(x2) > self.max_speed_rad_s, 2, OK)
            outside = (x1 < self.lower_rad - self.margin_rad) | (x1 > self.upper_rad + self.margin_rad)
        code = np.where(outside, 1, code)
        return np.where(~(np.isfinite(x1) & np.isfinite(x2)), 0, code)

"""Seeded decisions, message by message, for one direction of one joint's link.

Every message draws the same four uniform numbers (drop, corrupt, jitter,
spare) from its own generator, so the n-th message of a link meets the same
fate in every run with the same seed, whatever the other links do.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

CORRUPT_KINDS = ("nan", "inf", "out_of_range")
OUT_OF_RANGE_FACTOR = 10.0  # an out-of-range value is this many times the limit


@dataclass(frozen=True)
class LinkFaults:
    """What to inject on one link; fractions in [0, 1], times in seconds."""

    drop_fraction: float = 0.0
    delay_s: float = 0.0
    jitter_s: float = 0.0
    corrupt_fraction: float = 0.0
    corrupt_kind: str = "nan"

    def __post_init__(self):
        if self.corrupt_kind not in CORRUPT_KINDS:
            raise ValueError(f"corrupt_kind must be one of {CORRUPT_KINDS}, got {self.corrupt_kind!r}")

    @property
    def active(self) -> bool:
        return bool(self.drop_fraction or self.delay_s or self.jitter_s or self.corrupt_fraction)

    @classmethod
    def of(cls, link, joint: int) -> "LinkFaults":
        """From the settings of one link direction (``settings.faults.state`` or ``.effort``: per-joint
        drop_fraction, delay_ms, jitter_ms, corrupt_fraction and a corrupt_kind) for joint index ``joint``."""
        return cls(drop_fraction=link.drop_fraction[joint], delay_s=link.delay_ms[joint] / 1e3,
                   jitter_s=link.jitter_ms[joint] / 1e3, corrupt_fraction=link.corrupt_fraction[joint],
                   corrupt_kind=link.corrupt_kind)


class Fate(NamedTuple):
    drop: bool
    delay_s: float
    corrupt: bool


class FaultInjector:
    """Decides each message's fate and counts what was injected."""

    def __init__(self, faults: LinkFaults, seed):
        """``seed``: int or sequence of ints for numpy.random.default_rng."""
        self.faults = faults
        self._rng = np.random.default_rng(seed)
        self.messages = 0
        self.dropped = 0
        self.delayed = 0
        self.corrupted = 0

    def next_fate(self) -> Fate:
        """The fate of the next message (a dropped message is neither delayed nor corrupted)."""
        f = self.faults
        u_drop, u_corrupt, u_jitter, _ = self._rng.random(4).tolist()
        self.messages += 1
        if u_drop < f.drop_fraction:
            self.dropped += 1
            return Fate(True, 0.0, False)
        delay = f.delay_s + f.jitter_s * u_jitter
        corrupt = bool(u_corrupt < f.corrupt_fraction)
        self.delayed += int(delay > 0.0)
        self.corrupted += int(corrupt)
        return Fate(False, delay, corrupt)

    def corrupt_value(self, limit: float) -> float:
        """The value a corrupted message carries instead of the true one (``limit`` for out_of_range)."""
        kind = self.faults.corrupt_kind
        if kind == "nan":
            return float("nan")
        if kind == "inf":
            return float("inf") if self.corrupted % 2 else float("-inf")
        return OUT_OF_RANGE_FACTOR * abs(limit)

    def counters(self) -> dict[str, int]:
        return {"messages": self.messages, "dropped": self.dropped, "delayed": self.delayed,
                "corrupted": self.corrupted}

"""x_d(k) per joint from the reference batches on the wire, for observers that show |e| as it happens.

Fed with the raw JointTrajectory batches of <ns>/<joint>/reference (see
trajectory_cdr.py), it answers x_d at a step, the tracking error
e = x_d - x [rad] of a state, and keeps the worst |e| seen so far. Steps
already shown can be forgotten so a long run does not grow it. No ROS, no numpy.
"""
from __future__ import annotations

import math
import struct

from . import trajectory_cdr
from .steps import StepClock


class ReferenceBuffer:
    def __init__(self, n_joints: int, clock: StepClock):
        self.clock = clock
        self._x: list[dict[int, float]] = [{} for _ in range(n_joints)]
        self.malformed = 0
        self.worst_abs_error = math.nan  # max over observed states and joints of |x_d - x| [rad]

    def add(self, joint: int, first_step: int, offsets, positions) -> None:
        """x_d of ``joint`` at steps first_step + offsets [rad]."""
        self._x[joint].update(zip((first_step + o for o in offsets), positions))

    def add_cdr(self, joint: int, data: bytes) -> bool:
        """Add a raw JointTrajectory batch of ``joint`` (first position of each point); False if malformed."""
        try:
            sec, nanosec, _, points = trajectory_cdr.decode(data)
        except (ValueError, struct.error, UnicodeDecodeError):
            self.malformed += 1
            return False
        k0 = self.clock.step_of_sec_nanosec(sec, nanosec)
        self._x[joint].update((k0 + self.clock.step_of_ns(t_ns), pos[0]) for pos, _, t_ns in points if pos)
        return True

    def at(self, step: int) -> list[float]:
        """x_d(step) per joint [rad]; NaN where no batch covered the step."""
        return [d.get(step, math.nan) for d in self._x]

    def error(self, step: int, positions) -> list[float]:
        """e = x_d - x per joint at ``step`` [rad] (NaN without x_d), and the worst |e| so far updated."""
        e = [xd - x for xd, x in zip(self.at(step), positions)]
        finite = [abs(v) for v in e if math.isfinite(v)]
        if finite:
            worst = max(finite)
            if not worst <= self.worst_abs_error:  # also replaces the initial NaN
                self.worst_abs_error = worst
        return e

    def forget_before(self, step: int) -> None:
        """Drop x_d of steps before ``step`` (batches come in step order, so this pops from the front)."""
        for d in self._x:
            while d:
                k = next(iter(d))
                if k >= step:
                    break
                del d[k]

    def __len__(self) -> int:
        return sum(len(d) for d in self._x)

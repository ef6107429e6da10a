"""The plant's side of the loop, without ROS: which torque to apply at each step.

Lockstep: step k is applied when every joint's effort answering state k has
arrived, or when the timeout expires; a missing effort is replaced by the
joint's last applied torque ("hold") or zero, and counted; so is a non-finite
one, at once.
An effort for a later step (a player re-driving the plant from a bag sends
ahead) is kept until that step comes, up to ``max_pending`` steps.
Realtime (deadline-synchronous): at the deadline of tick k the efforts
answering state k that have arrived are applied; each missing one is
replaced the same way and counted as a miss for its joint (``take_deadline``).
The tick is on time when no joint missed it.
"""
from __future__ import annotations

import math

import numpy as np


class EffortGate:
    """Collects efforts by step for ``n_joints`` joints."""

    def __init__(self, n_joints: int, on_missing: str = "hold", max_pending: int = 100_000):
        if on_missing not in ("hold", "zero"):
            raise ValueError(f"on_missing must be 'hold' or 'zero', got {on_missing!r}")
        self.n = n_joints
        self.on_missing = on_missing
        self.step = 0
        self._efforts = np.zeros(n_joints)
        self._have = np.zeros(n_joints, dtype=bool)
        self.applied = np.zeros(n_joints)
        self.timeouts = np.zeros(n_joints, dtype=np.int64)     # lockstep: effort replaced after the timeout
        self.nonfinite = np.zeros(n_joints, dtype=np.int64)    # efforts rejected for NaN/Inf
        self.stale = np.zeros(n_joints, dtype=np.int64)        # efforts for a step already applied
        self.misses = np.zeros(n_joints, dtype=np.int64)       # realtime: effort not in by the tick's deadline
        self.ticks = 0
        self.ticks_all_on_time = 0
        self.max_pending = max_pending
        self._pending: dict[int, dict[int, float]] = {}      # lockstep: step -> {joint: effort} ahead of time
        self.dropped_ahead = np.zeros(n_joints, dtype=np.int64)  # efforts ahead beyond max_pending steps
        self.timeout_steps: list[list[int]] = [[] for _ in range(n_joints)]  # lockstep: steps filled in, per joint
        self.miss_steps: list[list[int]] = [[] for _ in range(n_joints)]     # realtime: the first MAX_KEPT misses
        self.bin_steps = 60_000  # realtime: on-time ticks are also counted per bin of this many steps
        self.ticks_per_bin: list[int] = []
        self.on_time_per_bin: list[int] = []

    def offer(self, joint: int, step: int, effort: float) -> bool:
        """Record joint ``joint``'s ``effort`` [N m] for ``step``; True when all joints have answered the current step.

        A non-finite effort for the current step counts as that joint's answer,
        replaced at once by its last applied torque ("hold") or zero, and counted.
        """
        if not math.isfinite(effort):
            self.nonfinite[joint] += 1
            if step != self.step or self._have[joint]:
                return False
            effort = self.applied[joint] if self.on_missing == "hold" else 0.0
            self._efforts[joint] = effort
            self._have[joint] = True
            return bool(self._have.all())
        if step != self.step:
            if step < self.step:
                self.stale[joint] += 1
            elif step in self._pending or len(self._pending) < self.max_pending:
                self._pending.setdefault(step, {}).setdefault(joint, effort)
            else:
                self.dropped_ahead[joint] += 1
            return False
        if self._have[joint]:
            return False  # a duplicate answer: the first one counts
        self._efforts[joint] = effort
        self._have[joint] = True
        return bool(self._have.all())

    @property
    def missing(self) -> list[int]:
        """Joints that have not answered the current step."""
        return [j for j in range(self.n) if not self._have[j]]

    def take_lockstep(self, timed_out: bool = False) -> np.ndarray:
        """Torques (n,) [N m] for the current step; with ``timed_out`` the missing joints are filled in and
        counted."""
        if not timed_out and not self._have.all():
            raise RuntimeError("take_lockstep before all efforts arrived")
        for j in np.flatnonzero(~self._have):
            self.timeouts[j] += 1
            self.timeout_steps[j].append(self.step)
        return self._fill_and_advance()

    def take_deadline(self) -> np.ndarray:
        """Realtime, at the deadline of the current step's tick: the efforts (n,) [N m] that arrived, the missing ones
        filled in (hold/zero) and counted as misses; the tick counts as on time when none was missing."""
        missed = np.flatnonzero(~self._have)
        for j in missed:
            self.misses[j] += 1
            if len(self.miss_steps[j]) < self.MAX_KEPT:
                self.miss_steps[j].append(self.step)
        on_time = missed.size == 0
        self.ticks += 1
        self.ticks_all_on_time += on_time
        b = self.step // self.bin_steps
        while len(self.ticks_per_bin) <= b:
            self.ticks_per_bin.append(0)
            self.on_time_per_bin.append(0)
        self.ticks_per_bin[b] += 1
        self.on_time_per_bin[b] += on_time
        return self._fill_and_advance()

    MAX_KEPT = 10_000  # miss steps kept per joint

    def _fill_and_advance(self) -> np.ndarray:
        for j in np.flatnonzero(~self._have):
            self._efforts[j] = self.applied[j] if self.on_missing == "hold" else 0.0
        self.applied = self._efforts.copy()
        self._have[:] = False
        self.step += 1
        for j, u in self._pending.pop(self.step, {}).items():
            self._efforts[j] = u
            self._have[j] = True
        return self.applied

    @property
    def ready(self) -> bool:
        """Lockstep: every joint has answered the current step."""
        return bool(self._have.all())

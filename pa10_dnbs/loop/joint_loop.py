"""One joint's control loop as the node runs it, without ROS.

Receives the joint's state for step k and reference points by step, and
answers each state exactly once with an effort. A state that arrives before
its references (x_d(k) and x_d(k + preview)) waits for them, so the answer
does not depend on message timing; a state seen again (a resend) gets the
same effort back without training the networks twice.

Defensive: a state that fails the StateGuard (non-finite, beyond the joint
limits by more than a margin, faster than the speed limit) is answered with
the last torque ("hold") or zero, without touching the controller, and
counted by reason; so is a non-finite torque from the controller. No
non-finite torque is ever returned.
"""
from __future__ import annotations

import math

from ..core.reference import ReferenceSample
from ..core.state_guard import REASONS, StateGuard


class JointLoop:
    """Bookkeeping around one joint controller (DNBS or PID, anything with ``step``)."""

    def __init__(self, controller, preview_steps: int, guard: StateGuard | None = None, on_bad_state: str = "hold"):
        if on_bad_state not in ("hold", "zero"):
            raise ValueError(f"on_bad_state must be 'hold' or 'zero', got {on_bad_state!r}")
        self.controller = controller
        self.preview_steps = preview_steps
        self.guard = guard
        self.on_bad_state = on_bad_state
        self.bad_states = dict.fromkeys(REASONS, 0)
        self.nonfinite_torques = 0
        self._ref_pos: dict[int, float] = {}
        self._ref_vel: dict[int, float] = {}
        self._pending: dict[int, tuple[float, float]] = {}
        self.last_step = -1
        self.last_effort = 0.0
        self.duplicates = 0
        self.out_of_order = 0

    @property
    def pending_steps(self) -> list[int]:
        """States waiting for their references."""
        return sorted(self._pending)

    @property
    def reference_span(self) -> tuple[int, int] | None:
        """(first, last) step of the buffered references."""
        return (min(self._ref_pos), max(self._ref_pos)) if self._ref_pos else None

    def add_reference(self, first_step: int, positions, velocities) -> list[tuple[int, float]]:
        """Store points for steps first_step, first_step + 1, ...; answer states that were waiting."""
        for i, (p, v) in enumerate(zip(positions, velocities)):
            self._ref_pos[first_step + i] = p
            self._ref_vel[first_step + i] = v
        return self._drain()

    def on_state(self, step: int, position: float, velocity: float) -> list[tuple[int, float]]:
        """Answer state ``step``: a list of (step, effort) ready to publish (empty while waiting)."""
        if step == self.last_step:
            self.duplicates += 1
            return [(step, self.last_effort)]
        if step < self.last_step:
            self.out_of_order += 1
            return []
        self._pending[step] = (position, velocity)
        return self._drain()

    def _answer(self, step: int, q: float, qd: float, ahead: int) -> float:
        safe = self.last_effort if self.on_bad_state == "hold" else 0.0
        reason = self.guard.check(q, qd) if self.guard is not None else None
        if reason is not None:
            self.bad_states[reason] += 1
            return safe
        sample = ReferenceSample(self._ref_pos[step], self._ref_vel[step], self._ref_pos[ahead])
        u = self.controller.step(q, qd, sample)
        if not math.isfinite(u):
            self.nonfinite_torques += 1
            return safe
        return u

    def _drain(self) -> list[tuple[int, float]]:
        out = []
        for step in sorted(self._pending):
            ahead = step + self.preview_steps
            if step not in self._ref_pos or ahead not in self._ref_pos:
                break
            q, qd = self._pending.pop(step)
            self.last_effort = self._answer(step, q, qd, ahead)
            self.last_step = step
            out.append((step, self.last_effort))
        if len(self._ref_pos) > 4096:  # forget references of answered steps, now and then
            for old in [k for k in self._ref_pos if k < self.last_step]:
                del self._ref_pos[old], self._ref_vel[old]
        return out

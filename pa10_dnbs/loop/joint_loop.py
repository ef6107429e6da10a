"""One joint's control loop as the node runs it, without ROS.

Receives the joint's state for step k and reference points by step, and
answers each state exactly once with an effort. A state that arrives before
its references (x_d(k) and x_d(k + preview)) waits for them, so the answer
does not depend on message timing; a state seen again (a resend) gets the
same effort back without training the networks twice (a bad one is still counted by the guard's reasons, so the
counters equal the corrupted states the plant sent, resends included). The answer comes
before the training: ``on_state`` returns the effort with the training
pending, and the node calls ``learn`` once the effort is out.

Defensive: the answer comes from GuardedControllers, the same guard the
in-process simulation steps through: a state that fails the StateGuard is
answered with the last torque ("hold") or zero, without training the
controller, and counted by reason; so is a non-finite torque. No non-finite
torque is ever returned.
"""
from __future__ import annotations

import numpy as np

from ..core.reference import ReferenceSample
from ..core.state_guard import REASONS
from .guarded_controllers import GuardedControllers


class JointLoop:
    """Bookkeeping around one joint's guarded controller (a bank of one row, DNBS or PID)."""

    def __init__(self, guarded: GuardedControllers, preview_steps: int):
        if guarded.controllers.n_joints != 1:
            raise ValueError(f"a joint loop runs one joint's controller, got {guarded.controllers.n_joints}")
        self.guarded = guarded
        self.controller = guarded.controllers
        self.preview_steps = preview_steps
        self._x1, self._x2 = np.zeros(1), np.zeros(1)
        # one sample, refilled each step (the controllers copy what they keep, as they do with x1 and x2)
        self._sample = ReferenceSample(np.zeros(1), np.zeros(1), np.zeros(1))
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

    def holds_references_for(self, step: int) -> bool:
        """True when the references state ``step`` needs (x_d(step) and x_d(step + preview)) are buffered."""
        return step in self._ref_pos and step + self.preview_steps in self._ref_pos

    def add_reference(self, first_step: int, positions, velocities) -> list[tuple[int, float]]:
        """Store reference points, ``positions`` [rad] and ``velocities`` [rad/s] (equal lengths), for steps
        first_step, first_step + 1, ...; answer states that were waiting: (step, effort [N m]) pairs."""
        for i, (p, v) in enumerate(zip(positions, velocities)):
            self._ref_pos[first_step + i] = p
            self._ref_vel[first_step + i] = v
        return self._drain()

    def on_state(self, step: int, position: float, velocity: float) -> list[tuple[int, float]]:
        """Answer state ``step`` (``position`` [rad], ``velocity`` [rad/s]): a list of (step, effort [N m]) ready
        to publish (empty while waiting)."""
        if step == self.last_step:
            self.duplicates += 1
            self._count_bad(position, velocity)
            return [(step, self.last_effort)]
        if step < self.last_step:
            self.out_of_order += 1
            self._count_bad(position, velocity)
            return []
        if step in self._pending:  # a resend while the first waits for its references: the newer one is kept
            self._count_bad(*self._pending[step])
        self._pending[step] = (position, velocity)
        return self._drain()

    def _count_bad(self, position: float, velocity: float) -> None:
        """Every state message is checked once: the one answered by the guard as it answers, any other here
        (counted, never answered again nor trained on), so a corrupted resend is counted as it was injected."""
        self._x1[0], self._x2[0] = position, velocity
        self.guarded.count_bad(self._x1, self._x2)

    @property
    def learning_pending(self) -> bool:
        """True when the last answer has not been trained on yet (a PID controller never has any)."""
        return self.controller.learning_pending

    def learn(self) -> None:
        """Train the controller on its last answer: call it after publishing what ``on_state`` or
        ``add_reference`` returned (the next answer trains first if this was not called)."""
        self.guarded.learn()

    @property
    def bad_states(self) -> dict[str, int]:
        """States rejected by the guard, by reason."""
        return {r: int(self.guarded.bad_states[r][0]) for r in REASONS}

    @property
    def nonfinite_torques(self) -> int:
        return int(self.guarded.nonfinite_torques[0])

    def _answer(self, step: int, q: float, qd: float, ahead: int) -> float:
        self._x1[0], self._x2[0] = q, qd
        sample = self._sample
        sample.position_rad[0], sample.velocity_rad_s[0] = self._ref_pos[step], self._ref_vel[step]
        sample.position_ahead_rad[0] = self._ref_pos[ahead]
        return float(self.guarded.answer(self._x1, self._x2, sample)[0])

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

"""Joint controllers behind the state guard: what every caller (node or in-process loop) steps.

A joint whose state fails the StateGuard (non-finite, beyond its limits by
more than a margin, faster than the speed limit) is answered with its last
torque ("hold") or zero, and its controller row is not trained on it; so is
a non-finite torque from the controller. Each case is counted per joint. No
non-finite torque is ever returned. One row per joint, arrays of shape (n,).

``step`` answers and trains; a node calls ``answer``, publishes the torque,
then ``learn``, so that the training of a learning controller (DNBS) is not
between the state and its answer. The results are the same either way.
"""
from __future__ import annotations

import math

import numpy as np

from ..core.controller_bank import ControllerBank
from ..core.reference import ReferenceSample
from ..core.state_guard import OK, REASONS, StateGuard


class GuardedControllers:
    """``controllers`` (a ControllerBank: DNBS, PID or computed torque) behind ``guard``."""

    def __init__(self, controllers: ControllerBank, guard: StateGuard | None, on_bad_state: str = "hold"):
        if on_bad_state not in ("hold", "zero"):
            raise ValueError(f"on_bad_state must be 'hold' or 'zero', got {on_bad_state!r}")
        self.controllers = controllers
        self.guard = guard
        self.hold = on_bad_state == "hold"
        n = controllers.n_joints
        self.bad_states = {r: np.zeros(n, dtype=np.int64) for r in REASONS}
        self.nonfinite_torques = np.zeros(n, dtype=np.int64)
        self.last_torque = np.zeros(n)
        self._answer = controllers.answer
        # learn(): train on the last answer (a no-op for a controller that does not learn, or when done)
        self.learn = controllers.learn

    def step(self, x1: np.ndarray, x2: np.ndarray, ref: ReferenceSample) -> np.ndarray:
        """Torques (n,) [N m], always finite, for states x1 (n,) [rad], x2 (n,) [rad/s]; trains the controllers."""
        u = self.answer(x1, x2, ref)
        self.learn()
        return u

    def count_bad(self, x1: np.ndarray, x2: np.ndarray) -> None:
        """Count a state that is received but not answered (a resend of an answered step, a stale or superseded
        one) by reason if it fails the guard, so the counters match every bad state message (docs/faults.md)."""
        if self.guard is None or self.guard.all_plausible(x1, x2):
            return
        code = self.guard.check(x1, x2)
        for i, reason in enumerate(REASONS):
            self.bad_states[reason] += code == i

    def answer(self, x1: np.ndarray, x2: np.ndarray, ref: ReferenceSample) -> np.ndarray:
        """The torques (n,) [N m] of ``step`` for x1 (n,) [rad], x2 (n,) [rad/s], leaving a learning controller's
        training pending until ``learn``."""
        if self.guard is None or self.guard.all_plausible(x1, x2):
            u = self._answer(x1, x2, ref)
            ok = None
        else:
            code = self.guard.check(x1, x2)
            ok = code == OK
            for i, reason in enumerate(REASONS):
                self.bad_states[reason] += code == i
            # the untrusted rows get finite stand-in inputs and no training; their torque is replaced below
            u = self._answer(np.where(ok, x1, ref.position_rad), np.where(ok, x2, 0.0), ref,
                             active=ok.astype(float))
        # one sum instead of isfinite + all: a NaN or an inf torque makes it non-finite (an overflow of the
        # sum, torques near 1e308, only sends finite torques through the element-wise check below)
        if ok is None and math.isfinite(np.add.reduce(u)):
            self.last_torque = u
            return u
        finite = np.isfinite(u)
        if not finite.all():
            self.nonfinite_torques += ~finite if ok is None else ~finite & ok
            ok = finite if ok is None else ok & finite
        if ok is not None:
            u = np.where(ok, u, self.last_torque if self.hold else 0.0)
        self.last_torque = u
        return u


    def counters(self, row: int = 0) -> dict[str, int]:
        """Row ``row``'s guard events (``bad_states_<reason>``, ``nonfinite_torques``) and its controller's
        (DNBS: ``ekf_resets_alpha``, ``ekf_resets_torque``): the names a joint controller node reports."""
        c = {f"bad_states_{r}": int(v[row]) for r, v in self.bad_states.items()}
        c["nonfinite_torques"] = int(self.nonfinite_torques[row])
        c.update(self.controllers.counters(row))
        return c

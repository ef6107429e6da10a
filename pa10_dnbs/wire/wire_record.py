"""A run rebuilt from messages: /joint_states by step, and the reference batches.

Used by the live wire monitor and by the bag analysis, so both turn the same
messages into the same RunData. Step k is the stamp k T. From /joint_states
stamped k: x(k) (positions [rad], velocities [rad/s]) and, as effort, the
torque [N m] applied over step k-1. From the reference batches: x_d(k) [rad].
numpy only.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from ..atomic_file import atomic_path

from ..run_data import RunData


class WireRecord:
    """Arrays of shape (n_steps + 1, n_joints), filled as messages arrive; duplicates are ignored."""

    def __init__(self, n_steps: int, dt_s: float, n_joints: int):
        self.n = n_steps
        self.dt_s = dt_s
        self.pos, self.vel, self.eff, self.ref = (np.full((n_steps + 1, n_joints), np.nan) for _ in range(4))
        self.got_state = np.zeros(n_steps + 1, dtype=bool)   # NaN in the data is data, not a gap
        self.got_ref = np.zeros((n_steps + 1, n_joints), dtype=bool)
        self.states_received = 0
        self.malformed = 0
        self._worst = np.nan     # worst |x_d - x| over the steps checked so far [rad]
        self._worst_from = 0     # first step not checked yet

    def add_joint_states(self, k: int, position, velocity, effort) -> bool:
        """Store state k; False if k is out of range or already stored."""
        if not 0 <= k <= self.n or self.got_state[k]:
            return False
        self.got_state[k] = True
        self.states_received += 1
        self.pos[k], self.vel[k], self.eff[k] = position, velocity, effort
        return True

    def add_reference(self, joint: int, first_step: int, offsets, positions) -> None:
        """x_d at steps first_step + offsets (offsets: steps from the batch stamp)."""
        for off, x in zip(offsets, positions):
            k = first_step + off
            if 0 <= k < self.n:
                self.ref[k, joint] = x
                self.got_ref[k, joint] = True

    def worst_abs_error(self, upto: int) -> float:
        """max |x_d - x| [rad] over joints and the steps up to ``upto`` that have both, NaN if none has.

        Incremental (for progress lines): steps already checked are not looked at again, so call it once a
        step's state and reference are in.
        """
        upto = min(upto, self.n - 1)
        if upto >= self._worst_from:
            rows = slice(self._worst_from, upto + 1)
            e = np.abs(self.ref[rows] - self.pos[rows])
            e = e[np.isfinite(e)]
            if e.size and not e.max() <= self._worst:
                self._worst = float(e.max())
            self._worst_from = upto + 1
        return self._worst

    @property
    def missing_reference_steps(self) -> int:
        return int((~self.got_ref[: self.n]).any(axis=1).sum())

    @property
    def complete(self) -> bool:
        return self.states_received == self.n + 1 and self.missing_reference_steps == 0

    def missing(self) -> str | None:
        """What is missing, or None when the record is complete."""
        states = int((~self.got_state).sum())
        refs = self.missing_reference_steps
        if states == 0 and refs == 0:
            return None
        return f"{states} of {self.n + 1} joint states and {refs} of {self.n} reference steps missing"

    def save(self, path: Path) -> None:
        """npz at ``path``, written to a temporary name first."""
        with atomic_path(path, ".tmp.npz") as tmp:
            np.savez(tmp, dt_s=self.dt_s, position_rad=self.pos, velocity_rad_s=self.vel, effort_nm=self.eff,
                     reference_rad=self.ref, got_state=self.got_state, got_ref=self.got_ref, malformed=self.malformed)

    @classmethod
    def load(cls, path: Path) -> "WireRecord":
        with np.load(path) as z:
            rec = cls(z["position_rad"].shape[0] - 1, float(z["dt_s"]), z["position_rad"].shape[1])
            rec.pos, rec.vel, rec.eff, rec.ref = z["position_rad"], z["velocity_rad_s"], z["effort_nm"], z["reference_rad"]
            rec.got_state, rec.got_ref = z["got_state"], z["got_ref"]
            rec.states_received = int(rec.got_state.sum())
            rec.malformed = int(z["malformed"])
        return rec

    def run_data(self, controller: str, joint_names, torque_limit_nm, wall_time_s: float) -> RunData:
        """The RunData of steps 0..n-1 (torque over step k is the effort stamped k+1)."""
        n = self.n
        return RunData(controller=controller, dt_s=self.dt_s, joint_names=tuple(joint_names),
                       torque_limit_nm=np.asarray(torque_limit_nm), position_rad=self.pos[:n].copy(),
                       velocity_rad_s=self.vel[:n].copy(), reference_rad=self.ref[:n].copy(),
                       torque_nm=self.eff[1:n + 1].copy(), wall_time_s=wall_time_s)


def load_wire_run(path: Path, controller: str, joint_names, torque_limit_nm,
                  wall_time_s: float) -> tuple[RunData, str | None]:
    """RunData from a saved WireRecord (the wire monitor's file), and what is missing (None when complete)."""
    rec = WireRecord.load(path)
    return rec.run_data(controller, joint_names, torque_limit_nm, wall_time_s), rec.missing()

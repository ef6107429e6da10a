"""The torque a reference asks of each joint: inverse dynamics with gravity along it, read once before a run.

tau(t) = (M(q) + J_r) qdd + h(q, qd) + F(qd) at the reference's q, qd, qdd (the plant's own model: PyBullet's
mass matrix and calculateInverseDynamics on the actuated block, the locked joints held, rotor inertia and
friction as the parameters it is given say). The reference rule (arm/reference_rule.py) keeps its peak within
the limits; its search reads a candidate's peak chunk by chunk (:class:`TorqueSweep`) and stops once the
candidate cannot be chosen.
"""
from __future__ import annotations

import numpy as np

from ..core.reference import Reference
from .pybullet_plant import PyBulletArmPlant

SAMPLE_STEP_S = 0.05  # the reference is sampled every 50 ms
HORIZON_S = 60.0      # at most this much of the run is checked (eq. 27's envelope is full well before)
FIELDS = ("amplitude_rad", "envelope_rate_per_s3", "frequency_rad_s", "centre_rad")
CHUNK_STEPS = 16      # a sweep's chunk: about this many sampled steps, spread over the whole horizon


class TorqueSweep:
    """The largest |tau_j| [N m] of one reference fragment over the sampled steps done so far: ``peak`` ((n,), None
    before the first chunk), ``done`` once every step is in it; ``more()`` adds the next chunk (every
    ``chunks``-th step, so each chunk spans the horizon). The peak of a done sweep has the bits of one pass
    over every step (a maximum does not depend on the order)."""

    def __init__(self, owner: "ReferenceTorque", values: list[np.ndarray]):
        self._owner, self._values = owner, values
        self._arrays = None
        self._next = 0
        self.peak: np.ndarray | None = None

    @property
    def done(self) -> bool:
        return self._next == self._owner.chunks

    def more(self) -> None:
        """Add the next chunk of steps to ``peak`` (nothing when done)."""
        if self.done:
            return
        if self._arrays is None:
            self._arrays = self._owner.along(self._values)
        rows = slice(self._next, None, self._owner.chunks)
        q, qd, qdd = (np.ascontiguousarray(x[rows]) for x in self._arrays)
        part = np.abs(self._owner.plant.torque_along(q, qd, qdd)).max(axis=0)
        self.peak = part if self.peak is None else np.maximum(self.peak, part)
        self._next += 1
        if self.done:
            self._arrays = None

    def finish(self) -> np.ndarray:
        """The peak over every sampled step, (n,) [N m] (a copy)."""
        while not self.done:
            self.more()
        return self.peak.copy()

    def release(self) -> None:
        """Drop the sampled reference (recomputed if more is asked): what a paused sweep keeps is its peak."""
        self._arrays = None


class ReferenceTorque:
    """peak(fragment) -> (n,) the largest |tau_j| [N m] along a ``reference`` fragment (amplitude_rad,
    envelope_rate_per_s3, frequency_rad_s, centre_rad) over ``duration_s`` (at most HORIZON_S), on ``plant``;
    sweep(fragment): the same, chunk by chunk. A fragment asked again (the reference rule's search tries some
    twice: a halved amplitude capped to the same value, its current reference) shares the first one's sweep."""

    def __init__(self, plant: PyBulletArmPlant, duration_s: float, dt_s: float):
        """``plant``: the arm's plant (the settings' plant section, a study scenario's payload, heavier links,
        friction: plant/from_config.py ``opened_plant``), held by the caller."""
        self.plant = plant
        arm = plant.arm
        self._dt = dt_s
        horizon = min(duration_s, HORIZON_S)
        self._steps = np.arange(0, int(round(horizon / dt_s)) + 1, max(1, int(round(SAMPLE_STEP_S / dt_s))))
        self.chunks = max(1, -(-len(self._steps) // CHUNK_STEPS))
        self._lower, self._upper = arm.lower_rad, arm.upper_rad
        self._sweeps: dict[tuple, TorqueSweep] = {}   # the fragment's values (shapes, bytes) -> its sweep

    def along(self, values: list[np.ndarray]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(q, qd, qdd) (k, n) of the reference ``values`` (FIELDS' order) at the sampled steps, q within the
        limits."""
        ref = Reference(*values[:3], dt_s=self._dt, centre_rad=values[3])
        q = np.clip(ref.position(self._steps), self._lower, self._upper)
        return q, ref.velocity(self._steps), ref.acceleration(self._steps)

    def sweep(self, fragment: dict) -> TorqueSweep:
        """The :class:`TorqueSweep` of ``fragment`` (the one of its values, shared)."""
        values = [np.asarray(fragment[k], dtype=float) for k in FIELDS]
        key = tuple((v.shape, v.tobytes()) for v in values)
        if key not in self._sweeps:
            self._sweeps[key] = TorqueSweep(self, values)
        return self._sweeps[key]

    def peak(self, fragment: dict) -> np.ndarray:
        """(n,) the largest |tau_j| [N m] along ``fragment`` over every sampled step."""
        return self.sweep(fragment).finish()

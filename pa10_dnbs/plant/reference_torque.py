"""The torque a reference asks of each joint: inverse dynamics with gravity along it, read once before a run.

tau(t) = (M(q) + J_r) qdd + h(q, qd) + F(qd) at the reference's q, qd, qdd (the plant's own model: PyBullet's
mass matrix and calculateInverseDynamics on the actuated block, the locked joints held, rotor inertia and
friction as the parameters it is given say). The reference rule (arm/reference_rule.py) keeps its peak within the limits.
"""
from __future__ import annotations

import numpy as np

from ..core.reference import Reference
from .pybullet_plant import PyBulletArmPlant

SAMPLE_STEP_S = 0.05  # the reference is sampled every 50 ms
HORIZON_S = 60.0      # at most this much of the run is checked (eq. 27's envelope is full well before)
FIELDS = ("amplitude_rad", "envelope_rate_per_s3", "frequency_rad_s", "centre_rad")


class ReferenceTorque:
    """peak(fragment) -> (n,) the largest |tau_j| [N m] along a ``reference`` fragment (amplitude_rad,
    envelope_rate_per_s3, frequency_rad_s, centre_rad) over ``duration_s`` (at most HORIZON_S), on ``plant``."""

    def __init__(self, plant: PyBulletArmPlant, duration_s: float, dt_s: float):
        """``plant``: the arm's plant (the settings' plant section, a study scenario's payload, heavier links,
        friction: plant/from_config.py ``opened_plant``), held by the caller."""
        self._plant = plant
        arm = plant.arm
        self._dt = dt_s
        horizon = min(duration_s, HORIZON_S)
        self._steps = np.arange(0, int(round(horizon / dt_s)) + 1, max(1, int(round(SAMPLE_STEP_S / dt_s))))
        self._lower, self._upper = arm.lower_rad, arm.upper_rad
        self._peaks: dict[tuple, np.ndarray] = {}   # the fragment's values (shapes, bytes) -> its peak

    def peak(self, fragment: dict) -> np.ndarray:
        """(n,) the largest |tau_j| [N m] along ``fragment``; a fragment asked again (the reference rule's search
        tries some twice: a halved amplitude capped to the same value, its current reference) is answered from
        the first answer (the same bits: the plant's dynamics are a function of q, qd, qdd)."""
        values = [np.asarray(fragment[k], dtype=float) for k in FIELDS]
        key = tuple((v.shape, v.tobytes()) for v in values)
        if key not in self._peaks:
            ref = Reference(*values[:3], dt_s=self._dt, centre_rad=values[3])
            q = np.clip(ref.position(self._steps), self._lower, self._upper)
            qd, qdd = ref.velocity(self._steps), ref.acceleration(self._steps)
            self._peaks[key] = np.abs(self._plant.torque_along(q, qd, qdd)).max(axis=0)
        return self._peaks[key].copy()

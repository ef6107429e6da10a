"""Computed-torque control: the centralized upper bound the decentralized controllers are compared to.

u = M(q) v + h(q, qd) + F,  v = x_d_ddot + Kd (x_d_dot - qd) + Kp (x_d - q), clipped to Table 2,
with the plant's own model: M includes the rotor inertias, h the Coriolis, centrifugal and gravity
torques, F the friction (viscous and Coulomb), payload and mass changes included. F is the friction the
plant's step meets (viscous at qd, Coulomb at the speed the step is asked to reach, as the plant applies
its implicit Coulomb term): with Coulomb at qd the controller chatters at every reversal (RMS 4.3x worse). It needs every
joint's state and the exact model, so it only runs in-process (it has no node).
"""
from __future__ import annotations

import numpy as np

from ..core.reference import ReferenceSample


class ComputedTorqueController:
    """All seven joints at once; ``kp_per_s2`` [1/s^2] and ``kd_per_s`` [1/s] shape the error dynamics
    e_ddot + Kd e_dot + Kp e = 0 (per joint, numbers or arrays (7,))."""

    def __init__(self, plant, kp_per_s2, kd_per_s, torque_limit_nm):
        self.plant = plant
        self.kp = np.asarray(kp_per_s2, dtype=float)
        self.kd = np.asarray(kd_per_s, dtype=float)
        self.limit = np.asarray(torque_limit_nm, dtype=float)
        self.n_joints = self.limit.size

    def step(self, x1: np.ndarray, x2: np.ndarray, ref: ReferenceSample, active: np.ndarray | None = None) -> np.ndarray:
        """Torques (7,) [N m]; needs ``ref.acceleration_rad_s2``. (No learning: ``active`` changes nothing.)"""
        if ref.acceleration_rad_s2 is None:
            raise ValueError("computed torque needs the reference acceleration")
        p = self.plant
        v = ref.acceleration_rad_s2 + self.kd * (ref.velocity_rad_s - x2) + self.kp * (ref.position_rad - x1)
        u = p.mass_matrix(x1) @ v + p.bias_torque(x1, x2) + p.step_friction_torque(x2, v)
        return np.minimum(np.maximum(u, -self.limit), self.limit)

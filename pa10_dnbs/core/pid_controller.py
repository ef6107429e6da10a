"""Decentralized PID baseline with velocity feed-forward, one per joint, computed as rows of arrays.

u = Kp e + Ki int(e) dt + Kd (xd_dot - x2),  e = x_d - x1, saturated at the
joint's torque limit. Row i uses only joint i's measurements and reference.

Anti-windup by conditional integration (as control_toolbox's PID clamps its integral, and as the DNBS
controller's own anti-windup does): a row whose torque is saturated does not integrate an error that pushes
it further into the limit. Unsaturated rows compute exactly what the plain PID does.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .controller_bank import FixedGainBank
from .reference import ReferenceSample


@dataclass(frozen=True)
class PIDParams:
    """Per joint (arrays (n,)): kp [N m/rad], ki [N m/(rad s)], kd [N m s/rad], torque_limit_nm [N m]; dt_s [s];
    anti_windup: conditional integration on (module docstring)."""

    kp: np.ndarray
    ki: np.ndarray
    kd: np.ndarray
    torque_limit_nm: np.ndarray
    dt_s: float
    anti_windup: bool = True

    def select(self, rows) -> "PIDParams":
        rows = np.asarray(rows)
        return PIDParams(self.kp[rows], self.ki[rows], self.kd[rows], self.torque_limit_nm[rows], self.dt_s,
                         self.anti_windup)


class PIDControllers(FixedGainBank):
    """Fixed-gain PIDs of n joints (a :class:`~pa10_dnbs.core.controller_bank.ControllerBank` that does not
    learn: its integrator is state, not learning, and is not checkpointed)."""

    def __init__(self, params: PIDParams):
        self.params = params
        self.integral = np.zeros(np.size(params.kp))  # int(e) dt [rad s]

    @property
    def n_joints(self) -> int:
        return self.integral.size

    def answer(self, x1: np.ndarray, x2: np.ndarray, ref: ReferenceSample, active: np.ndarray | None = None) -> np.ndarray:
        """Torques (n,) [N m] for angles x1 (n,) [rad] and velocities x2 (n,) [rad/s]; a row whose ``active``
        is 0.0 does not integrate (its state was not trusted)."""
        p = self.params
        e = ref.position_rad - x1
        integral = self.integral + (e * p.dt_s if active is None else e * (p.dt_s * active))
        damping = p.kd * (ref.velocity_rad_s - x2)
        u = p.kp * e + p.ki * integral + damping
        if p.anti_windup:
            winding = ((u > p.torque_limit_nm) & (e > 0.0)) | ((u < -p.torque_limit_nm) & (e < 0.0))
            if winding.any():  # those rows keep their integral: the torque is already at the limit
                integral = np.where(winding, self.integral, integral)
                u = p.kp * e + p.ki * integral + damping
        self.integral = integral
        return np.minimum(np.maximum(u, -p.torque_limit_nm), p.torque_limit_nm)

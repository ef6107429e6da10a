"""Decentralized PID baseline with velocity feed-forward (paper_notes.md).

u = Kp e + Ki int(e) dt + Kd (xd_dot - x2),  e = x_d - x1, saturated at the
Table 2 limit. Uses only the joint's own measurements and reference.
"""
from __future__ import annotations

from dataclasses import dataclass

from .reference import ReferenceSample


@dataclass(frozen=True)
class PIDParams:
    """kp [N m/rad], ki [N m/(rad s)], kd [N m s/rad], dt_s [s], torque_limit_nm [N m]."""

    kp: float
    ki: float
    kd: float
    dt_s: float
    torque_limit_nm: float


class PIDJointController:
    """Fixed-gain PID for one joint."""

    def __init__(self, params: PIDParams):
        self.params = params
        self.integral = 0.0  # int(e) dt [rad s]

    def step(self, x1: float, x2: float, ref: ReferenceSample) -> float:
        """Torque [N m] for state (x1 [rad], x2 [rad/s]) at the reference sample."""
        p = self.params
        e = ref.position_rad - x1
        self.integral += e * p.dt_s
        u = p.kp * e + p.ki * self.integral + p.kd * (ref.velocity_rad_s - x2)
        return min(max(u, -p.torque_limit_nm), p.torque_limit_nm)

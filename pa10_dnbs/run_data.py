"""Time series of one closed-loop run, and its npz form.

Arrays of shape (n_steps, n_joints), sampled at t_k = k dt: position_rad and
velocity_rad_s are the plant state x(k) the controllers saw; reference_rad is
x_d(k); torque_nm is the torque applied during [t_k, t_k+1) (after the
torque-limit saturation).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np


@dataclass
class RunData:
    controller: str
    dt_s: float
    joint_names: tuple[str, ...]
    torque_limit_nm: np.ndarray
    position_rad: np.ndarray
    velocity_rad_s: np.ndarray
    reference_rad: np.ndarray
    torque_nm: np.ndarray
    wall_time_s: float = float("nan")
    extra: dict = field(default_factory=dict)

    @property
    def n_steps(self) -> int:
        return self.position_rad.shape[0]

    @property
    def time_s(self) -> np.ndarray:
        return np.arange(self.n_steps) * self.dt_s

    @property
    def error_rad(self) -> np.ndarray:
        """x_d(k) - x1(k)."""
        return self.reference_rad - self.position_rad

    def save_npz(self, path: Path) -> None:
        np.savez_compressed(
            path, controller=self.controller, dt_s=self.dt_s, joint_names=np.array(self.joint_names),
            torque_limit_nm=self.torque_limit_nm, time_s=self.time_s, position_rad=self.position_rad,
            velocity_rad_s=self.velocity_rad_s, reference_rad=self.reference_rad, torque_nm=self.torque_nm,
        )

    @classmethod
    def load_npz(cls, path: Path) -> "RunData":
        with np.load(path) as z:
            return cls(controller=str(z["controller"]), dt_s=float(z["dt_s"]),
                       joint_names=tuple(str(n) for n in z["joint_names"]),
                       torque_limit_nm=z["torque_limit_nm"], position_rad=z["position_rad"],
                       velocity_rad_s=z["velocity_rad_s"], reference_rad=z["reference_rad"],
                       torque_nm=z["torque_nm"])

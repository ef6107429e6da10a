"""What every arm plant (PyBullet, MuJoCo) reports the same way: the arm and parameters it was built with, its
joints and limits, its step, its counters, and the nominal friction law. A plant sets ``_arm``, ``_params``,
``_n``, ``_lower``, ``_upper`` ((n,) rad), ``_dt`` [s], ``_applied`` ((n,) N m), ``_step_count``,
``_limit_hits`` ((n,)), ``_fv`` [N m s/rad], ``_fc`` [N m] and ``_inv_eps`` [s/rad]."""
from __future__ import annotations

import numpy as np

from ..arm import Arm
from .plant_params import PlantParams, as_joint_vector


class ArmPlantBase:
    """The read-only facts and counters of an arm plant; the engine's class adds stepping and dynamics."""

    @property
    def params(self) -> PlantParams:
        """Parameters the plant was built with."""
        return self._params

    @property
    def arm(self) -> Arm:
        """The arm the plant was built for."""
        return self._arm

    @property
    def n_joints(self) -> int:
        """Number of actuated joints n."""
        return self._n

    @property
    def joint_names(self) -> tuple[str, ...]:
        """Actuated joint names in chain order."""
        return self._arm.joint_names

    @property
    def lower_limit_rad(self) -> np.ndarray:
        """(n,) lower joint limits from the URDF, rad."""
        return self._lower.copy()

    @property
    def upper_limit_rad(self) -> np.ndarray:
        """(n,) upper joint limits from the URDF, rad."""
        return self._upper.copy()

    @property
    def dt_s(self) -> float:
        """Integration step, s."""
        return self._dt

    @property
    def applied_torque_nm(self) -> np.ndarray:
        """(n,) torque applied in the last step (after saturation), N m."""
        return self._applied.copy()

    @property
    def step_count(self) -> int:
        """Steps taken since the last reset."""
        return self._step_count

    @property
    def limit_hits(self) -> np.ndarray:
        """(n,) number of steps in which each joint was clamped to a limit."""
        return self._limit_hits.copy()

    def friction_torque(self, qd) -> np.ndarray:
        """(n,) the nominal friction law Fv qd + Fc tanh(qd / eps), N m, at the speeds qd (n,) rad/s."""
        qd = as_joint_vector("qd", qd, self._n)
        return self._fv * qd + self._fc * np.tanh(qd * self._inv_eps)

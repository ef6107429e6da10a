"""The arm's plant on a second, independent engine: torque in, joint state out, dynamics and stepping by MuJoCo.

The same arm (``pa10_dnbs/arm``), parameters (:class:`PlantParams`) and Python interface as
:class:`~pa10_dnbs.plant.pybullet_plant.PyBulletArmPlant` where the in-process loop, computed torque and the
robot node need it (state, step, reset, mass matrix, bias torques, counters), so either engine runs the same
controllers. The model: ``mujoco_model.py``. Per step::

    tau <- clip(tau, -limit, limit);  qfrc_applied <- tau;  mj_step   (MuJoCo's semi-implicit Euler, dt)

then a joint past a limit is clamped there, its outward velocity zeroed and counted, as in the PyBullet plant.
What differs from the PyBullet plant (both stated in docs/engines.md): viscous friction is implicit in MuJoCo's
Euler step (``(M + J + dt D) qdd = ...``) where the PyBullet plant's is explicit, and Coulomb friction is
MuJoCo's ``frictionloss`` constraint instead of the implicit ``Fc tanh(qd / eps)``.
"""
from __future__ import annotations

import math

import numpy as np

from ..arm import Arm
from .mujoco_model import build_model
from .arm_plant_base import ArmPlantBase
from .plant_params import PlantParams, as_joint_vector, checked_for_arm


class MuJoCoArmPlant(ArmPlantBase):
    """A torque-driven serial arm of n actuated revolute joints simulated by MuJoCo.

    Parameters
    ----------
    arm : Arm
        The arm (pa10_dnbs.arm): URDF, actuated and locked joints, flange, facts.
    params : PlantParams
        Step, gravity, rotor inertia (armature), friction (damping, frictionloss), torque limits, payload and
        link mass scale (None fields: the arm's facts). ``coulomb_smoothing_rad_s`` is not used (MuJoCo's
        frictionloss is a constraint, not a smooth law).
    """

    engine = "mujoco"

    def __init__(self, arm: Arm, params: PlantParams) -> None:
        import mujoco

        if not isinstance(params, PlantParams):
            raise TypeError(f"params: expected PlantParams, got {type(params).__name__}")
        params = checked_for_arm(params, arm)
        self._mj = mujoco
        self._arm = arm
        self._params = params
        self._n = n = arm.n_joints
        self.model = build_model(arm, params)
        if self.model.nv != n:
            raise ValueError(f"{arm.urdf}: MuJoCo's model has {self.model.nv} degrees of freedom, the arm {n}")
        self._qadr = np.array([self.model.joint(name).qposadr[0] for name in arm.joint_names])
        self._vadr = np.array([self.model.joint(name).dofadr[0] for name in arm.joint_names])
        self.data = mujoco.MjData(self.model)
        self._scratch = mujoco.MjData(self.model)  # model queries (M, h) without touching the state
        self._m_full = np.zeros((n, n))
        self._lower = np.array(arm.lower_rad, dtype=float)
        self._upper = np.array(arm.upper_rad, dtype=float)
        self._tau_max = np.array(params.torque_limit_nm, dtype=float)
        self._fv = np.array(params.viscous_nms_per_rad, dtype=float)
        self._fc = np.array(params.coulomb_nm, dtype=float)
        self._inv_eps = 1.0 / params.coulomb_smoothing_rad_s
        self._dt = params.dt_s
        self._applied = np.zeros(n)
        self._limit_hits = np.zeros(n, dtype=np.int64)
        self._step_count = 0
        self.reset(np.clip(np.zeros(n), self._lower, self._upper), np.zeros(n))

    # ------------------------------------------------------------------ info (the rest: ArmPlantBase)
    @property
    def time_s(self) -> float:
        """MuJoCo's simulated time since the last reset, s."""
        return float(self.data.time)

    # ------------------------------------------------------------- stepping
    def reset(self, q0, qd0) -> None:
        """Set the state (q0 rad, qd0 rad/s, each (n,)) and clear the counters and MuJoCo's time."""
        q0 = as_joint_vector("q0", q0, self._n)
        qd0 = as_joint_vector("qd0", qd0, self._n)
        if np.any(q0 < self._lower) or np.any(q0 > self._upper):
            raise ValueError(f"q0: outside the joint limits [{self._lower}, {self._upper}]")
        self._mj.mj_resetData(self.model, self.data)
        self.data.qpos[self._qadr] = q0
        self.data.qvel[self._vadr] = qd0
        self._applied[:] = 0.0
        self._limit_hits[:] = 0
        self._step_count = 0

    def step(self, torque_nm) -> None:
        """Saturate ``torque_nm`` (n,) N m to the limits and advance one dt. Infinite entries saturate to the
        limit; NaN raises ValueError."""
        tau = np.asarray(torque_nm, dtype=float)
        if tau.shape != (self._n,):
            raise ValueError(f"torque_nm: expected shape ({self._n},), got {tau.shape}")
        applied = np.minimum(np.maximum(tau, -self._tau_max), self._tau_max)
        if not math.isfinite(applied.sum()) and np.isnan(applied).any():  # a finite sum: no NaN (the fast test)
            raise ValueError("torque_nm: values must not be NaN")
        self._applied = applied
        d = self.data
        d.qfrc_applied[self._vadr] = applied
        self._mj.mj_step(self.model, d)
        q = d.qpos[self._qadr]
        below, above = q < self._lower, q > self._upper
        if below.any() or above.any():
            qd = d.qvel[self._vadr]
            q = np.where(below, self._lower, np.where(above, self._upper, q))
            qd[(below & (qd < 0.0)) | (above & (qd > 0.0))] = 0.0
            d.qpos[self._qadr] = q
            d.qvel[self._vadr] = qd
            self._limit_hits += below
            self._limit_hits += above
        self._step_count += 1

    @property
    def state(self) -> tuple[np.ndarray, np.ndarray]:
        """(q rad, qd rad/s), each a (n,) copy."""
        return self.data.qpos[self._qadr].copy(), self.data.qvel[self._vadr].copy()

    # ------------------------------------------------------------- dynamics
    def _at(self, q: np.ndarray, qd: np.ndarray):
        """The scratch data at (q, qd): positions and velocities computed (M, bias), nothing integrated."""
        s = self._scratch
        s.qpos[self._qadr] = q
        s.qvel[self._vadr] = qd
        self._mj.mj_fwdPosition(self.model, s)
        self._mj.mj_fwdVelocity(self.model, s)
        return s

    def mass_matrix(self, q) -> np.ndarray:
        """(n, n) joint-space inertia M(q) + diag(armature), kg m^2 (MuJoCo's, the locked joints welded)."""
        q = as_joint_vector("q", q, self._n)
        s = self._at(q, np.zeros(self._n))
        self._mj.mj_fullM(self.model, s, self._m_full)
        return self._m_full[np.ix_(self._vadr, self._vadr)].copy()

    def bias_torque(self, q, qd) -> np.ndarray:
        """(n,) Coriolis + centrifugal + gravity torque, N m (MuJoCo's ``qfrc_bias``)."""
        q = as_joint_vector("q", q, self._n)
        qd = as_joint_vector("qd", qd, self._n)
        return self._at(q, qd).qfrc_bias[self._vadr].copy()

    def step_friction_torque(self, qd, qdd) -> np.ndarray:
        """(n,) the friction a step from speed qd with acceleration qdd meets, N m: viscous at the end-of-step
        speed qd + dt qdd (MuJoCo's implicit damping), Coulomb as Fc tanh of that speed over eps (the
        frictionloss constraint's nominal law)."""
        qd = as_joint_vector("qd", qd, self._n)
        qdd = as_joint_vector("qdd", qdd, self._n)
        v = qd + self._dt * qdd
        return self._fv * v + self._fc * np.tanh(v * self._inv_eps)

    def forward_acceleration(self, q, qd, tau) -> np.ndarray:
        """(n,) qdd = (M + J)^-1 (tau - bias - friction), rad/s^2 (friction: :meth:`friction_torque`)."""
        q = as_joint_vector("q", q, self._n)
        qd = as_joint_vector("qd", qd, self._n)
        tau = as_joint_vector("tau", tau, self._n)
        rhs = tau - self.bias_torque(q, qd) - self.friction_torque(qd)
        return np.linalg.solve(self.mass_matrix(q), rhs)

    def close(self) -> None:
        """Nothing to release (MuJoCo's model and data are freed with the object); for symmetry with a client."""

"""PA10-7C(E) plant: torque in, joint state out, dynamics from PyBullet.

PyBullet supplies the rigid-body terms only (``calculateMassMatrix`` and
``calculateInverseDynamics``). The plant adds what URDF cannot carry: the
reflected rotor inertia on the diagonal of the mass matrix, joint friction,
torque saturation and joint-limit clamping, and integrates with
semi-implicit (symplectic) Euler at a fixed step. ``stepSimulation`` is never
called, so PyBullet's own joint state is only a display copy (see
:meth:`PyBulletPA10Plant.sync_visual`).
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass

import numpy as np
import pybullet

N_JOINTS = 7

#: Reflected (joint-side) rotor inertia, kg m^2, source D (motor inertia x 50^2).
ROTOR_INERTIA_KGM2 = (0.75, 0.75, 0.2125, 0.2125, 0.00575, 0.00575, 0.00575)
#: Default viscous friction, N m s/rad: source E's simulation values (not identified).
VISCOUS_NMS_PER_RAD = (10.0, 10.0, 5.0, 5.0, 2.0, 2.0, 2.0)
#: Default Coulomb friction, N m: none identified, so zero.
COULOMB_NM = (0.0,) * N_JOINTS
#: Maximum joint torques, N m, paper Table 2.
TORQUE_LIMIT_NM = (232.0, 232.0, 100.0, 100.0, 14.5, 14.5, 14.5)

_VECTOR_FIELDS = (
    # name, lower bound, bound is strict
    ("rotor_inertia_kgm2", 0.0, False),
    ("viscous_nms_per_rad", 0.0, False),
    ("coulomb_nm", 0.0, False),
    ("torque_limit_nm", 0.0, True),
)


@dataclass(frozen=True)
class PlantParams:
    """Plant parameters (SI units); validated on construction.

    Attributes
    ----------
    dt_s : float
        Integration step, s (> 0).
    gravity_mps2 : float
        Gravity magnitude along -z, m/s^2 (>= 0; 0 disables gravity).
    rotor_inertia_kgm2 : tuple of 7 float
        Reflected rotor inertia added to diag(M), kg m^2 (>= 0).
    viscous_nms_per_rad : tuple of 7 float
        Viscous friction Fv, N m s/rad (>= 0).
    coulomb_nm : tuple of 7 float
        Coulomb friction Fc, N m (>= 0).
    coulomb_smoothing_rad_s : float
        eps in Fc tanh(qd / eps), rad/s (> 0).
    torque_limit_nm : tuple of 7 float
        Symmetric torque saturation, N m (> 0).
    payload_kg : float
        Point mass at the tool flange, kg (>= 0; the PA10's rated payload is 10 kg).
    link_mass_scale : float
        Factor on every link's mass and inertia tensor (> 0; 1 is the URDF as written): a model error
        the controllers were not tuned for. The rotor inertias are not scaled.
    """

    dt_s: float = 1e-3
    gravity_mps2: float = 9.81
    rotor_inertia_kgm2: tuple[float, ...] = ROTOR_INERTIA_KGM2
    viscous_nms_per_rad: tuple[float, ...] = VISCOUS_NMS_PER_RAD
    coulomb_nm: tuple[float, ...] = COULOMB_NM
    coulomb_smoothing_rad_s: float = 1e-2
    torque_limit_nm: tuple[float, ...] = TORQUE_LIMIT_NM
    payload_kg: float = 0.0
    link_mass_scale: float = 1.0

    def __post_init__(self) -> None:
        _check_scalar("dt_s", self.dt_s, strict=True)
        _check_scalar("payload_kg", self.payload_kg, strict=False)
        _check_scalar("link_mass_scale", self.link_mass_scale, strict=True)
        _check_scalar("gravity_mps2", self.gravity_mps2, strict=False)
        _check_scalar("coulomb_smoothing_rad_s", self.coulomb_smoothing_rad_s, strict=True)
        for name, _, strict in _VECTOR_FIELDS:
            value = getattr(self, name)
            try:
                arr = np.asarray(value, dtype=float)
            except (TypeError, ValueError) as exc:
                raise ValueError(f"{name}: expected {N_JOINTS} numbers, got {value!r}") from exc
            if arr.shape != (N_JOINTS,):
                raise ValueError(f"{name}: expected {N_JOINTS} values, got shape {arr.shape}")
            if not np.all(np.isfinite(arr)):
                raise ValueError(f"{name}: values must be finite, got {value!r}")
            if np.any(arr <= 0.0) if strict else np.any(arr < 0.0):
                bound = "> 0" if strict else ">= 0"
                raise ValueError(f"{name}: values must be {bound}, got {value!r}")
            object.__setattr__(self, name, tuple(float(v) for v in arr))


def _check_scalar(name: str, value: float, strict: bool) -> None:
    try:
        v = float(value)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name}: expected a number, got {value!r}") from exc
    if not math.isfinite(v):
        raise ValueError(f"{name}: must be finite, got {value!r}")
    if (v <= 0.0) if strict else (v < 0.0):
        raise ValueError(f"{name}: must be {'> 0' if strict else '>= 0'}, got {value!r}")


def _as_joint_vector(name: str, value) -> np.ndarray:
    arr = np.asarray(value, dtype=float)
    if arr.shape != (N_JOINTS,):
        raise ValueError(f"{name}: expected shape ({N_JOINTS},), got {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name}: values must be finite")
    return arr


def _implicit_coulomb_speed(v_free: np.ndarray, k: np.ndarray, inv_eps: float) -> np.ndarray:
    """Per joint, the root v of v - v_free + k tanh(v inv_eps) = 0 (k >= 0): monotone in v, bracketed in
    [v_free - k, v_free + k]; Newton steps, bisection where one would leave the bracket."""
    lo, hi = v_free - k, v_free + k
    v = np.clip(v_free - k * np.tanh(v_free * inv_eps), lo, hi)
    for _ in range(60):
        th = np.tanh(v * inv_eps)
        g = v - v_free + k * th
        if np.max(np.abs(g)) <= 1e-13 * (1.0 + np.max(np.abs(v_free))):
            break
        hi = np.where(g > 0.0, v, hi)
        lo = np.where(g < 0.0, v, lo)
        step = v - g / (1.0 + k * inv_eps * (1.0 - th * th))
        v = np.where((step > lo) & (step < hi), step, 0.5 * (lo + hi))
    return v


class PyBulletPA10Plant:
    """Seven-joint torque-driven arm with rotor inertia, friction and limits.

    Parameters
    ----------
    client : pybullet_utils.bullet_client.BulletClient
        A connected client (DIRECT for simulation), owned by the caller.
    urdf_path : str or os.PathLike
        Arm description with exactly 7 revolute joints and a fixed base.
    params : PlantParams
        Step, gravity, rotor inertia, friction and torque limits.

    Notes
    -----
    Per step, with tau the saturated torque and J = diag(rotor inertia)::

        qdd = (M(q) + J)^-1 (tau - h(q, qd) - Fv qd - Fc tanh(qd+ / eps))
        qd <- qd + dt qdd;  q <- q + dt qd          (semi-implicit Euler)

    The Coulomb term is implicit: qd+ is the joint's speed at the end of the
    step, from v = v_free - dt Fc (M + J)^-1_jj tanh(v / eps) per joint, where
    v_free is the speed without it (so friction never reverses a joint within
    a step); the torques it gives act through the full (M + J)^-1. Without
    Coulomb friction the step is explicit in qd.

    where M and h (Coriolis, centrifugal and gravity) come from PyBullet.
    PyBullet's gravity belongs to the client, so the plant sets it to its own
    value before every inverse-dynamics call (plants with different gravity
    may share a client). ``stepSimulation`` is never called.
    A joint that leaves [lower, upper] is clamped to the limit, its velocity
    component pointing outward is set to zero and its hit counter goes up by
    one (one count per step spent clamped).
    """

    def __init__(self, client, urdf_path, params: PlantParams) -> None:
        if not isinstance(params, PlantParams):
            raise TypeError(f"params: expected PlantParams, got {type(params).__name__}")
        urdf_path = os.fspath(urdf_path)
        if not os.path.isfile(urdf_path):
            raise FileNotFoundError(f"URDF file not found: {urdf_path}")
        self._client = client
        self._params = params
        self._body = client.loadURDF(
            urdf_path,
            useFixedBase=True,
            flags=pybullet.URDF_USE_INERTIA_FROM_FILE,
        )
        joint_indices, names, lower, upper = [], [], [], []
        for j in range(client.getNumJoints(self._body)):
            info = client.getJointInfo(self._body, j)
            if info[2] == pybullet.JOINT_REVOLUTE:
                joint_indices.append(j)
                names.append(info[1].decode("utf-8"))
                lower.append(info[8])
                upper.append(info[9])
            elif info[2] != pybullet.JOINT_FIXED:
                raise ValueError(f"{urdf_path}: joint {info[1]!r} is neither revolute nor fixed")
        if len(joint_indices) != N_JOINTS:
            raise ValueError(f"{urdf_path}: expected {N_JOINTS} revolute joints, found {len(joint_indices)}")
        if joint_indices != list(range(N_JOINTS)):
            raise ValueError(f"{urdf_path}: the revolute joints must come before any fixed joint")
        self._joint_indices = tuple(joint_indices)
        self._joint_names = tuple(names)
        self._lower = np.array(lower, dtype=float)
        self._upper = np.array(upper, dtype=float)
        if not np.all(self._lower < self._upper):
            raise ValueError(f"{urdf_path}: every revolute joint needs lower < upper limits")
        self._n_links = client.getNumJoints(self._body)
        # Mass changes must come before PyBullet's first dynamics call, which caches the multibody tree.
        self._apply_mass_changes(client, params)
        # Link masses for the potential energy (every non-base link, incl. massless frames).
        self._link_masses = np.array(
            [client.getDynamicsInfo(self._body, j)[0] for j in range(self._n_links)], dtype=float
        )
        # No built-in motors: the plant applies torques itself.
        client.setJointMotorControlArray(
            self._body, list(self._joint_indices), pybullet.VELOCITY_CONTROL, forces=[0.0] * N_JOINTS
        )

        # Cached bound calls (BulletClient builds a partial on every attribute access).
        self._calc_mass_matrix = client.calculateMassMatrix
        self._calc_inverse_dynamics = client.calculateInverseDynamics
        self._set_gravity = client.setGravity
        self._gravity_z = -float(params.gravity_mps2)
        self._set_gravity(0.0, 0.0, self._gravity_z)
        self._zero_acc = [0.0] * N_JOINTS

        self._rotor = np.array(params.rotor_inertia_kgm2, dtype=float)
        self._fv = np.array(params.viscous_nms_per_rad, dtype=float)
        self._fc = np.array(params.coulomb_nm, dtype=float)
        self._inv_eps = 1.0 / params.coulomb_smoothing_rad_s
        self._has_coulomb = bool(np.any(self._fc > 0.0))
        self._tau_max = np.array(params.torque_limit_nm, dtype=float)
        self._neg_tau_max = -self._tau_max
        self._dt = params.dt_s
        self._diag = np.diag_indices(N_JOINTS)

        self._q = np.zeros(N_JOINTS)
        self._qd = np.zeros(N_JOINTS)
        self._applied = np.zeros(N_JOINTS)
        self._tau_scratch = np.zeros(N_JOINTS)
        self._limit_hits = np.zeros(N_JOINTS, dtype=np.int64)
        self._below = np.zeros(N_JOINTS, dtype=bool)
        self._above = np.zeros(N_JOINTS, dtype=bool)
        self._step_count = 0
        self.reset(np.zeros(N_JOINTS), np.zeros(N_JOINTS))

    def _apply_mass_changes(self, client, params: PlantParams) -> None:
        """Scale every link's mass and inertia by ``link_mass_scale``; put ``payload_kg`` at the flange."""
        if params.link_mass_scale != 1.0:
            for j in range(self._n_links):
                info = client.getDynamicsInfo(self._body, j)
                if info[0] > 0.0:
                    client.changeDynamics(self._body, j, mass=info[0] * params.link_mass_scale,
                                          localInertiaDiagonal=[x * params.link_mass_scale for x in info[2]])
        if params.payload_kg > 0.0:
            names = [client.getJointInfo(self._body, j)[12].decode("utf-8") for j in range(self._n_links)]
            if "flange" not in names:
                raise ValueError("payload_kg: the URDF has no link named 'flange' to carry the payload")
            # a point mass at the flange frame's origin (a tiny inertia keeps the link's inertia valid)
            client.changeDynamics(self._body, names.index("flange"), mass=params.payload_kg,
                                  localInertiaDiagonal=[1e-9] * 3)

    # ------------------------------------------------------------------ info
    @property
    def params(self) -> PlantParams:
        """Parameters the plant was built with."""
        return self._params

    @property
    def body_id(self) -> int:
        """PyBullet body unique id of the arm."""
        return self._body

    @property
    def joint_names(self) -> tuple[str, ...]:
        """Revolute joint names in URDF order."""
        return self._joint_names

    @property
    def lower_limit_rad(self) -> np.ndarray:
        """(7,) lower joint limits from the URDF, rad."""
        return self._lower.copy()

    @property
    def upper_limit_rad(self) -> np.ndarray:
        """(7,) upper joint limits from the URDF, rad."""
        return self._upper.copy()

    @property
    def dt_s(self) -> float:
        """Integration step, s."""
        return self._dt

    # ------------------------------------------------------------- stepping
    def reset(self, q0, qd0) -> None:
        """Set the state (q0 rad, qd0 rad/s, each (7,)) and clear the counters."""
        q0 = _as_joint_vector("q0", q0)
        qd0 = _as_joint_vector("qd0", qd0)
        if np.any(q0 < self._lower) or np.any(q0 > self._upper):
            raise ValueError(f"q0: outside the joint limits [{self._lower}, {self._upper}]")
        self._q[:] = q0
        self._qd[:] = qd0
        self._applied[:] = 0.0
        self._limit_hits[:] = 0
        self._step_count = 0

    def step(self, torque_nm) -> None:
        """Saturate ``torque_nm`` (7,) N m to the limits and advance one dt.

        Infinite entries saturate to the limit; NaN raises ValueError.
        """
        tau = np.asarray(torque_nm, dtype=float)
        if tau.shape != (N_JOINTS,):
            raise ValueError(f"torque_nm: expected shape ({N_JOINTS},), got {tau.shape}")
        applied = self._tau_scratch
        np.minimum(np.maximum(tau, self._neg_tau_max, out=applied), self._tau_max, out=applied)
        if not math.isfinite(applied @ applied):  # only NaN survives the saturation
            raise ValueError("torque_nm: values must not be NaN")
        self._tau_scratch, self._applied = self._applied, applied
        q, qd = self._q, self._qd
        qd += self._dt * self._qdd(q, qd, applied)
        q += self._dt * qd
        np.less(q, self._lower, out=self._below)
        np.greater(q, self._upper, out=self._above)
        if self._below.any() or self._above.any():
            self._clamp(self._below, self._above)
        self._step_count += 1

    def _clamp(self, below: np.ndarray, above: np.ndarray) -> None:
        q, qd = self._q, self._qd
        np.copyto(q, self._lower, where=below)
        np.copyto(q, self._upper, where=above)
        np.copyto(qd, 0.0, where=(below & (qd < 0.0)) | (above & (qd > 0.0)))
        self._limit_hits += below
        self._limit_hits += above

    @property
    def state(self) -> tuple[np.ndarray, np.ndarray]:
        """(q rad, qd rad/s), each a (7,) copy."""
        return self._q.copy(), self._qd.copy()

    @property
    def applied_torque_nm(self) -> np.ndarray:
        """(7,) torque applied in the last step (after saturation), N m."""
        return self._applied.copy()

    @property
    def step_count(self) -> int:
        """Steps taken since the last reset."""
        return self._step_count

    @property
    def limit_hits(self) -> np.ndarray:
        """(7,) number of steps in which each joint was clamped to a limit."""
        return self._limit_hits.copy()

    # ------------------------------------------------------------- dynamics
    def _qdd(self, q: np.ndarray, qd: np.ndarray, tau: np.ndarray) -> np.ndarray:
        q_list = q.tolist()
        qd_list = qd.tolist()
        m = np.array(self._calc_mass_matrix(self._body, q_list), dtype=float)
        m[self._diag] += self._rotor
        self._set_gravity(0.0, 0.0, self._gravity_z)
        bias = np.array(self._calc_inverse_dynamics(self._body, q_list, qd_list, self._zero_acc), dtype=float)
        rhs = tau - bias - self._fv * qd
        if not self._has_coulomb:
            return np.linalg.solve(m, rhs)
        # Coulomb friction, implicit: an explicit Fc tanh(qd / eps) rings on a light joint (its slope at rest,
        # e.g. 72 N m s/rad on a wrist, gives dt Fc / (eps J) ~ 7) and a linearised one settles into a 2-cycle.
        m_inv = np.linalg.inv(m)
        v_free = qd + self._dt * (m_inv @ rhs)
        f = self._fc * np.tanh(_implicit_coulomb_speed(v_free, self._dt * self._fc * np.diag(m_inv), self._inv_eps)
                               * self._inv_eps)
        return m_inv @ (rhs - f)

    def mass_matrix(self, q) -> np.ndarray:
        """(7, 7) joint-space inertia M(q) + diag(rotor inertia), kg m^2."""
        q = _as_joint_vector("q", q)
        m = np.array(self._calc_mass_matrix(self._body, q.tolist()))
        m[self._diag] += self._rotor
        return m

    def bias_torque(self, q, qd) -> np.ndarray:
        """(7,) Coriolis + centrifugal + gravity torque, N m (inverse dynamics at qdd = 0)."""
        q = _as_joint_vector("q", q)
        qd = _as_joint_vector("qd", qd)
        self._set_gravity(0.0, 0.0, self._gravity_z)
        return np.array(
            self._calc_inverse_dynamics(self._body, q.tolist(), qd.tolist(), self._zero_acc)
        )

    def friction_torque(self, qd) -> np.ndarray:
        """(7,) friction torque Fv qd + Fc tanh(qd / eps), N m."""
        qd = _as_joint_vector("qd", qd)
        return self._fv * qd + self._fc * np.tanh(qd * self._inv_eps)

    def step_friction_torque(self, qd, qdd) -> np.ndarray:
        """(7,) the friction torque a step from speed qd with acceleration qdd meets, N m: viscous at qd (explicit),
        Coulomb at the end-of-step speed qd + dt qdd (implicit), as :meth:`step` applies them."""
        qd = _as_joint_vector("qd", qd)
        qdd = _as_joint_vector("qdd", qdd)
        return self._fv * qd + self._fc * np.tanh((qd + self._dt * qdd) * self._inv_eps)

    def forward_acceleration(self, q, qd, tau) -> np.ndarray:
        """(7,) qdd = (M + J)^-1 (tau - bias - friction), rad/s^2; tau is not saturated."""
        q = _as_joint_vector("q", q)
        qd = _as_joint_vector("qd", qd)
        tau = _as_joint_vector("tau", tau)
        m = self.mass_matrix(q)
        rhs = tau - self.bias_torque(q, qd) - self.friction_torque(qd)
        return np.linalg.solve(m, rhs)

    def energy(self, q, qd) -> tuple[float, float]:
        """(kinetic, potential) energy, J; slow, meant for tests.

        Kinetic energy includes the rotor inertia: 0.5 qd^T (M + J) qd.
        Potential energy is sum(m_i g z_i) over the moving links, z_i the
        world height of link i's centre of mass (base link excluded: constant).
        PyBullet's joint state is set to (q, qd) for the forward kinematics and
        put back to the plant state afterwards.
        """
        q = _as_joint_vector("q", q)
        qd = _as_joint_vector("qd", qd)
        kinetic = 0.5 * float(qd @ self.mass_matrix(q) @ qd)
        self._write_joint_state(q, qd)
        get_link_state = self._client.getLinkState
        heights = np.array(
            [get_link_state(self._body, j, computeForwardKinematics=1)[0][2] for j in range(self._n_links)]
        )
        potential = float(self._params.gravity_mps2 * (self._link_masses @ heights))
        self._write_joint_state(self._q, self._qd)
        return kinetic, potential

    def sync_visual(self) -> None:
        """Copy the plant state into PyBullet's joint state (GUI, forward kinematics)."""
        self._write_joint_state(self._q, self._qd)

    def _write_joint_state(self, q: np.ndarray, qd: np.ndarray) -> None:
        reset_joint_state = self._client.resetJointState
        for j, qj, qdj in zip(self._joint_indices, q.tolist(), qd.tolist()):
            reset_joint_state(self._body, j, qj, qdj)

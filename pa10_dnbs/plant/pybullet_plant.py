"""The arm's plant: torque in, joint state out, dynamics from PyBullet (any serial arm of revolute joints).

PyBullet supplies the rigid-body terms only (``calculateMassMatrix`` and
``calculateInverseDynamics``). The plant adds what URDF cannot carry: the
reflected rotor inertia on the diagonal of the mass matrix, joint friction,
torque saturation and joint-limit clamping, and integrates with
semi-implicit (symplectic) Euler at a fixed step. ``stepSimulation`` is never
called, so PyBullet's own joint state is only a display copy (see
:meth:`PyBulletArmPlant.sync_visual`).
"""

from __future__ import annotations

import math
import os
import re

import numpy as np
import pybullet

from ..arm import Arm, ArmError
from .arm_plant_base import ArmPlantBase
from .plant_params import PlantParams, as_joint_vector, checked_for_arm
from .quiet_stdout import c_output_into


def _pybullet_reason(printed: str) -> str:
    """': <what PyBullet printed>' on one line, its b3Error[file,line] tags left out ('' when it printed nothing)."""
    text = " ".join(re.sub(r"b3(Error|Warning)\[[^\]]*\]:?", " ", printed).split())
    return f": {text[:300]}{'...' if len(text) > 300 else ''}" if text else ""


def _unforeseen_warnings(printed: str, root_link: str) -> str:
    """What PyBullet printed while loading, less the warning the plant expects: "No inertial data for link" on
    the fixed base (``root_link``; its mass never moves, so the copy leaves it as written: plant_urdf.py), which
    PyBullet prints as two warnings, the message and then the link's name."""
    parts = re.split(r"b3Warning\[[^\]]*\]:\n", printed)
    kept, i = [parts[0]], 1
    while i < len(parts):
        if parts[i].startswith("No inertial data for link") and i + 1 < len(parts) and \
                parts[i + 1].strip() == root_link:
            i += 2
            continue
        kept.append(parts[i])
        i += 1
    return " ".join(p.strip() for p in kept if p.strip())


def _coulomb_root(v_free: float, k: float, inv_eps: float) -> float:
    """The root v of g(v) = v - v_free + k tanh(v inv_eps) (k >= 0), to |g| <= 1e-13 (1 + |v_free|).

    g is increasing, g(v_free - k) <= 0 <= g(v_free + k). Newton from the linearised root (sticking, |v_free| < k)
    or the sliding one, safeguarded as Numerical Recipes' rtsafe: a bisection of the bracket whenever the Newton
    step would leave it or would not halve the step before last. Plain Newton cycles across the steep part of
    tanh (from one flat side to the other), which a bracket test alone does not catch."""
    if k <= 0.0:
        return v_free
    lo, hi = v_free - k, v_free + k
    v = v_free / (1.0 + k * inv_eps) if abs(v_free) < k else v_free - math.copysign(k, v_free)
    v = min(max(v, lo), hi)
    tol = 1e-13 * (1.0 + abs(v_free))
    dx_before = dx = hi - lo
    for _ in range(200):
        th = math.tanh(v * inv_eps)
        g = v - v_free + k * th
        if abs(g) <= tol:
            return v
        if g > 0.0:
            hi = v
        else:
            lo = v
        slope = 1.0 + k * inv_eps * (1.0 - th * th)
        step = v - g / slope
        if lo < step < hi and abs(2.0 * g) <= abs(dx_before * slope):
            dx_before, dx = dx, g / slope
            v = step
        else:
            dx_before, dx = dx, 0.5 * (hi - lo)
            v = lo + dx
        if hi - lo <= 4e-16 * (1.0 + abs(v)):  # the bracket is a few ulps wide: v is the root in floating point
            return v
    return v


def _implicit_coulomb_speed(v_free: np.ndarray, k: np.ndarray, inv_eps: float) -> np.ndarray:
    """Per joint, the root v of v - v_free + k tanh(v inv_eps) = 0 (k >= 0; ``_coulomb_root``), shape (n,)."""
    return np.array([_coulomb_root(vf, kk, inv_eps) for vf, kk in zip(v_free.tolist(), k.tolist())])


class PyBulletArmPlant(ArmPlantBase):
    """A torque-driven serial arm of n actuated revolute joints with rotor inertia, friction and limits.

    Parameters
    ----------
    client : pybullet_utils.bullet_client.BulletClient
        A connected client (DIRECT for simulation), owned by the caller.
    arm : Arm
        The arm (pa10_dnbs.arm): URDF (loaded with a fixed base), actuated joints, locked joints, flange.
    params : PlantParams
        Step, gravity, rotor inertia, friction and torque limits (None fields: the arm's facts).

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
    Movable joints the arm does not actuate (``arm.locked_joints``, e.g. gripper fingers) are held at their
    locked positions: M and h are the actuated block and rows of PyBullet's, which is exact for a joint held
    still. PyBullet's gravity belongs to the client, so the plant sets it to its own
    value before every inverse-dynamics call (plants with different gravity
    may share a client). ``stepSimulation`` is never called.
    A joint that leaves [lower, upper] is clamped to the limit, its velocity
    component pointing outward is set to zero and its hit counter goes up by
    one (one count per step spent clamped).
    """

    def __init__(self, client, arm: Arm, params: PlantParams) -> None:
        if not isinstance(params, PlantParams):
            raise TypeError(f"params: expected PlantParams, got {type(params).__name__}")
        urdf_path = os.fspath(arm.physics_urdf)  # the URDF itself, or its cleaned copy (pa10_dnbs.arm.plant_urdf)
        if not os.path.isfile(urdf_path):
            raise FileNotFoundError(f"URDF file not found: {urdf_path}")
        n = self._n = arm.n_joints
        params = checked_for_arm(params, arm)
        self._client = client
        self._params = params
        self._arm = arm
        said: list[str] = []   # what PyBullet prints while loading: its reason, when it fails
        try:
            with c_output_into(said):
                self._body = client.loadURDF(
                    urdf_path,
                    useFixedBase=True,
                    flags=pybullet.URDF_USE_INERTIA_FROM_FILE,
                )
        except pybullet.error:  # what the intake's checks (pa10_dnbs.kinematics.urdf_tree) did not foresee
            raise ArmError(f"{arm.urdf}: PyBullet cannot load this URDF"
                           + (f" (its cleaned copy {urdf_path})" if arm.plant_urdf is not None else "")
                           + _pybullet_reason(said[0])) from None
        left = _unforeseen_warnings(said[0], arm.chain.root_link)
        if left:   # a warning the cleaned copy did not foresee: on stderr, one line, never glued to stdout's
            os.write(2, f"PyBullet, loading {arm.urdf}:{_pybullet_reason(left)[1:]}\n".encode())
        self._n_links = client.getNumJoints(self._body)
        index_of, dofs = {}, []
        for j in range(self._n_links):
            info = client.getJointInfo(self._body, j)
            index_of[info[1].decode("utf-8")] = j
            if info[2] != pybullet.JOINT_FIXED:
                dofs.append(j)
        self._joint_indices = tuple(index_of[name] for name in arm.joint_names)
        self._lower = np.array(arm.lower_rad, dtype=float)
        self._upper = np.array(arm.upper_rad, dtype=float)
        # PyBullet's dynamics take every movable joint (its DOFs, in joint order); the actuated ones are a
        # subset when the arm locks some (None: they are all of them, in order: no gathering needed)
        if list(self._joint_indices) == dofs:
            self._dof_rows = None
        else:
            self._dof_rows = np.array([dofs.index(j) for j in self._joint_indices])
            self._dof_block = np.ix_(self._dof_rows, self._dof_rows)
            self._q_full = np.zeros(len(dofs))
            for name, q_locked in zip(arm.locked_joints, arm.locked_position_rad):
                self._q_full[dofs.index(index_of[name])] = q_locked
            self._qd_full = np.zeros(len(dofs))
            for name, q_locked in zip(arm.locked_joints, arm.locked_position_rad):
                client.resetJointState(self._body, index_of[name], q_locked, 0.0)
        # Mass changes must come before PyBullet's first dynamics call, which caches the multibody tree.
        self._apply_mass_changes(client, params)
        # Link masses for the potential energy (every non-base link, incl. massless frames).
        self._link_masses = np.array(
            [client.getDynamicsInfo(self._body, j)[0] for j in range(self._n_links)], dtype=float
        )
        # No built-in motors: the plant applies torques itself.
        client.setJointMotorControlArray(
            self._body, dofs, pybullet.VELOCITY_CONTROL, forces=[0.0] * len(dofs)
        )

        # Cached bound calls (BulletClient builds a partial on every attribute access).
        self._calc_mass_matrix = client.calculateMassMatrix
        self._calc_inverse_dynamics = client.calculateInverseDynamics
        self._set_gravity = client.setGravity
        self._gravity_z = -float(params.gravity_mps2)
        self._set_gravity(0.0, 0.0, self._gravity_z)
        self._zero_acc = [0.0] * len(dofs)

        self._rotor = np.array(params.rotor_inertia_kgm2, dtype=float)
        self._fv = np.array(params.viscous_nms_per_rad, dtype=float)
        self._fc = np.array(params.coulomb_nm, dtype=float)
        self._inv_eps = 1.0 / params.coulomb_smoothing_rad_s
        self._has_coulomb = bool(np.any(self._fc > 0.0))
        self._tau_max = np.array(params.torque_limit_nm, dtype=float)
        self._neg_tau_max = -self._tau_max
        self._dt = params.dt_s
        self._diag = np.diag_indices(n)

        self._q = np.zeros(n)
        self._qd = np.zeros(n)
        self._applied = np.zeros(n)
        self._tau_scratch = np.zeros(n)
        self._limit_hits = np.zeros(n, dtype=np.int64)
        self._below = np.zeros(n, dtype=bool)
        self._above = np.zeros(n, dtype=bool)
        self._step_count = 0
        self.reset(np.clip(np.zeros(n), self._lower, self._upper), np.zeros(n))

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
            flange = self._arm.flange_link
            if flange not in names:
                raise ValueError(f"payload_kg: the URDF has no link named {flange!r} (the arm's flange_link) to "
                                 f"carry the payload")
            # a point mass at the flange frame's origin (a tiny inertia keeps the link's inertia valid); on a
            # link that has a mass of its own, the payload is added to it at the link's CoM
            info = client.getDynamicsInfo(self._body, names.index(flange))
            if info[0] > 0.0:
                client.changeDynamics(self._body, names.index(flange), mass=info[0] + params.payload_kg)
            else:
                client.changeDynamics(self._body, names.index(flange), mass=params.payload_kg,
                                      localInertiaDiagonal=[1e-9] * 3)

    # ------------------------------------------------------------------ info (the rest: ArmPlantBase)
    @property
    def body_id(self) -> int:
        """PyBullet body unique id of the arm."""
        return self._body

    # ------------------------------------------------------------- stepping
    def reset(self, q0, qd0) -> None:
        """Set the state (q0 rad, qd0 rad/s, each (n,)) and clear the counters."""
        q0 = as_joint_vector("q0", q0, self._n)
        qd0 = as_joint_vector("qd0", qd0, self._n)
        if np.any(q0 < self._lower) or np.any(q0 > self._upper):
            raise ValueError(f"q0: outside the joint limits [{self._lower}, {self._upper}]")
        self._q[:] = q0
        self._qd[:] = qd0
        self._applied[:] = 0.0
        self._limit_hits[:] = 0
        self._step_count = 0

    def step(self, torque_nm) -> None:
        """Saturate ``torque_nm`` (n,) N m to the limits and advance one dt.

        Infinite entries saturate to the limit; NaN raises ValueError.
        """
        tau = np.asarray(torque_nm, dtype=float)
        if tau.shape != (self._n,):
            raise ValueError(f"torque_nm: expected shape ({self._n},), got {tau.shape}")
        applied = self._tau_scratch
        np.minimum(np.maximum(tau, self._neg_tau_max, out=applied), self._tau_max, out=applied)
        if not math.isfinite(applied.sum()) and np.isnan(applied).any():  # only NaN survives the saturation
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
        """(q rad, qd rad/s), each a (n,) copy."""
        return self._q.copy(), self._qd.copy()

    # ------------------------------------------------------------- dynamics
    def _qdd(self, q: np.ndarray, qd: np.ndarray, tau: np.ndarray) -> np.ndarray:
        m, bias = self._m_and_bias(q, qd)
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

    def _m_and_bias(self, q: np.ndarray, qd: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(M(q) + J (n, n), h(q, qd) (n,)) of the actuated joints, the locked ones held still."""
        if self._dof_rows is None:
            q_list = q.tolist()
            m = np.array(self._calc_mass_matrix(self._body, q_list), dtype=float)
            m[self._diag] += self._rotor
            self._set_gravity(0.0, 0.0, self._gravity_z)
            bias = np.array(self._calc_inverse_dynamics(self._body, q_list, qd.tolist(), self._zero_acc), dtype=float)
            return m, bias
        self._q_full[self._dof_rows] = q
        self._qd_full[self._dof_rows] = qd
        q_list = self._q_full.tolist()
        m = np.array(self._calc_mass_matrix(self._body, q_list), dtype=float)[self._dof_block]
        m[self._diag] += self._rotor
        self._set_gravity(0.0, 0.0, self._gravity_z)
        bias = np.array(self._calc_inverse_dynamics(self._body, q_list, self._qd_full.tolist(), self._zero_acc),
                        dtype=float)[self._dof_rows]
        return m, bias

    def mass_matrix(self, q) -> np.ndarray:
        """(n, n) joint-space inertia M(q) + diag(rotor inertia), kg m^2."""
        q = as_joint_vector("q", q, self._n)
        return self._m_and_bias(q, np.zeros(self._n))[0]

    def bias_torque(self, q, qd) -> np.ndarray:
        """(n,) Coriolis + centrifugal + gravity torque, N m (inverse dynamics at qdd = 0)."""
        q = as_joint_vector("q", q, self._n)
        qd = as_joint_vector("qd", qd, self._n)
        return self._m_and_bias(q, qd)[1]

    def torque_along(self, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray) -> np.ndarray:
        """(k, n) tau = (M(q) + J) qdd + h(q, qd) + Fv qd + Fc tanh(qd / eps) [N m] at each row of q [rad],
        qd [rad/s], qdd [rad/s^2] (k, n): row by row the bits of
        ``mass_matrix(q) @ qdd + bias_torque(q, qd) + friction_torque(qd)``, from one mass-matrix and one
        inverse-dynamics call per row (M(q) does not depend on qd) instead of two of each. ValueError as
        theirs for a shape other than (k, n) or a value that is not finite."""
        for name, x in (("q", q), ("qd", qd), ("qdd", qdd)):
            if np.ndim(x) != 2 or np.shape(x)[1] != self._n or np.shape(x) != np.shape(q):
                raise ValueError(f"{name}: expected shape (k, {self._n}) like q, got {np.shape(x)}")
            if not np.all(np.isfinite(x)):
                raise ValueError(f"{name}: values must be finite")
        m_and_bias = self._m_and_bias
        rows = []
        for a, b, c in zip(q, qd, qdd):
            m, bias = m_and_bias(a, b)
            rows.append(m @ c + bias)
        tau = np.array(rows, dtype=float).reshape(np.shape(q))
        return tau + (self._fv * qd + self._fc * np.tanh(qd * self._inv_eps))

    def step_friction_torque(self, qd, qdd) -> np.ndarray:
        """(n,) the friction torque a step from speed qd with acceleration qdd meets, N m: viscous at qd (explicit),
        Coulomb at the end-of-step speed qd + dt qdd (implicit), as :meth:`step` applies them."""
        qd = as_joint_vector("qd", qd, self._n)
        qdd = as_joint_vector("qdd", qdd, self._n)
        return self._fv * qd + self._fc * np.tanh((qd + self._dt * qdd) * self._inv_eps)

    def forward_acceleration(self, q, qd, tau) -> np.ndarray:
        """(n,) qdd = (M + J)^-1 (tau - bias - friction), rad/s^2; tau is not saturated."""
        q = as_joint_vector("q", q, self._n)
        qd = as_joint_vector("qd", qd, self._n)
        tau = as_joint_vector("tau", tau, self._n)
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
        q = as_joint_vector("q", q, self._n)
        qd = as_joint_vector("qd", qd, self._n)
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

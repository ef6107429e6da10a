"""The PyBullet plant's rigid-body dynamics against MuJoCo's reading of the same URDF (an independent library).

MuJoCo parses the URDF itself (``MjSpec.from_file``: its own handling of fixed joints, massless links and
inertial frames); its geometry is dropped and its inertias are the URDF's (``inertiafromgeom`` off). At
seeded random states within the joint limits (a continuous joint in [-pi, pi]), locked joints held at the
arm's locked positions, it compares with the plant (rotor inertia and friction zero):

- M(q): the actuated block of MuJoCo's full inertia matrix (``mj_fullM``);
- bias torques h(q, qd) (Coriolis, centrifugal and gravity): rows of ``qfrc_bias``;
- forward dynamics qdd = M^-1 (tau - h): MuJoCo's ``qacc`` from ``mj_forward`` with the torques applied and
  its constraints, limits and passive forces off (an arm that locks joints: its block solved instead).

Each figure is the largest relative difference over the states: max |a - b| / max |b|, b MuJoCo's.
"""
from __future__ import annotations

import math
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..arm import Arm
from .from_config import open_client
from .plant_params import PlantParams
from .pybullet_plant import PyBulletArmPlant

GRAVITY_MPS2 = 9.81


@dataclass(frozen=True)
class DynamicsDifference:
    """Largest relative differences plant vs MuJoCo over the sampled states (dimensionless)."""

    mass_matrix: float
    bias_torque: float
    forward_dynamics: float
    states: int

    @property
    def worst(self) -> float:
        return max(self.mass_matrix, self.bias_torque, self.forward_dynamics)


def mujoco_model(urdf: Path):
    """MuJoCo's model of ``urdf``: geometry and mesh assets dropped, inertias from the file, gravity -z,
    contacts, limits, constraints and passive forces off."""
    import mujoco

    spec = mujoco.MjSpec.from_file(os.fspath(urdf))
    spec.compiler.inertiafromgeom = mujoco.mjtInertiaFromGeom.mjINERTIAFROMGEOM_FALSE
    for item in list(spec.geoms) + list(spec.meshes):
        spec.delete(item)
    spec.option.gravity = [0.0, 0.0, -GRAVITY_MPS2]
    bits = mujoco.mjtDisableBit
    for flag in (bits.mjDSBL_CONTACT, bits.mjDSBL_LIMIT, bits.mjDSBL_CONSTRAINT, bits.mjDSBL_DAMPER,
                 bits.mjDSBL_SPRING, bits.mjDSBL_FRICTIONLOSS):
        spec.option.disableflags |= int(flag)
    for joint in spec.joints:
        joint.armature = 0.0
    return spec.compile()


def compare_with_mujoco(arm: Arm, states: int = 20, seed: int = 0, urdf: Path | None = None) -> DynamicsDifference:
    """The plant of ``arm`` against MuJoCo's model of ``urdf`` (default: the arm's URDF as written) at
    ``states`` seeded random states; joint limits from the arm, torques up to half the arm's limits."""
    import mujoco

    model = mujoco_model(urdf or arm.urdf)
    data = mujoco.MjData(model)
    n = arm.n_joints
    adr = {model.joint(i).name: (int(model.jnt_qposadr[i]), int(model.jnt_dofadr[i])) for i in range(model.njnt)}
    missing = [j for j in arm.joint_names + arm.locked_joints if j not in adr]
    if missing:
        raise ValueError(f"MuJoCo's model of {urdf or arm.urdf} has no joint {missing[0]!r}")
    qpos_of = np.array([adr[j][0] for j in arm.joint_names])
    dof_of = np.array([adr[j][1] for j in arm.joint_names])
    block = np.ix_(dof_of, dof_of)
    lower = np.where(np.isfinite(arm.lower_rad), arm.lower_rad, -math.pi)
    upper = np.where(np.isfinite(arm.upper_rad), arm.upper_rad, math.pi)
    rng = np.random.default_rng(seed)
    zeros = tuple([0.0] * n)
    client = open_client()
    try:
        plant = PyBulletArmPlant(client, arm, PlantParams(gravity_mps2=GRAVITY_MPS2, rotor_inertia_kgm2=zeros,
                                                          viscous_nms_per_rad=zeros, coulomb_nm=zeros,
                                                          torque_limit_nm=tuple(float(t) for t in arm.torque_limit_nm)))
        worst = np.zeros(3)
        full = np.zeros((model.nv, model.nv))
        for _ in range(states):
            q = rng.uniform(lower, upper)
            qd = rng.uniform(-1.0, 1.0, n)
            tau = rng.uniform(-0.5, 0.5, n) * arm.torque_limit_nm
            data.qpos[:] = 0.0
            data.qvel[:] = 0.0
            data.qfrc_applied[:] = 0.0
            for name, q_locked in zip(arm.locked_joints, arm.locked_position_rad):
                data.qpos[adr[name][0]] = q_locked
            data.qpos[qpos_of] = q
            data.qvel[dof_of] = qd
            data.qfrc_applied[dof_of] = tau
            mujoco.mj_forward(model, data)
            mujoco.mj_fullM(model, data, full)
            m_ref, h_ref = full[block], data.qfrc_bias[dof_of].copy()
            qdd_ref = data.qacc[dof_of].copy() if not arm.locked_joints else np.linalg.solve(m_ref, tau - h_ref)
            got = (plant.mass_matrix(q), plant.bias_torque(q, qd), plant.forward_acceleration(q, qd, tau))
            for i, (a, b) in enumerate(zip(got, (m_ref, h_ref, qdd_ref))):
                worst[i] = max(worst[i], float(np.max(np.abs(a - b)) / max(np.max(np.abs(b)), 1e-300)))
    finally:
        client.disconnect()
    return DynamicsDifference(*(float(w) for w in worst), states=states)

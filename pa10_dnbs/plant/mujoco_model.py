"""The arm as a MuJoCo model: its URDF loaded by MuJoCo's own parser, with the arm file's facts as joint properties.

Built from the same :class:`~pa10_dnbs.arm.Arm` as the PyBullet plant (no URDF parsing of ours): MuJoCo reads
the URDF the PyBullet plant loads (``arm.physics_urdf``: the URDF, or its cleaned copy where massless links and
inconsistent inertias were made explicit) into an ``MjSpec``, which is then edited before compiling:

- every geom and mesh is removed (no contacts, no inertia from geometry, no mesh file read: each link keeps
  its ``<inertial>``);
- each locked joint (``arm.locked_joints``) is removed and its child body posed at the locked position, which
  welds it there (exact, as the PyBullet plant's block of M(q) is for a joint held still);
- rotor inertia -> joint ``armature`` (added to diag(M) by MuJoCo itself), viscous friction -> ``damping``,
  Coulomb friction -> ``frictionloss`` (a constraint solved by MuJoCo, not the PyBullet plant's Fc tanh(qd/eps));
- ``link_mass_scale`` scales every body's mass and inertia; ``payload_kg`` sits at the flange link (on its
  centre of mass when it has a mass of its own, else a point mass at its origin), as in the PyBullet plant;
- gravity -z, step dt, MuJoCo's semi-implicit Euler (its damping implicit in the step), joint limits and
  contacts off in the solver (the plant clamps at the limits as the PyBullet plant does).
"""
from __future__ import annotations

import os

import numpy as np

from ..arm import Arm, ArmError

MIN_PAYLOAD_INERTIA_KGM2 = 1e-9  # a point mass still needs a valid inertia (the PyBullet plant's value)


def build_model(arm: Arm, params):
    """The compiled ``mujoco.MjModel`` of ``arm`` with ``params`` (a PlantParams with every per-joint field
    filled); its degrees of freedom are exactly the actuated joints."""
    import mujoco

    urdf_path = os.fspath(arm.physics_urdf)
    if not os.path.isfile(urdf_path):
        raise FileNotFoundError(f"URDF file not found: {urdf_path}")
    try:
        spec = mujoco.MjSpec.from_file(urdf_path)
    except ValueError as exc:  # an XML error PyBullet's importer and the intake's checks let pass
        why = " ".join(str(exc).split())
        raise ArmError(f"{arm.urdf}: MuJoCo cannot load this URDF"
                       + (f" (its cleaned copy {urdf_path})" if arm.plant_urdf is not None else "")
                       + f": {why}") from None
    spec.compiler.inertiafromgeom = mujoco.mjtInertiaFromGeom.mjINERTIAFROMGEOM_FALSE
    for geom in list(spec.geoms):
        spec.delete(geom)
    for mesh in list(spec.meshes):
        spec.delete(mesh)
    _scale_and_load(spec, arm, params)
    joints = {j.name: j for j in spec.joints}
    for name, q_locked in zip(arm.locked_joints, arm.locked_position_rad):
        _weld(spec, joints.pop(name), float(q_locked))
    unknown = sorted(set(joints) - set(arm.joint_names))
    if unknown:  # a movable joint the arm neither actuates nor locks (the arm object follows one chain)
        raise ValueError(f"{arm.urdf}: joint {unknown[0]!r} is movable but neither actuated nor locked by arm "
                         f"{arm.name}")
    for i, name in enumerate(arm.joint_names):
        j = joints[name]
        j.armature = params.rotor_inertia_kgm2[i]
        j.damping = [params.viscous_nms_per_rad[i], 0.0, 0.0]  # linear term only (4.0: [linear, poly...])
        j.frictionloss = params.coulomb_nm[i]
        j.limited = mujoco.mjtLimited.mjLIMITED_FALSE
        j.actfrclimited = mujoco.mjtLimited.mjLIMITED_FALSE
    opt = spec.option
    opt.timestep = params.dt_s
    opt.gravity = [0.0, 0.0, -float(params.gravity_mps2)]
    opt.integrator = mujoco.mjtIntegrator.mjINT_EULER
    opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_CONTACT) | int(mujoco.mjtDisableBit.mjDSBL_LIMIT)
    # A step whose accelerations blow up (non-finite or huge) keeps the state it reached, as the PyBullet plant
    # does, for the loop to see and report: MuJoCo would otherwise reset the state to the model's zero pose
    # and go on, silently.
    opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_AUTORESET)
    _quiet_warnings(mujoco)
    return _compile(spec, arm, params, urdf_path)


def _compile(spec, arm: Arm, params, urdf_path: str):
    """``spec.compile()``; MuJoCo's refusal (an inertia too small for its checks, which PyBullet accepts) as one
    line naming the URDF, and ``plant.link_mass_scale`` when it scaled the inertias."""
    try:
        return spec.compile()
    except ValueError as exc:
        why = " ".join(str(exc).split())
        scaled = f" with plant.link_mass_scale {params.link_mass_scale:g}" if params.link_mass_scale != 1.0 else ""
        raise ArmError(f"{arm.urdf}: MuJoCo cannot compile this URDF"
                       + (f" (its cleaned copy {urdf_path})" if arm.plant_urdf is not None else "")
                       + f"{scaled}: {why}") from None


def _ignore_warning(text: str) -> None:
    """MuJoCo's run-time warnings (a state or acceleration gone bad) show in the plant's state, which the loop
    reports; nothing is written to the working directory."""


def _quiet_warnings(mujoco) -> None:
    """MuJoCo's warnings handled in this process instead of by its default handler, which prints them and writes
    MUJOCO_LOG.TXT into the working directory (a run writes only into its output folder)."""
    if mujoco.get_mju_user_warning() is None:
        mujoco.set_mju_user_warning(_ignore_warning)


def _scale_and_load(spec, arm: Arm, params) -> None:
    """Link masses and inertias times ``link_mass_scale``; the payload at the flange link."""
    bodies = {b.name: b for b in spec.bodies}
    if params.link_mass_scale != 1.0:
        for b in bodies.values():
            if b.mass > 0.0:
                b.mass = b.mass * params.link_mass_scale
                b.fullinertia = np.asarray(b.fullinertia) * params.link_mass_scale
    if params.payload_kg > 0.0:
        flange = bodies.get(arm.flange_link)
        if flange is None:
            raise ValueError(f"payload_kg: the URDF has no link named {arm.flange_link!r} (the arm's flange_link) "
                             f"to carry the payload")
        if flange.mass > 0.0:
            flange.mass = flange.mass + params.payload_kg
        else:
            flange.mass = params.payload_kg
            flange.ipos = [0.0, 0.0, 0.0]
            flange.iquat = [1.0, 0.0, 0.0, 0.0]
            flange.fullinertia = [MIN_PAYLOAD_INERTIA_KGM2] * 3 + [0.0] * 3
            flange.explicitinertial = True


def _weld(spec, joint, q: float) -> None:
    """Remove ``joint`` and pose its body as the joint at ``q`` would (rad for a hinge, m for a slide)."""
    import mujoco

    body = joint.parent
    axis = np.asarray(joint.axis, float)
    axis = axis / np.linalg.norm(axis)
    p = np.asarray(joint.pos, float)
    pos, quat = np.asarray(body.pos, float), np.asarray(body.quat, float)
    rot = np.zeros(9)
    mujoco.mju_quat2Mat(rot, quat)
    rot = rot.reshape(3, 3)
    if joint.type == mujoco.mjtJoint.mjJNT_HINGE:
        dq = np.zeros(4)
        mujoco.mju_axisAngle2Quat(dq, axis, q)
        rq = np.zeros(9)
        mujoco.mju_quat2Mat(rq, dq)
        new_quat = np.zeros(4)
        mujoco.mju_mulQuat(new_quat, quat, dq)
        body.pos = pos + rot @ (p - rq.reshape(3, 3) @ p)  # rotation about the joint's point, in the body frame
        body.quat = new_quat
    elif joint.type == mujoco.mjtJoint.mjJNT_SLIDE:
        body.pos = pos + rot @ (axis * q)
    else:
        raise ValueError(f"joint {joint.name!r}: only hinge and slide joints can be locked")
    spec.delete(joint)

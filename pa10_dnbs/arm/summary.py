"""What an arm is, in words: the line a plant logs at start, so that a placeholder shows (numpy only)."""
from __future__ import annotations

from ..number_text import fixed
from .arm import Arm


def arm_line(arm: Arm) -> str:
    """One line: the arm, its file and, per joint, limits [rad], torque limit [N m] and rotor inertia [kg m^2];
    the locked joints and the cleaned copy PyBullet loads, where there are."""
    joints = "; ".join(f"{n} [{fixed(lo, '+.2f')}, {fixed(hi, '+.2f')}] rad, {t:g} N m, rotor {r:g} kg m^2"
                       for n, lo, hi, t, r in zip(arm.joint_names, arm.lower_rad, arm.upper_rad, arm.torque_limit_nm,
                                                  arm.rotor_inertia_kgm2))
    locked = f"; locked: {', '.join(arm.locked_joints)}" if arm.locked_joints else ""
    copy = (f"; the plant loads the cleaned copy {arm.plant_urdf} (massless links explicit, meshes dropped: "
            f"docs/arms.md)" if arm.plant_urdf is not None else "")
    return f"ARM {arm.name} ({arm.description}) from {arm.file}: {arm.n_joints} joints: {joints}{locked}{copy}"

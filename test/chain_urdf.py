"""A synthetic serial arm of n revolute joints (a URDF text), for timing the intake on long chains.

Links of 0.5 kg, 0.1 m apart, axes alternating z (yaw) and y (pitch), limits +/-2 rad, effort ``effort_nm``;
a massless flange on a fixed joint at the end. Used by scripts/intake_timing.py and the tests of the rules'
speed-ups (same results before and after).
"""
from __future__ import annotations


def chain_urdf(n_joints: int, effort_nm: float = 200.0, name: str = "chain") -> str:
    """The URDF text of an ``n_joints`` revolute chain (see the module's docstring)."""
    def link(k: int) -> str:
        return (f'<link name="l{k}"><inertial><origin xyz="0 0 0.05"/><mass value="0.5"/>'
                f'<inertia ixx="0.002" ixy="0" ixz="0" iyy="0.002" iyz="0" izz="0.001"/></inertial></link>')

    parts = [link(k) for k in range(n_joints + 1)] + ['<link name="flange"/>']
    for k in range(n_joints):
        axis = "0 0 1" if k % 2 == 0 else "0 1 0"
        parts.append(f'<joint name="j{k + 1}" type="revolute"><parent link="l{k}"/><child link="l{k + 1}"/>'
                     f'<origin xyz="0 0 0.1"/><axis xyz="{axis}"/>'
                     f'<limit lower="-2" upper="2" effort="{effort_nm:g}" velocity="2"/></joint>')
    parts.append(f'<joint name="flange_joint" type="fixed"><parent link="l{n_joints}"/><child link="flange"/>'
                 f'<origin xyz="0 0 0.1"/></joint>')
    return f'<robot name="{name}">\n' + "\n".join(parts) + "\n</robot>\n"

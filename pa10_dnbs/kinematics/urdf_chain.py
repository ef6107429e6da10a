"""Forward kinematics of a URDF joint tree, one transform per joint (what /tf carries).

Parses the ``<joint>`` elements of a URDF (origin xyz/rpy, axis, type) with
the standard library and evaluates, for joint positions q [rad], the pose of
each child link frame in its parent link frame: translation [m], shape (3,),
and rotation as a unit quaternion (x, y, z, w), shape (4,). This is what
robot_state_publisher would put on /tf and /tf_static; numpy only.
"""
from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .urdf_xml import urdf_root
from .urdf_tree import (JOINT_TYPES, MAX_AXIS, MAX_OFFSET_M, UrdfError, check_link, check_name, number, tree_root,
                        vector3)


@dataclass(frozen=True)
class UrdfJoint:
    name: str
    kind: str                 # revolute, continuous, prismatic or fixed
    parent: str
    child: str
    origin_xyz: np.ndarray    # (3,) [m]
    origin_rot: np.ndarray    # (3, 3) rotation of the joint frame in the parent frame
    axis: np.ndarray          # (3,) unit axis in the joint frame
    lower: float = -math.inf  # <limit lower> [rad or m]; +/-inf when absent (continuous)
    upper: float = math.inf
    velocity: float = math.inf  # <limit velocity> [rad/s or m/s]
    effort: float = math.nan    # <limit effort> [N m or N]; NaN when absent
    mimics: str | None = None   # <mimic joint=...>: the joint whose position this one follows (no own actuator)


@dataclass(frozen=True)
class FrameTransform:
    parent: str
    child: str
    translation_m: tuple[float, float, float]
    rotation_xyzw: tuple[float, float, float, float]


def rpy_matrix(roll: float, pitch: float, yaw: float) -> np.ndarray:
    """URDF rpy (fixed axes x, y, z) as a 3x3 rotation: Rz(yaw) Ry(pitch) Rx(roll)."""
    cr, sr, cp, sp, cy, sy = math.cos(roll), math.sin(roll), math.cos(pitch), math.sin(pitch), math.cos(yaw), math.sin(yaw)
    return np.array([[cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
                     [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
                     [-sp, cp * sr, cp * cr]])


def axis_angle_matrix(axis: np.ndarray, angle: float) -> np.ndarray:
    """Rodrigues' rotation about the unit ``axis`` by ``angle`` [rad]."""
    x, y, z = axis
    k = np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])
    return np.eye(3) + math.sin(angle) * k + (1.0 - math.cos(angle)) * (k @ k)


def matrix_quaternion(r: np.ndarray) -> tuple[float, float, float, float]:
    """Unit quaternion (x, y, z, w) of a rotation matrix, w >= 0."""
    t = r[0, 0] + r[1, 1] + r[2, 2]
    if t > 0.0:
        s = 2.0 * math.sqrt(t + 1.0)
        q = ((r[2, 1] - r[1, 2]) / s, (r[0, 2] - r[2, 0]) / s, (r[1, 0] - r[0, 1]) / s, 0.25 * s)
    elif r[0, 0] >= r[1, 1] and r[0, 0] >= r[2, 2]:
        s = 2.0 * math.sqrt(1.0 + r[0, 0] - r[1, 1] - r[2, 2])
        q = (0.25 * s, (r[0, 1] + r[1, 0]) / s, (r[0, 2] + r[2, 0]) / s, (r[2, 1] - r[1, 2]) / s)
    elif r[1, 1] >= r[2, 2]:
        s = 2.0 * math.sqrt(1.0 + r[1, 1] - r[0, 0] - r[2, 2])
        q = ((r[0, 1] + r[1, 0]) / s, 0.25 * s, (r[1, 2] + r[2, 1]) / s, (r[0, 2] - r[2, 0]) / s)
    else:
        s = 2.0 * math.sqrt(1.0 + r[2, 2] - r[0, 0] - r[1, 1])
        q = ((r[0, 2] + r[2, 0]) / s, (r[1, 2] + r[2, 1]) / s, 0.25 * s, (r[1, 0] - r[0, 1]) / s)
    n = math.sqrt(sum(c * c for c in q))
    sign = -1.0 if q[3] < 0 else 1.0
    return tuple(sign * c / n for c in q)


def _joint(el: ET.Element, i: int) -> UrdfJoint:
    """The ``i``-th ``<joint>`` element, checked: a name (no surrounding whitespace), a URDF joint type, parent
    and child links, 3 finite numbers in each of origin xyz (within +/-MAX_OFFSET_M)/rpy and axis xyz (a unit
    axis; zero only for a fixed joint), numeric limits."""
    name = check_name("joint", el.get("name"), i)
    kind = el.get("type")
    if kind not in JOINT_TYPES:
        raise UrdfError(f"joint {name!r}: type={kind!r}: expected one of {', '.join(JOINT_TYPES)}")
    ends = {}
    for role in ("parent", "child"):
        end = el.find(role)
        if end is None or not end.get("link"):
            raise UrdfError(f"joint {name!r}: no <{role} link=...>")
        ends[role] = end.get("link")
    origin, axis_el, limit = el.find("origin"), el.find("axis"), el.find("limit")
    xyz = np.array(vector3(origin, "xyz", "0 0 0", name, MAX_OFFSET_M))
    rpy = vector3(origin, "rpy", "0 0 0", name)
    axis = np.array(vector3(axis_el, "xyz", "1 0 0", name))
    if np.max(np.abs(axis)) > MAX_AXIS:   # a direction; its squared length would overflow past ~1e154
        raise UrdfError(f'joint {name!r}: <axis xyz="{axis_el.get("xyz")}">: each component must be within '
                        f'+/-{MAX_AXIS:g} (a direction, its length divided out; see pa10_dnbs/kinematics/urdf_tree.py)')
    norm = np.linalg.norm(axis)
    if norm == 0.0:
        if kind != "fixed":
            raise UrdfError(f'joint {name!r}: <axis xyz="{axis_el.get("xyz")}">: zero axis (a {kind} joint needs '
                            f'a direction)')
        axis, norm = np.array([1.0, 0.0, 0.0]), 1.0  # a fixed joint's axis is never used
    keys = (("lower", "upper", "velocity") if kind != "continuous" else ()) + ("effort",)
    bounds = {k: number(limit, k, name) for k in keys if limit is not None and limit.get(k) is not None}
    mimic = el.find("mimic")
    return UrdfJoint(name=name, kind=kind, parent=ends["parent"], child=ends["child"], origin_xyz=xyz,
                     origin_rot=rpy_matrix(*rpy), axis=axis / norm, **bounds,
                     mimics=None if mimic is None else (mimic.get("joint") or ""))


class UrdfChain:
    """The joints of a URDF and their transforms at given joint positions.

    Raises :class:`UrdfError` (a ValueError) naming the joint or link when the URDF is not one tree of
    uniquely named links and joints with well-formed vectors and limits (:mod:`.urdf_tree`)."""

    def __init__(self, urdf_xml: str):
        root = urdf_root(urdf_xml)
        if root.tag != "robot":
            raise ValueError(f"not a URDF: root element is <{root.tag}>, expected <robot>")
        self.robot_name = root.get("name", "")
        links = [check_link(el, i) for i, el in enumerate(root.findall("link"), 1)]
        joints = [_joint(el, i) for i, el in enumerate(root.findall("joint"), 1)]
        self.links = tuple(links)
        self.root_link = tree_root(links, [(j.name, j.parent, j.child) for j in joints])
        self.joints = joints
        self.movable = [j for j in joints if j.kind != "fixed"]
        self.fixed = [j for j in joints if j.kind == "fixed"]
        # per revolute/continuous joint: origin translation and rotation as a quaternion, for moving_transforms
        self._origin = {j.name: (tuple(float(v) for v in j.origin_xyz), matrix_quaternion(j.origin_rot),
                                 tuple(float(v) for v in j.axis))
                        for j in joints if j.kind in ("revolute", "continuous")}

    def joint(self, name: str) -> UrdfJoint:
        """The joint called ``name``; KeyError if the URDF has none."""
        for j in self.joints:
            if j.name == name:
                return j
        raise KeyError(f"no joint {name!r} in the URDF")

    @classmethod
    def from_file(cls, path: Path) -> "UrdfChain":
        return cls(Path(path).read_text())

    @staticmethod
    def _transform(j: UrdfJoint, q: float) -> FrameTransform:
        if j.kind == "prismatic":
            t = j.origin_xyz + j.origin_rot @ (j.axis * q)
            r = j.origin_rot
        elif j.kind == "fixed":
            t, r = j.origin_xyz, j.origin_rot
        else:  # revolute, continuous
            t, r = j.origin_xyz, j.origin_rot @ axis_angle_matrix(j.axis, q)
        return FrameTransform(j.parent, j.child, tuple(float(v) for v in t), matrix_quaternion(r))

    def _revolute(self, j: UrdfJoint, q: float) -> FrameTransform:
        """``_transform`` of a revolute joint as a product of quaternions, in plain floats: origin rotation
        times the rotation by ``q`` about the axis (about 10x faster than the 3x3 matrices, for /tf at frame rate)."""
        t, (x0, y0, z0, w0), (ax, ay, az) = self._origin[j.name]
        s, c = math.sin(0.5 * q), math.cos(0.5 * q)
        xa, ya, za = ax * s, ay * s, az * s
        x = w0 * xa + x0 * c + y0 * za - z0 * ya
        y = w0 * ya - x0 * za + y0 * c + z0 * xa
        z = w0 * za + x0 * ya - y0 * xa + z0 * c
        w = w0 * c - x0 * xa - y0 * ya - z0 * za
        n = math.sqrt(x * x + y * y + z * z + w * w)
        if w < 0:
            n = -n
        return FrameTransform(j.parent, j.child, t, (x / n, y / n, z / n, w / n))

    def moving_transforms(self, positions: dict[str, float]) -> list[FrameTransform]:
        """Parent-to-child transforms of the movable joints; a joint missing from ``positions`` is at 0."""
        return [self._revolute(j, float(positions.get(j.name, 0.0))) if j.name in self._origin
                else self._transform(j, float(positions.get(j.name, 0.0))) for j in self.movable]

    def fixed_transforms(self) -> list[FrameTransform]:
        """Parent-to-child transforms of the fixed joints (/tf_static)."""
        return [self._transform(j, 0.0) for j in self.fixed]

    def link_poses(self, positions: dict[str, float]) -> dict[str, tuple[np.ndarray, np.ndarray]]:
        """Pose (translation (3,), rotation (3, 3)) of every link in the root link's frame."""
        poses = {self.root_link: (np.zeros(3), np.eye(3))}
        pending = list(self.joints)
        while pending:
            rest = []
            for j in pending:
                if j.parent not in poses:
                    rest.append(j)
                    continue
                tr = self._transform(j, float(positions.get(j.name, 0.0)))
                x, y, z, w = tr.rotation_xyzw
                r_local = np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                                    [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                                    [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])
                p_pos, p_rot = poses[j.parent]
                poses[j.child] = (p_pos + p_rot @ np.array(tr.translation_m), p_rot @ r_local)
            if len(rest) == len(pending):
                raise ValueError("URDF joints do not form a tree from one root link")
            pending = rest
        return poses

"""An arm: its URDF, which joints are actuated, and the facts a URDF cannot carry (numpy only).

Built once from an arm file (``urdf/<name>/arm.yaml``) or a bare URDF by :func:`pa10_dnbs.arm.load_arm`,
validated there, and handed to the plant, the controllers' factory, the reference rule, the nodes and the
reports. Every per-joint array has shape (n,), n = ``n_joints``, in chain order (base to tip).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..kinematics.urdf_chain import UrdfChain


@dataclass(frozen=True, eq=False)
class Arm:
    """A serial arm: URDF, actuated joints and their limits, rotor inertia and friction (SI units).

    Attributes
    ----------
    name : str
        What ``--arm`` calls it (the folder's name for a preset; the file's stem otherwise).
    description : str
        One line for people.
    file : Path
        The arm file it was read from (the URDF itself for a bare URDF).
    urdf : Path
        The URDF.
    joint_names : tuple of str
        Actuated joints, chain order: the controllers' and the topics' names.
    locked_joints : tuple of str
        Movable joints of the URDF that are not actuated (gripper fingers, excluded joints): held at
        ``locked_position_rad`` by the plant.
    locked_position_rad : tuple of float
        Where each locked joint is held: 0 where 0 is within its limits, else the nearer limit.
    lower_rad, upper_rad : ndarray (n,)
        URDF position limits, rad (+/-inf for a continuous joint).
    torque_limit_nm : ndarray (n,)
        Symmetric torque limits, N m (> 0).
    rotor_inertia_kgm2 : ndarray (n,)
        Reflected rotor inertia (armature) added to diag(M(q)), kg m^2 (>= 0).
    viscous_nms_per_rad, coulomb_nm : ndarray (n,)
        Friction Fv [N m s/rad] and Fc [N m] (>= 0).
    flange_link : str
        The link a payload is attached to.
    sources : dict
        Fact name -> where its numbers came from (one line each).
    settings : dict
        The arm's own config values (a config fragment, per-joint lists of length n), merged over what the
        rule of docs/arms.md derives and under the user's config.
    chain : UrdfChain
        The URDF's joints (parsed once).
    plant_urdf : Path or None
        What PyBullet loads: a cleaned copy of ``urdf`` (:mod:`pa10_dnbs.arm.plant_urdf`: massless links made
        explicit, inertias PyBullet would zero repaired, meshes dropped), or None for ``urdf`` itself.
    """

    name: str
    description: str
    file: Path
    urdf: Path
    joint_names: tuple[str, ...]
    locked_joints: tuple[str, ...]
    locked_position_rad: tuple[float, ...]
    lower_rad: np.ndarray
    upper_rad: np.ndarray
    torque_limit_nm: np.ndarray
    rotor_inertia_kgm2: np.ndarray
    viscous_nms_per_rad: np.ndarray
    coulomb_nm: np.ndarray
    flange_link: str
    sources: dict = field(default_factory=dict)
    settings: dict = field(default_factory=dict)
    chain: UrdfChain | None = None
    plant_urdf: Path | None = None

    @property
    def n_joints(self) -> int:
        """Number of actuated joints."""
        return len(self.joint_names)

    def index(self, joint: str) -> int:
        """Chain index of actuated joint ``joint``; KeyError naming the arm's joints otherwise."""
        try:
            return self.joint_names.index(joint)
        except ValueError:
            raise KeyError(f"{joint!r} is not a joint of arm {self.name} ({', '.join(self.joint_names)})") from None

    @property
    def physics_urdf(self) -> Path:
        """The URDF the plant loads: the cleaned copy where one was needed, else ``urdf``."""
        return self.plant_urdf if self.plant_urdf is not None else self.urdf

    def urdf_text(self) -> str:
        """The URDF as text (what /robot_description carries)."""
        return self.urdf.read_text()

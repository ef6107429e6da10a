"""The effective inertia each joint of an arm feels along a trajectory: what the gain rule is built on."""
from __future__ import annotations

import numpy as np

from ..arm.gain_rule import InertiaSweep
from .pybullet_plant import PyBulletArmPlant


def inertia_sweep(plant: PyBulletArmPlant, positions_rad: np.ndarray) -> InertiaSweep:
    """J_light and J_heavy of every joint over the poses ``positions_rad`` (m, n), from the arm's ``plant``
    (M(q) with its rotor inertia, the locked joints held)."""
    arm = plant.arm
    poses = np.clip(positions_rad, arm.lower_rad, arm.upper_rad)
    inv_diag = np.array([np.diag(np.linalg.inv(plant.mass_matrix(q))) for q in poses])
    minv = [np.linalg.inv(plant.mass_matrix(q)) for q in poses[:: max(1, len(poses) // 200)]]
    return InertiaSweep(1.0 / inv_diag.max(axis=0), 1.0 / inv_diag.min(axis=0), poses, tuple(minv))

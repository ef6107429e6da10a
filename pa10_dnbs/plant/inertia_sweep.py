"""The effective inertia each joint of an arm feels along a trajectory: what the gain rule is built on."""
from __future__ import annotations

import numpy as np

from ..arm import Arm
from ..arm.gain_rule import InertiaSweep
from .from_config import open_client
from .pybullet_plant import PlantParams, PyBulletArmPlant


def inertia_sweep(arm: Arm, positions_rad: np.ndarray, params: PlantParams) -> InertiaSweep:
    """J_light and J_heavy of every joint over the poses ``positions_rad`` (m, n), from the arm's plant with
    ``params`` (M(q) with their rotor inertia, the locked joints held)."""
    client = open_client()
    try:
        plant = PyBulletArmPlant(client, arm, params)
        poses = np.clip(positions_rad, arm.lower_rad, arm.upper_rad)
        inv_diag = np.array([np.diag(np.linalg.inv(plant.mass_matrix(q))) for q in poses])
        minv = [np.linalg.inv(plant.mass_matrix(q)) for q in poses[:: max(1, len(poses) // 200)]]
    finally:
        client.disconnect()
    return InertiaSweep(1.0 / inv_diag.max(axis=0), 1.0 / inv_diag.min(axis=0), poses, tuple(minv))

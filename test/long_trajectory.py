"""A long JointTrajectory file (m random points inside half of each joint's range), for timing the trajectory
intake and checking that its speed-ups keep every sample. Used by scripts/intake_timing.py and the tests."""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np


def long_trajectory(joint_names, lower_rad, upper_rad, m: int, seed: int = 0, spacing_s: float = 0.01,
                    velocities: bool = False) -> dict:
    """A trajectory mapping (the file's fields) of ``m`` points ``spacing_s`` apart, positions a random walk
    kept inside the middle half of each joint's limits; ``velocities``: each point gives them too (the last
    zero)."""
    rng = np.random.default_rng(seed)
    lo, hi = np.asarray(lower_rad, float), np.asarray(upper_rad, float)
    mid, half = 0.5 * (lo + hi), 0.25 * (hi - lo)
    walk = np.cumsum(rng.normal(0.0, 0.02, (m, len(lo))), axis=0)
    q = mid + half * np.sin(walk)          # inside [mid - half, mid + half]
    if m > 1:
        q[-1] = q[-2]
    points = []
    for i in range(m):
        pt = {"time_from_start": round((i + 1) * spacing_s, 9), "positions": q[i].tolist()}
        if velocities:
            pt["velocities"] = ([0.0] * len(lo) if i == m - 1
                                else (0.1 * np.cos(walk[i]) * half).tolist())
        points.append(pt)
    return {"joint_names": list(joint_names), "points": points}


def write_long_trajectory(path: Path, arm, m: int, seed: int = 0, **kw) -> Path:
    """``long_trajectory`` of ``arm`` (an Arm) written as JSON to ``path``; returns ``path``."""
    Path(path).write_text(json.dumps(long_trajectory(arm.joint_names, arm.lower_rad, arm.upper_rad, m, seed, **kw)))
    return Path(path)

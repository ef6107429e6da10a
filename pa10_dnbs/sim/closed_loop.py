"""Run the plant and seven per-joint controllers in one process, step by step."""
from __future__ import annotations

import time

import numpy as np

from .. import JOINT_NAMES
from ..controller_factory import build_controller, build_reference
from ..core.reference import ReferenceSample
from ..plant.from_config import open_client, plant_from_config
from ..run_data import RunData


def simulate(cfg: dict, controller: str, duration_s: float, progress: bool = False) -> RunData:
    """Closed loop for ``duration_s`` seconds of simulated time.

    At each step k every joint controller gets only its own x1(k), x2(k) and
    reference sample, returns its torque, and the plant advances to k+1.
    """
    dt = cfg["simulation"]["dt_s"]
    n = int(round(duration_s / dt))
    reference = build_reference(cfg)
    controllers = [build_controller(cfg, controller, j) for j in range(len(JOINT_NAMES))]
    client = open_client()
    try:
        plant = plant_from_config(cfg, client)
        nj = len(JOINT_NAMES)
        pos = np.empty((n, nj))
        vel = np.empty((n, nj))
        tau = np.empty((n, nj))
        ref = reference.position(np.arange(n))
        ref_vel = reference.velocity(np.arange(n))
        ref_ahead = reference.position(np.arange(n) + reference.preview_steps)

        bar = _progress_bar(n, controller) if progress else None
        u = np.empty(nj)
        t0 = time.perf_counter()
        for k in range(n):
            q, qd = plant.state
            pos[k] = q
            vel[k] = qd
            for j, ctrl in enumerate(controllers):
                u[j] = ctrl.step(q[j], qd[j], ReferenceSample(ref[k, j], ref_vel[k, j], ref_ahead[k, j]))
            plant.step(u)
            tau[k] = plant.applied_torque_nm
            if bar is not None and k % 500 == 499:
                bar.update(500)
        wall = time.perf_counter() - t0
        if bar is not None:
            bar.update(n - bar.n)
            bar.close()
        return RunData(controller=controller, dt_s=dt, joint_names=JOINT_NAMES,
                       torque_limit_nm=np.array(cfg["plant"]["torque_limit_nm"]),
                       position_rad=pos, velocity_rad_s=vel, reference_rad=ref, torque_nm=tau,
                       wall_time_s=wall, extra={"limit_hits": plant.limit_hits.tolist()})
    finally:
        client.disconnect()


def _progress_bar(n_steps: int, label: str):
    from tqdm import tqdm

    return tqdm(total=n_steps, desc=f"simulate {label}", unit="step", unit_scale=True, mininterval=0.5)

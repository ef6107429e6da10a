"""Run the plant and the arm's joint controllers in one process, step by step (no ROS).

The controllers are the nodes' own: one bank of n rows (one per joint) behind the same
state guard (``controller_factory.joint_loop``), so an in-process run equals the
lockstep node graph bit for bit, guards included.
"""
from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from ..controller_factory import joint_loop
from ..core.reference import ReferenceSample
from ..plant.engines import DEFAULT_ENGINE, open_plant
from ..report.progress import ProgressBar
from ..run_data import RunData
from ..run_steps import run_steps
from ..settings import Settings
from .computed_torque import ComputedTorqueController

CONTROLLERS = ("dnbs", "pid", "ctc")  # ctc: centralized computed torque with the plant's model, in-process only


@dataclass(frozen=True)
class Disturbances:
    """What the in-process loop can add between plant and controllers (the study's scenarios; not in the graph).

    position_noise_std_rad, velocity_noise_std_rad_s: white Gaussian noise on the x1 and x2 the controllers
    see (encoders), seeded by ``seed``; torque_delay_steps: each torque is applied that many steps late
    (zero torque until the first one arrives). The recorded run is the true state.
    """

    position_noise_std_rad: float = 0.0
    velocity_noise_std_rad_s: float = 0.0
    torque_delay_steps: int = 0
    seed: int = 0


def simulate(settings: Settings, controller: str, duration_s: float, progress: bool = False,
             init_states: list[dict] | None = None, disturbances: Disturbances | None = None,
             engine: str = DEFAULT_ENGINE, trajectory=None) -> RunData:
    """Closed loop for ``duration_s`` seconds of simulated time.

    At each step k every joint controller gets only its own x1(k), x2(k) and
    reference sample, returns its torque, and the plant advances to k+1.
    ``init_states``: one controller ``state_dict`` per joint to start from (a warm start).
    ``disturbances``: sensor noise and actuator delay (the study's scenarios); None: none.
    ``engine``: the plant's physics engine, pybullet (default) or mujoco (``plant/engines.py``).
    ``trajectory``: a JointTrajectory (``--trajectory FILE``) followed from step 0 instead of eq. 27; the
    reference node builds the same reference (controller_factory.py), so the lockstep graph gives the same bits.
    """
    dt = settings.simulation.dt_s
    n = run_steps(duration_s, dt)
    s = settings
    plant, close_plant = open_plant(s, engine)
    try:
        ctc = None
        if controller == "ctc":  # centralized, on the plant's own model: built here, behind the same guard
            ctc = ComputedTorqueController(plant, s.ctc.kp_per_s2, s.ctc.kd_per_s, s.plant.torque_limit_nm,
                                           s.ctc.on_saturation)
        reference, guarded = joint_loop(controller, s.arm, s.simulation, s.reference, s.plant.torque_limit_nm,
                                        s.guards, s.dnbs, s.pid, trajectory=trajectory, bank=ctc)
        if init_states is not None:
            for row, state in enumerate(init_states):
                guarded.controllers.load_state_dict(row, state, resume_steps=False)
        nj = plant.n_joints
        pos = np.empty((n, nj))
        vel = np.empty((n, nj))
        tau = np.empty((n, nj))
        steps = np.arange(n)
        ref = reference.position(steps)
        ref_vel = reference.velocity(steps)
        ref_ahead = reference.position(steps + reference.preview_steps)
        ref_acc = reference.acceleration(steps) if controller == "ctc" else [None] * n

        dist = disturbances or Disturbances()
        noise = _sensor_noise(dist, n, nj)
        delayed = [np.zeros(nj)] * dist.torque_delay_steps
        limit = np.asarray(s.plant.torque_limit_nm, dtype=float) * (1 + 1e-12)
        asked_beyond = np.zeros(nj, dtype=np.int64)   # steps a controller asked more than its joint's limit
        bar = ProgressBar(n, dt, f"simulate {controller}") if progress else None
        t0 = time.perf_counter()
        for k in range(n):
            q, qd = plant.state
            pos[k] = q
            vel[k] = qd
            if noise is not None:
                q, qd = q + noise[0][k], qd + noise[1][k]
            u = guarded.step(q, qd, ReferenceSample(ref[k], ref_vel[k], ref_ahead[k], ref_acc[k]))
            asked_beyond += np.abs(u) > limit
            if delayed:
                delayed.append(u)
                u = delayed.pop(0)
            plant.step(u)
            tau[k] = plant.applied_torque_nm
            if bar is not None and k % 100 == 99:
                bar.update(k + 1, float(np.abs(ref[k - 99:k + 1] - pos[k - 99:k + 1]).max()))
        wall = time.perf_counter() - t0
        if bar is not None:
            bar.update(n)
            bar.close()
        return RunData(controller=controller, dt_s=dt, joint_names=plant.joint_names,
                       torque_limit_nm=np.array(settings.plant.torque_limit_nm),
                       position_rad=pos, velocity_rad_s=vel, reference_rad=ref, torque_nm=tau,
                       wall_time_s=wall, extra={"limit_hits": plant.limit_hits.tolist(),
                                                "controllers": guarded.controllers,
                                                "guard_counters": [guarded.counters(row) for row in range(nj)],
                                                "torques_asked_beyond_limits": asked_beyond.tolist()})
    finally:
        close_plant()


def _sensor_noise(dist: Disturbances, n: int, nj: int):
    """(position noise (n, nj), velocity noise (n, nj)), or None without noise."""
    if dist.position_noise_std_rad == 0.0 and dist.velocity_noise_std_rad_s == 0.0:
        return None
    rng = np.random.default_rng(dist.seed)
    return (rng.normal(0.0, dist.position_noise_std_rad, (n, nj)),
            rng.normal(0.0, dist.velocity_noise_std_rad_s, (n, nj)))

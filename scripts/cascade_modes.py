#!/usr/bin/env python3
"""Does the decentralized cascade the rule gives an arm hold along its reference? Its sampled loop, linearized.

At poses along the arm's reference (every 50 ms; q and qd of the reference, the plant's own model), each
joint's loop as DNBS runs it, without and with its torque network's bias term:

- ``PD``: u = k_u e2, e2 = x_d_dot + k_a e1 - x2 (the linear part: DNBS's robust term, PID's PD);
- ``PD + adaptive bias``: u = k_u e2 + b, b += K U / E2 e2 every step: the network's constant term trained by
  its EKF, an integral action on e2 at K k_u per step (E2 = U / k_u by the rule); K is the EKF's steady gain for
  one weight from its q and r (0.095 at the default q = 0.01, r = 1).

The arm: M(q) + J_r, G = dh/dq and D = dh/dqd (h the bias torques, gravity and Coriolis, central differences);
the step is the plant's semi-implicit Euler at T. Printed: the fastest growth of the coupled linear loop
[1/s] (log |lambda| / T; > 0: a mode grows), its frequency and the joint that leads it, and per joint the
stiffness gravity takes away (max over the poses of -dg_j/dq_j) beside the position loop's k_a k_u. Frozen
poses only: a guide, not a proof (docs/arms.md, "Arms without rotor inertia").

    .venv/bin/python scripts/cascade_modes.py --arm iiwa
"""
from __future__ import annotations

import math
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
sys.path.insert(0, str(Path(__file__).resolve().parent))

import script_main  # noqa: E402  (first: a Ctrl-C while the modules load is one line)
import numpy as np  # noqa: E402
from flag_values import arm_settings  # noqa: E402
from pa10_dnbs.cli_values import OneLineParser, number_in  # noqa: E402
from pa10_dnbs.core.reference import Reference  # noqa: E402
from pa10_dnbs.plant.from_config import opened_plant, plant_params  # noqa: E402

POSE_STEP_S = 0.05
DIFF_STEP = 1e-4   # rad, rad/s: central differences of the bias torques


def ekf_gain(q: float, r: float) -> float:
    """The steady gain of a scalar Kalman filter with process noise q and measurement noise r (random walk)."""
    p = (q + math.sqrt(q * q + 4.0 * q * r)) / 2.0
    return p / (p + r)


def linearized(plant, q: np.ndarray, qd: np.ndarray):
    """(M^-1, G, D) at (q, qd): the inverse mass matrix and the bias torques' slopes in q and qd, (n, n) each."""
    n = q.size
    G, D = np.zeros((n, n)), np.zeros((n, n))
    for k in range(n):
        d = np.zeros(n)
        d[k] = DIFF_STEP
        G[:, k] = (plant.bias_torque(q + d, qd) - plant.bias_torque(q - d, qd)) / (2.0 * DIFF_STEP)
        D[:, k] = (plant.bias_torque(q, qd + d) - plant.bias_torque(q, qd - d)) / (2.0 * DIFF_STEP)
    return np.linalg.inv(plant.mass_matrix(q)), G, D


def step_matrix(dt_s: float, m_inv, G, D, k_a, k_u, k_i) -> np.ndarray:
    """The one-step map of (dq, dv, b) (3n,): e2 = -(k_a dq + dv), u = k_u e2 + b, b+ = b + k_i e2,
    v+ = v + T M^-1 (u - G dq - D dv), q+ = q + T v+ (k_i = 0: the PD alone, b stays 0)."""
    n = k_a.size
    eye, zero = np.eye(n), np.zeros((n, n))
    e2 = np.hstack([-np.diag(k_a), -eye, zero])
    u = np.diag(k_u) @ e2 + np.hstack([zero, zero, eye])
    v_next = np.hstack([zero, eye, zero]) + dt_s * m_inv @ (u - np.hstack([G, D, zero]))
    q_next = np.hstack([eye, zero, zero]) + dt_s * v_next
    b_next = np.hstack([zero, zero, eye]) + np.diag(k_i) @ e2
    return np.vstack([q_next, v_next, b_next])


def fastest_mode(dt_s: float, poses, k_a, k_u, k_i):
    """(growth [1/s], frequency [Hz], leading joint, pose index) of the fastest-growing mode over ``poses``
    ((M^-1, G, D) each)."""
    best = (-math.inf, 0.0, 0, 0)
    n = k_a.size
    size = 3 * n if np.any(k_i) else 2 * n   # without the bias, b stays 0: (dq, dv) alone
    for i, (m_inv, G, D) in enumerate(poses):
        values, vectors = np.linalg.eig(step_matrix(dt_s, m_inv, G, D, k_a, k_u, k_i)[:size, :size])
        j = int(np.argmax(np.abs(values)))
        growth = math.log(abs(values[j])) / dt_s
        if growth > best[0]:
            lead = int(np.argmax(np.abs(vectors[:n, j])))
            best = (growth, abs(np.angle(values[j])) / dt_s / (2.0 * math.pi), lead, i)
    return best


def main() -> int:
    ap = OneLineParser(description=__doc__.splitlines()[0])
    ap.add_argument("--arm", default="pa10", help="preset name, arm file or URDF")
    ap.add_argument("--ekf-gain", type=number_in(0.0, 1.0), default=None,
                    help="K of the bias's EKF, in (0, 1] (a Kalman gain; default: the torque network's steady "
                    "gain from its q and r)")
    a = ap.parse_args()
    settings = arm_settings(ap, a.arm)
    arm, run, ref_s = settings.arm, settings.simulation, settings.reference
    rt, tn = settings.dnbs.remedies.robust_term, settings.dnbs.torque_net
    k_a, k_u = np.asarray(rt.alpha_gain_per_s, float), np.asarray(rt.torque_gain_nms_per_rad, float)
    K = a.ekf_gain if a.ekf_gain is not None else ekf_gain(float(np.max(tn.q)), float(np.max(tn.r)))
    k_i = K * np.asarray(tn.output_scale_nm, float) / np.asarray(tn.error_scale_rad_s, float)
    dt = run.dt_s
    ref = Reference(ref_s.amplitude_rad, ref_s.envelope_rate_per_s3, ref_s.frequency_rad_s, dt_s=dt,
                    centre_rad=ref_s.centre_rad)
    steps = np.arange(0, int(round(run.duration_s / dt)) + 1, max(1, int(round(POSE_STEP_S / dt))))
    q_all = np.clip(ref.position(steps), arm.lower_rad, arm.upper_rad)
    with opened_plant(arm, plant_params(settings.plant, dt)) as plant:
        poses = [linearized(plant, q, qd) for q, qd in zip(q_all, ref.velocity(steps))]
    softening = np.max([np.maximum(0.0, -np.diag(G)) for _, G, _ in poses], axis=0) + 0.0   # no -0
    print(f"{arm.name}: the sampled cascade linearized at {len(poses)} poses of its reference (T = {dt * 1e3:g} ms)")
    for name, ki in (("PD", np.zeros_like(k_i)), (f"PD + adaptive bias (K = {K:.3g})", k_i)):
        growth, hz, lead, i = fastest_mode(dt, poses, k_a, k_u, ki)
        verdict = "a mode grows" if growth > 0 else "every mode decays"
        print(f"  {name}: fastest growth {growth:+.3f} /s at {hz:.2f} Hz, led by {arm.joint_names[lead]} "
              f"(t = {steps[i] * dt:.2f} s): {verdict}")
    w = max(7, *map(len, arm.joint_names))
    print(f"  {'joint':<{w}}  k_a k_u [N m/rad]  gravity takes [N m/rad]")
    for j, name in enumerate(arm.joint_names):
        flag = "  <- the PD alone cannot hold it" if softening[j] > k_a[j] * k_u[j] else ""
        print(f"  {name:<{w}}  {k_a[j] * k_u[j]:>16.4g}  {softening[j]:>23.4g}{flag}")
    return 0


if __name__ == "__main__":
    sys.exit(script_main.run(main, "cascade_modes", {"arm": "--arm"}, interrupted="the rows above are complete: "
                                                                                "run the same command again"))

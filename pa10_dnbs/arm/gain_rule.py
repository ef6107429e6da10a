"""Per-joint controller gains for any arm, from its model, read once (docs/arms.md, "The gain rule").

Each decentralized loop is, per joint j, a torque gain on a joint whose effective inertia J_j(q) changes
along the run. Sampled at T, the velocity loop J x2' = k_u (alpha - x2) diverges once T k_u / J > 2; the
coupled figure is the largest eigenvalue of T K^1/2 (M(q) + J_r)^-1 K^1/2 (K = diag k_u). So, with the
lightest effective inertia the joint ever feels along the reference, J_light = 1 / max_q (M + J_r)^-1_jj, and
the heaviest, J_heavy = 1 / min_q (M + J_r)^-1_jj:

- k_u = RHO J_light / T: the velocity loop's discrete-time figure is RHO at the lightest pose;
- k_a = clip(k_u / (SEPARATION J_heavy), K_A_MIN, K_A_MAX): the position loop SEPARATION times slower than
  the velocity loop at the heaviest pose;
- DNBS: U = the torque limit; E2 = torque limit / k_u (the e2 at which the linear term alone saturates);
- PID: Kd = k_u, Kp = k_a k_u, Ki = Kp k_a / 4 (the outer pair critically damped).

The model enters here only (plant/inertia_sweep.py reads M(q) once, before the run): at run time every controller still sees its own joint alone. The rule warns
(one line, naming the joint) where J_heavy / J_light > INERTIA_RATIO_WARN (one fixed gain is either slow at
the heavy pose or unstable at the light one), where the coupled figure exceeds COUPLED_WARN, and where the
plant's explicit viscous friction is near its own limit (T Fv / J_light > 1).
"""
from __future__ import annotations

import sys
from dataclasses import dataclass

import numpy as np

from .arm import Arm

RHO = 0.4               # T k_u / J_light: the velocity loop's discrete-time figure at the lightest pose (< 2)
SEPARATION = 8.0        # velocity-loop bandwidth at the heaviest pose / k_a
K_A_MIN, K_A_MAX = 5.0, 20.0   # 1/s: the PA10's hand-tuned k_a span 10-20
INERTIA_RATIO_WARN = 10.0
COUPLED_WARN = 1.0
SWEEP_STEP_S = 0.02     # the reference is sampled every 20 ms for the inertia sweep


@dataclass(frozen=True)
class InertiaSweep:
    """Effective inertias along a reference: light, heavy (n,) [kg m^2], and (M + J_r)^-1 at up to 200 poses."""

    light_kgm2: np.ndarray
    heavy_kgm2: np.ndarray
    poses: np.ndarray            # (m, n) the sampled reference positions [rad]
    inverse_mass: tuple          # of (n, n) (M(q) + J_r)^-1 [1/(kg m^2)], for the coupled figure


def coupled_figure(sweep: InertiaSweep, k_u: np.ndarray, dt_s: float) -> float:
    """max over the sweep's poses of the largest eigenvalue of T K^1/2 (M + J_r)^-1 K^1/2 (diverges above 2)."""
    s = np.sqrt(k_u)
    return float(max(np.linalg.eigvalsh(dt_s * (s[:, None] * m * s[None, :])).max() for m in sweep.inverse_mass))


def gain_rule(arm: Arm, sweep: InertiaSweep, dt_s: float) -> dict:
    """The per-joint config values the rule gives (a config fragment, lists of n floats)."""
    k_u = RHO * sweep.light_kgm2 / dt_s
    k_a = np.clip(k_u / (SEPARATION * sweep.heavy_kgm2), K_A_MIN, K_A_MAX)
    tau = arm.torque_limit_nm
    kp = k_a * k_u
    return {
        "dnbs": {"torque_net": {"output_scale_nm": tau.tolist(), "error_scale_rad_s": (tau / k_u).tolist()},
                 "remedies": {"robust_term": {"alpha_gain_per_s": k_a.tolist(),
                                              "torque_gain_nms_per_rad": k_u.tolist()}}},
        "pid": {"kp": kp.tolist(), "ki": (kp * k_a / 4.0).tolist(), "kd": k_u.tolist()},
    }


def rule_warnings(arm: Arm, sweep: InertiaSweep, k_u: np.ndarray, dt_s: float) -> list[str]:
    """One line per joint (or for the arm) where the rule cannot promise what it aims at."""
    out = []
    ratio = sweep.heavy_kgm2 / sweep.light_kgm2
    for j, name in enumerate(arm.joint_names):
        if ratio[j] > INERTIA_RATIO_WARN:
            out.append(f"arm {arm.name}: joint {name}: effective inertia varies {ratio[j]:.0f}x along the reference "
                       f"({sweep.light_kgm2[j]:.3g}-{sweep.heavy_kgm2[j]:.3g} kg m^2): one fixed gain is slow at the "
                       f"heavy pose (no rotor inertia in the arm file?)")
        if dt_s * arm.viscous_nms_per_rad[j] / sweep.light_kgm2[j] > 1.0:
            out.append(f"arm {arm.name}: joint {name}: T Fv / J = "
                       f"{dt_s * arm.viscous_nms_per_rad[j] / sweep.light_kgm2[j]:.2f} > 1: the plant's explicit "
                       f"viscous friction is near its stability limit (2)")
    figure = coupled_figure(sweep, k_u, dt_s)
    if figure > COUPLED_WARN:
        out.append(f"arm {arm.name}: the coupled loop figure max eig(T K^1/2 M^-1 K^1/2) is {figure:.2f} (> "
                   f"{COUPLED_WARN:g}; diverges above 2): lower dnbs...torque_gain_nms_per_rad in the arm file")
    return out


def report_rule(arm: Arm, sweep: InertiaSweep, fragment: dict, dt_s: float, stream=None) -> None:
    """Print what the rule derived, one line per joint, and its warnings (so that a placeholder shows), on
    ``stream`` (stderr when None)."""
    stream = sys.stderr if stream is None else stream
    rt = fragment["dnbs"]["remedies"]["robust_term"]
    k_u = np.array(rt["torque_gain_nms_per_rad"])
    print(f"arm {arm.name}: {arm.n_joints} joints from {arm.file}; gains by the rule of docs/arms.md "
          f"(figure {coupled_figure(sweep, k_u, dt_s):.2f} < 2)", file=stream)
    print("  joint   limits [rad]       torque [N m]  rotor [kg m^2]  J light-heavy [kg m^2]   k_u     k_a",
          file=stream)
    for j, name in enumerate(arm.joint_names):
        print(f"  {name:<7} [{arm.lower_rad[j]:+.2f}, {arm.upper_rad[j]:+.2f}]  {arm.torque_limit_nm[j]:>9.1f}  "
              f"{arm.rotor_inertia_kgm2[j]:>13.4g}  {sweep.light_kgm2[j]:>9.4g} - {sweep.heavy_kgm2[j]:<9.4g}  "
              f"{k_u[j]:>7.4g} {rt['alpha_gain_per_s'][j]:>6.3g}", file=stream)
    for line in rule_warnings(arm, sweep, k_u, dt_s):
        print(f"warning: {line}", file=stream)

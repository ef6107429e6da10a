"""Per-joint controller gains for any arm, from its model, read once (docs/arms.md, "The gain rule").

Each decentralized loop is, per joint j, a torque gain on a joint whose effective inertia J_j(q) changes
along the run. Sampled at T, the velocity loop J x2' = k_u (alpha - x2) diverges once T k_u / J > 2; the
coupled figure is the largest eigenvalue of T K^1/2 (M(q) + J_r)^-1 K^1/2 (K = diag k_u). So, with the
lightest effective inertia the joint ever feels along the reference, J_light = 1 / max_q (M + J_r)^-1_jj, and
the heaviest, J_heavy = 1 / min_q (M + J_r)^-1_jj:

- k_u = RHO J_light / T: the velocity loop's discrete-time figure is RHO at the lightest pose;
- k_a = min(k_u / (SEPARATION J_heavy), K_A_MAX): the position loop SEPARATION times slower than the velocity
  loop at the heaviest pose (never raised above that: a faster outer loop would invert the cascade);
- DNBS: U = the torque limit; E2 = torque limit / k_u (the torque network adapts at k_u per step); E1 =
  E1_BASE s^3 on every joint, s = max(1, the arm's largest J_heavy / J_light / RATIO_SAFE). Up to a 10x
  inertia range E1 = E1_BASE (the presets: nothing changes). Beyond, the alpha networks of every joint slow
  with the arm's largest range: through the coupling that makes the range, the outer adaptation must stay
  below the slowest inner loop (measured: without this the SO-101's alpha weights ran to 700 and every joint
  diverged; s^2 was not enough on the SO-101 and the Panda without rotor inertia, s^3 was; slowing E2 as well
  cost 10-50 % of RMS on every bare arm and let the Kinova's joint 4 pass 1 rad);
- DNBS slope bound, on where the arm's largest range exceeds RATIO_SAFE (within it the rule's gains keep the
  margin without it, and the Panda preset's payload runs would touch the box: its bits would change): the
  torque network's slope in x1, x2 and alpha stays within f = min(SLOPE_FRACTION,
  FIGURE_MAX / figure - 1) of the linear term's own gain in that input (figure: the coupled figure of k_u), so
  the loop's gains stay within (1 +- f) of the linear term's and the coupled figure below FIGURE_MAX < 2
  (with the alpha networks at E1_BASE, the Panda without rotor inertia grew torque weights of alpha and x2 of
  15-60; test_slope_bound.py has a joint that diverges without the bound and not with it);
- PID: Kd = k_u, Kp = k_a k_u, Ki = Kp k_a / 4 (the outer pair critically damped).

The model enters here only (plant/inertia_sweep.py reads M(q) once, before the run): at run time every
controller still sees its own joint alone. The rule warns (one line, naming the joint) where J_heavy /
J_light > INERTIA_RATIO_WARN (one fixed gain is slow at the heavy pose: the line gives the joint's
discrete-time limit and the rotor inertia that would bring the range to 10x), where the coupled figure
exceeds COUPLED_WARN, and where the plant's explicit viscous friction is near its own limit (T Fv / J_light >
1).
"""
from __future__ import annotations

import sys
from dataclasses import dataclass

import numpy as np

from ..number_text import fixed
from .arm import Arm

RHO = 0.4               # T k_u / J_light: the velocity loop's discrete-time figure at the lightest pose (< 2)
SEPARATION = 8.0        # velocity-loop bandwidth at the heaviest pose / k_a
K_A_MAX = 20.0          # 1/s: the PA10's hand-tuned k_a span 10-20
RATIO_SAFE = 10.0       # J_heavy / J_light up to which the adaptation gains are the PA10-like ones
E1_BASE = 0.5           # rad: E1 where the inertia range is within RATIO_SAFE
FIGURE_MAX = 1.5        # the coupled figure the linear term plus the network's slope may reach (< 2)
SLOPE_FRACTION = 0.5    # the network's slope in each input / the linear term's gain in it, at most
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
    k_a = np.minimum(k_u / (SEPARATION * sweep.heavy_kgm2), K_A_MAX)
    slow = np.maximum(1.0, sweep.heavy_kgm2 / sweep.light_kgm2 / RATIO_SAFE)
    tau = arm.torque_limit_nm
    kp = k_a * k_u
    fraction = float(np.clip(FIGURE_MAX / coupled_figure(sweep, k_u, dt_s) - 1.0, 0.0, SLOPE_FRACTION))
    e1 = np.full(arm.n_joints, E1_BASE * float(slow.max()) ** 3)
    return {
        "dnbs": {"alpha_net": {"error_scale_rad": e1.tolist()},
                 "torque_net": {"output_scale_nm": tau.tolist(), "error_scale_rad_s": (tau / k_u).tolist()},
                 "remedies": {"robust_term": {"alpha_gain_per_s": k_a.tolist(),
                                              "torque_gain_nms_per_rad": k_u.tolist()},
                              "slope_bound": {"enabled": bool(slow.max() > 1.0),
                                              "fraction": [fraction] * arm.n_joints}}},
        "pid": {"kp": kp.tolist(), "ki": (kp * k_a / 4.0).tolist(), "kd": k_u.tolist()},
    }


def discrete_limit_rad_s(light_kgm2, heavy_kgm2, dt_s: float):
    """The largest velocity-loop bandwidth [rad/s] a fixed gain can give at the heavy pose while the sampled
    loop stays stable at the light one (T k_u / J_light < 2): 2 J_light / (T J_heavy)."""
    return 2.0 * np.asarray(light_kgm2) / (dt_s * np.asarray(heavy_kgm2))


def rotor_inertia_for_ratio(light_kgm2, heavy_kgm2, ratio: float = INERTIA_RATIO_WARN):
    """The reflected rotor inertia [kg m^2] that, added to both ends of the range, brings J_heavy / J_light down
    to ``ratio``: (J_heavy - ratio J_light) / (ratio - 1), at least 0."""
    return np.maximum(0.0, (np.asarray(heavy_kgm2) - ratio * np.asarray(light_kgm2)) / (ratio - 1.0))


def rule_warnings(arm: Arm, sweep: InertiaSweep, k_u: np.ndarray, dt_s: float) -> list[str]:
    """One line per joint (or for the arm) where the rule cannot promise what it aims at."""
    out = []
    ratio = sweep.heavy_kgm2 / sweep.light_kgm2
    for j, name in enumerate(arm.joint_names):
        if ratio[j] > INERTIA_RATIO_WARN:
            lo, hi = sweep.light_kgm2[j], sweep.heavy_kgm2[j]
            out.append(f"arm {arm.name}: joint {name}: effective inertia varies {ratio[j]:.0f}x along the reference "
                       f"({lo:.3g}-{hi:.3g} kg m^2): at T = {dt_s * 1e3:g} ms one fixed gain gives at most "
                       f"{discrete_limit_rad_s(lo, hi, dt_s):.3g} rad/s of velocity bandwidth at the heavy pose "
                       f"(2 J_light / (T J_heavy); the rule takes {RHO / 2:g} of it); add the reflected rotor "
                       f"inertia N^2 Jm (rotor_inertia_kgm2, >= {rotor_inertia_for_ratio(lo, hi):.3g} kg m^2 "
                       f"brings the range to {INERTIA_RATIO_WARN:g}x)")
        if dt_s * arm.viscous_nms_per_rad[j] / sweep.light_kgm2[j] > 1.0:
            figure = fixed(dt_s * arm.viscous_nms_per_rad[j] / sweep.light_kgm2[j], ".2f")
            out.append(f"arm {arm.name}: joint {name}: T Fv / J = {figure} > 1: the plant's explicit "
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
    w = max([7, *map(len, arm.joint_names)])   # the name column, as wide as the longest name
    print(f"  {'joint':<{w}} limits [rad]       torque [N m]  rotor [kg m^2]  J light-heavy [kg m^2]   k_u     k_a",
          file=stream)
    for j, name in enumerate(arm.joint_names):
        print(f"  {name:<{w}} [{fixed(arm.lower_rad[j], '+.2f')}, {fixed(arm.upper_rad[j], '+.2f')}]  "
              f"{fixed(arm.torque_limit_nm[j], '>9.1f')}  "
              f"{arm.rotor_inertia_kgm2[j]:>13.4g}  {sweep.light_kgm2[j]:>9.4g} - {sweep.heavy_kgm2[j]:<9.4g}  "
              f"{k_u[j]:>7.4g} {rt['alpha_gain_per_s'][j]:>6.3g}", file=stream)
    for line in rule_warnings(arm, sweep, k_u, dt_s):
        print(f"warning: {line}", file=stream)

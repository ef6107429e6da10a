#!/usr/bin/env python3
"""Would an EKF that slows its learning under encoder noise put DNBS below PID there, and at what cost?

The study's ``encoder_noise`` scenario (1e-4 rad on x1, 1e-3 rad/s on x2, white at 1 kHz) on the collection's
arm files (or the presets), seeds 0..N-1: DNBS as shipped, DNBS with a noise-scaled R, and PID. The noise-scaled R is
what an adaptive Kalman filter would do with the measurement noise it estimates (covariance matching): each joint
estimates its own encoder noise from the third differences of the x1 it receives (white noise of std s gives
them variance 20 s^2; a smooth motion almost none: jerk T^3), averaged over ``--window`` s, and both of its
networks' R become R max(1, (s_hat / floor)^2). Without noise s_hat stays below the floor and the run is the
shipped one bit for bit: the last column is the largest (s_hat / floor)^2 of a run of the scenario ``--check``
names (below 1: R never moved; test_noise_scaled_r checks the bits).

Worst joint's RMS over the second half [rad]: DNBS's worst seed, PID's best (the study's comparison); and, with
the shipped R (seed 0), how much of the error each joint sees is noise. Figures only; nothing asserted, no
setting of the project changed (docs/arms.md, the 2-DOF arm).

    .venv/bin/python scripts/noise_scaled_r.py --arms twodof,so100,ur5       # ~35 s per arm on 2 cores
"""
from __future__ import annotations

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
sys.path.insert(0, str(Path(__file__).resolve().parent))

import script_main  # noqa: E402  (first: a Ctrl-C while the modules load is one line)
import numpy as np  # noqa: E402
from flag_values import arm_settings, names_in  # noqa: E402
from pa10_dnbs.arm.arm_path import preset_names  # noqa: E402
from pa10_dnbs.cli_values import OneLineParser, positive, seconds, whole_in  # noqa: E402
from pa10_dnbs.run_steps import run_steps  # noqa: E402
from pa10_dnbs.study.collection import ARMS, arm_file  # noqa: E402
from pa10_dnbs.study.scenarios import SCENARIOS  # noqa: E402
from wrapped_loop import second_half_worst_rms  # noqa: E402

THIRD_DIFFERENCE_GAIN = 20.0   # var(x[k] - 3 x[k-1] + 3 x[k-2] - x[k-3]) / var(x) for white x: 1 + 9 + 9 + 1


class NoiseScaledR:
    """The run's joint loop, its DNBS bank's R (both networks of each joint) scaled by that joint's noise estimate
    before every step (``scale`` False: only watched). ``largest_factor`` (n,): the largest (s_hat / floor)^2 seen,
    whether above 1 or not; ``error_to_noise`` (n,): the mean square of e1 = x_d - x1 as received over the last
    ``window_s``, over s_hat^2, averaged over the run's second half (1: the error the joint sees is all noise)."""

    def __init__(self, loop, dt_s: float, floor_rad: float, window_s: float, scale: bool = True):
        self.loop, self.scale = loop, scale
        bank = loop.controllers
        self.r, self.n = bank.ekf.r, bank.n_joints      # the bank's own array (the compiled step reads it too)
        self.r0 = self.r.copy()
        self.floor_sq, self.smooth = floor_rad ** 2, dt_s / window_s
        self.last: list[np.ndarray] = []
        self.mean_sq = np.zeros(self.n)
        self.largest_factor = np.zeros(self.n)
        self.error_sq = np.zeros(self.n)
        self.ratios: list[np.ndarray] = []

    def step(self, x1, x2, reference):
        self.last = (self.last + [np.array(x1, dtype=float)])[-4:]
        if len(self.last) == 4:
            a, b, c, d = self.last
            third = d - 3.0 * c + 3.0 * b - a
            self.mean_sq += self.smooth * (third * third - self.mean_sq)
            ratio = self.mean_sq / THIRD_DIFFERENCE_GAIN / self.floor_sq
            self.largest_factor = np.maximum(self.largest_factor, ratio)
            e1 = reference.position_rad - np.asarray(x1, dtype=float)
            self.error_sq += self.smooth * (e1 * e1 - self.error_sq)
            self.ratios.append(self.error_sq * THIRD_DIFFERENCE_GAIN / np.maximum(self.mean_sq, 1e-300))
            if self.scale:
                factor = np.maximum(1.0, ratio)
                self.r[:self.n] = self.r0[:self.n] * factor
                self.r[self.n:] = self.r0[self.n:] * factor
        return self.loop.step(x1, x2, reference)

    @property
    def error_to_noise(self) -> np.ndarray:
        return np.mean(self.ratios[len(self.ratios) // 2:], axis=0)

    def __getattr__(self, name: str):
        """The rest of the loop's interface (its controllers, its guard's counters)."""
        if name == "loop":
            raise AttributeError(name)
        return getattr(self.loop, name)


def run(settings, scenario: str, controller: str, seed: int, duration_s: float, scaled, scale: bool = True):
    """(worst joint's RMS over the second half [rad], the wrapper or None) of one run; ``scaled`` = None or
    (floor [rad], window [s]): the loop behind a NoiseScaledR that scales R (``scale``) or only watches."""
    wrapped: list[NoiseScaledR] = []

    def wrap(loop, dt_s):
        wrapped.append(NoiseScaledR(loop, dt_s, *scaled, scale=scale))
        return wrapped[-1]

    rms = second_half_worst_rms(settings, scenario, controller, seed, duration_s, None if scaled is None else wrap)
    return rms, (wrapped[0] if wrapped else None)


def main() -> int:
    ap = OneLineParser(description=__doc__.splitlines()[0])
    ap.add_argument("--arms", type=names_in([*ARMS, *preset_names()]), default=",".join(ARMS),
                    help="the collection's arms (their arm files; default: all), or the presets")
    ap.add_argument("--seeds", type=whole_in(1), default=3)
    ap.add_argument("--duration", type=seconds, default=20.0, help="simulated seconds per run")
    ap.add_argument("--floor", type=positive, default=1e-5, help="noise [rad] below which R is left as it is")
    ap.add_argument("--window", type=positive, default=0.5, help="averaging time of the noise estimate [s]")
    ap.add_argument("--check", choices=sorted(SCENARIOS), default="nominal",
                    help="a scenario without noise, run once per arm with the scaled R: its largest factor "
                         "(< 1: R untouched)")
    a = ap.parse_args()
    scaled = (a.floor, a.window)
    print(f"encoder_noise, {a.duration:g} s, seeds 0-{a.seeds - 1}; noise-scaled R: floor {a.floor:g} rad, window "
          f"{a.window:g} s. Worst-joint RMS over the second half [rad]: DNBS's worst seed, PID's best\n\n"
          f"| arm | DNBS | DNBS, noise-scaled R | PID | R factor reached | below PID: DNBS / scaled | DNBS: e1's mean "
          f"square / s_hat^2, per joint | {a.check}: largest (s_hat / floor)^2 |\n|---|---|---|---|---|---|---|---|")
    for key in a.arms:
        settings = arm_settings(ap, key if key in preset_names() else str(arm_file(key)))
        run_steps(a.duration, settings.simulation.dt_s)   # too short a run: refused before the first row
        dnbs = [run(settings, "encoder_noise", "dnbs", sd, a.duration, scaled, scale=False) for sd in range(a.seeds)]
        both = [run(settings, "encoder_noise", "dnbs", sd, a.duration, scaled) for sd in range(a.seeds)]
        pid = [run(settings, "encoder_noise", "pid", sd, a.duration, None)[0] for sd in range(a.seeds)]
        clean = run(settings, a.check, "dnbs", 0, a.duration, scaled)[1].largest_factor.max()
        worst, worst_scaled, best = max(x for x, _ in dnbs), max(x for x, _ in both), min(pid)
        seen = dnbs[0][1].error_to_noise
        print(f"| {key} | {worst:.2e} | {worst_scaled:.2e} | {best:.2e} | "
              f"{max(w.largest_factor.max() for _, w in both):.0f} | {'yes' if worst < best else 'no'} / "
              f"{'yes' if worst_scaled < best else 'no'} | {seen.min():.2f}-{seen.max():.2f} | {clean:.2g} |",
              flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(script_main.run(main, "noise_scaled_r", {"duration_s": "--duration"},
                             interrupted="the rows above are complete: run the same command again"))

#!/usr/bin/env python3
"""Does filtering what the controllers see separate DNBS from PID under the study's encoder noise?

The study's ``encoder_noise`` scenario (1e-4 rad on x1, 1e-3 rad/s on x2, white at 1 kHz) on one arm, DNBS
and PID, seeds 0..N-1, with the same per-joint filter in front of both controllers (each joint filters only
its own x1, x2):

- ``none``: what the study runs;
- ``position``: x1 fused with the integrated measured x2, ``q+ = q + T v; q += L (x1 - q+)``, L the
  steady-state Kalman gain of this noise (velocity noise as the process noise, position noise as the
  measurement's);
- ``position+lowpass W``: the same, and x2 through a first-order low-pass of cut-off W rad/s.

Worst joint's RMS over the second half [rad]. Figures only; nothing asserted (docs/arms.md, the 2-DOF arm).

    .venv/bin/python scripts/encoder_noise_filters.py --arm urdf/collection/twodof/arm.yaml --seeds 3
"""
from __future__ import annotations

import math
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
sys.path.insert(0, str(Path(__file__).resolve().parent))

import script_main  # noqa: E402  (first: a Ctrl-C while the modules load is one line)
from flag_values import arm_settings, list_of  # noqa: E402
from pa10_dnbs.cli_values import OneLineParser, positive, seconds, whole_in  # noqa: E402
from pa10_dnbs.run_steps import run_steps  # noqa: E402
from pa10_dnbs.study.scenarios import scenario_settings  # noqa: E402
from wrapped_loop import second_half_worst_rms  # noqa: E402


def kalman_gain(dt_s: float, position_std_rad: float, velocity_std_rad_s: float) -> float:
    """Steady-state gain of q+ = q + T v_measured, measured q: process variance (T sv)^2, measurement sq^2."""
    w, v = (dt_s * velocity_std_rad_s) ** 2, position_std_rad ** 2
    p = (w + math.sqrt(w * w + 4.0 * w * v)) / 2.0
    return p / (p + v)


class FilteredLoop:
    """The joint loop the run built, behind one filter per joint: ``step`` gets the measured x1, x2 (n,)."""

    def __init__(self, loop, dt_s: float, gain: float, cutoff_rad_s: float | None):
        self.loop = loop
        self.dt_s, self.gain = dt_s, gain
        self.smooth = 1.0 if cutoff_rad_s is None else dt_s * cutoff_rad_s / (1.0 + dt_s * cutoff_rad_s)
        self.q = self.v = None

    def step(self, x1, x2, reference):
        if self.q is None:
            self.q, self.v = x1.copy(), x2.copy()
        else:
            self.v = self.v + self.smooth * (x2 - self.v)
            ahead = self.q + self.dt_s * self.v
            self.q = ahead + self.gain * (x1 - ahead)
        return self.loop.step(self.q, self.v, reference)

    def __getattr__(self, name: str):
        """The rest of the loop's interface (its controllers, its guard's counters), unfiltered."""
        if name == "loop":   # not set yet (a copy being made): no loop to ask
            raise AttributeError(name)
        return getattr(self.loop, name)


def worst_rms(settings, controller: str, seed: int, duration_s: float, filt) -> float:
    """One run of the scenario with ``filt`` = None or (gain, cut-off or None) in front of the controllers."""
    wrap = None if filt is None else (lambda loop, dt_s: FilteredLoop(loop, dt_s, *filt))
    return second_half_worst_rms(settings, "encoder_noise", controller, seed, duration_s, wrap)


def main() -> int:
    ap = OneLineParser(description=__doc__.splitlines()[0])
    ap.add_argument("--arm", default="urdf/collection/twodof/arm.yaml", help="preset name, arm file or URDF")
    ap.add_argument("--seeds", type=whole_in(1), default=3)
    ap.add_argument("--duration", type=seconds, default=20.0, help="simulated seconds per run")
    ap.add_argument("--cutoffs", type=list_of(positive, allow_empty=True), default="200,50",
                    help="velocity low-pass cut-offs to try [rad/s]")
    a = ap.parse_args()
    settings = arm_settings(ap, a.arm)
    run_steps(a.duration, settings.simulation.dt_s)   # too short a run: refused before the first row
    _, dist = scenario_settings(settings, "encoder_noise", 0)
    gain = kalman_gain(settings.simulation.dt_s, dist.position_noise_std_rad, dist.velocity_noise_std_rad_s)
    variants = [("none", None), (f"position (L = {gain:.4f})", (gain, None))]
    variants += [(f"position+lowpass {float(c):g} rad/s", (gain, c)) for c in a.cutoffs]
    print(f"encoder_noise on {settings.arm.name}, {a.duration:g} s, seeds 0-{a.seeds - 1}: worst-joint RMS over "
          "the second half [rad]\n\n| filter | DNBS | PID |\n|---|---|---|")
    for name, filt in variants:
        cells = [", ".join(f"{worst_rms(settings, c, sd, a.duration, filt):.2e}" for sd in range(a.seeds))
                 for c in ("dnbs", "pid")]
        print(f"| {name} | {cells[0]} | {cells[1]} |", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(script_main.run(main, "encoder_noise_filters", {"arm": "--arm", "duration_s": "--duration"},
                             interrupted="the rows above are complete: run the same command again"))

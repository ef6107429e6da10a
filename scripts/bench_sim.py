#!/usr/bin/env python3
"""Benchmark: the in-process closed loop (DNBS and PID, 20 s): speed, and the DNBS targets.

Prints, from --repeat interleaved runs of each controller (DNBS once per kernel of ``--kernels``: numpy,
the reference; c, the same step compiled; auto, the default of config/default.yaml: c where it builds,
else numpy, the line it prints says which):
- the loop's wall time per 1 ms step (plant + 7 controllers, behind their state guards) and the real-time
  factor, best and median;
- each DNBS run's cost relative to the PID run (ratio of the medians, and of the best runs), and whether
  the kernels' runs were bit-identical;
- the DNBS figures of the default config against the controller's must and aim targets (docs/controller.md):
  settling into the 1e-2 rad band, max |e|, torque variation, steps at the limit after 0.2 s, RMS [10, 20) s.
Figures only; asserts nothing (the machines are shared and noisy: the load average is printed).

    python scripts/bench_sim.py [--duration 20] [--repeat 5] [--kernels numpy,auto] [--save-record FILE]

``--save-record benchmarks/bench_sim.json``: the figures as a record (scripts/bench_record.py).
"""
from __future__ import annotations

import statistics
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
sys.path.insert(0, str(Path(__file__).resolve().parent))

import script_main  # noqa: E402  (first: a Ctrl-C while the modules load is one line)
import bench_record  # noqa: E402
from flag_values import names_in  # noqa: E402

import numpy as np  # noqa: E402

from pa10_dnbs.accel.choice import KERNELS, auto_kernel  # noqa: E402
from pa10_dnbs.cli_values import OneLineParser, seconds, whole_in  # noqa: E402
from pa10_dnbs.config import default_config_path  # noqa: E402
from pa10_dnbs.run_settings import build_settings  # noqa: E402
from pa10_dnbs.settings import replace_in  # noqa: E402
from pa10_dnbs.report.metrics_file import metrics_dict, metrics_settings  # noqa: E402
from pa10_dnbs.sim.closed_loop import simulate  # noqa: E402

# (figure, must, aim) of the default config's cold-start DNBS run, worst joint
TARGETS = [("worst_settling_time_s", 1.0, 0.5), ("worst_max_abs_error_run_rad", 0.12, 0.12),
           ("worst_torque_variation", 10.0, 3.0), ("worst_saturated_fraction_after_s", 0.0, 0.0),
           ("worst_rms_error_rad", 6e-4, 3e-4)]


def _load() -> str:
    return " ".join(Path("/proc/loadavg").read_text().split()[:3])


def main() -> int:
    ap = OneLineParser(description=__doc__.splitlines()[0])
    ap.add_argument("--duration", type=seconds, default=20.0, help="simulated seconds")
    ap.add_argument("--repeat", type=whole_in(1), default=5)
    ap.add_argument("--kernels", type=names_in(KERNELS), default="numpy,auto",
                    help="comma-separated DNBS kernels to run: numpy, c, auto")
    bench_record.add_argument(ap)
    args = ap.parse_args()
    record = bench_record.Record.start("bench_sim")
    settings = build_settings(default_config_path())
    kernels = args.kernels
    print(f"in-process closed loop, {args.duration:g} s simulated, T = {settings.simulation.dt_s * 1e3:g} ms, "
          f"{args.repeat} interleaved runs per controller; load average {_load()}")
    if "auto" in kernels:
        print(auto_kernel().line)
    runs = {f"dnbs/{k}": ("dnbs", k) for k in kernels} | {"pid": ("pid", None)}
    per_step = {label: [] for label in runs}
    last = {}
    for _ in range(args.repeat):
        for label, (kind, kernel) in runs.items():
            run_settings = settings
            if kernel:
                run_settings = replace_in(settings, "dnbs.kernel", kernel)
            run = simulate(run_settings, kind, args.duration)
            per_step[label].append(run.wall_time_s / run.n_steps * 1e6)
            last[label] = run
    for label, us in per_step.items():
        print(f"{label:10s} {min(us):6.1f} us per step best, {statistics.median(us):6.1f} median "
              f"(real-time factor {1e3 / min(us):.1f}x best, {1e3 / statistics.median(us):.1f}x median)")
    p = per_step["pid"]
    figures = {"duration_s": args.duration, "repeat": args.repeat, "kernels": kernels,
               "us_per_step": {label: {"best": round(min(us), 2), "median": round(statistics.median(us), 2)}
                               for label, us in per_step.items()},
               "dnbs_over_pid_median": {}, "dnbs_over_pid_best": {}}
    if "auto" in kernels:
        figures["auto_kernel"] = auto_kernel().line
    for k in kernels:
        d = per_step[f"dnbs/{k}"]
        figures["dnbs_over_pid_median"][k] = round(statistics.median(d) / statistics.median(p), 3)
        figures["dnbs_over_pid_best"][k] = round(min(d) / min(p), 3)
        print(f"DNBS run ({k}) / PID run: {statistics.median(d) / statistics.median(p):.2f} (medians), "
              f"{min(d) / min(p):.2f} (best runs)")
    if len(kernels) > 1:
        a, *others = (last[f"dnbs/{k}"] for k in kernels)
        same = all(np.array_equal(getattr(a, f), getattr(b, f)) for b in others
                   for f in ("position_rad", "velocity_rad_s", "torque_nm"))
        print(f"the kernels' last runs are bit-identical (positions, velocities, torques): {'yes' if same else 'NO'}")
        figures["kernels_bit_identical"] = same
    m = metrics_dict(last[f"dnbs/{kernels[0]}"], metrics_settings(settings, args.duration))
    print("DNBS, default config, cold start (worst joint):")
    for key, must, aim in TARGETS:
        v = m[key]
        ok = lambda t: v is not None and v <= t  # noqa: E731
        print(f"  {key:34s} {'never' if v is None else format(v, '.4g'):>10s}   must <= {must:g}: "
              f"{'yes' if ok(must) else 'NO'}   aim <= {aim:g}: {'yes' if ok(aim) else 'no'}")
    figures["dnbs_targets"] = {key: m[key] for key, _, _ in TARGETS}
    print(f"load average at the end {_load()}")
    record.save(args.save_record, figures)
    return 0


if __name__ == "__main__":
    sys.exit(script_main.run(main, "bench_sim", {"duration_s": "--duration"},
                             interrupted="no record written: run the same command again"))

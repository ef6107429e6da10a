#!/usr/bin/env python3
"""Benchmark: real-time factor of the in-process closed loop (20 s, DNBS and PID).

Prints figures; asserts nothing (the machines are shared and noisy). Repeats
each run and reports the best and the median wall time.

    python scripts/bench_sim.py [--duration 20] [--repeat 3] [--controller dnbs]
"""
from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from pa10_dnbs.config import default_config_path, load_config  # noqa: E402
from pa10_dnbs.sim.closed_loop import simulate  # noqa: E402


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--duration", type=float, default=20.0, help="simulated seconds")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--controller", choices=("dnbs", "pid", "both"), default="both")
    args = ap.parse_args()
    cfg = load_config(default_config_path())
    kinds = ("dnbs", "pid") if args.controller == "both" else (args.controller,)
    print(f"in-process closed loop, {args.duration:g} s simulated, T = {cfg['simulation']['dt_s'] * 1e3:g} ms, "
          f"best/median of {args.repeat}")
    for kind in kinds:
        walls = []
        for _ in range(args.repeat):
            t0 = time.perf_counter()
            run = simulate(cfg, kind, args.duration)
            walls.append(time.perf_counter() - t0)  # includes plant set-up
        best, med = min(walls), statistics.median(walls)
        loop_us = run.wall_time_s / run.n_steps * 1e6
        print(f"{kind:5s} real-time factor: best {args.duration / best:5.2f}x  median {args.duration / med:5.2f}x  "
              f"(wall {best:.2f} s; {loop_us:.0f} us per 1 ms step in the last loop)")
    return 0


if __name__ == "__main__":
    sys.exit(main())

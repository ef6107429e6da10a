#!/usr/bin/env python3
"""Benchmark: the ROS 2 node graph (plant + 7 DNBS controller processes + reference).

Prints, for a run of --duration simulated seconds (default 10):
- lockstep: real-time factor of the stepping phase (simulated / wall time);
- realtime: fraction of 1 ms ticks at which every joint's effort for the
  previous state had arrived, missed ticks and state-to-effort latency
  (median / p99) per joint, and how often the plant itself was late.
Figures only; nothing is asserted (the machines are shared and noisy).

    python scripts/bench_graph.py [--duration 10] [--repeat 2] [--modes lockstep realtime]
"""
from __future__ import annotations

import argparse
import resource
import statistics
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from pa10_dnbs.config import default_config_path  # noqa: E402
from pa10_dnbs.launch.graph_run import GraphOptions, run_graph  # noqa: E402


def one_run(mode: str, duration: float, reliability: str) -> tuple[dict, float]:
    with tempfile.TemporaryDirectory(prefix="pa10_bench_") as tmp:
        r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
        res = run_graph(GraphOptions(config_path=default_config_path(), mode=mode, duration_s=duration,
                                     reliability=reliability), Path(tmp), say=lambda s: None)
        r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (r1.ru_utime - r0.ru_utime) + (r1.ru_stime - r0.ru_stime)
    return res.stats, cpu


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--duration", type=float, default=10.0)
    ap.add_argument("--repeat", type=int, default=2)
    ap.add_argument("--modes", nargs="+", default=["lockstep", "realtime"], choices=["lockstep", "realtime"])
    ap.add_argument("--reliability", default="reliable", choices=["reliable", "best_effort"])
    args = ap.parse_args()
    print(f"node graph, DNBS, {args.duration:g} s simulated, {args.reliability} QoS, {args.repeat} runs per mode")
    for mode in args.modes:
        rtfs = []
        for i in range(args.repeat):
            stats, cpu = one_run(mode, args.duration, args.reliability)
            rtfs.append(stats["real_time_factor"])
            line = (f"{mode:8s} run {i + 1}: real-time factor {stats['real_time_factor']:.2f}, "
                    f"children CPU {cpu:.1f} s ({1e3 * cpu / stats['steps']:.2f} ms per step incl. start-up)")
            if mode == "realtime":
                line += (f", ticks with every effort on time {100 * stats['on_time_fraction']:.1f} %, "
                         f"plant late on {stats['late_ticks']} of {stats['steps']} ticks")
            print(line)
            for j in stats["joints"]:
                print(f"    {j['name']}: latency median {j['latency_median_us']:7.0f} us, p99 {j['latency_p99_us']:7.0f} us"
                      + (f", missed ticks {j['missed_ticks']}" if mode == "realtime" else
                         f", effort timeouts {j['effort_timeouts']}"))
        print(f"{mode:8s} real-time factor: best {max(rtfs):.2f}, median {statistics.median(rtfs):.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

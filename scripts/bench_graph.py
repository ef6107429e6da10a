#!/usr/bin/env python3
"""Benchmark: the ROS 2 node graph (plant + 7 DNBS controller processes + reference).

Prints, for a run of --duration simulated seconds (default 10):
- lockstep: real-time factor of the stepping phase (simulated / wall time),
  with the wire monitor observing /joint_states and the references;
- record: lockstep with the recorder in the wire monitor's place, writing
  every topic into an MCAP bag (what `launch --record` runs): its real-time
  factor, the cost against plain lockstep (runs interleaved), and the bag
  size per simulated second;
- realtime: fraction of 1 ms ticks at which every joint's effort for the
  previous state had arrived, missed ticks and state-to-effort latency
  (median / p99) per joint, and how often the plant itself was late.
Figures only; nothing is asserted (the machines are shared and noisy).

    python scripts/bench_graph.py [--duration 10] [--repeat 2] [--modes lockstep record realtime]
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


def one_run(mode: str, duration: float, reliability: str) -> tuple[dict, float, int]:
    """Plant stats, children's CPU time [s] and bag size [bytes] (0 without recording) of one run."""
    with tempfile.TemporaryDirectory(prefix="pa10_bench_") as tmp:
        bag = Path(tmp) / "bag" if mode == "record" else None
        r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
        res = run_graph(GraphOptions(config_path=default_config_path(), mode="realtime" if mode == "realtime"
                                     else "lockstep", duration_s=duration, reliability=reliability, record_bag=bag),
                        Path(tmp), say=lambda s: None)
        r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
        size = sum(f.stat().st_size for f in bag.iterdir()) if bag else 0
    cpu = (r1.ru_utime - r0.ru_utime) + (r1.ru_stime - r0.ru_stime)
    return res.stats, cpu, size


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--duration", type=float, default=10.0)
    ap.add_argument("--repeat", type=int, default=2)
    ap.add_argument("--modes", nargs="+", default=["lockstep", "record", "realtime"],
                    choices=["lockstep", "record", "realtime"])
    ap.add_argument("--reliability", default="reliable", choices=["reliable", "best_effort"])
    args = ap.parse_args()
    print(f"node graph, DNBS, {args.duration:g} s simulated, {args.reliability} QoS, {args.repeat} runs per mode")
    rtfs = {m: [] for m in args.modes}
    for i in range(args.repeat):  # modes interleaved, so a slow spell of the machine hits all of them
        for mode in args.modes:
            stats, cpu, size = one_run(mode, args.duration, args.reliability)
            rtfs[mode].append(stats["real_time_factor"])
            line = (f"{mode:8s} run {i + 1}: real-time factor {stats['real_time_factor']:.2f}, "
                    f"children CPU {cpu:.1f} s ({1e3 * cpu / stats['steps']:.2f} ms per step incl. start-up)")
            if size:
                line += f", bag {size / 1e6:.1f} MB = {size / 1e6 / args.duration:.2f} MB per simulated second"
            if mode == "realtime":
                line += (f", ticks with every effort on time {100 * stats['on_time_fraction']:.1f} %, "
                         f"plant late on {stats['late_ticks']} of {stats['steps']} ticks")
            print(line)
            for j in stats["joints"]:
                print(f"    {j['name']}: latency median {j['latency_median_us']:7.0f} us, p99 {j['latency_p99_us']:7.0f} us"
                      + (f", missed ticks {j['missed_ticks']}" if mode == "realtime" else
                         f", effort timeouts {j['effort_timeouts']}"))
    for mode, r in rtfs.items():
        print(f"{mode:8s} real-time factor: best {max(r):.2f}, median {statistics.median(r):.2f}")
    if "lockstep" in rtfs and "record" in rtfs:
        cost = 1 - statistics.median(rtfs["record"]) / statistics.median(rtfs["lockstep"])
        print(f"recording costs {100 * cost:.0f} % of the lockstep rate (medians; target <= 25 %)")
    return 0


if __name__ == "__main__":
    sys.exit(main())

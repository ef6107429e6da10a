#!/usr/bin/env python3
"""Benchmark: the ROS 2 node graph (plant + 7 joint-controller processes + reference + observer).

Prints, from --repeat runs of --duration simulated seconds each (default 2 x 10 s):
- lockstep: the real-time factor it reaches, and its ceiling on this machine's cores (cores x 1 ms / CPU per tick);
- realtime at each factor R of --factors (default 1.0 0.75 0.5 0.35): the fraction of ticks at which every
  joint's effort came before the deadline (median of the runs), late tick starts, the achieved factor, and
  the state-to-effort latency p50 / p99 per joint;
- the CPU time per tick of every process (plant, each controller, reference, observer), measured inside
  each process between its first and last step (start-up left out), per mode;
- the sustainable factor: the highest R at which the median run had >= 99 % of ticks with every effort
  on time, and how many cores 1 kHz real time (R = 1) would need from the CPU per tick.
``--controller pid`` runs the same graph with the PID baseline in the seven controller processes: the
same wire and plant, a step about a fifth the cost of the DNBS step: the difference is what the DNBS
arithmetic costs inside a node.
Every node runs under SCHED_FIFO 50 where the OS allows it, as ``launch`` does (``--rt-priority 0``: the
default policy). The machine's load average is printed before and after: the figures mean little on a busy machine.
Figures only; nothing is asserted.

    python scripts/bench_graph.py [--duration 10] [--repeat 2] [--factors 1.0 0.75 0.5 0.35] [--no-lockstep]
                                  [--controller dnbs|pid] [--rt-priority 0] [--config config/compiled.yaml]
                                  [--save-record FILE]

``--save-record benchmarks/bench_graph.json``: the figures as a record (scripts/bench_record.py; ``--record``
is the recorder run, an older flag).
"""
from __future__ import annotations

import os
import re
import shutil
import statistics
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
sys.path.insert(0, str(Path(__file__).resolve().parent))

import script_main  # noqa: E402  (first: a Ctrl-C while the modules load is one line)
import bench_record  # noqa: E402

from pa10_dnbs.cli_values import RTF_MAX, RTF_MIN, OneLineParser, number_in, seconds, whole_in  # noqa: E402
from pa10_dnbs.config import ConfigError, default_config_path  # noqa: E402
from pa10_dnbs.config_error import said_as  # noqa: E402
from pa10_dnbs.run_settings import build_settings  # noqa: E402
from pa10_dnbs.supervisor.graph_run import GraphFailure, GraphOptions, run_graph  # noqa: E402
from pa10_dnbs.supervisor.realtime_advice import ON_TIME_TARGET  # noqa: E402
from pa10_dnbs.loop.scheduling import DEFAULT_RT_PRIORITY, check_priority, granted_priority  # noqa: E402

#: the settings a graph failure can name (config_error.SETTING_MARK), as this script's flags
FLAGS = {"rt_priority": "--rt-priority", "real_time_factor": "--factors"}

CPU_LINE = re.compile(r"^CPU (\S+) ([0-9.]+) us per step")


def load() -> str:
    """The 1, 5 and 15 minute load averages."""
    try:
        return " ".join(Path("/proc/loadavg").read_text().split()[:3])
    except OSError:
        return "?"


def one_run(mode: str, factor: float, args, attempts: int = 3) -> tuple[dict | None, dict[str, float]]:
    """Plant stats and {process: CPU per tick [us]} of one run (a failed run, e.g. a node whose teardown
    outlived the launcher's grace period on a loaded machine, is reported and run again); (None, {}) when
    every attempt failed (e.g. an observer starved under --rt-priority): the run counts as 0 % on time."""
    for attempt in range(1, attempts + 1):
        try:
            return _run(mode, factor, args)
        except GraphFailure as exc:
            if exc.interrupted:   # a Ctrl-C stopped the graph: it stops the benchmark, not this attempt alone
                raise KeyboardInterrupt from None
            first = said_as(str(exc).splitlines()[0], FLAGS)   # the launcher's settings, as this script's flags
            print(f"  ({mode} R={factor:g} attempt {attempt} failed: {first})", flush=True)
    return None, {}


def _run(mode: str, factor: float, args) -> tuple[dict, dict[str, float]]:
    with tempfile.TemporaryDirectory(prefix="pa10_bench_") as tmp:
        opt = GraphOptions(config_path=args.config, mode="lockstep" if mode == "record" else mode,
                           controller=args.controller, duration_s=args.duration, reliability=args.reliability,
                           real_time_factor=factor, rt_priority=args.rt_priority,
                           sched_batch=args.sched_batch, joint_names=args.joint_names,
                           record_bag=Path(tmp) / "bag" if mode == "record" else None)
        res = run_graph(opt, Path(tmp), say=lambda s: None,   # a second Ctrl-C: the run's folder goes too
                        on_hard_stop=lambda: shutil.rmtree(tmp, ignore_errors=True))
        cpu = {}
        for log in sorted((Path(tmp) / "logs").glob("*.log")):
            for line in log.read_text(errors="replace").splitlines():
                if m := CPU_LINE.match(line):
                    cpu[m.group(1)] = float(m.group(2))
    return res.stats, cpu


def on_time(stats: dict | None) -> float:
    """The fraction of ticks with every effort on time; 0 for a run that failed."""
    return 0.0 if stats is None else stats["on_time_fraction"]


def runs_text(values) -> str:
    return ", ".join("failed" if v is None else f"{v:.3f}" for v in values)


def med(xs):
    xs = [x for x in xs if x is not None]
    return statistics.median(xs) if xs else float("nan")


def main() -> int:
    ap = OneLineParser(description=__doc__.splitlines()[0])
    ap.add_argument("--duration", type=seconds, default=10.0, help="simulated seconds per run (default 10)")
    ap.add_argument("--repeat", type=whole_in(1), default=2, help="runs per mode and factor (default 2; medians)")
    ap.add_argument("--factors", type=number_in(RTF_MIN, RTF_MAX, low_open=False), nargs="+",
                    default=[1.0, 0.75, 0.5, 0.35],
                    help=f"real-time factors of the realtime runs, each in [{RTF_MIN:g}, {RTF_MAX:g}] (launch --rtf's range)")
    ap.add_argument("--no-lockstep", action="store_true", help="realtime runs only")
    ap.add_argument("--record", action="store_true",
                    help="also lockstep with the recorder as the observer (what launch --record runs)")
    ap.add_argument("--reliability", default=None, choices=["reliable", "best_effort"],
                    help="QoS of the per-joint topics (default: the mode's own)")
    ap.add_argument("--rt-priority", type=whole_in(0, 99), default=DEFAULT_RT_PRIORITY,
                    help=f"as launch's (default {DEFAULT_RT_PRIORITY} where the OS allows SCHED_FIFO; "
                         "0: the default policy)")
    ap.add_argument("--sched-batch", action="store_true",
                    help="every node but the plant under SCHED_BATCH, the plant at the default policy (implies "
                         "--rt-priority 0: a granted SCHED_FIFO would replace SCHED_BATCH)")
    ap.add_argument("--controller", default="dnbs", choices=["dnbs", "pid"],
                    help="what the seven controller processes run (default dnbs; pid: the wire's own cost)")
    ap.add_argument("--config", type=Path, default=default_config_path(),
                    help="YAML config of the runs (default config/default.yaml; config/compiled.yaml: the DNBS step "
                         "on the compiled kernel)")
    bench_record.add_argument(ap)
    args = ap.parse_args()
    record = bench_record.Record.start("bench_graph")
    args.config = args.config.resolve()
    try:
        args.joint_names = build_settings(args.config).arm.joint_names  # a bad config fails here, not in every run
    except ConfigError as exc:
        ap.error(f"argument --config: {exc}")
    check_priority(args.rt_priority)
    if args.sched_batch and args.rt_priority:
        print("--sched-batch: every node but the plant under SCHED_BATCH, so no SCHED_FIFO (--rt-priority 0)",
              flush=True)
        args.rt_priority = 0
    args.rt_priority, refused = granted_priority(args.rt_priority)
    if refused:
        print(refused, flush=True)
    policy = f"SCHED_FIFO {args.rt_priority}" if args.rt_priority else "the default policy"
    if args.sched_batch:
        policy = "SCHED_BATCH (the plant: the default policy)"
    print(f"node graph, {args.controller.upper()} ({args.config.name}), {args.duration:g} s simulated per run, "
          f"{args.repeat} runs each, every node under {policy}; load average before: {load()}", flush=True)
    cases = (([("lockstep", 1.0)] if not args.no_lockstep else []) + ([("record", 1.0)] if args.record else [])
             + [("realtime", r) for r in args.factors])
    runs: dict[tuple, list] = {c: [] for c in cases}
    for i in range(args.repeat):  # cases interleaved, so a slow spell of the machine hits all of them
        for mode, r in cases:
            stats, cpu = one_run(mode, r, args)
            runs[(mode, r)].append((stats, cpu))
            line = f"run {i + 1} {mode:8s}"
            if stats is None:
                print(line + (f" R={r:<5g}" if mode == "realtime" else "") + f" failed every attempt; load {load()}",
                      flush=True)
                continue
            if mode == "realtime":
                line += (f" R={r:<5g} on time {100 * stats['on_time_fraction']:6.2f} %, late starts "
                         f"{stats['late_start_ticks']:5d}, achieved factor {stats['real_time_factor']:.3f}")
            else:
                line += f"         achieved real-time factor {stats['real_time_factor']:.3f}"
            line += (f", CPU {sum(cpu.values()) / 1e3:.2f} ms per tick in all, plant woken "
                     f"{stats['effort_wakeups_per_step']:.2f}x per tick for its 7 efforts; load {load()}")
            print(line, flush=True)
    if all(stats is None for case in runs.values() for stats, _ in case):
        print(f"bench_graph: every run failed every attempt (load {load()}): no figures, no record written",
              file=sys.stderr, flush=True)
        return 1

    print("\nCPU per tick [us] (median of runs; inside each process, start-up excluded)")
    names = ["plant"] + [f"joint_controller_{j}" for j in args.joint_names] + ["reference", "wire_monitor"]
    names += ["recorder"] if args.record else []
    header = f"  {'process':22s}" + "".join(f"{(m if m != 'realtime' else f'R={r:g}'):>10s}" for m, r in cases)
    print(header)
    totals = {}
    figures = {"controller": args.controller, "config": args.config.name, "policy": policy,
               "duration_s": args.duration, "repeat": args.repeat, "factors": args.factors,
               "cpu_us_per_tick_median": {}}
    for n in names:
        row = f"  {n:22s}"
        for c in cases:
            v = med([cpu.get(n) for _, cpu in runs[c]])
            row += f"{v:10.0f}" if v == v else f"{'-':>10s}"
        print(row)
    row = f"  {'total':22s}"
    for c in cases:
        totals[c] = med([sum(cpu.values()) if cpu else None for _, cpu in runs[c]])
        row += f"{totals[c]:10.0f}"
        figures["cpu_us_per_tick_median"][c[0] if c[0] != "realtime" else f"R={c[1]:g}"] = \
            None if totals[c] != totals[c] else round(totals[c], 1)
    print(row)

    if args.factors:
        print("\nrealtime: ticks with every effort before the deadline, and state-to-effort latency per joint")
        for r in args.factors:
            every = [s for s, _ in runs[("realtime", r)]]
            rs = [s for s in every if s is not None]
            figures.setdefault("realtime", {})[f"{r:g}"] = {
                "on_time_fraction_median": med([on_time(s) for s in every]),
                "on_time_fraction_runs": [None if s is None else s["on_time_fraction"] for s in every],
                "achieved_factor_median": med([s["real_time_factor"] for s in rs])}
            print(f"  R={r:g} (tick {1e3 * 1e-3 / r:.2f} ms, deadline {0.9e3 * 1e-3 / r:.2f} ms): on time "
                  f"{100 * med([on_time(s) for s in every]):.2f} % (runs: "
                  + ", ".join("failed" if s is None else f"{100 * s['on_time_fraction']:.2f}" for s in every)
                  + f"), late starts {med([s['late_start_ticks'] for s in rs]):.0f}, achieved factor "
                  f"{med([s['real_time_factor'] for s in rs]):.3f}")
            for j, name in enumerate(args.joint_names):
                print(f"      {name}: p50 {med([s['joints'][j]['latency_median_us'] for s in rs]):6.0f} us, "
                      f"p99 {med([s['joints'][j]['latency_p99_us'] for s in rs]):6.0f} us, missed "
                      f"{med([s['joints'][j]['missed_ticks'] for s in rs]):.0f}")
        ok = [r for r in args.factors if med([on_time(s) for s, _ in runs[("realtime", r)]]) >= ON_TIME_TARGET]
        figures["on_time_target"] = ON_TIME_TARGET
        figures["sustainable_factor"] = max(ok) if ok else None
        print(f"\nsustainable real-time factor (median run >= {100 * ON_TIME_TARGET:.0f} % of ticks on time): "
              + (f"{max(ok):g}" if ok else f"none of {', '.join(f'{r:g}' for r in args.factors)}"))
        busiest = max(args.factors)
        cpu_ms = totals[("realtime", busiest)] / 1e3
        print(f"CPU per tick of the whole graph at R={busiest:g}: {cpu_ms:.2f} ms; 1 kHz real time needs at least "
              f"{cpu_ms:.1f} cores fully busy (more in practice: to keep p99 latency under the 0.9 ms deadline "
              f"the cores must stay well below full load)")
    if not args.no_lockstep:
        factors = [None if s is None else s["real_time_factor"] for s, _ in runs[("lockstep", 1.0)]]
        print(f"lockstep real-time factor: median {med(factors):.3f} (runs: {runs_text(factors)})")
        figures["lockstep_factor_median"], figures["lockstep_factor_runs"] = med(factors), factors
        cores = len(os.sched_getaffinity(0))
        ceiling = cores * 1000.0 / totals[("lockstep", 1.0)]  # 1 ms of simulated time per tick, in us of CPU
        print(f"lockstep ceiling on {cores} cores: {ceiling:.2f}x real time ({cores} ms of CPU per ms over "
              f"{totals[('lockstep', 1.0)] / 1e3:.2f} ms of CPU per tick: the loop cannot go faster even with "
              f"every core busy all the time); achieved {100 * med(factors) / ceiling:.0f} % of it")
    if args.record:
        factors = [None if s is None else s["real_time_factor"] for s, _ in runs[("record", 1.0)]]
        print(f"lockstep with the recorder: real-time factor median {med(factors):.3f} (runs: {runs_text(factors)})")
        figures["record_factor_median"] = med(factors)
    print(f"load average after: {load()}")
    record.save(args.save_record, {k: (None if isinstance(v, float) and v != v else v) for k, v in figures.items()})
    return 0


if __name__ == "__main__":
    sys.exit(script_main.run(main, "bench_graph", FLAGS, interrupted="the graph stopped; no record written: run "
                                                                      "the same command again"))

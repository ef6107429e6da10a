#!/usr/bin/env python3
"""Run the main job (``bash scripts/run_main.sh``) once and record its figures (scripts/bench_record.py).

The figures: the lockstep real-time factor and the total wall time of the launch (runs/main/metrics.json), the
worst joint's RMS error, the SCHED_FIFO priority the nodes got (0: the default policy), and the bag's size (every file of
runs/main_bag/) in MB and MB per simulated second. The main job's output is printed as it comes. Extra
arguments go to run_main.sh (i.e. to ``pa10-dnbs launch``). Exit code: the main job's (no record unless 0).

    .venv/bin/python scripts/record_main_job.py [--save-record benchmarks/main_job.json] [-- launch args]
"""
from __future__ import annotations

import json
import shlex
import subprocess
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
sys.path.insert(0, str(Path(__file__).resolve().parent))

import script_main  # noqa: E402  (first: a Ctrl-C while the modules load is one line)
import bench_record  # noqa: E402

from pa10_dnbs.cli_values import OneLineParser  # noqa: E402

ROOT = bench_record.ROOT


def figures(out: Path, bag: Path) -> dict:
    """The main job's figures from its output folder and its bag folder."""
    m = json.loads((out / "metrics.json").read_text())
    size = sum(f.stat().st_size for f in bag.iterdir() if f.is_file())
    timing = m.get("timing") or {}
    return {"duration_s": m["duration_s"], "mode": m.get("mode"), "real_time_factor": m["real_time_factor"],
            "wall_time_total_s": m.get("wall_time_total_s"),
            "rt_priority": timing.get("rt_priority") if timing.get("rt_priority_applied") else 0,
            "worst_rms_error_rad": m["worst_rms_error_rad"], "bag_mb": round(size / 1e6, 2),
            "bag_mb_per_simulated_s": round(size / 1e6 / m["duration_s"], 3)}


def main() -> int:
    ap = OneLineParser(description=__doc__.splitlines()[0])
    bench_record.add_argument(ap)
    ap.add_argument("launch_args", nargs="*", help="passed to scripts/run_main.sh (after --)")
    args = ap.parse_args()
    cmd = ["bash", "scripts/run_main.sh", *args.launch_args]
    record = bench_record.Record.start("main_job", command=" ".join(shlex.quote(c) for c in cmd))
    rc = script_main.wait_child(script_main.start_child(cmd, cwd=ROOT))   # stopped: the launcher stops its graph
    if rc != 0:
        print(f"record_main_job: the main job exited {rc}: no record", file=sys.stderr)
        return rc
    figs = figures(ROOT / "runs" / "main", ROOT / "runs" / "main_bag")
    print(f"main job: real-time factor {figs['real_time_factor']:.2f}, bag {figs['bag_mb']:.1f} MB "
          f"({figs['bag_mb_per_simulated_s']:.2f} MB per simulated second)")
    record.save(args.save_record, figs)
    return 0


if __name__ == "__main__":
    sys.exit(script_main.run(main, "record_main_job", interrupted="no record written: run the same command "
                                                                  "again"))

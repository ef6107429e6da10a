#!/usr/bin/env python3
"""What the joint bus costs per tick: lockstep runs of the graph with the plant, and with the PyBullet plant as an
external robot behind the joint bus (docs/your_robot.md), interleaved.

    .venv/bin/python scripts/bench_joint_bus.py --duration 3 --rounds 2 [--json FILE]

Per run: wall time per tick of the stepping phase (the plant's or the bus's stats: wall_time_s / steps), the
CPU per tick of the plant / the bus / the robot process (their ``CPU ... per step`` lines), and whether the
bus run equals the plain run bit for bit (timeseries.npz). Each run on its own leased ROS domain.
"""
from __future__ import annotations

import contextlib
import json
import os
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "scripts"))

import script_main  # noqa: E402  (first: a Ctrl-C while the modules load is one line)
from bench_record import record_path  # noqa: E402
from flag_values import folder  # noqa: E402
from pa10_dnbs.cli_values import OneLineParser, seconds, whole_in  # noqa: E402

from pa10_dnbs.supervisor.domain_ids import lease_domain  # noqa: E402
from pa10_dnbs.run_data import RunData  # noqa: E402

CPU = re.compile(r"CPU (\S+) ([\d.]+) us per step")


def _env(domain: int) -> dict:
    return {**os.environ, "ROS_DOMAIN_ID": str(domain), "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST",
            "PYTHONPATH": str(ROOT)}


def _cpu(log: Path) -> float | None:
    m = CPU.search(log.read_text()) if log.is_file() else None
    return float(m.group(2)) if m else None


def run(kind: str, duration: float, out: Path) -> dict:
    launch = [sys.executable, "-m", "pa10_dnbs.cli", "launch", "--duration", str(duration), "--out", str(out),
              "--no-figures", "--no-progress", "--force"]
    with lease_domain() as lease:
        env = _env(lease.domain_id)
        robot = None
        if kind == "bus":
            robot_log = out.parent / f"{out.name}_robot.log"
            robot = script_main.start_child([sys.executable, "-m", "pa10_dnbs.ros.plant.node", "--ros-args", "-r",
                                             "__node:=robot", "-p", "interface:=standard", "-p",
                                             f"duration_s:={duration}", "-p", "start_timeout_s:=120.0"], env=env,
                                            stdout=open(robot_log, "w"), stderr=subprocess.STDOUT)
            launch += ["--robot", "external"]
        t0 = time.monotonic()
        graph = script_main.start_child(launch + ["--domain-id", str(lease.domain_id)], env=env,
                                        stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        try:
            rc = graph.wait()
            total = time.monotonic() - t0
            if robot is not None:
                with contextlib.suppress(subprocess.TimeoutExpired):   # a robot that never ends: stopped below
                    robot.wait(timeout=60)
        finally:   # a Ctrl-C, or that robot: both stopped, one SIGINT each first, before the lease goes
            script_main.stop_child(graph, *([robot] if robot is not None else []), grace_s=15.0)
    if rc != 0:
        raise SystemExit(f"{kind} run failed (exit {rc}); logs in {out}.failed")
    stats = json.loads((out / "metrics.json").read_text())
    node = "joint_bus" if kind == "bus" else "plant"
    steps = int(round(duration * 1000))
    wall = stats["wall_time_s"] if "wall_time_s" in stats else None
    res = {"kind": kind, "wall_total_s": total, "run_wall_s": wall,
           "wall_per_tick_us": 1e6 * wall / steps if wall else None,
           "cpu_per_tick_us": {node: _cpu(out / "logs" / f"{node}.log")},
           "load": open("/proc/loadavg").read().split()[:3]}
    if kind == "bus":
        res["cpu_per_tick_us"]["robot"] = _cpu(out.parent / f"{out.name}_robot.log")
    return res


class _Keep:
    def __init__(self, path: Path):
        self.path = path

    def __enter__(self) -> str:
        return str(self.path)

    def __exit__(self, *exc) -> None:
        return None


def main() -> int:
    ap = OneLineParser(description=__doc__.splitlines()[0])
    ap.add_argument("--duration", type=seconds, default=3.0)
    ap.add_argument("--rounds", type=whole_in(1), default=2)
    ap.add_argument("--json", type=record_path, default=None)
    ap.add_argument("--workdir", type=folder, default=None, help="keep every run's output here (default: a "
                    "temporary folder, removed at the end)")
    a = ap.parse_args()
    results = []
    if a.workdir is not None:
        a.workdir.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory() if a.workdir is None else _Keep(a.workdir) as tmp:
        for r in range(a.rounds):
            pair = {}
            for kind in ("plant", "bus"):
                out = Path(tmp) / f"{kind}{r}"
                pair[kind] = run(kind, a.duration, out)
                print(json.dumps(pair[kind]), flush=True)
            x = RunData.load_npz(Path(tmp) / f"plant{r}" / "timeseries.npz")
            y = RunData.load_npz(Path(tmp) / f"bus{r}" / "timeseries.npz")
            same = all(np.array_equal(getattr(x, f), getattr(y, f))
                       for f in ("position_rad", "velocity_rad_s", "reference_rad", "torque_nm"))
            print(f"round {r}: bus run equals the plant run bit for bit: {same}", flush=True)
            results.append({"plant": pair["plant"], "bus": pair["bus"], "bit_identical": same})
    if a.json:
        a.json.write_text(json.dumps(results, indent=2))
    return 0 if all(r["bit_identical"] for r in results) else 1


if __name__ == "__main__":
    sys.exit(script_main.run(main, "bench_joint_bus", interrupted="its graphs stopped, nothing written: run the "
                                                                  "same command again"))

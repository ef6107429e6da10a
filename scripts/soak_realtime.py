#!/usr/bin/env python3
"""Soak benchmark (not in CI): a long realtime run of the graph; miss rate per minute and memory growth.

Starts `pa10-dnbs launch --mode realtime --rtf R --duration SECONDS`, samples each
node's resident memory (VmRSS from /proc) 20 s after the plant starts and
just before the end, then prints, per simulated minute, the fraction of 1 ms
ticks at which some joint's effort was missing, and each process's memory at
the start and the end. Figures only; nothing is asserted.

    python scripts/soak_realtime.py [--minutes 10] [--rtf 0.5] [--out runs/soak]

R defaults to 0.5, the factor this project's 2-core machine sustains (docs/timing.md); a simulated minute
then takes two of wall time.
"""
from __future__ import annotations

import json
import re
import subprocess
import sys
import threading
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "scripts"))

import script_main  # noqa: E402  (first: a Ctrl-C while the modules load is one line)
from pa10_dnbs.cli_values import RTF_MAX, RTF_MIN, OneLineParser, number_in, positive  # noqa: E402


def rss_kb(pid: int) -> int | None:
    try:
        for line in Path(f"/proc/{pid}/status").read_text().splitlines():
            if line.startswith("VmRSS:"):
                return int(line.split()[1])
    except OSError:
        return None
    return None


def _sample(proc: subprocess.Popen, lines: list[str], pids: dict, start_mem: dict, end_mem: dict) -> None:
    """Until the launcher ends: the nodes' pids from its line, their VmRSS [kB] 20 s after the plant starts
    (``start_mem``) and the last complete sample before they stop (``end_mem``), every second."""
    t_running = None
    while proc.poll() is None:
        text = "".join(lines)
        if not pids and (m := re.search(r"launch: domain \d+, \d+ nodes: (.*); observer (\w+)=(\d+)", text)):
            pids.update({k: int(v) for k, v in (kv.split("=") for kv in m.group(1).split(", "))})
            pids[m.group(2)] = int(m.group(3))
        if t_running is None and "launch: plant running" in text:
            t_running = time.monotonic()
        if t_running is not None and not start_mem and time.monotonic() - t_running > 20.0:
            start_mem.update({n: rss_kb(p) for n, p in pids.items()})
        if start_mem:
            sample = {n: rss_kb(p) for n, p in pids.items()}
            if all(v is not None for v in sample.values()):
                end_mem.update(sample)  # the last complete sample before the nodes stop
        time.sleep(1.0)


def main() -> int:
    ap = OneLineParser(description=__doc__.splitlines()[0])
    ap.add_argument("--minutes", type=positive, default=10.0, help="simulated minutes (default 10)")
    ap.add_argument("--rtf", type=number_in(RTF_MIN, RTF_MAX, low_open=False), default=0.5,
                    help="real-time factor of the paced run (launch --rtf's range; default 0.5, sustainable here)")
    ap.add_argument("--out", type=Path, default=ROOT / "runs" / "soak")
    args = ap.parse_args()
    duration = args.minutes * 60.0
    cmd = [sys.executable, "-m", "pa10_dnbs.cli", "launch", "--mode", "realtime", "--rtf", str(args.rtf),
           "--duration", str(duration),
           "--out", str(args.out), "--force", "--no-progress"]
    proc = script_main.start_child(cmd, cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    lines: list[str] = []
    t = threading.Thread(target=lambda: lines.extend(proc.stdout), daemon=True)
    t.start()
    pids: dict[str, int] = {}
    start_mem: dict[str, int | None] = {}
    end_mem: dict[str, int | None] = {}
    try:
        _sample(proc, lines, pids, start_mem, end_mem)
    except KeyboardInterrupt:   # the launcher stops its graph (SIGINT first) before this ends
        script_main.stop_child(proc)
        raise
    t.join(timeout=5)
    print("".join(lines[-3:]), end="")
    if proc.returncode != 0:
        print(f"launch failed with exit code {proc.returncode}")
        return 1
    stats = json.loads((args.out / "plant_stats.json").read_text())
    print(f"realtime soak: {duration:g} s simulated at --rtf {args.rtf:g}, "
          f"plant real-time factor {stats['real_time_factor']:.2f}")
    for i, f in enumerate(stats["on_time_fraction_per_bin"]):
        print(f"  minute {i + 1:2d}: missed ticks {100 * (1 - f):5.1f} %")
    print("memory (VmRSS, MB): start (20 s after the plant starts) -> end")
    for n in pids:
        a, b = start_mem.get(n), end_mem.get(n)
        if a and b:
            print(f"  {n:22s} {a / 1024:7.1f} -> {b / 1024:7.1f}  ({(b - a) / 1024:+.1f})")
    return 0


if __name__ == "__main__":
    sys.exit(script_main.run(main, "soak_realtime", interrupted="the graph stopped, nothing printed"))

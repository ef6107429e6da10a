#!/usr/bin/env python3
"""Soak of the graph's life cycle (not a timed test): N back-to-back short lockstep runs, counted.

Each run is ``pa10-dnbs launch --duration D --no-figures --no-progress`` in a
temporary directory of its own (the launcher leases its own ROS domain), with
``--busy K`` CPU-bound processes (``while True: pass``) running beside the
whole soak. Per run it reads the launcher's output, ``plant_stats.json`` and
the node logs, and counts:

- failed: the launcher's exit code is not 0;
- timeouts: efforts the plant replaced after ``--effort-timeout`` (lockstep:
  the run is no longer the in-process run bit for bit);
- stalled runs: runs in which the plant re-sent some state (an answer still
  missing after ``resend_s``, 0.25 s of wall time; with busy loops beside the
  graph a starved controller can be that late) or replaced an effort;
- deadline exits: nodes whose ``close()`` outlasted its limit and was cut
  short by the exit deadline (``Timeout (`` in the node's log, ``ros/runtime.py``);
- leftover processes: the run's node processes still alive after the
  launcher returned; leftover shm: new ``/dev/shm`` Fast DDS / LTTng files
  that no live process maps.

With ``--catch-hangs`` a node still alive ``--catch-after`` s after it printed
its ``CPU`` line (its ``close()`` is nearly done: it should be gone at once) gets
``gdb -batch -ex 'thread apply all bt'`` and ``py-spy dump --native`` (when
installed) written to ``hang_<run>_<node>.txt`` in ``--keep``.

Also the plant's start handshake time (``HANDSHAKE every node ready after``).
Prints a table and writes a JSON (``--json``); exits 1 when some run failed,
timed out an effort, hit a deadline or left something behind.

    python scripts/soak_lifecycle.py --runs 20 --busy 2 [--config config/compiled.yaml] [--json soak.json]
"""
from __future__ import annotations

import json
import os
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "scripts"))

from bench_record import record_path  # noqa: E402
from flag_values import folder  # noqa: E402

from pa10_dnbs.cli_values import OneLineParser, positive, seconds, whole_in  # noqa: E402
from pa10_dnbs.ros.shm_cleanup import shm_files, unused  # noqa: E402

HUNG_MARK = "Timeout ("  # faulthandler's header when a node's teardown outlived its limit
NODES_LINE = re.compile(r"launch: domain (\d+), \d+ nodes: (.*); observer (\w+)=(\d+)")


def _alive(pid: int) -> bool:
    try:
        with open(f"/proc/{pid}/stat") as f:
            return f.read().split()[2] != "Z"
    except (FileNotFoundError, IndexError):
        return False


def _busy_loops(k: int) -> list[subprocess.Popen]:
    return [subprocess.Popen([sys.executable, "-c", "while True: pass"]) for _ in range(k)]


def _dump_hung(pid: int, path: Path) -> None:
    """Native and Python stacks of ``pid`` into ``path`` (gdb, and py-spy when installed)."""
    parts = []
    if shutil.which("gdb"):
        r = subprocess.run(["gdb", "-p", str(pid), "-batch", "-ex", "set pagination off", "-ex",
                            "thread apply all bt"], capture_output=True, text=True, timeout=60)
        parts.append("=== gdb thread apply all bt ===\n" + r.stdout + r.stderr)
    spy = shutil.which("py-spy") or str(Path(sys.executable).parent / "py-spy")
    if Path(spy).is_file():
        r = subprocess.run([spy, "dump", "--native", "--pid", str(pid)], capture_output=True, text=True, timeout=60)
        parts.append("=== py-spy dump --native ===\n" + r.stdout + r.stderr)
    path.write_text("\n".join(parts) or "no gdb and no py-spy\n")


class HangCatcher(threading.Thread):
    """Watches one run's node processes; stacks of a node still alive ``after_s`` after its CPU line."""

    def __init__(self, out_lines: list[str], logs: Path, keep: Path, run: int, after_s: float):
        super().__init__(daemon=True)
        self.out_lines, self.logs, self.keep, self.run_no, self.after_s = out_lines, logs, keep, run, after_s
        self.done = threading.Event()
        self.caught: list[str] = []

    def run(self) -> None:
        pids: dict[str, int] = {}
        closed_at: dict[str, float] = {}
        while not self.done.is_set():
            if not pids:
                m = next((NODES_LINE.search(x) for x in list(self.out_lines) if NODES_LINE.search(x)), None)
                if m:
                    pids = {k: int(v) for k, v in (kv.split("=") for kv in m.group(2).split(", "))}
                    pids[m.group(3)] = int(m.group(4))
            for name, pid in pids.items():
                if name in self.caught or not _alive(pid):
                    continue
                log = self.logs / f"{name}.log"
                try:
                    closed = "\nCPU " in "\n" + log.read_text(errors="replace")
                except OSError:
                    closed = False
                if closed:
                    t0 = closed_at.setdefault(name, time.monotonic())
                    if time.monotonic() - t0 > self.after_s:
                        self.caught.append(name)
                        _dump_hung(pid, self.keep / f"hang_{self.run_no:03d}_{name}.txt")
            time.sleep(0.1)


def one_run(i: int, args, keep: Path | None) -> dict:
    work = Path(tempfile.mkdtemp(prefix=f"soak{i:03d}_"))
    out = work / "run"
    cmd = [sys.executable, "-m", "pa10_dnbs.cli", "launch", "--duration", str(args.duration), "--no-figures",
           "--no-progress", "--out", str(out)] + (["--config", str(args.config)] if args.config else []) + args.extra
    shm_before = shm_files()
    t0 = time.monotonic()
    proc = subprocess.Popen(cmd, cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                            env={**os.environ, "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST"})
    lines: list[str] = []
    reader = threading.Thread(target=lambda: lines.extend(proc.stdout), daemon=True)
    reader.start()
    catcher = None
    if keep is not None and args.catch_hangs:
        catcher = HangCatcher(lines, out / "logs", keep, i, args.catch_after)
        catcher.start()
    try:
        rc = proc.wait(timeout=args.run_timeout)
    except subprocess.TimeoutExpired:
        proc.send_signal(signal.SIGINT)
        try:
            rc = proc.wait(timeout=30)
        except subprocess.TimeoutExpired:
            proc.kill()
            rc = proc.wait()
    reader.join(timeout=5)
    if catcher is not None:
        catcher.done.set()
        catcher.join(timeout=120)
    wall = time.monotonic() - t0
    text = "".join(lines)
    m = NODES_LINE.search(text)
    pids = {}
    if m:
        pids = {k: int(v) for k, v in (kv.split("=") for kv in m.group(2).split(", "))}
        pids[m.group(3)] = int(m.group(4))
    time.sleep(0.2)
    left_procs = sorted(n for n, p in pids.items() if _alive(p))
    left_shm = sorted(unused(shm_files() - shm_before))
    logs = out / "logs"
    hung = sorted(p.stem for p in logs.glob("*.log") if HUNG_MARK in p.read_text(errors="replace")) \
        if logs.is_dir() else []
    timeouts = resends = 0
    resent_at: list[int] = []
    stats_file = out / "plant_stats.json"
    if stats_file.is_file():
        joints = json.loads(stats_file.read_text())["joints"]
        timeouts = sum(j["effort_timeouts"] for j in joints)
        resends = sum(j.get("resent_states", 0) for j in joints)
        resent_at = sorted({a for j in joints for a, _ in j.get("resent_step_ranges", [])})
    ready_s = None
    plant_log = logs / "plant.log"
    row = {"run": i, "rc": rc, "wall_s": round(wall, 2), "effort_timeouts": timeouts, "resends": resends, "resent_from_steps": resent_at,
           "stalled": bool(timeouts or resends), "deadline_exits": hung, "leftover_processes": left_procs,
           "leftover_shm": left_shm, "ready_s": ready_s, "load_1min": round(os.getloadavg()[0], 2)}
    if plant_log.is_file():
        mt = re.search(r"HANDSHAKE every node ready after ([0-9.]+) s", plant_log.read_text(errors="replace"))
        row["ready_s"] = float(mt.group(1)) if mt else None
    if catcher is not None:
        row["caught"] = catcher.caught
    bad = rc != 0 or timeouts or resends or hung or left_procs or left_shm
    if keep is not None and bad:
        shutil.copytree(out, keep / f"run_{i:03d}", dirs_exist_ok=True)
        (keep / f"run_{i:03d}" / "launch.out").write_text(text)
    shutil.rmtree(work, ignore_errors=True)
    return row


def summary(rows: list[dict]) -> dict:
    return {"runs": len(rows), "failed_runs": sum(r["rc"] != 0 for r in rows),
            "effort_timeouts": sum(r["effort_timeouts"] for r in rows),
            "runs_with_timeouts": sum(bool(r["effort_timeouts"]) for r in rows),
            "stalled_runs": sum(r["stalled"] for r in rows),
            "runs_resending_state_0": sum(0 in r.get("resent_from_steps", []) for r in rows),
            "deadline_exits": sum(len(r["deadline_exits"]) for r in rows),
            "leftover_processes": sum(len(r["leftover_processes"]) for r in rows),
            "leftover_shm_files": sum(len(r["leftover_shm"]) for r in rows),
            "wall_s_median": _median([r["wall_s"] for r in rows]),
            "handshake_s_median": _median([r["ready_s"] for r in rows if r["ready_s"] is not None]),
            "handshake_s_max": max((r["ready_s"] for r in rows if r["ready_s"] is not None), default=None),
            "load_1min_min": min((r["load_1min"] for r in rows), default=None),
            "load_1min_median": _median([r["load_1min"] for r in rows])}


def _median(xs: list[float]) -> float | None:
    return sorted(xs)[len(xs) // 2] if xs else None


def main() -> int:
    ap = OneLineParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=whole_in(1), default=20, help="back-to-back runs (default 20)")
    ap.add_argument("--duration", type=seconds, default=1.0, help="simulated seconds per run (default 1)")
    ap.add_argument("--busy", type=whole_in(0), default=0, help="CPU-bound processes beside the soak (default 0)")
    ap.add_argument("--config", type=Path, help="the launcher's --config")
    ap.add_argument("--json", type=record_path, default=Path("soak_lifecycle.json"), help="where the JSON goes")
    ap.add_argument("--keep", type=folder, help="copy the output of every run that went wrong here")
    ap.add_argument("--catch-hangs", action="store_true",
                    help="gdb / py-spy stacks of a node whose teardown outlasts --catch-after (needs --keep)")
    ap.add_argument("--catch-after", type=positive, default=1.5, help="seconds after its CPU line (default 1.5)")
    ap.add_argument("--run-timeout", type=positive, default=300.0, help="wall seconds before a run is stopped")
    ap.add_argument("extra", nargs="*", help="more launcher arguments (after --)")
    args = ap.parse_args()
    if args.catch_hangs and args.keep is None:
        ap.error("--catch-hangs needs --keep DIR")
    if args.keep is not None:
        args.keep.mkdir(parents=True, exist_ok=True)
    busy = _busy_loops(args.busy)
    rows: list[dict] = []
    try:
        for i in range(args.runs):
            r = one_run(i, args, args.keep)
            rows.append(r)
            flags = [k for k in ("deadline_exits", "leftover_processes", "leftover_shm") if r[k]]
            print(f"run {i:3d}: rc {r['rc']}, {r['wall_s']:6.2f} s, timeouts {r['effort_timeouts']}, resends "
                  f"{r['resends']}{' from steps ' + str(r['resent_from_steps']) if r['resent_from_steps'] else ''}, "
                  f"ready {r['ready_s']} s, load {r['load_1min']}" + "".join(f", {k} {r[k]}" for k in flags), flush=True)
    except KeyboardInterrupt:
        print("interrupted; the table covers the runs done", flush=True)
    finally:
        for p in busy:
            p.kill()
            p.wait()
    s = summary(rows)
    load = os.getloadavg()
    print(f"\nsoak: {s['runs']} runs of {args.duration:g} s lockstep, {args.busy} busy loops, 1-min load at the "
          f"runs' ends min {s['load_1min_min']} median {s['load_1min_median']}, load after "
          f"{load[0]:.1f} {load[1]:.1f} {load[2]:.1f}")
    print("| runs | failed | effort timeouts (runs) | stalled runs (resend or timeout; state 0 re-sent) | deadline exits | "
          "leftover processes | leftover shm files | wall per run, median [s] | start handshake, median / max [s] |")
    print("|---|---|---|---|---|---|---|---|---|")
    print(f"| {s['runs']} | {s['failed_runs']} | {s['effort_timeouts']} ({s['runs_with_timeouts']}) | "
          f"{s['stalled_runs']} ({s['runs_resending_state_0']}) | {s['deadline_exits']} | {s['leftover_processes']} | {s['leftover_shm_files']} | "
          f"{s['wall_s_median']} | {s['handshake_s_median']} / {s['handshake_s_max']} |")
    args.json.write_text(json.dumps({"args": {"runs": args.runs, "duration_s": args.duration, "busy": args.busy,
                                              "config": str(args.config) if args.config else None,
                                              "extra": args.extra},
                                     "load_after": load, "summary": s, "runs": rows}, indent=1))
    print(f"written {args.json}")
    bad = s["failed_runs"] or s["effort_timeouts"] or s["deadline_exits"] or s["leftover_processes"] \
        or s["leftover_shm_files"]
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())

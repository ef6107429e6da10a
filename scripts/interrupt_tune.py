#!/usr/bin/env python3
"""Ctrl-C of `pa10-dnbs tune` at random moments: exit code, seconds to exit, processes left, resume.

Each try runs a short tune into a fresh folder in its own process group, sends SIGINT to the group (as a
terminal's Ctrl-C does) at a seeded random moment between start-up and the end of a full run, and measures
the seconds from the signal to the exit, the exit code, the processes of that group or with that folder on
their command line still alive one second later, and whether stderr holds a traceback. Every --resume-every'th
interrupted try then runs the same command again and checks that it completes (rc 0, tune.json holding
--trials trials). Prints a table and a summary line; --out writes both, as Markdown (FILE.md) or JSON
(docs/tuning.md, "Interrupting").

    .venv/bin/python scripts/interrupt_tune.py --tries 50 --seed 0 --out benchmarks/interrupt_tune.md
"""
from __future__ import annotations

import datetime
import json
import os
import random
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "scripts"))

import script_main  # noqa: E402  (first: a Ctrl-C while the modules load is one line)
from bench_record import record_path  # noqa: E402
from pa10_dnbs import interrupt  # noqa: E402
from pa10_dnbs.cli_values import OneLineParser, seconds, whole_in  # noqa: E402

HANG_S = 60.0   # a try not ended this long after its SIGINT counts as a hang (then killed)


def tune_command(out: Path, trials: int, duration: float) -> list[str]:
    return [sys.executable, "-m", "pa10_dnbs.cli", "tune", "--controller", "dnbs", "--trials", str(trials),
            "--duration", f"{duration:g}", "--held-out-seeds", "1", "--no-progress", "--out", str(out)]


def leftovers(pgid: int, marker: str) -> list[str]:
    """Living processes of group ``pgid`` or whose command line holds ``marker`` (zombies count: unreaped)."""
    left = []
    for name in os.listdir("/proc"):
        if not name.isdigit() or int(name) == os.getpid():
            continue
        try:
            stat = Path(f"/proc/{name}/stat").read_text()
            cmd = Path(f"/proc/{name}/cmdline").read_bytes().replace(b"\0", b" ").decode(errors="replace")
        except OSError:
            continue
        fields = stat[stat.rfind(")") + 2:].split()
        if int(fields[2]) == pgid or (marker in cmd and "interrupt_tune" not in cmd):
            left.append(f"{name}:{fields[0]}:{cmd[:60]}")
    return left


def one_try(cmd: list[str], delay_s: float, env: dict) -> dict:
    """Start ``cmd``, SIGINT its group after ``delay_s``; what happened."""
    t0 = time.monotonic()
    proc = subprocess.Popen(cmd, cwd=ROOT, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            start_new_session=True)
    try:
        return _interrupt(proc, cmd, delay_s, t0)
    finally:   # this script stopped (Ctrl-C, SIGTERM, an error): the try's processes go with it
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.communicate()


def _interrupt(proc: subprocess.Popen, cmd: list[str], delay_s: float, t0: float) -> dict:
    try:
        proc.wait(delay_s)
        finished_first = True
    except subprocess.TimeoutExpired:
        finished_first = False
    t_sig = time.monotonic()
    if not finished_first:
        os.killpg(proc.pid, signal.SIGINT)
    hang = False
    try:
        out, err = proc.communicate(timeout=HANG_S)
    except subprocess.TimeoutExpired:
        hang = True
        os.killpg(proc.pid, signal.SIGKILL)
        out, err = proc.communicate()
    exit_s = time.monotonic() - t_sig
    time.sleep(1.0)
    left = leftovers(proc.pid, cmd[-1])
    for entry in left:   # leave nothing behind ourselves either
        try:
            os.kill(int(entry.split(":")[0]), signal.SIGKILL)
        except OSError:
            pass
    err_text = err.decode(errors="replace")
    lines = [ln for ln in err_text.splitlines() if ln.strip()]
    return {"delay_s": round(delay_s, 3), "finished_before_sigint": finished_first,
            "ran_s": round(t_sig - t0, 3) if finished_first else None, "rc": proc.returncode,
            "exit_s": round(exit_s, 3), "hang": hang, "left": left, "traceback": "Traceback" in err_text,
            "stderr_lines": len(lines), "line": lines[-1] if lines else "",
            "output_complete": (Path(cmd[-1]) / "tune.json").is_file()}


def resume(cmd: list[str], env: dict, out: Path, trials: int) -> bool:
    """The same command again: completes with the study holding ``trials`` trials."""
    r = subprocess.run(cmd, cwd=ROOT, env=env, capture_output=True, timeout=600)
    if r.returncode != 0 or not (out / "tune.json").exists():
        return False
    return json.loads((out / "tune.json").read_text())["trials"] == trials


def main(argv: list[str] | None = None) -> int:
    p = OneLineParser(description=__doc__.splitlines()[0])
    p.add_argument("--tries", type=whole_in(1), default=50,
                   help="interrupted runs (default 50); a run that ends before its SIGINT does not count, and is "
                        "listed (at most --tries of them)")
    p.add_argument("--seed", type=int, default=0, help="seed of the random moments (default 0)")
    p.add_argument("--trials", type=whole_in(1), default=3, help="--trials of each tune (default 3)")
    p.add_argument("--duration", type=seconds, default=1.0, help="--duration of each tune [s] (default 1)")
    p.add_argument("--resume-every", type=whole_in(1), default=5, metavar="K",
                   help="run the same command again after every K-th try, to completion (default 5; 1: every try)")
    p.add_argument("--out", type=record_path, default=None, metavar="FILE",
                   help="write the table and summary: Markdown if FILE ends in .md, else JSON")
    args = p.parse_args(argv)
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    rng = random.Random(args.seed)
    base = Path(tempfile.mkdtemp(prefix="interrupt_tune-"))
    interrupt.on_second_sigint("interrupt_tune: interrupted again: stopped at once; the tries' folders removed",
                               cleanup=lambda: shutil.rmtree(base, ignore_errors=True))
    load = list(os.getloadavg())
    try:
        return _run(args, argv, env, rng, base, load)
    finally:
        shutil.rmtree(base, ignore_errors=True)


def _run(args, argv, env, rng, base: Path, load: list) -> int:
    t = time.monotonic()   # the length of an uninterrupted run: the window the SIGINTs are drawn from
    full = subprocess.run(tune_command(base / "full", args.trials, args.duration), cwd=ROOT, env=env,
                          capture_output=True, timeout=600)
    full_s = time.monotonic() - t
    if full.returncode != 0:
        print(f"interrupt_tune: the uninterrupted run failed (rc {full.returncode}): "
              f"{full.stderr.decode(errors='replace').strip().splitlines()[-1:]}", file=sys.stderr)
        return 1
    rows, window_s, table = [], full_s, []

    def show(line: str) -> None:
        table.append(line)
        print(line, flush=True)
    show(f"uninterrupted run: {full_s:.1f} s; SIGINT at a uniform moment in [0.05, {full_s:.1f}] s (shortened to "
         "0.95 x a run that ends first)")
    show(f"{'try':>3} {'sigint_s':>8} {'rc':>4} {'exit_s':>6} {'left':>4} {'tb':>3} {'resumed':>7}  line")
    i = 0
    while sum(not r["finished_before_sigint"] for r in rows) < args.tries and i < 2 * args.tries:
        out = base / f"try{i:03d}"
        cmd = tune_command(out, args.trials, args.duration)
        row = one_try(cmd, rng.uniform(0.05, window_s), env)
        if row["finished_before_sigint"]:   # the machine got faster (load): draw from the shorter run from now on
            window_s = max(0.5, min(window_s, 0.95 * row["ran_s"]))
        row["try"] = i
        row["resumed"] = None
        if not row["finished_before_sigint"] and (sum(not r["finished_before_sigint"] for r in rows) + 1) \
                % args.resume_every == 0:
            row["resumed"] = resume(cmd, env, out, args.trials)
        rows.append(row)
        i += 1
        show(f"{row['try']:>3} {row['delay_s']:>8.2f} {row['rc']:>4} {row['exit_s']:>6.2f} {len(row['left']):>4} "
             f"{'yes' if row['traceback'] else 'no':>3} "
             f"{'-' if row['resumed'] is None else ('yes' if row['resumed'] else 'NO'):>7}  {row['line'][:90]}")
    summary, line = summarize(rows, args.resume_every)
    show(line)
    if args.out is not None:
        args.out.parent.mkdir(parents=True, exist_ok=True)
        record = {
            "date": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
            "command": "python scripts/interrupt_tune.py " + " ".join(argv if argv is not None else sys.argv[1:]),
            "tune_command": " ".join(tune_command(Path("DIR"), args.trials, args.duration)[1:]),
            "uninterrupted_s": round(full_s, 2), "load_at_start": load, "cpus": os.cpu_count(),
            "summary": summary, "summary_line": line, "table": table, "rows": rows}
        args.out.write_text(markdown(record) if args.out.suffix == ".md" else json.dumps(record, indent=1) + "\n")
    ok = (summary["all_rc_130"] and not summary["hangs"] and not summary["tries_with_leftovers"]
          and not summary["tracebacks"] and summary["resumes_ok"] == summary["resumes_tried"])
    return 0 if ok else 1


def markdown(record: dict) -> str:
    """The record as a page: when, what, how busy the machine was, the summary, the printed table."""
    out = [f"# Ctrl-C of `pa10-dnbs tune` at random moments ({record['date']})", "",
           f"- command: `{record['command']}`", f"- each try: `python {record['tune_command']}`",
           f"- uninterrupted run: {record['uninterrupted_s']} s; load average at the start (1, 5, 15 min): "
           f"{', '.join(f'{x:.2f}' for x in record['load_at_start'])} on {record['cpus']} CPUs"]
    out += [f"- {note}" for note in record.get("notes", [])]
    out += ["", "**" + record["summary_line"] + "**", "", "```text", *record["table"], "```", ""]
    for title, earlier in record.get("earlier", {}).items():
        out += [f"## {title}", "", f"- command: `{earlier['command']}`",
                f"- load average at the start: {', '.join(f'{x:.2f}' for x in earlier['load_at_start'])}"]
        out += [f"- {note}" for note in earlier.get("notes", [])]
        out += ["", "**" + earlier["summary_line"] + "**", ""]
        if earlier.get("table"):
            out += ["```text", *earlier["table"], "```", ""]
    return "\n".join(out)


def shell_rc(rc: int) -> int:
    """The exit status a shell shows: 128 + N for a process ended by signal N (Popen's -N)."""
    return 128 - rc if rc < 0 else rc


def summarize(rows: list[dict], resume_every: int) -> tuple[dict, str]:
    """The summary of the tries and its line. A SIGINT that came as the finished tune exited (its work and
    output complete, ``tune.json`` written) leaves the tune's own exit code, 0, and no line
    (``interrupt._hold_sigint_to_the_end``): counted as right (``after_finish``), shown apart in ``rc_counts``.
    A try ended by the SIGINT itself (rc -2; before that fix, in the same window) is 130 to a shell."""
    hit = [r for r in rows if not r["finished_before_sigint"]]
    resumed = [r for r in hit if r["resumed"] is not None]
    after = [r for r in hit if r["rc"] == 0 and r.get("output_complete") and not r["stderr_lines"]]
    summary = {
        "tries": len(rows), "interrupted": len(hit), "finished_before_sigint": len(rows) - len(hit),
        "all_rc_130": all(shell_rc(r["rc"]) == 130 or r in after for r in hit), "after_finish": len(after),
        "rc_counts": _counts(r["rc"] for r in hit),
        "max_exit_s": max((r["exit_s"] for r in hit), default=None), "hangs": sum(r["hang"] for r in rows),
        "tries_with_leftovers": sum(bool(r["left"]) for r in rows), "tracebacks": sum(r["traceback"] for r in rows),
        "not_one_line": sum(r["stderr_lines"] != 1 for r in hit if r not in after),
        "resumes_tried": len(resumed), "resumes_ok": sum(bool(r["resumed"]) for r in resumed)}
    line = (f"{summary['interrupted']} of {summary['tries']} tries interrupted ({summary['finished_before_sigint']} "
            f"finished first); shell status 130: {'all' if summary['all_rc_130'] else 'NOT all'}"
            + (f" but {summary['after_finish']} that came as the finished tune exited (its rc 0 stands, no line)"
               if summary["after_finish"] else "")
            + f" (rc {summary['rc_counts']}); max exit {summary['max_exit_s']} s; hangs {summary['hangs']}; tries with "
            f"processes left {summary['tries_with_leftovers']}; tracebacks {summary['tracebacks']}; not one line "
            f"{summary['not_one_line']}; resumed {summary['resumes_ok']}/{summary['resumes_tried']} "
            f"(every {resume_every}th try)")
    return summary, line


def _counts(values) -> dict:
    out: dict = {}
    for v in values:
        out[str(v)] = out.get(str(v), 0) + 1
    return out


if __name__ == "__main__":   # stopped (Ctrl-C, SIGTERM): the try's processes and folders go in the finally blocks
    sys.exit(script_main.run(main, "interrupt_tune",
                             interrupted="the tries' processes and folders removed; nothing written: run the same "
                                         "command again"))

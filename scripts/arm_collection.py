"""The collection benchmark: every serial arm of example-robot-data, bare and with its shipped arm file.

    .venv/bin/python scripts/arm_collection.py --install            # the pinned collection (131 MB), once
    .venv/bin/python scripts/arm_collection.py                      # every arm, both modes, 20 s runs
    .venv/bin/python scripts/arm_collection.py --arms ur5,so101 --duration 5 --out /tmp/collection.json
    .venv/bin/python scripts/arm_collection.py --study --arms ur5                 # + the study on its arm file

Each (arm, mode) runs DNBS, PID and CTC in-process (pa10_dnbs/study/collection.py) in a pool of ``--jobs``
processes. The table goes to ``--out`` (benchmarks/collection/arm_collection.json) and beside it as markdown
(.md: the full table, the study's, and the README's one line per arm), rewritten after every row, so Ctrl-C
(exit 130) keeps the completed rows, as does a worker process killed (one line naming --jobs, exit 2). The
collection is not in requirements.txt: it is the benchmark's choice (131 MB that no test needs), pinned in ONE
place, requirements-collection.txt, which ``--install`` installs.
Exit 2 with one line when it is not installed. ``--study`` then runs every study scenario x DNBS and PID x 3
seeds on each accepted arm file (about a minute per arm on 2 cores at 20 s) and adds a second table: where
DNBS's worst seed is below PID's best, and which scenarios are beyond the arm's torque limits (named with the
joint, the torque it needs and its limit; not run: study/feasibility.py).
"""
from __future__ import annotations

import argparse
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "scripts"))

import script_main  # noqa: E402  (first: a Ctrl-C while the modules load is one line)
from flag_values import file_to_write, names_in  # noqa: E402
from pa10_dnbs.atomic_file import atomic_path, write_json  # noqa: E402
from pa10_dnbs.cli_values import OneLineParser, seconds  # noqa: E402
from pa10_dnbs.config import ConfigError, default_config_path, load_config  # noqa: E402
from pa10_dnbs.interrupt import EXIT_INTERRUPTED  # noqa: E402
from pa10_dnbs.run_steps import run_steps  # noqa: E402
from pa10_dnbs.study.collection import (ARMS, COLLECTION_VERSION, MODES, arm_file, collection_root,  # noqa: E402
                                        compact_table, markdown_table, run_row, study_summary, study_table)

REQUIREMENTS = ROOT / "requirements-collection.txt"
MAX_DURATION_S = 1e4  # [s] per run: the table of every arm would take days


def duration(text: str) -> float:
    """``--duration``'s argparse type: at least two steps of the config's simulation.dt_s (a shorter run is an
    error in every cell), below MAX_DURATION_S."""
    value = seconds(text)
    dt = load_config(default_config_path())["simulation"]["dt_s"]
    try:
        run_steps(value, dt)
    except ConfigError:
        raise argparse.ArgumentTypeError(f"{text} s is shorter than two steps of the default config's "
                                         f"simulation.dt_s ({dt:g} s)") from None
    if value >= MAX_DURATION_S:
        raise argparse.ArgumentTypeError(f"must be below {MAX_DURATION_S:g} s, got {text!r}")
    return value


def out_path(text: str) -> Path:
    """``--out``'s argparse type: the JSON table's file and its markdown sibling (.md), each a file to write
    (flag_values.file_to_write), checked before any run; a .md path would be its own sibling."""
    path = file_to_write(text)
    if path.suffix == ".md":
        raise argparse.ArgumentTypeError(f"{text!r} ends in .md: give the JSON's path (the table goes beside it "
                                         "as .md)")
    file_to_write(str(path.with_suffix(".md")))
    return path


def _args(argv):
    ap = OneLineParser(description=__doc__.splitlines()[0])
    ap.add_argument("--arms", type=names_in(tuple(ARMS)), default=",".join(ARMS),
                    help=f"comma-separated, of: {', '.join(ARMS)}")
    ap.add_argument("--modes", type=names_in(MODES), default=",".join(MODES),
                    help="comma-separated, of: bare, arm_file (default: both)")
    ap.add_argument("--duration", type=duration, default=20.0, help="s per run (the window is [10, 20) s at 20 s)")
    ap.add_argument("--jobs", type=int, default=2, help="worker processes (default 2)")
    ap.add_argument("--out", type=out_path, default=ROOT / "benchmarks" / "collection" / "arm_collection.json",
                    help="the JSON table; the markdown goes beside it as .md (its folder is made)")
    ap.add_argument("--study", action="store_true", help="also the study (8 scenarios x DNBS, PID x 3 seeds) of "
                    "every accepted arm file")
    ap.add_argument("--install", action="store_true", help="pip install requirements-collection.txt, then exit")
    return ap.parse_args(argv)


def _fail(msg: str) -> int:
    print(f"arm_collection: error: {msg}", file=sys.stderr)
    return 2


def main(argv=None) -> int:
    a = _args(argv)
    if a.install:
        return subprocess.call([sys.executable, "-m", "pip", "install", "--quiet", "-r", str(REQUIREMENTS)])
    arms, modes = a.arms, a.modes
    if a.jobs < 1:
        return _fail(f"--jobs: must be >= 1, got {a.jobs}")
    root = collection_root()
    if root is None:
        return _fail(f"example-robot-data is not installed: --install (pip install -r {REQUIREMENTS.name}, 131 MB)")
    tasks = {}
    for k in arms:
        for m in modes:
            spec = str(root / ARMS[k][0]) if m == "bare" else str(arm_file(k))
            tasks[(k, m)] = (k, m, spec, a.duration)
    done: dict = {}
    t0 = time.perf_counter()

    def write() -> None:
        rows = [done[key] for key in tasks if key in done]
        meta = {"collection": f"example-robot-data {COLLECTION_VERSION}", "duration_s": a.duration,
                "jobs": a.jobs, "wall_time_s": round(time.perf_counter() - t0, 1), "rows_done": len(rows),
                "rows_planned": len(tasks),
                "command": "scripts/arm_collection.py " + " ".join(argv if argv is not None else sys.argv[1:])}
        a.out.parent.mkdir(parents=True, exist_ok=True)
        write_json(a.out, {"meta": meta, "rows": rows}, indent=1)
        with atomic_path(a.out.with_suffix(".md")) as tmp:
            tmp.write_text(markdown_table(rows) + ("\n" + study_table(rows) if study_table(rows) else "")
                           + "\nOne line per arm (the README's table):\n\n" + compact_table(rows))

    def on_done(key, row) -> None:
        done[key] = row
        d = row.get("dnbs", {})
        print(f"{row['arm']} {row['mode']}: {row['status']} {row['reason']}"
              + (f" DNBS RMS {d.get('rms_rad')}" if d else ""), flush=True)
        write()

    from pa10_dnbs.study.executor import Executor
    from pa10_dnbs.study.lost_runs import RunsLost
    try:
        with Executor(min(a.jobs, len(tasks))) as ex:
            ex.run(run_row, tasks, on_done)
        if a.study:
            for k in arms:
                row = done.get((k, "arm_file"))
                if row is None or row["status"] != "accepted":
                    continue
                row["study"] = study_summary(k, a.duration, a.jobs)
                print(f"{k} arm_file: study done ({row['study']['wall_time_s']} s)", flush=True)
                write()
    except KeyboardInterrupt:
        write()
        print(f"arm_collection: interrupted: {len(done)} of {len(tasks)} rows kept in {a.out}", file=sys.stderr)
        return EXIT_INTERRUPTED
    except RunsLost as exc:   # a worker process killed (the OOM killer): the completed rows kept, as for a Ctrl-C
        write()
        print(f"arm_collection: error: {exc.named({'jobs': '--jobs'})}; {len(done)} of {len(tasks)} rows kept in "
              f"{a.out}", file=sys.stderr)
        return 2
    write()
    print(f"wrote {a.out} and {a.out.with_suffix('.md')} ({len(done)} rows, "
          f"{time.perf_counter() - t0:.0f} s)")
    return 0


if __name__ == "__main__":   # a Ctrl-C in the pool's wait is taken at a safe point (pa10_dnbs/interrupt.py)
    sys.exit(script_main.run(main, "arm_collection", {"jobs": "--jobs", "duration_s": "--duration"},
                             interrupted="no row kept"))

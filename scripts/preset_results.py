#!/usr/bin/env python3
"""The README's results table: each preset arm under DNBS, PID and CTC, measured and recorded.

    .venv/bin/python scripts/preset_results.py --save-record benchmarks/preset_results.json
    .venv/bin/python scripts/readme_figures.py      # the README's results table, from that record

Each arm (``--arms``, default pa10,iiwa,panda) runs as ``pa10-dnbs simulate --arm A --controller all`` does:
the default config, its seed, a cold start 0.1 rad off on every joint, ``--duration`` s (20: the window is
[10, 20) s), in-process (the graph gives the DNBS numbers bit for bit). Per controller it keeps the worst
joint's settling time into 1e-2 rad [s], max |e| over the run [rad], torque variation (sum |d tau| / limit),
steps with a joint at its torque limit after startup (0.2 s), and RMS error over the window [rad]
(pa10_dnbs/study/collection.py ``run_row``, the collection benchmark's row). About 1 min per arm on 2 cores.
Exit 2 with one line for a bad flag or an arm that does not load; 130 on Ctrl-C, nothing written.
"""
from __future__ import annotations

import argparse
import contextlib
import io
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "scripts"))

import script_main  # noqa: E402  (first: a Ctrl-C while the modules load is one line)
import bench_record  # noqa: E402
from flag_values import names_in  # noqa: E402
from pa10_dnbs.arm import preset_names  # noqa: E402
from pa10_dnbs.cli_values import OneLineParser, seconds  # noqa: E402
from pa10_dnbs.config import default_config_path  # noqa: E402
from pa10_dnbs.interrupt import EXIT_INTERRUPTED  # noqa: E402
from pa10_dnbs.report.metrics_file import metrics_settings  # noqa: E402
from pa10_dnbs.run_settings import build_settings  # noqa: E402
from pa10_dnbs.study.collection import CONTROLLERS, run_row  # noqa: E402

PRESETS = ("pa10", "iiwa", "panda")   # the README's columns, in order
MIN_DURATION_S, MAX_DURATION_S = 0.5, 1e4   # [s]: a window of at least 0.25 s; below days of runs


def duration(text: str) -> float:
    """``--duration``'s argparse type [s]."""
    value = seconds(text)
    if not MIN_DURATION_S <= value < MAX_DURATION_S:
        raise argparse.ArgumentTypeError(f"must be in [{MIN_DURATION_S:g}, {MAX_DURATION_S:g}) s, got {text!r}")
    return value


def arm_result(key: str, duration_s: float) -> dict:
    """One column: the arm's description, the metrics' window [s], band [rad] and startup [s], and per
    controller the row's figures; RuntimeError with the one line of an arm that does not load or a controller
    that fails."""
    row = run_row(key, "preset", key, duration_s)
    if row["status"] != "accepted":
        raise RuntimeError(f"--arms: {key}: {row['reason']}")
    for kind in CONTROLLERS:
        if "error" in row[kind]:
            raise RuntimeError(f"{key}, {kind}: {row[kind]['error']}")
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):  # the rules' table
        settings = build_settings(default_config_path(), arm=key)
    return {"arm": key, "description": settings.arm.description, **metrics_settings(settings, duration_s),
            **{kind: row[kind] for kind in CONTROLLERS}}


def main(argv: list[str] | None = None) -> int:
    ap = OneLineParser(description=__doc__.splitlines()[0])
    ap.add_argument("--arms", type=names_in(tuple(preset_names())), default=",".join(PRESETS),
                    help=f"comma-separated presets (default {','.join(PRESETS)})")
    ap.add_argument("--duration", type=duration, default=20.0, help="s per run (default 20)")
    bench_record.add_argument(ap)
    args = ap.parse_args(argv)
    rec = bench_record.Record.start("preset_results")
    try:
        arms = []
        for key in args.arms:
            arms.append(arm_result(key, args.duration))
            d = arms[-1]["dnbs"]
            print(f"{key}: DNBS worst RMS {d['rms_rad']:.3e} rad, settled after {d['settled_s']} s", flush=True)
    except RuntimeError as exc:
        print(f"preset_results: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("preset_results: interrupted: nothing written", file=sys.stderr)
        return EXIT_INTERRUPTED
    rec.save(args.save_record, {"duration_s": args.duration, "controllers": list(CONTROLLERS), "arms": arms})
    return 0


if __name__ == "__main__":   # SIGTERM, SIGHUP as a Ctrl-C; a Ctrl-C while it loads or exits: one line
    sys.exit(script_main.run(main, "preset_results", {"duration_s": "--duration"}, interrupted="nothing written"))

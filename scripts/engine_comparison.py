#!/usr/bin/env python3
"""PyBullet against MuJoCo: each arm's controllers run in-process on both engines, printed side by side
(docs/engines.md's table) with the target per arm (MuJoCo's DNBS settles by 0.5 s, RMS within 2x).

    .venv/bin/python scripts/engine_comparison.py --arms pa10,iiwa,panda --duration 20

Exit 1 when a target is not met or a run left the torque limits or went non-finite; 2 on bad arguments.
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
sys.path.insert(0, str(Path(__file__).resolve().parent))

import script_main  # noqa: E402  (first: a Ctrl-C while the modules load is one line)
from flag_values import names_in  # noqa: E402

from pa10_dnbs.arm import ArmError  # noqa: E402
from pa10_dnbs.cli_values import OneLineParser, seconds  # noqa: E402
from pa10_dnbs.config import ConfigError  # noqa: E402
from pa10_dnbs.sim.engine_comparison import engine_table, run_engines, target_lines  # noqa: E402

CONTROLLERS = ("dnbs", "pid", "ctc")
NAMES = {"arm": "--arms", "duration_s": "--duration"}   # the library's settings, as this script's flags


def _arms(text: str) -> list[str]:
    """``--arms``: one or more arm names or paths, comma-separated, each once."""
    arms = list(dict.fromkeys(a.strip() for a in text.split(",") if a.strip()))
    if not arms:
        raise argparse.ArgumentTypeError(f"expected one or more arm names or paths, got {text!r}")
    return arms


def main(argv: list[str] | None = None) -> int:
    parser = OneLineParser(description=__doc__.splitlines()[0])
    parser.add_argument("--arms", type=_arms, default="pa10,iiwa,panda",
                        help="comma-separated arms (default pa10,iiwa,panda)")
    parser.add_argument("--controllers", type=names_in(CONTROLLERS), default=",".join(CONTROLLERS),
                        help="comma-separated, of dnbs,pid,ctc")
    parser.add_argument("--duration", type=seconds, default=20.0, metavar="SECONDS", help="simulated time (default 20)")
    args = parser.parse_args(argv)
    if not args.duration > 0:
        print(f"engine_comparison: error: --duration: must be > 0, got {args.duration}", file=sys.stderr)
        return 2
    try:
        runs = run_engines(args.arms, list(dict.fromkeys(args.controllers)), args.duration,
                           say=lambda line: print(line, file=sys.stderr, flush=True))
    except (ArmError, ConfigError) as exc:
        print(f"engine_comparison: error: {exc.named(NAMES)}", file=sys.stderr)
        return 2
    print(engine_table(runs), end="")
    lines = target_lines(runs)
    for line in lines:
        print(line)
    ok = all(r.ok for r in runs) and not any(line.startswith("NOT") for line in lines)
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(script_main.run(main, "engine_comparison", NAMES, interrupted="nothing printed (the table comes "
                             "whole, at the end): run the same command again"))

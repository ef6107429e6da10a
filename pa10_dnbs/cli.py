"""``pa10-dnbs`` command line: simulate (in-process); more sub-commands join as they land.

Exit codes: 0 success, 1 run failure, 2 bad input (config, arguments, existing output).
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

from .config import ConfigError, default_config_path, load_config
from .report.outputs import OutputExistsError


def _simulate(args: argparse.Namespace) -> int:
    from .commands.simulate import run_simulate

    return run_simulate(config_path=args.config, controller=args.controller, duration_s=args.duration,
                        out=args.out, force=args.force, progress=not args.no_progress)


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="pa10-dnbs", description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="command", required=True)

    sim = sub.add_parser("simulate", help="closed loop in one process (no ROS), with metrics, figures, report")
    sim.add_argument("--config", type=Path, default=None,
                     help=f"YAML config (default: {default_config_path()})")
    sim.add_argument("--controller", choices=("dnbs", "pid", "both"), default="dnbs")
    sim.add_argument("--duration", type=float, default=None, metavar="SECONDS",
                     help="simulated time [s] (default: simulation.duration_s of the config, 20 s)")
    sim.add_argument("--out", type=Path, required=True, metavar="DIR", help="output directory")
    sim.add_argument("--force", action="store_true", help="replace an existing output directory")
    sim.add_argument("--no-progress", action="store_true", help="no progress bar")
    sim.set_defaults(func=_simulate)
    return parser


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    try:
        return args.func(args)
    except (ConfigError, OutputExistsError, FileNotFoundError) as exc:
        print(f"pa10-dnbs: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("pa10-dnbs: interrupted, no output written", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())

#!/usr/bin/env python3
"""Tune several controllers on one arm with the same budget, then compare them on held-out seeds.

Each controller is tuned with the same trials, objective, training scenarios and seeds (``pa10-dnbs tune`` once
per controller, into DIR/<controller>/); then DIR/comparison.md holds the held-out figures of each controller as
shipped (hand- or rule-tuned, the start of its search) and as tuned, per scenario (docs/tuning.md, "Equal budget").

    .venv/bin/python scripts/equal_budget.py --arm pa10 --controllers pid,dnbs,ctc --trials 20 --out runs/eq

Every option is checked before the first tune starts (bad input: one line, exit 2). A tune that exists in
DIR/<controller>/ resumes (the same command finishes an interrupted comparison); a second copy running into the
same DIR at once is refused, and so is a --controllers that leaves out a controller DIR holds a tune of.
"""
from __future__ import annotations

import argparse
import json
import shlex
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from pa10_dnbs.atomic_file import atomic_path  # noqa: E402
from pa10_dnbs.cli import main as cli_main  # noqa: E402
from pa10_dnbs.cli_values import OneLineParser, seconds, whole_in  # noqa: E402
from pa10_dnbs.output_lock import OutputInUseError, lock_output, release_output  # noqa: E402
from pa10_dnbs.report.outputs import OutputExistsError, check_output_dir  # noqa: E402
from pa10_dnbs.config_error import said_as  # noqa: E402
from pa10_dnbs.setting_flags import SETTING_FLAGS  # noqa: E402
from pa10_dnbs.tune.comparison import comparison_markdown  # noqa: E402
from pa10_dnbs.tune.objective import TRAINING_SCENARIOS, TRAINING_SEEDS  # noqa: E402

CONTROLLERS = ("pid", "dnbs", "ctc")
PROG = "equal_budget"


def _controllers(text: str) -> list[str]:
    names = [c.strip() for c in text.split(",") if c.strip()]
    bad = [c for c in names if c not in CONTROLLERS]
    if bad or not names:
        raise argparse.ArgumentTypeError(f"expected a comma-separated list of {', '.join(CONTROLLERS)}, got {text!r}")
    return list(dict.fromkeys(names))


def build_parser() -> argparse.ArgumentParser:
    doc = __doc__.split("\n\n")
    p = OneLineParser(prog=PROG, description=doc[0] + "\n\n" + doc[1],
                      epilog=doc[3], formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--out", type=Path, required=True, metavar="DIR",
                   help="the comparison: DIR/<controller>/ (each tune) and DIR/comparison.md")
    p.add_argument("--controllers", type=_controllers, default=list(CONTROLLERS), metavar="LIST",
                   help=f"comma-separated, of {', '.join(CONTROLLERS)} (default {','.join(CONTROLLERS)})")
    p.add_argument("--arm", default=None, metavar="NAME|PATH", help="the arm: pa10, iiwa, panda or an arm file "
                   "(default: the config's)")
    p.add_argument("--config", type=Path, default=None, help="YAML config every search starts from")
    p.add_argument("--trials", type=whole_in(1, 1000000), default=None, metavar="N",
                   help="completed trials per controller (tune's default 20)")
    p.add_argument("--scenarios", default=None, metavar="LIST", help=f"training scenarios ({TRAINING_SCENARIOS})")
    p.add_argument("--seeds", type=whole_in(1, 100000), default=None, metavar="N",
                   help=f"training seeds 0..N-1 (default {TRAINING_SEEDS})")
    p.add_argument("--held-out-seeds", type=whole_in(1, 100000), default=None, metavar="N",
                   help="held-out seeds 100..100+N-1 the comparison is made on (>= 1; default 3)")
    p.add_argument("--duration", type=seconds, default=None, metavar="SECONDS", help="simulated time per run (20)")
    p.add_argument("--seed", type=whole_in(0, 2**32 - 1), default=None, help="the samplers' seed (default 0)")
    p.add_argument("--jobs", "--workers", dest="jobs", type=whole_in(1, 4096), default=None, metavar="N",
                   help="local worker processes (default: one per core)")
    p.add_argument("--scheduler", default=None, metavar="ADDRESS", help="a Dask scheduler to run on instead")
    p.add_argument("--no-progress", action="store_true", help="no progress line")
    return p


def tune_arguments(args: argparse.Namespace) -> list[str]:
    """The options every ``pa10-dnbs tune`` of the comparison gets, as words."""
    words = []
    for dest in ("arm", "config", "trials", "scenarios", "seeds", "held_out_seeds", "duration", "seed", "jobs",
                 "scheduler"):
        value = getattr(args, dest)
        if value is not None:
            words += ["--" + dest.replace("_", "-"), str(value)]
    return words + (["--no-progress"] if args.no_progress else [])


def check_one_tune(controller: str, args: argparse.Namespace) -> str | None:
    """What ``pa10-dnbs tune`` would refuse for ``controller`` before it writes anything (its options, its
    DIR/<controller>: another command's output, another tune, a study of other options), in one line naming
    DIR/<controller> and this script's flags; None if it would start."""
    from pa10_dnbs.cli import build_parser as cli_parser, command_options
    from pa10_dnbs.commands.tune import check_tune
    from pa10_dnbs.config_error import ConfigError
    from pa10_dnbs.refused import Refused

    where = args.out / controller
    try:
        check_tune(command_options(cli_parser().parse_args(
            ["tune", "--controller", controller, "--out", str(where), *tune_arguments(args)])))
    except ConfigError as exc:
        text = exc.named(SETTING_FLAGS)
    except Refused as exc:
        text = said_as(str(exc), SETTING_FLAGS)
    else:
        return None
    return (text.replace("--out/--storage: study", f"{where}: study")
            .replace("give another --out (or --storage) to start a new study",
                     "give another --out (a new comparison)"))


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    try:
        check_output_dir(args.out, False, "out", inputs={"config_path": args.config},   # never "" (the cwd), ...;
                         resume=frozenset(CONTROLLERS) | {"comparison.md"})           # the same command resumes
        lock_output(args.out, "comparison directory")
    except (OutputExistsError, OutputInUseError) as exc:
        print(f"{PROG}: error: {said_as(str(exc), SETTING_FLAGS)}", file=sys.stderr)
        return 2
    try:
        dropped = [c for c in CONTROLLERS if c not in args.controllers
                   and any((args.out / c / f).exists() for f in ("tune.db", "tune.json"))]
        if dropped:   # comparison.md is rewritten whole, from the listed controllers' tunes alone
            print(f"{PROG}: error: --controllers: {args.out} holds the tune of {', '.join(dropped)} too, which "
                  "comparison.md would drop: list every controller of the comparison (the same command resumes), "
                  "or give another --out", file=sys.stderr)
            return 2
        for c in args.controllers:   # every tune checked before the first starts (a refusal after a tune: lost time)
            line = check_one_tune(c, args)
            if line is not None:
                print(f"{PROG}: error: {line}", file=sys.stderr)
                return 2
        results = {}
        for c in args.controllers:
            rc = cli_main(["tune", "--controller", c, "--out", str(args.out / c), *tune_arguments(args)])
            if rc != 0:
                return rc
            results[c] = json.loads((args.out / c / "tune.json").read_text())
        command = "python scripts/equal_budget.py " + " ".join(shlex.quote(a) for a in (argv or sys.argv[1:]))
        with atomic_path(args.out / "comparison.md") as tmp:   # a Ctrl-C while it is written: the old one stays
            tmp.write_text(comparison_markdown(results, command))
    finally:
        release_output(args.out)
    print(f"wrote {args.out}/comparison.md")
    return 0


def interruptible_main(argv: list[str] | None = None) -> int:
    """``main`` with Ctrl-C done right (docs/tuning.md, "Interrupting"): exit 130 and one line; each tune keeps
    its completed trials and says where; a second Ctrl-C ends at once (pa10_dnbs/interrupt.py)."""
    from pa10_dnbs.interrupt import EXIT_INTERRUPTED, say, two_stage_sigint

    try:
        with two_stage_sigint():
            return main(argv)
    except KeyboardInterrupt:   # between two tunes or while comparison.md is written (the same command rewrites it)
        say(f"{PROG}: interrupted; every tune keeps its completed trials in DIR/<controller>/tune.db: the same "
            "command resumes")
        return EXIT_INTERRUPTED


if __name__ == "__main__":
    sys.exit(interruptible_main())

#!/usr/bin/env python3
"""The tuned controllers of several equal-budget comparisons side by side (the README's table): one column per
arm, per scenario each tuned controller's held-out worst RMS [rad], and each one's objective over all its
held-out runs, shipped -> tuned (docs/tuning.md, "Equal budget").

    .venv/bin/python scripts/equal_budget_table.py runs/eq_pa10 runs/eq_iiwa runs/eq_panda

Each DIR is the --out of one ``scripts/equal_budget.py``. Exit 2 with one line when a DIR holds no tune.
"""
from __future__ import annotations

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

import script_main  # noqa: E402  (first: a Ctrl-C while the modules load is one line)
from pa10_dnbs.tune.comparison import arms_table  # noqa: E402
from pa10_dnbs.cli_values import OneLineParser  # noqa: E402


def main(argv: list[str] | None = None) -> int:
    parser = OneLineParser(description=" ".join(__doc__.split("\n\n")[0].split()))
    parser.add_argument("dirs", nargs="+", type=Path, metavar="DIR", help="comparison directories, one per arm")
    args = parser.parse_args(argv)
    try:
        table = arms_table(args.dirs)
    except ValueError as exc:
        print(f"equal_budget_table: error: {exc}", file=sys.stderr)
        return 2
    except (KeyError, TypeError, IndexError, AttributeError) as exc:   # a value of the wrong kind inside a tune.json
        print(f"equal_budget_table: error: a tune.json under {', '.join(map(str, args.dirs))} is not a tune report "
              f"({type(exc).__name__}: {exc})", file=sys.stderr)
        return 2
    print(table, end="")
    return 0


if __name__ == "__main__":
    sys.exit(script_main.run(main, "equal_budget_table", interrupted="nothing printed: run the same command again"))

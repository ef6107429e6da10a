#!/usr/bin/env python3
"""Equal budget, side by side: tune several controllers on one arm with the same trials, objective, training
scenarios and seeds (``pa10-dnbs tune`` once per controller, into DIR/<controller>/), then write
DIR/comparison.md: the held-out figures of each controller as shipped (hand- or rule-tuned, the start of its
search) and as tuned, per scenario (docs/tuning.md, "Equal budget").

    .venv/bin/python scripts/equal_budget.py --arm pa10 --controllers pid,dnbs,ctc --trials 20 --out runs/eq

Every option but --controllers is passed to each tune as it is (--trials, --arm, --config, --scenarios,
--seeds, --held-out-seeds, --duration, --seed, --jobs, --scheduler). A tune that exists in DIR/<controller>/
resumes (the same command finishes an interrupted comparison)."""
from __future__ import annotations

import argparse
import json
import shlex
import sys
from pathlib import Path

from pa10_dnbs.cli import main as cli_main
from pa10_dnbs.tune.comparison import comparison_markdown


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument("--controllers", default="pid,dnbs,ctc", help="comma-separated (default pid,dnbs,ctc)")
    parser.add_argument("--out", type=Path, required=True, metavar="DIR")
    args, rest = parser.parse_known_args(argv)
    if "--held-out-seeds" in rest and rest[rest.index("--held-out-seeds") + 1] == "0":
        print("equal_budget: error: --held-out-seeds: the comparison is on held-out seeds (>= 1)", file=sys.stderr)
        return 2
    ctrls = [c.strip() for c in args.controllers.split(",") if c.strip()]
    results = {}
    for c in ctrls:
        rc = cli_main(["tune", "--controller", c, "--out", str(args.out / c), *rest])
        if rc != 0:
            return rc
        results[c] = json.loads((args.out / c / "tune.json").read_text())
    command = "python scripts/equal_budget.py " + " ".join(shlex.quote(a) for a in (argv or sys.argv[1:]))
    (args.out / "comparison.md").write_text(comparison_markdown(results, command))
    print(f"wrote {args.out}/comparison.md")
    return 0


if __name__ == "__main__":
    sys.exit(main())

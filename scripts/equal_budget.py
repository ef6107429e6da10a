#!/usr/bin/env python3
"""Equal budget, side by side: tune several controllers on one arm with the same trials, objective, training
scenarios and seeds (``pa10-dnbs tune`` once per controller, into DIR/<controller>/), then write
DIR/comparison.md: the held-out figures of each controller as shipped (hand- or rule-tuned, the start of its
search) and as tuned, per scenario (docs/tuning.md, "Equal budget").

    .venv/bin/python scripts/equal_budget.py --arm pa10 --controllers pid,dnbs,ctc --trials 20 --out runs/eq

Every option but --controllers is passed to each tune as it is (--trials, --arm, --config, --scenarios,
--seeds, --held-out-seeds, --duration, --seed, --jobs, --scheduler). A tune that exists in DIR/<controller>/
resumes (the same command finishes an interrupted comparison).
"""
from __future__ import annotations

import argparse
import json
import shlex
import sys
from pathlib import Path

from pa10_dnbs.cli import main as cli_main
from pa10_dnbs.tune.objective import objective


def _worst(rows, key="worst_rms_error_rad"):
    vals = [r[key] for r in rows]
    return None if any(v is None for v in vals) else max(vals)


def _e(v) -> str:
    return "diverged" if v is None else f"{v:.2e}"


def comparison_markdown(results: dict[str, dict], command: str) -> str:
    """One table: per scenario, each controller's worst held-out RMS as shipped and as tuned; the objective."""
    ctrls = list(results)
    first = next(iter(results.values()))
    scenarios = list(dict.fromkeys(r["scenario"] for r in first["held_out"]["start"]))
    seeds = first["held_out_seeds"]
    opts = first["options"]
    lines = [f"# Equal budget on {first['arm']}", "", f"`{command}`", "",
             f"Each controller tuned with the same budget: {first['trials']} trials, the same objective "
             f"(docs/tuning.md), training scenarios {', '.join(opts['scenarios'])} x seeds "
             f"{', '.join(map(str, opts['seeds']))}, {opts['duration_s']:g} s runs, sampler seed {opts['seed']}. "
             f"Below, held-out: seeds {', '.join(map(str, seeds))} (never seen by a search) on every scenario; "
             "worst-joint RMS over the metrics window, worst over the seeds [rad]; 'shipped' is the arm's "
             "settings the search started from (hand-tuned on the PA10, the gain rule elsewhere).", "",
             "| scenario | " + " | ".join(f"{c.upper()} shipped | {c.upper()} tuned" for c in ctrls) + " |",
             "|---|" + "---|---|" * len(ctrls)]
    for sc in scenarios:
        cells = []
        for c in ctrls:
            h = results[c]["held_out"]
            cells += [_e(_worst([r for r in h["start"] if r["scenario"] == sc])),
                      _e(_worst([r for r in h["tuned"] if r["scenario"] == sc]))]
        lines.append(f"| {sc} | " + " | ".join(cells) + " |")
    lines.append("| **objective (all held-out runs)** | " + " | ".join(
        f"{objective(results[c]['held_out']['start']):.3f} | {objective(results[c]['held_out']['tuned']):.3f}"
        for c in ctrls) + " |")
    lines.append("| objective (training, best trial) | " + " | ".join(
        f"{results[c]['start_objective']:.3f} | {results[c]['best_objective']:.3f}" for c in ctrls) + " |")
    lines += ["", "Best points (multipliers of the shipped values; docs/tuning.md):", ""]
    for c in ctrls:
        p = results[c]["best_params"]
        lines.append(f"- {c.upper()}: trial {results[c]['best_trial']}: "
                     + ", ".join(f"{k} {v:.3g}" for k, v in p.items()))
    return "\n".join(lines) + "\n"


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

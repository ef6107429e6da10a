"""The equal-budget comparison's tables (docs/tuning.md, "Equal budget"): one arm's shipped-against-tuned
table, and the tuned controllers of several arms side by side (the README's). Input: the ``tune.json`` that
``pa10-dnbs tune`` writes in each ``DIR/<controller>/``."""
from __future__ import annotations

import json
from pathlib import Path

from .objective import objective
from .report import worst_rms


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
             "settings the search started from (its arm file's values, the gain rule's where the file gives none).", "",
             "| scenario | " + " | ".join(f"{c.upper()} shipped | {c.upper()} tuned" for c in ctrls) + " |",
             "|---|" + "---|---|" * len(ctrls)]
    for sc in scenarios:
        cells = []
        for c in ctrls:
            h = results[c]["held_out"]
            cells += [_e(worst_rms([r for r in h["start"] if r["scenario"] == sc])),
                      _e(worst_rms([r for r in h["tuned"] if r["scenario"] == sc]))]
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


def _short(v) -> str:
    """2 digits, the exponent without its leading zero (3.2e-5)."""
    return "diverged" if v is None else f"{v:.1e}".replace("e-0", "e-").replace("e+0", "e+")


TUNE_KEYS = ("arm", "options", "trials", "held_out_seeds", "held_out", "start_objective", "best_objective",
             "best_params", "best_trial")   # what a table reads of a tune.json
OPTION_KEYS = ("scenarios", "seeds", "duration_s", "seed")


def _tune_report(path: Path) -> dict:
    """One tune.json; ValueError naming it when it is not JSON or lacks a key the tables read."""
    try:
        tune = json.loads(path.read_text())
    except (OSError, UnicodeDecodeError, ValueError) as exc:
        raise ValueError(f"{path}: not a tune report: {exc}") from None
    if not isinstance(tune, dict) or not isinstance(tune.get("options", {}), dict):
        raise ValueError(f"{path}: not a tune report: not a JSON object with an object of options")
    missing = [k for k in TUNE_KEYS if k not in tune] or [f"options.{k}" for k in OPTION_KEYS
                                                            if k not in tune["options"]]
    if missing:
        raise ValueError(f"{path}: not a tune report: no {missing[0]}")
    if not isinstance(tune["held_out"], dict):   # a tune run with --held-out-seeds 0: nothing to compare
        raise ValueError(f"{path}: a tune without held-out runs (no held-out seeds): the comparison's tables are of "
                         "held-out runs")
    return tune


def load_comparison(directory: Path) -> dict[str, dict]:
    """{controller: its tune.json} of one finished comparison DIR (its comparison.md written), DNBS, PID and CTC
    first; ValueError when there is none, or it is unfinished (an interrupted equal_budget.py)."""
    directory = Path(directory)
    reports = [c / "tune.json" for c in (sorted(directory.iterdir()) if directory.is_dir() else [])
               if (c / "tune.json").is_file()]
    if not reports:
        raise ValueError(f"no DIR/<controller>/tune.json under {directory}")
    if not (directory / "comparison.md").is_file():
        raise ValueError(f"{directory} is an unfinished comparison (no comparison.md: its equal_budget.py was "
                         "interrupted): run that command again to finish it")
    results = {path.parent.name: _tune_report(path) for path in reports}
    first = [c for c in ("dnbs", "pid", "ctc") if c in results]
    return {c: results[c] for c in first + [c for c in results if c not in first]}


def budget(tune: dict) -> str:
    """A tune's budget in words (tune.json): trials, training runs, held-out seeds, the sampler's seed."""
    o = tune["options"]
    return (f"{tune['trials']} trials of {len(o['scenarios'])} scenarios x {len(o['seeds'])} seeds x "
            f"{o['duration_s']:g} s, {len(tune['held_out_seeds'])} held-out seeds, seed {o['seed']}")


def arms_table(dirs: list[Path]) -> str:
    """Per scenario and arm, each tuned controller's held-out worst RMS [rad] (``DIR/<controller>/tune.json`` of
    every comparison DIR); the last row: each controller's objective over all its held-out runs."""
    arms, budgets = [], {}
    for d in dirs:
        results = load_comparison(d)
        arms.append((next(iter(results.values()))["arm"], results))
        for c, t in results.items():
            budgets.setdefault(budget(t), f"{d}/{c}")
    if len(budgets) > 1:   # the table says 'equal budget': so must its columns be
        raise ValueError("not equal budgets: " + "; ".join(f"{where}: {text}" for text, where in budgets.items()))
    first: dict[str, Path] = {}
    for d, (arm, _) in zip(dirs, arms):   # the columns are arms: two of one arm would read as two arms
        if arm in first:
            raise ValueError(f"{d} given twice" if Path(first[arm]).resolve() == Path(d).resolve() else
                             f"{first[arm]} and {d} are both comparisons on an arm named {arm} (the columns are "
                             "named by arm): give one DIR per arm")
        first[arm] = d
    scenarios = list(dict.fromkeys(r["scenario"] for _, res in arms for t in res.values()
                                   for r in t["held_out"]["tuned"]))
    lines = ["| scenario | " + " | ".join(f"{arm} {' / '.join(c.upper() for c in res)}" for arm, res in arms) + " |",
             "|---|" + "---|" * len(arms)]
    for sc in scenarios:
        lines.append(f"| {sc} | " + " | ".join(" / ".join(
            _short(worst_rms([r for r in t["held_out"]["tuned"] if r["scenario"] == sc])) for t in res.values())
            for _, res in arms) + " |")
    lines.append("| objective, all held-out runs (shipped -> tuned) | " + " | ".join(" / ".join(
        f"{objective(t['held_out']['start']):.1f} -> {objective(t['held_out']['tuned']):.1f}" for t in res.values())
        for _, res in arms) + " |")
    return "\n".join(lines) + "\n"

"""What a tune writes in its directory: tuned.yaml (a config that extends the one the tune started from),
tune.md (space, best trial, held-out table, every trial), history.png and importance.png."""
from __future__ import annotations

import warnings
from pathlib import Path

import yaml

from ..interrupt import check, immediate
from .objective import FAIL_COST, objective, run_cost
from .space import SPACES, Param, on_bound, settings_fragment


def tuned_yaml(spec, base, values: dict, arm_value: str, extends: Path, header: list[str]) -> str:
    """The tuned settings as a config file: ``extends`` the config the tune started from, names the arm, and
    sets the per-joint values of the best point (``simulate --config`` takes it as it is)."""
    fragment = settings_fragment(spec.controller, base, dict(spec.fixed, **values))
    doc = {"extends": str(Path(extends).resolve()), "arm": arm_value, **fragment}
    return "".join(f"# {line}\n" for line in header) + yaml.safe_dump(doc, sort_keys=False, width=110,
                                                                      default_flow_style=None)


def worst_rms(rows: list[dict]) -> float | None:
    """The largest worst-joint RMS [rad] of ``rows`` (runs); None when one of them has none (diverged)."""
    vals = [r["worst_rms_error_rad"] for r in rows]
    return None if any(v is None for v in vals) else max(vals)


def _e(v):
    return "-" if v is None else f"{v:.2e}"


def held_out_table(rows: dict[str, list[dict]], scenarios: list[str]) -> list[str]:
    """Per scenario, worst over the held-out seeds: RMS and cost of the start and tuned settings, divergences."""
    lines = ["| scenario | start RMS worst [rad] | tuned RMS worst [rad] | tuned / start | start cost | tuned cost | "
             "diverged start / tuned |", "|---|---|---|---|---|---|---|"]
    for sc in scenarios + ["all"]:
        s = [r for r in rows["start"] if sc in ("all", r["scenario"])]
        t = [r for r in rows["tuned"] if sc in ("all", r["scenario"])]
        rs, rt = worst_rms(s), worst_rms(t)
        ratio = f"{rt / rs:.2f}" if rs and rt is not None else "-"
        name = "**all (objective)**" if sc == "all" else sc
        lines.append(f"| {name} | {_e(rs)} | {_e(rt)} | {ratio} | {objective(s):.3f} | {objective(t):.3f} | "
                     f"{sum(r['diverged'] for r in s)} / {sum(r['diverged'] for r in t)} |")
    return lines


def held_out_verdict(rows: dict[str, list[dict]]) -> str | None:
    """A warning when the tuned settings score worse than the start on the held-out runs (their worst run, the
    objective), naming the run that is worst; None when they are at least as good. The search only saw its
    training runs: a point that fits them can lose on a scenario none of them contains."""
    start, tuned = objective(rows["start"]), objective(rows["tuned"])
    if tuned <= start:
        return None
    worst = max(rows["tuned"], key=run_cost)
    return (f"The tuned settings are worse than the start on the held-out runs (objective {tuned:.3f} against "
            f"{start:.3f}; worst: {worst['scenario']} seed {worst['seed']}): keep the start, or tune again with "
            "that scenario among the training runs (--scenarios).")


def tune_markdown(spec, study, best, start_trial, command: str, where: str, wall_s: float,
                  held: dict | None, held_scenarios: list[str], held_seeds: list[int], storage_url: str,
                  figures: list[str]) -> str:
    from .tuner import completed

    trials = completed(study)
    values = dict(spec.fixed, **best.params)
    lines = [f"# Tune: {spec.controller.upper()} on {spec.arm_name}", "", f"`{command}`", "",
             f"Study `{spec.study_name}` in `{storage_url}` (optuna-dashboard opens it: docs/tuning.md); "
             f"{len(trials)} completed trials, TPE sampler seeded {spec.seed}; runs on {where}; "
             f"this invocation {wall_s:.0f} s of wall time.", "",
             f"Training (the search sees only these): scenarios {', '.join(spec.scenarios)} x seeds "
             f"{', '.join(map(str, spec.seeds))}, {spec.duration_s:g} s each. Objective: the worst run's cost, "
             "cost = log10(worst-joint RMS over the metrics window) + 0.2 x settling time [s] + 0.5 x "
             "max(0, log10(torque variation / 20)) + 5 x saturated fraction after start-up; a diverged run "
             f"costs {FAIL_COST:g} (docs/tuning.md). Lower is better.", "",
             "## Search space and best point", "",
             "| parameter | range | scale | meaning | start | best |", "|---|---|---|---|---|---|"]
    searched = {p.name for p in spec.params}
    for p in SPACES[spec.controller]:
        best_v = f"{values[p.name]:.4g}" if p.name in searched else "(not searched)"
        lines.append(f"| {p.name} | [{p.low:g}, {p.high:g}] | {'log' if p.log else 'linear'} | {p.what} | "
                     f"{spec.start[p.name]:.4g} | {best_v} |")
    bound = on_bound(spec.params, values)
    lines += ["", f"Best: trial {best.number}, objective {best.value:.3f} on the training runs; the start settings "
              f"(trial {start_trial.number}): {start_trial.value:.3f}." if start_trial is not None else
              f"Best: trial {best.number}, objective {best.value:.3f} on the training runs.", ""]
    lines.append(("**On a bound:** " + ", ".join(bound) + ": the best may lie outside the space; widen it "
                  "(pa10_dnbs/tune/space.py) or fix that parameter (--params).") if bound else
                 "No parameter of the best point is on a bound of its range.")
    lines.append("")
    if held is not None:
        lines += ["## Held-out", "",
                  f"The best point and the start settings re-run on seeds {', '.join(map(str, held_seeds))} "
                  f"(never used by the search) and every scenario ({len(held_scenarios)}), {spec.duration_s:g} s; "
                  "worst over the seeds.", ""]
        lines += held_out_table(held, held_scenarios)
        verdict = held_out_verdict(held)
        lines += ["", f"**Worse than the start:** {verdict}" if verdict else
                  "The tuned settings are at least as good as the start on the held-out runs (the objective)."]
        lines.append("")
    for f in figures:
        lines += [f"![{f}]({f})", ""]
    names = [p.name for p in spec.params]
    lines += ["## Trials", "", "| trial | " + " | ".join(names) + " | objective | worst run |",
              "|---|" + "---|" * len(names) + "---|---|"]
    for t in trials:
        rows = t.user_attrs.get("rows", [])
        worst = max(rows, key=lambda r: r["cost"], default=None)
        where_w = f"{worst['scenario']} seed {worst['seed']}" if worst else "-"
        mark = " (start)" if t.user_attrs.get("start") else (" (best)" if t.number == best.number else "")
        lines.append(f"| {t.number}{mark} | " + " | ".join(f"{t.params[n]:.4g}" for n in names)
                     + f" | {t.value:.3f} | {where_w} |")
    return "\n".join(lines) + "\n"


def tune_figures(study, directory: Path) -> list[str]:
    """history.png and importance.png (optuna.visualization.matplotlib); the names written (importances need
    at least two completed trials with different points)."""
    with immediate():   # seconds of imports on a busy machine: a Ctrl-C stops them at once
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        from optuna.visualization.matplotlib import plot_optimization_history, plot_param_importances

    from optuna.trial import TrialState

    points = {tuple(sorted(t.params.items())) for t in study.get_trials(deepcopy=False, states=(TrialState.COMPLETE,))}
    out = []
    for name, plot in (("history.png", plot_optimization_history), ("importance.png", plot_param_importances)):
        check()   # a Ctrl-C noted meanwhile (the plots read the storage: never interrupted inside)
        if name == "importance.png" and len(points) < 2:   # optuna draws equal shares from one point: no measure
            continue
        try:
            with warnings.catch_warnings():   # optuna's "too few trials" for importances: not the user's concern
                warnings.simplefilter("ignore", UserWarning)
                ax = plot(study)
        except (ValueError, RuntimeError, ZeroDivisionError):
            continue
        fig = ax.figure
        fig.set_size_inches(7, 4)
        fig.tight_layout()
        fig.savefig(directory / name, dpi=90, bbox_inches="tight")
        plt.close(fig)
        out.append(name)
    return out


def describe(params: tuple[Param, ...]) -> str:
    return ", ".join(p.name for p in params)

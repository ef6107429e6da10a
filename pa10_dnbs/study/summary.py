"""study.md and the study figure: per scenario and controller, the median and worst over the seeds;
and the checks of the controller's robustness targets (docs/controller.md)."""
from __future__ import annotations

from pathlib import Path

import numpy as np


def _values(rows, scenario, controller, key):
    return [r[key] for r in rows if r["scenario"] == scenario and r["controller"] == controller]


def _worst(vals):
    """Largest value; None (never settled, non-finite) is worse than any number."""
    return None if any(v is None for v in vals) else max(vals)


def _fmt(v, spec):
    return "never" if v is None else format(v, spec)


def checks(rows: list[dict]) -> list[tuple[str, bool, str]]:
    """(target, met, figures) for the DNBS robustness targets the rows allow checking."""
    scenarios = list(dict.fromkeys(r["scenario"] for r in rows))
    controllers = set(r["controller"] for r in rows)
    out = []
    if "dnbs" in controllers:
        dnbs = [r for r in rows if r["controller"] == "dnbs"]
        div = sum(r["diverged"] for r in dnbs)
        out.append(("no DNBS run diverges", div == 0, f"{div} of {len(dnbs)} diverged"))
        for s in scenarios:
            rms = _values(rows, s, "dnbs", "worst_rms_error_rad")
            if len(rms) > 1 and None not in rms:
                med = float(np.median(rms))
                out.append((f"{s}: worst seed's RMS within 2x the median", max(rms) <= 2 * med,
                            f"worst {max(rms):.3e}, median {med:.3e} rad"))
    if {"dnbs", "pid"} <= controllers:
        for s in scenarios:
            d, p = _values(rows, s, "dnbs", "worst_rms_error_rad"), _values(rows, s, "pid", "worst_rms_error_rad")
            if None in d or None in p:
                out.append((f"{s}: DNBS RMS below PID's", False, "a run has no finite RMS"))
            else:
                out.append((f"{s}: DNBS RMS below PID's", max(d) < min(p),
                            f"DNBS worst {max(d):.3e}, PID best {min(p):.3e} rad"))
    nom, late = _values(rows, "nominal", "dnbs", "worst_rms_error_rad"), _values(rows, "delay_1_tick", "dnbs",
                                                                                "worst_rms_error_rad")
    if nom and late and None not in nom + late:
        out.append(("delay_1_tick: DNBS within 3x its nominal RMS", np.median(late) <= 3 * np.median(nom),
                    f"{np.median(late):.3e} vs nominal {np.median(nom):.3e} rad (medians)"))
    return out


def study_markdown(rows: list[dict], command: str, duration_s: float, descriptions: dict[str, str],
                   infeasible: dict[str, str] | None = None) -> str:
    """study.md; ``infeasible``: {scenario: its line} of the scenarios the arm cannot track (study/feasibility.py),
    each a section that says so instead of comparing controllers."""
    scenarios = list(dict.fromkeys(r["scenario"] for r in rows))
    controllers = list(dict.fromkeys(r["controller"] for r in rows))
    n_seeds = len(set(r["seed"] for r in rows))
    lines = ["# Robustness study", "", f"`{command}`", "",
             f"{len(rows)} runs of {duration_s:g} s: {len(scenarios)} scenarios x {len(controllers)} controllers x "
             f"{n_seeds} seeds (a seed sets the DNBS initial weights and the noise). RMS over the metrics window, "
             "settling time (|e| below the band for good), max |e| and torque variation over the whole run: the worst "
             "joint of each run, then the median and the worst over the seeds. DNBS and PID are decentralized; CTC is "
             "centralized computed torque with the plant's own model (the reference). All controllers keep their "
             "nominal tuning.", ""]
    for s in scenarios:
        lines += [f"## {s}", "", descriptions.get(s, ""), "",
                  "| controller | RMS median [rad] | RMS worst [rad] | settled median [s] | settled worst [s] | "
                  "max abs worst [rad] | torque variation worst | diverged |", "|---|---|---|---|---|---|---|---|"]
        for c in controllers:
            rms = _values(rows, s, c, "worst_rms_error_rad")
            st = _values(rows, s, c, "worst_settling_time_s")
            finite_rms = [v for v in rms if v is not None]
            finite_st = [v for v in st if v is not None]
            lines.append(f"| {c} | {_fmt(float(np.median(finite_rms)) if finite_rms else None, '.3e')} | "
                         f"{_fmt(_worst(rms), '.3e')} | "
                         f"{_fmt(float(np.median(finite_st)) if len(finite_st) == len(st) else None, '.3f')} | "
                         f"{_fmt(_worst(st), '.3f')} | {_fmt(_worst(_values(rows, s, c, 'worst_max_abs_error_run_rad')), '.4f')} | "
                         f"{_fmt(_worst(_values(rows, s, c, 'worst_torque_variation')), '.2f')} | "
                         f"{sum(_values(rows, s, c, 'diverged'))} of {len(rms)} |")
        lines.append("")
    for s, line in (infeasible or {}).items():
        lines += [f"## {s}", "", descriptions.get(s, ""), "",
                  f"**Not run**: {line.split(': ', 1)[-1]}", ""]
    lines += ["## Targets", "", "| target | met | figures |", "|---|---|---|"]
    lines += [f"| {t} | {'yes' if ok else '**no**'} | {f} |" for t, ok, f in checks(rows)]
    lines += [f"| {s}: DNBS RMS below PID's | n/a: infeasible | not run (see {s} above) |" for s in infeasible or {}]
    return "\n".join(lines) + "\n"


def study_figure(rows: list[dict], path: Path) -> None:
    """Worst-joint RMS per scenario and controller: median (bar) and the range over the seeds (whiskers), log scale."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    scenarios = list(dict.fromkeys(r["scenario"] for r in rows))
    controllers = list(dict.fromkeys(r["controller"] for r in rows))
    width = 0.8 / len(controllers)
    fig, ax = plt.subplots(figsize=(max(6, 1.4 * len(scenarios)), 4.5), constrained_layout=True)
    for i, c in enumerate(controllers):
        x = np.arange(len(scenarios)) + (i - (len(controllers) - 1) / 2) * width
        vals = [[v for v in _values(rows, s, c, "worst_rms_error_rad") if v is not None] for s in scenarios]
        med = np.array([np.median(v) if v else np.nan for v in vals])
        lo = np.array([min(v) if v else np.nan for v in vals])
        hi = np.array([max(v) if v else np.nan for v in vals])
        ax.bar(x, med, width, label=c.upper(), yerr=[med - lo, hi - med], capsize=2)
    ax.set_yscale("log")
    ax.set_xticks(np.arange(len(scenarios)), scenarios, rotation=25, ha="right")
    ax.set_ylabel("worst-joint RMS error [rad]")
    ax.set_title("Robustness study: median over the seeds, whiskers min..max")
    ax.grid(axis="y", alpha=0.3, which="both")
    ax.legend()
    fig.savefig(path, dpi=90)
    plt.close(fig)

#!/usr/bin/env python3
"""Ablation of the DNBS remedies: the default config against each remedy off (or on) in turn, and the paper's law.

Each remedy of the default config is switched off in turn (and the ones it leaves off switched on in turn),
against the default and the paper's law, on three runs:

- nominal, 20 s: settling time, max |e| over the run, torque variation, steps at the limit after 0.2 s,
  RMS over [10, 20) s (worst joint of each);
- payload_5kg, 20 s: settling time, torque variation, RMS;
- encoder_noise, 100 s: RMS over [80, 100) s, where covariance windup shows (it does not within 20 s).

Prints a Markdown table (docs/controller.md holds the one of the last run). Figures only; nothing asserted.

    python scripts/ablation.py [--workers N] [--long-s 100]
"""
from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
sys.path.insert(0, str(Path(__file__).resolve().parent))

import script_main  # noqa: E402  (first: a Ctrl-C while the modules load is one line)
from pa10_dnbs.cli_values import OneLineParser, number_in, whole_in  # noqa: E402
from pa10_dnbs.config import default_config_path  # noqa: E402
from pa10_dnbs.paths import share_path  # noqa: E402
from pa10_dnbs.numeric_platform import numeric_platform, platform_line  # noqa: E402
from pa10_dnbs.report.metrics_file import metrics_dict, metrics_settings  # noqa: E402
from pa10_dnbs.sim.closed_loop import simulate  # noqa: E402
from pa10_dnbs.study.executor import Executor  # noqa: E402
from pa10_dnbs.study.lost_runs import RunsLost  # noqa: E402
from pa10_dnbs.study.scenarios import scenario_settings  # noqa: E402
from pa10_dnbs.run_settings import build_settings  # noqa: E402
from pa10_dnbs.settings import replace_in  # noqa: E402


NOTHING_PRINTED = "nothing printed (the table comes whole, once every run is done): run the same command again"


def _set(path: str, value):
    def edit(settings):
        return replace_in(settings, path, value)
    return edit


def _with(**remedies):
    def edit(settings):
        for name, kv in remedies.items():
            for key, value in kv.items():
                settings = replace_in(settings, f"dnbs.remedies.{name}.{key}", value)
        return settings
    return edit


REMEDIES = "dnbs.remedies"
VARIANTS = [
    ("default", None),
    ("paper's law (config/paper.yaml)", "paper"),
    ("paper's law without its anti-windup", ("paper", _set(f"{REMEDIES}.anti_windup.enabled", False))),
    ("robust term off", _set(f"{REMEDIES}.robust_term.enabled", False)),
    ("velocity feed-forward off", _set(f"{REMEDIES}.robust_term.velocity_feedforward", False)),
    ("anti-windup off", _set(f"{REMEDIES}.anti_windup.enabled", False)),
    ("learning ramp off", _set(f"{REMEDIES}.learning_ramp.enabled", False)),
    ("covariance bound off", _set(f"{REMEDIES}.covariance_bound.enabled", False)),
    ("+ dead zone (2e-4 rad, 3e-3 rad/s)", _with(dead_zone={"enabled": True, "alpha_rad": (2e-4,) * 7,
                                                          "torque_rad_s": (3e-3,) * 7})),
    ("+ e-modification (sigma 1e-3)", _with(e_modification={"enabled": True, "sigma": 1e-3})),
    ("+ projection (B = 2)", _with(projection={"enabled": True, "weight_bound": 2.0})),
]


def _run(args) -> dict:
    variant, scenario, duration, window = args
    spec = VARIANTS[variant][1]
    preset, edit = spec if isinstance(spec, tuple) else (spec, spec)
    base = build_settings(share_path("config", "paper.yaml") if preset == "paper" else default_config_path())
    if callable(edit):
        base = edit(base)
    cfg, dist = scenario_settings(base, scenario, base.simulation.seed)
    cfg = replace_in(replace_in(cfg, "simulation.duration_s", duration), "simulation.window_s", window)
    run = simulate(cfg, "dnbs", duration, disturbances=dist)
    m = metrics_dict(run, metrics_settings(cfg, duration))
    return {"variant": variant, "scenario": scenario, **{k: m[k] for k in (
        "worst_settling_time_s", "worst_max_abs_error_run_rad", "worst_torque_variation",
        "worst_saturated_fraction_after_s", "worst_rms_error_rad")}}


def _f(v, spec):
    return "never" if v is None else format(v, spec)


def _variants(text: str) -> list[int]:
    try:
        rows = [int(x) for x in text.split(",") if x.strip()]
    except ValueError:
        rows = []
    if not rows or any(not 0 <= r < len(VARIANTS) for r in rows):
        raise argparse.ArgumentTypeError(f"expected comma-separated variant numbers 0..{len(VARIANTS) - 1}, "
                                         f"got {text!r}")
    return list(dict.fromkeys(rows))


def main(argv: list[str] | None = None) -> int:
    ap = OneLineParser(prog="ablation", description=__doc__.split("\n\n")[0],
                       epilog="variants: " + "; ".join(f"{i} {name}" for i, (name, _) in enumerate(VARIANTS)))
    ap.add_argument("--workers", "--jobs", dest="workers", type=whole_in(1, 4096), default=None, metavar="N",
                    help="worker processes (default: one per core)")
    ap.add_argument("--long-s", type=number_in(20.0, 1e5, low_open=False), default=100.0, metavar="SECONDS",
                    help="length of the noisy run [s], >= 20 (its RMS is over the last 20 s; default 100)")
    ap.add_argument("--only", type=_variants, default=None, metavar="LIST",
                    help="comma-separated variant numbers to run (0 = the default config; default: all)")
    a = ap.parse_args(argv)
    rows = range(len(VARIANTS)) if a.only is None else a.only
    jobs = [(i, sc, d, w) for i in rows for sc, d, w in (
        ("nominal", 20.0, (10.0, 20.0)), ("payload_5kg", 20.0, (10.0, 20.0)),
        ("encoder_noise", a.long_s, (a.long_s - 20.0, a.long_s)))]
    try:
        with Executor(min(a.workers or os.cpu_count() or 1, len(jobs))) as ex:   # Ctrl-C: its workers stopped
            res = {(r["variant"], r["scenario"]): r
                   for r in ex.run(_run, dict(enumerate((j,) for j in jobs))).values()}
    except RunsLost as exc:   # a worker process killed (the OOM killer)
        print(f"ablation: error: {exc.named({'jobs': '--workers'})}; {NOTHING_PRINTED}", file=sys.stderr)
        return 2
    print(f"| variant | nominal: settled [s] | max abs [rad] | torque variation | at limit after 0.2 s | RMS [rad] | "
          f"payload 5 kg: settled [s] | torque variation | RMS [rad] | noise, {a.long_s:g} s: RMS last 20 s [rad] |")
    print("|---" * 10 + "|")
    for i in rows:
        name = VARIANTS[i][0]
        n, p, z = res[(i, "nominal")], res[(i, "payload_5kg")], res[(i, "encoder_noise")]
        print(f"| {name} | {_f(n['worst_settling_time_s'], '.3f')} | {n['worst_max_abs_error_run_rad']:.4f} | "
              f"{n['worst_torque_variation']:.2f} | {n['worst_saturated_fraction_after_s']:.4f} | "
              f"{n['worst_rms_error_rad']:.2e} | {_f(p['worst_settling_time_s'], '.3f')} | "
              f"{p['worst_torque_variation']:.2f} | {p['worst_rms_error_rad']:.2e} | {z['worst_rms_error_rad']:.2e} |")
    # the diverged and the long noisy runs carry the last bits of the plant's solve and numpy's loops into their
    # printed digits: their cells are this platform's (docs/controller.md, "Ablation")
    print(f"\nnumeric platform: {platform_line(numeric_platform())}")
    return 0


if __name__ == "__main__":   # Ctrl-C: the workers stopped, one line, exit 130 (docs/tuning.md, "Interrupting")
    sys.exit(script_main.run(main, "ablation", {"jobs": "--workers"}, interrupted=NOTHING_PRINTED))

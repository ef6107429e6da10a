"""Run every (scenario, controller, seed) of a study in worker processes; one row of figures per run."""
from __future__ import annotations

import math
import os
from concurrent.futures import ProcessPoolExecutor, as_completed
from itertools import product

import numpy as np

from ..report.metrics_file import metrics_dict, metrics_settings
from ..sim.closed_loop import simulate
from .scenarios import scenario_config

DIVERGED_RAD = 1.0  # a run with |e| above this (or a non-finite value) counts as diverged


def _finite_or_none(x):
    return float(x) if x is not None and math.isfinite(x) else None


def run_one(cfg: dict, scenario: str, controller: str, seed: int, duration_s: float) -> dict:
    """The row of one run (the fields of study.json)."""
    scfg, dist = scenario_config(cfg, scenario, seed)
    run = simulate(scfg, controller, duration_s, disturbances=dist)
    m = metrics_dict(run, metrics_settings(scfg, run.n_steps * run.dt_s))
    err = run.error_rad
    diverged = not (np.all(np.isfinite(err)) and np.all(np.isfinite(run.torque_nm))) or bool(
        np.nanmax(np.abs(err)) > DIVERGED_RAD)
    return {"scenario": scenario, "controller": controller, "seed": seed,
            "worst_rms_error_rad": _finite_or_none(m["worst_rms_error_rad"]),
            "worst_settling_time_s": _finite_or_none(m["worst_settling_time_s"]),
            "worst_max_abs_error_run_rad": _finite_or_none(m["worst_max_abs_error_run_rad"]),
            "worst_torque_variation": _finite_or_none(m["worst_torque_variation"]),
            "diverged": diverged}


def run_study(cfg: dict, scenarios, controllers, seeds: int, duration_s: float, workers: int | None = None,
              on_done=None) -> list[dict]:
    """Rows of every combination, sorted by scenario, controller, seed; ``on_done(row)`` after each run.

    ``workers``: processes (default: one per core); 1 runs in this process.
    """
    jobs = list(product(scenarios, controllers, range(seeds)))
    workers = workers or os.cpu_count() or 1
    rows = []
    if workers == 1:
        for sc, ctrl, seed in jobs:
            rows.append(run_one(cfg, sc, ctrl, seed, duration_s))
            if on_done:
                on_done(rows[-1])
    else:
        with ProcessPoolExecutor(max_workers=min(workers, len(jobs))) as pool:
            futures = [pool.submit(run_one, cfg, sc, ctrl, seed, duration_s) for sc, ctrl, seed in jobs]
            for f in as_completed(futures):
                rows.append(f.result())
                if on_done:
                    on_done(rows[-1])
    order = {(s, c): i for i, (s, c) in enumerate(product(scenarios, controllers))}
    return sorted(rows, key=lambda r: (order[(r["scenario"], r["controller"])], r["seed"]))

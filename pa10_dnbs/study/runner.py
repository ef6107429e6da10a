"""Run every (scenario, controller, seed) of a study in worker processes or on a Dask cluster; one row of
figures per run (study/executor.py)."""
from __future__ import annotations

import math
import os
from itertools import product

from ..report.metrics_file import metrics_dict, metrics_settings
from ..sim.closed_loop import simulate
from .executor import Executor
from .scenarios import scenario_settings



def _finite_or_none(x):
    return float(x) if x is not None and math.isfinite(x) else None


def run_one(settings, scenario: str, controller: str, seed: int, duration_s: float) -> dict:
    """The row of one run (the fields of study.json); ``settings``: the nominal run's Settings."""
    changed, dist = scenario_settings(settings, scenario, seed)
    run = simulate(changed, controller, duration_s, disturbances=dist)
    m = metrics_dict(run, metrics_settings(changed, run.n_steps * run.dt_s))
    diverged = m["diverged"] is not None   # |e| > 1 rad or a non-finite value (core/metrics.divergence)
    return {"scenario": scenario, "controller": controller, "seed": seed,
            "worst_rms_error_rad": _finite_or_none(m["worst_rms_error_rad"]),
            "worst_settling_time_s": _finite_or_none(m["worst_settling_time_s"]),
            "worst_max_abs_error_run_rad": _finite_or_none(m["worst_max_abs_error_run_rad"]),
            "worst_torque_variation": _finite_or_none(m["worst_torque_variation"]),
            "diverged": diverged,
            # states the guards refused, non-finite torques replaced, EKF resets: all joints (report/metrics_file)
            "guard_events": sum(sum(c.values()) for c in m.get("guard_counters", {}).values())}


def run_study(settings, scenarios, controllers, seeds: int, duration_s: float, workers: int | None = None,
              on_done=None, scheduler: str | None = None) -> list[dict]:
    """Rows of every combination, sorted by scenario, controller, seed; ``on_done(row)`` once per run.

    ``workers``: local processes (default: one per core; 1 runs in this process); ``scheduler``: the address of
    a Dask scheduler to run on instead.
    Results are keyed by (scenario, controller, seed): a run a cluster redid is one row.
    """
    tasks = {(sc, ctrl, seed): (settings, sc, ctrl, seed, duration_s)
             for sc, ctrl, seed in product(scenarios, controllers, range(seeds))}

    def done(key, row):
        if on_done:
            on_done(row)

    with Executor(min(workers or os.cpu_count() or 1, len(tasks)) if scheduler is None else None, scheduler) as ex:
        results = ex.run(run_one, tasks, done)
    return [results[k] for k in tasks]

"""The metrics.json of a run (same schema for in-process, graph and bag runs)."""
from __future__ import annotations

import numpy as np

from ..core.metrics import joint_metrics
from ..run_data import RunData


def effective_window(duration_s: float, window_s: tuple[float, float]) -> tuple[float, float]:
    """The configured window, or the second half of a run too short to hold it."""
    if window_s[1] <= duration_s + 1e-9:
        return window_s
    return (duration_s / 2.0, duration_s)


def metrics_dict(run: RunData, window_s: tuple[float, float], **extra) -> dict:
    """Per-joint figures over the window plus run-level facts; ``extra`` keys are added as they are."""
    duration = run.n_steps * run.dt_s
    joints = joint_metrics(run.error_rad, run.torque_nm, run.torque_limit_nm, run.dt_s, window_s)
    for name, j in zip(run.joint_names, joints):
        j["name"] = name
    finite = bool(np.all(np.isfinite(run.position_rad)) and np.all(np.isfinite(run.torque_nm)))
    within = bool(np.all(np.abs(run.torque_nm) <= run.torque_limit_nm * (1 + 1e-12)))
    out = {
        "controller": run.controller,
        "duration_s": duration,
        "dt_s": run.dt_s,
        "window_s": list(window_s),
        "wall_time_s": run.wall_time_s,
        "real_time_factor": duration / run.wall_time_s if run.wall_time_s > 0 else None,
        "worst_rms_error_rad": max(j["rms_error_rad"] for j in joints),
        "all_finite": finite,
        "torques_within_limits": within,
        "joints": [{k: j[k] for k in ("name", "rms_error_rad", "max_abs_error_rad", "max_abs_torque_nm",
                                      "torque_limit_nm", "saturated_fraction")} for j in joints],
    }
    out.update(extra)
    return out

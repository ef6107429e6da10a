"""The metrics.json of a run (same schema for in-process, graph and bag runs)."""
from __future__ import annotations

import numpy as np

from ..core.metrics import (DIVERGED_RAD, at_limit, divergence, first_non_finite, first_step, joint_metrics,
                             run_metrics)
from ..run_data import RunData


def effective_window(duration_s: float, window_s: tuple[float, float]) -> tuple[float, float]:
    """The configured window, or the second half of a run too short to hold it."""
    if window_s[1] <= duration_s + 1e-9:
        return window_s
    return (duration_s / 2.0, duration_s)


def metrics_settings(settings, duration_s: float) -> dict:
    """window_s (the settings' window, or the second half of a shorter run), settle_band_rad [rad], startup_s
    [s]. ``settings``: a run's :class:`~pa10_dnbs.settings.Settings`."""
    m = settings.metrics
    return window_settings(settings.simulation.window_s, m.settle_band_rad, m.startup_s, duration_s)


def window_settings(window_s, settle_band_rad: float, startup_s: float, duration_s: float) -> dict:
    """What :func:`metrics_dict` takes: the window [t0, t1] s (or the second half of a run shorter than it),
    settle_band_rad [rad], startup_s [s]."""
    return {"window_s": tuple(effective_window(duration_s, tuple(window_s))),
            "settle_band_rad": float(settle_band_rad), "startup_s": float(startup_s)}


def _worst_settling(values: list) -> float | None:
    return None if any(v is None for v in values) else max(values)


def metrics_dict(run: RunData, settings: dict, **extra) -> dict:
    """Per-joint figures over the window and over the whole run, plus run-level facts; ``extra`` keys are
    added as they are. ``settings``: :func:`metrics_settings`.

    ``diverged`` is None, or where the run diverged: ``{"step", "time_s", "joint", "why"}``, the first step with
    |e| > DIVERGED_RAD (why ``"|e| > 1 rad"``) or a non-finite sample (why ``"non-finite"``), whichever comes first
    (:func:`pa10_dnbs.core.metrics.divergence`, the study's and the tuner's definition too). A run that went
    non-finite (``non_finite_from_step``, its figures end there): a figure of a joint that the non-finite samples
    leave undefined (NaN) is Infinity here, and so is that joint's max |e| over the run, so that the worst
    joint is the diverged one; metrics.json writes every non-finite figure null (``json_text.py``)."""
    duration = run.n_steps * run.dt_s
    window_s = settings["window_s"]
    joints = joint_metrics(run.error_rad, run.torque_nm, run.torque_limit_nm, run.dt_s, window_s)
    whole = run_metrics(run.error_rad, run.torque_nm, run.torque_limit_nm, run.dt_s, settings["settle_band_rad"],
                        settings["startup_s"])
    for name, j, w in zip(run.joint_names, joints, whole):
        j["name"] = name
        j.update(w)
    gone = first_non_finite(run.position_rad, run.velocity_rad_s, run.torque_nm)
    if gone is not None:
        _unbounded(joints, run)
    diverged = divergence(run.error_rad, run.position_rad, run.velocity_rad_s, run.torque_nm)
    if diverged is not None:
        diverged = {"step": diverged["step"], "time_s": diverged["step"] * run.dt_s,
                    "joint": run.joint_names[diverged["joint"]],
                    "why": "non-finite" if diverged["non_finite"] else f"|e| > {DIVERGED_RAD:g} rad"}
    finite = bool(np.all(np.isfinite(run.position_rad)) and np.all(np.isfinite(run.torque_nm)))
    # (steps from startup_s on, joints): the torque at its limit; a step with any joint there counts once (the
    # README's and the arms' tables)
    limited_after = at_limit(run.torque_nm[first_step(settings["startup_s"], run.dt_s):], run.torque_limit_nm)
    # the applied torque (which the plant clips), and in-process what the controllers asked (the paper's claim)
    within = bool(np.all(np.abs(run.torque_nm) <= run.torque_limit_nm * (1 + 1e-12))
                  and not any(run.extra.get("torques_asked_beyond_limits", ())))
    out = {
        "controller": run.controller,
        "duration_s": duration,
        "dt_s": run.dt_s,
        "window_s": list(window_s),
        "settle_band_rad": settings["settle_band_rad"],
        "startup_s": settings["startup_s"],
        "wall_time_s": run.wall_time_s,
        "real_time_factor": duration / run.wall_time_s if run.wall_time_s > 0 else None,
        "worst_rms_error_rad": max(j["rms_error_rad"] for j in joints),
        "worst_settling_time_s": _worst_settling([j["settling_time_s"] for j in joints]),
        "worst_max_abs_error_run_rad": max(j["max_abs_error_run_rad"] for j in joints),
        "worst_torque_variation": max(j["torque_variation"] for j in joints),
        "worst_saturated_fraction_after_s": max(j["saturated_fraction_after_s"] for j in joints),
        "steps_at_limit_after_s": int(np.sum(np.any(limited_after, axis=1))),
        "all_finite": finite,
        "diverged": diverged,
        "non_finite_from_step": None if gone is None else gone["step"],
        **guard_counters(run),
        "torques_within_limits": within,
        "joints": [{k: j[k] for k in ("name", "rms_error_rad", "max_abs_error_rad", "max_abs_torque_nm",
                                      "torque_limit_nm", "saturated_fraction", "settling_time_s",
                                      "max_abs_error_run_rad", "torque_variation", "saturated_fraction_after_s")}
                   for j in joints],
    }
    out.update(extra)
    return out


def guard_counters(run: RunData) -> dict:
    """``{"guard_counters": {joint: {counter: count}}}``, the joints and counters that are not 0, for a run that
    holds its guards' counts (an in-process run: GuardedControllers.counters); {} for one that does not (a run
    rebuilt from a bag: the graph's nodes report theirs in the launcher's faults section)."""
    if "guard_counters" not in run.extra:
        return {}
    return {"guard_counters": {name: {k: v for k, v in c.items() if v}
                               for name, c in zip(run.joint_names, run.extra["guard_counters"]) if any(c.values())}}


def guard_text(m: dict) -> str:
    """'s1: bad_states_speed 10090, ...; e1: ...' of a run's non-zero guard counters ('' when none)."""
    return "; ".join(f"{joint}: " + ", ".join(f"{k} {v}" for k, v in c.items())
                     for joint, c in (m.get("guard_counters") or {}).items())


def run_ok(m: dict) -> bool:
    """A run that neither diverged nor left the torque limits (every value finite): exit code 0, else 1."""
    return bool(m["all_finite"] and m["torques_within_limits"] and not m.get("diverged"))


def diverged_text(m: dict) -> str:
    """'non-finite from step k (t = ... s), joint J' or '|e| > 1 rad from step k ...': where and why a run
    diverged, for the summary lines and the report ('' when it did not)."""
    d = m.get("diverged")
    if not d:
        return ""
    return f"{d.get('why', 'non-finite')} from step {d['step']} (t = {d['time_s']:.3f} s), joint {d['joint']}"


def _unbounded(joints: list[dict], run: RunData) -> None:
    """In place: NaN figures become Infinity; a joint with non-finite samples gets max |e| over the run inf."""
    gone = ~np.all(np.isfinite(run.error_rad), axis=0) | ~np.all(np.isfinite(run.torque_nm), axis=0)
    for j, fig in enumerate(joints):
        for key, value in fig.items():
            if isinstance(value, float) and np.isnan(value):
                fig[key] = float("inf")
        if gone[j]:
            fig["max_abs_error_run_rad"] = float("inf")

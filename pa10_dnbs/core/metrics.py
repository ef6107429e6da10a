"""Tracking metrics over a time window, per joint.

All inputs are time series sampled every dt_s: error_rad and torque_nm of
shape (n_steps, n_joints); the window is [t0, t1] seconds, inclusive of t0,
exclusive of t1 (samples k with t0 <= k dt < t1).
"""
from __future__ import annotations

import numpy as np

DIVERGED_RAD = 1.0   # a tracking error |e| above this [rad], or a non-finite sample: the run diverged
AT_LIMIT_FRACTION = 1.0 - 1e-9   # |tau| at or above this fraction of its limit: the step is at the limit


def first_step(t_s: float, dt_s: float) -> int:
    """The first sample k with k dt_s >= t_s [s], a t_s on the grid up to rounding included (0.2 / 0.001 is
    200.00000000000003: step 200)."""
    return int(np.ceil(t_s / dt_s - 1e-9))


def at_limit(torque_nm: np.ndarray, torque_limit_nm) -> np.ndarray:
    """Bool, the shape of ``torque_nm`` (n_steps, n_joints) [N m]: the torque at its joint's limit (n_joints,)
    [N m] (AT_LIMIT_FRACTION); a NaN torque is not."""
    with np.errstate(invalid="ignore"):
        return np.abs(torque_nm) >= np.asarray(torque_limit_nm, dtype=float) * AT_LIMIT_FRACTION


def window_slice(n_steps: int, dt_s: float, window_s: tuple[float, float]) -> slice:
    """Index range of the samples k with t0 <= k dt_s < t1, ``window_s`` = (t0, t1) [s], of a run of ``n_steps``."""
    t0, t1 = window_s
    if not (0.0 <= t0 < t1):
        raise ValueError(f"window must satisfy 0 <= t0 < t1, got {window_s}")
    k0 = first_step(t0, dt_s)
    k1 = min(n_steps, first_step(t1, dt_s))
    if k1 <= k0:
        raise ValueError(f"window {window_s} s holds no sample of a {n_steps * dt_s:g} s run")
    return slice(k0, k1)


def joint_metrics(error_rad: np.ndarray, torque_nm: np.ndarray, torque_limit_nm,
                  dt_s: float, window_s: tuple[float, float]) -> list[dict]:
    """Per joint: RMS and max |error| in the window, max |torque| and saturated fraction over the run.

    ``error_rad`` and ``torque_nm`` (n_steps, n_joints) [rad, N m], ``torque_limit_nm`` (n_joints,) [N m],
    ``dt_s`` [s], ``window_s`` (t0, t1) [s].

    A step counts as saturated when |torque| >= limit * AT_LIMIT_FRACTION (:func:`at_limit`).
    """
    error_rad = np.asarray(error_rad, dtype=float)
    torque_nm = np.asarray(torque_nm, dtype=float)
    limit = np.asarray(torque_limit_nm, dtype=float)
    w = window_slice(error_rad.shape[0], dt_s, window_s)
    ew = error_rad[w]
    with np.errstate(over="ignore"):   # a diverged run's huge errors: RMS inf, no warning on stderr
        rms = np.sqrt(np.mean(ew**2, axis=0))
    emax = np.max(np.abs(ew), axis=0)
    tmax = np.max(np.abs(torque_nm), axis=0)
    sat = np.mean(at_limit(torque_nm, limit), axis=0)
    return [
        {
            "rms_error_rad": float(rms[j]),
            "max_abs_error_rad": float(emax[j]),
            "max_abs_torque_nm": float(tmax[j]),
            "torque_limit_nm": float(limit[j]),
            "saturated_fraction": float(sat[j]),
        }
        for j in range(error_rad.shape[1])
    ]


def run_metrics(error_rad: np.ndarray, torque_nm: np.ndarray, torque_limit_nm, dt_s: float,
                settle_band_rad: float, startup_s: float) -> list[dict]:
    """Per joint, over the whole run (error_rad, torque_nm of shape (n_steps, n_joints)):

    - settling_time_s: from this time on |e| <= settle_band_rad, i.e. one step after the last sample outside
      the band (0.0 when never outside, None when still outside at the last sample);
    - max_abs_error_run_rad: max |e| over the whole run [rad];
    - torque_variation: sum over k of |tau(k) - tau(k-1)| divided by the joint's limit (dimensionless: 2 is
      one swing from zero to the limit and back);
    - saturated_fraction_after_s: fraction of the steps with t >= startup_s at which |tau| is at its limit (:func:`at_limit`).
    """
    error_rad = np.asarray(error_rad, dtype=float)
    torque_nm = np.asarray(torque_nm, dtype=float)
    limit = np.asarray(torque_limit_nm, dtype=float)
    n = error_rad.shape[0]
    outside = ~(np.abs(error_rad) <= settle_band_rad)  # NaN counts as outside
    k0 = min(n, first_step(startup_s, dt_s))
    after = at_limit(torque_nm[k0:], limit)
    sat_after = after.mean(axis=0) if after.shape[0] else np.zeros(limit.shape)
    tv = np.abs(np.diff(torque_nm, axis=0)).sum(axis=0) / limit
    out = []
    for j in range(error_rad.shape[1]):
        idx = np.flatnonzero(outside[:, j])
        if idx.size == 0:
            settle = 0.0
        elif idx[-1] == n - 1:
            settle = None
        else:
            settle = float((idx[-1] + 1) * dt_s)
        out.append({"settling_time_s": settle, "max_abs_error_run_rad": float(np.nanmax(np.abs(error_rad[:, j]))),
                    "torque_variation": float(tv[j]), "saturated_fraction_after_s": float(sat_after[j])})
    return out


def first_non_finite(position_rad: np.ndarray, velocity_rad_s: np.ndarray | None, torque_nm: np.ndarray) -> dict | None:
    """Where a run went non-finite, or None when every sample is finite.

    Inputs of shape (n_steps, n_joints) (``velocity_rad_s`` may be None). Returns ``{"step": k, "joint": j}``:
    k the first step with a non-finite position, velocity or torque, j the joint running away: the one with the
    largest |velocity| (|position| without velocities) at the last step before k, or the first non-finite
    joint at step 0.
    """
    series = [np.asarray(a, dtype=float) for a in (position_rad, velocity_rad_s, torque_nm) if a is not None]
    bad = np.zeros(series[0].shape, dtype=bool)
    for a in series:
        bad |= ~np.isfinite(a)
    rows = np.flatnonzero(bad.any(axis=1))
    if rows.size == 0:
        return None
    k = int(rows[0])
    if k == 0:
        return {"step": 0, "joint": int(np.flatnonzero(bad[0])[0])}
    before = np.abs(np.asarray(velocity_rad_s if velocity_rad_s is not None else position_rad, dtype=float)[k - 1])
    return {"step": k, "joint": int(np.argmax(before))}


def divergence(error_rad: np.ndarray, position_rad: np.ndarray, velocity_rad_s: np.ndarray | None,
               torque_nm: np.ndarray) -> dict | None:
    """Where a run diverged, or None: the first step with |error| > DIVERGED_RAD on some joint, or with a
    non-finite sample (:func:`first_non_finite`), whichever comes first. Inputs (n_steps, n_joints).

    Returns ``{"step": k, "joint": j, "non_finite": bool}``: j the first joint beyond DIVERGED_RAD at k, or for a
    non-finite step the joint running away (:func:`first_non_finite`). One definition for every figure that says
    diverged: metrics.json, the exit codes, the study, the tuner's objective and the arm collection."""
    gone = first_non_finite(position_rad, velocity_rad_s, torque_nm)
    with np.errstate(invalid="ignore"):
        beyond = np.abs(np.asarray(error_rad, dtype=float)) > DIVERGED_RAD   # NaN: False (non-finite, above)
    rows = np.flatnonzero(beyond.any(axis=1))
    if rows.size and (gone is None or rows[0] < gone["step"]):
        k = int(rows[0])
        return {"step": k, "joint": int(np.flatnonzero(beyond[k])[0]), "non_finite": False}
    return None if gone is None else dict(gone, non_finite=True)

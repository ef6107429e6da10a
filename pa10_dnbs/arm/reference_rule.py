"""Eq. 27's reference for any arm: Table 1's pattern, each joint's amplitude and centre inside its limits.

The rule (docs/arms.md): joint i takes Table 1's row i mod its row count (c, d, w); its centre is the middle of its URDF
limits (0 for symmetric limits and for continuous joints) and its amplitude is c capped at two thirds of the
half range, so the reference, the 0.1 rad start offset and the transient stay clear of the limits. On the
PA10 (symmetric limits, the narrowest half range 1.64 rad on s2) the rule gives Table 1 exactly.

Then, once before the run, :func:`feasible_reference` checks the torque the reference asks of each joint
(inverse dynamics with gravity along it, plant/reference_torque.py) against TORQUE_FRACTION of its limit.
Where it asks more, it moves centres (a grid across each joint's range, amplitude capped as above, or halved)
until it does not; where no such reference is found, one line names the joint and what it needs.
"""
from __future__ import annotations

import math
from typing import Callable

import numpy as np

#: Table 1 of the paper: c [rad], d [1/s^3], w [rad/s], one row per joint of the PA10 (the pattern every arm takes).
TABLE1_AMPLITUDE_RAD = (math.pi / 2, math.pi / 3, math.pi / 2, math.pi / 3, math.pi / 2, math.pi / 3, math.pi / 2)
TABLE1_ENVELOPE_RATE_PER_S3 = (0.001, 0.001, 0.01, 0.01, 0.01, 0.01, 0.01)
TABLE1_FREQUENCY_RAD_S = (0.285, 0.435, 0.555, 0.645, 0.345, 0.615, 0.465)
#: The amplitude is at most this fraction of the half range between the limits.
RANGE_FRACTION = 2.0 / 3.0
#: The reference may ask each joint for at most this fraction of its torque limit (the rest is the controller's).
TORQUE_FRACTION = 0.8
CENTRE_GRID = 9        # candidate centres across a joint's range (the two limits excluded)
AMPLITUDE_SCALES = (1.0, 0.5)
SEARCH_PASSES = 2


def reference_rule(lower_rad: np.ndarray, upper_rad: np.ndarray) -> dict:
    """``reference`` config values (amplitude_rad, envelope_rate_per_s3, frequency_rad_s, centre_rad: lists of
    n floats) for joints with limits ``lower_rad``, ``upper_rad`` (n,) [rad], +/-inf for continuous joints."""
    n = len(lower_rad)
    rows = [i % len(TABLE1_AMPLITUDE_RAD) for i in range(n)]
    amplitude, centre = [], []
    for i, (lo, hi) in enumerate(zip(np.asarray(lower_rad, float), np.asarray(upper_rad, float))):
        c = TABLE1_AMPLITUDE_RAD[rows[i]]
        if math.isfinite(lo) and math.isfinite(hi):
            with np.errstate(over="ignore"):   # limits of +/-1.7e308: a range of inf, the table's amplitude kept
                centre.append(0.5 * (lo + hi))
                c = min(c, RANGE_FRACTION * 0.5 * (hi - lo))
        else:
            centre.append(0.0)
        amplitude.append(c)
    return {"amplitude_rad": amplitude,
            "envelope_rate_per_s3": [TABLE1_ENVELOPE_RATE_PER_S3[r] for r in rows],
            "frequency_rad_s": [TABLE1_FREQUENCY_RAD_S[r] for r in rows],
            "centre_rad": centre}


def _with_centre(fragment: dict, j: int, centre: float, scale: float, lower: float, upper: float) -> dict:
    """``fragment`` with joint j's centre moved to ``centre`` and its Table 1 amplitude times ``scale``, capped at
    RANGE_FRACTION of the distance to the nearer limit."""
    out = {k: list(v) for k, v in fragment.items()}
    c = TABLE1_AMPLITUDE_RAD[j % len(TABLE1_AMPLITUDE_RAD)] * scale
    if math.isfinite(lower) and math.isfinite(upper):
        c = min(c, RANGE_FRACTION * min(centre - lower, upper - centre))
    out["centre_rad"][j], out["amplitude_rad"][j] = centre, c
    return out


def _centres(lower: float, upper: float) -> np.ndarray:
    if not (math.isfinite(lower) and math.isfinite(upper)):
        lower, upper = -math.pi, math.pi
    return lower + (upper - lower) * np.arange(1, CENTRE_GRID - 1) / (CENTRE_GRID - 1)


def _key(r: np.ndarray, amplitude: float) -> tuple:
    """A candidate's rank (lower is better) from its torque ratios r (n,): a feasible one by its amplitude
    [rad] (larger first), an infeasible one by its worst joint's ratio."""
    ok = r.max() <= TORQUE_FRACTION
    return not ok, -amplitude if ok else r.max()


def _first_least(sweeps, amplitudes, limit) -> int:
    """The index of the first candidate of least :func:`_key` (as ``min`` over the candidates' keys in order),
    reading the candidates' TorqueSweeps only as far as needed: each one's key is bounded below by its steps
    done (no step: it may be feasible; a ratio above TORQUE_FRACTION: infeasible, at least that ratio), and the
    candidate whose (bound, index) is least gets its next chunk, until that candidate is done. A NaN torque met:
    every sweep is finished and ``min`` decides (one in a chunk not read is not seen: PyBullet's torques are
    finite for the finite states torque_along takes, short of overflow)."""
    while True:
        bounds = []
        for i, (s, a) in enumerate(zip(sweeps, amplitudes)):
            if s.peak is None:
                bounds.append(((False, -a), i))
                continue
            r = s.peak / limit
            if np.isnan(r).any():
                keys = [_key(t.finish() / limit, b) for t, b in zip(sweeps, amplitudes)]
                return min(range(len(keys)), key=lambda k: keys[k])
            worst = r.max()
            bounds.append((_key(r, a) if s.done else ((False, -a) if worst <= TORQUE_FRACTION else (True, worst)), i))
        _, i = min(bounds)
        if sweeps[i].done:
            return i
        sweeps[i].more()


def feasible_reference(fragment: dict, lower_rad, upper_rad, torque_limit_nm, peak_torque: Callable[[dict], np.ndarray],
                       joint_names, sweep: Callable | None = None) -> tuple[dict, list[str]]:
    """(the reference fragment, lines): ``fragment`` itself where ``peak_torque(fragment)`` (n,) [N m] stays
    within TORQUE_FRACTION of every limit; else the first fragment of a coordinate search over the joints'
    centres (and halved amplitudes) that does, or the one that asks least of its worst joint, with one line
    per joint still over.

    ``sweep`` (plant/reference_torque.py ReferenceTorque.sweep): a candidate's peak read chunk by chunk, as far
    as telling the search's choice needs (:func:`_first_least`): the same choice, fewer inverse-dynamics steps."""
    limit = np.asarray(torque_limit_nm, float)
    best, best_r = fragment, peak_torque(fragment) / limit
    if best_r.max() <= TORQUE_FRACTION:
        return fragment, []
    first = best_r.copy()
    for _ in range(SEARCH_PASSES):
        for j in np.argsort(-best_r):
            # every candidate of joint j: a feasible one with the largest amplitude, else the least asking one
            trials = [_with_centre(best, int(j), float(centre), scale, float(lower_rad[j]), float(upper_rad[j]))
                      for centre in _centres(float(lower_rad[j]), float(upper_rad[j])) for scale in AMPLITUDE_SCALES]
            amplitudes = [t["amplitude_rad"][j] for t in trials]
            if sweep is None:
                ratios = [peak_torque(t) / limit for t in trials]
                keys = [_key(r, a) for r, a in zip(ratios, amplitudes)]
                pick = min(range(len(trials)), key=lambda k: keys[k])
                trial, r = trials[pick], ratios[pick]
            else:
                sweeps = [sweep(t) for t in trials]
                pick = _first_least(sweeps, amplitudes, limit)
                trial, r = trials[pick], sweeps[pick].finish() / limit
                for s in sweeps:
                    s.release()
            if r.max() < best_r.max() - 1e-9:
                best, best_r = trial, r
            if best_r.max() <= TORQUE_FRACTION:
                break
        if best_r.max() <= TORQUE_FRACTION:
            break
    lines = []
    for j in np.flatnonzero(first > TORQUE_FRACTION):
        lines.append(f"reference: joint {joint_names[j]}: the rule's reference asked {first[j]:.0%} of its "
                     f"{limit[j]:g} N m (inverse dynamics with gravity along it); "
                     + ("moved: " + ", ".join(f"{joint_names[k]} centre {best['centre_rad'][k]:+.2f} rad amplitude "
                                               f"{best['amplitude_rad'][k]:.2f} rad" for k in range(len(limit))
                                               if best["centre_rad"][k] != fragment["centre_rad"][k]
                                               or best["amplitude_rad"][k] != fragment["amplitude_rad"][k])
                        + f" (now {best_r.max():.0%} at most)"))
    for j in np.flatnonzero(best_r > TORQUE_FRACTION):
        lines.append(f"reference: joint {joint_names[j]} cannot hold any reference the rule tried: it needs "
                     f"{best_r[j]:.0%} of its {limit[j]:g} N m at best: raise torque_limit_nm (if the data sheet "
                     f"allows) or give reference.centre_rad / amplitude_rad in the arm file's settings")
    return best, lines

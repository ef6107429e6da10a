"""Eq. 27's reference for any arm: Table 1's pattern, each joint's amplitude and centre inside its limits.

The rule (docs/arms.md): joint i takes Table 1's row i mod 7 (c, d, w); its centre is the middle of its URDF
limits (0 for symmetric limits and for continuous joints) and its amplitude is c capped at two thirds of the
half range, so the reference, the 0.1 rad start offset and the transient stay clear of the limits. On the
PA10 (symmetric limits, the narrowest half range 1.64 rad on s2) the rule gives Table 1 exactly.
"""
from __future__ import annotations

import math

import numpy as np

#: Table 1 of the paper: c [rad], d [1/s^3], w [rad/s] of the PA10's seven joints.
TABLE1_AMPLITUDE_RAD = (math.pi / 2, math.pi / 3, math.pi / 2, math.pi / 3, math.pi / 2, math.pi / 3, math.pi / 2)
TABLE1_ENVELOPE_RATE_PER_S3 = (0.001, 0.001, 0.01, 0.01, 0.01, 0.01, 0.01)
TABLE1_FREQUENCY_RAD_S = (0.285, 0.435, 0.555, 0.645, 0.345, 0.615, 0.465)
#: The amplitude is at most this fraction of the half range between the limits.
RANGE_FRACTION = 2.0 / 3.0


def reference_rule(lower_rad: np.ndarray, upper_rad: np.ndarray) -> dict:
    """``reference`` config values (amplitude_rad, envelope_rate_per_s3, frequency_rad_s, centre_rad: lists of
    n floats) for joints with limits ``lower_rad``, ``upper_rad`` (n,) [rad], +/-inf for continuous joints."""
    n = len(lower_rad)
    rows = [i % len(TABLE1_AMPLITUDE_RAD) for i in range(n)]
    amplitude, centre = [], []
    for i, (lo, hi) in enumerate(zip(np.asarray(lower_rad, float), np.asarray(upper_rad, float))):
        c = TABLE1_AMPLITUDE_RAD[rows[i]]
        if math.isfinite(lo) and math.isfinite(hi):
            centre.append(0.5 * (lo + hi))
            c = min(c, RANGE_FRACTION * 0.5 * (hi - lo))
        else:
            centre.append(0.0)
        amplitude.append(c)
    return {"amplitude_rad": amplitude,
            "envelope_rate_per_s3": [TABLE1_ENVELOPE_RATE_PER_S3[r] for r in rows],
            "frequency_rad_s": [TABLE1_FREQUENCY_RAD_S[r] for r in rows],
            "centre_rad": centre}

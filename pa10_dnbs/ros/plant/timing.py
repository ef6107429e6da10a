"""The plant's timing record, without ROS: when each state went out, when each answer came back.

``published(k, t_ns)`` notes the first send of state k; ``answered(k, j,
t_ns)`` the first reception of joint j's effort for it (both in ns of the
same clock, the system clock the DDS reception stamps use). Latency is the
difference, per step and joint [s]; ``joint_summary`` gives p50 / p99 / max.
"""
from __future__ import annotations

import numpy as np


class PlantTiming:
    def __init__(self, n_steps: int, n_joints: int):
        self.t_pub_ns = np.zeros(n_steps + 1, dtype=np.int64)          # 0: not published yet
        self.latency_s = np.full((n_steps + 1, n_joints), np.nan)      # state k -> effort k [s]

    def published(self, k: int, t_ns: int) -> None:
        if self.t_pub_ns[k] == 0:
            self.t_pub_ns[k] = t_ns

    def answered(self, k: int, joint: int, t_ns: int) -> None:
        if 0 <= k < len(self.t_pub_ns) and self.t_pub_ns[k] and np.isnan(self.latency_s[k, joint]):
            self.latency_s[k, joint] = (t_ns - int(self.t_pub_ns[k])) * 1e-9

    def joint_summary(self, joint: int, steps: int) -> dict:
        """Latency of joint ``joint`` over steps [0, steps): p50, p99 and max [us] (None when nothing came)."""
        li = self.latency_s[:steps, joint]
        li = li[np.isfinite(li)]
        if not li.size:
            return {"latency_median_us": None, "latency_p99_us": None, "latency_max_us": None}
        return {"latency_median_us": float(np.median(li) * 1e6), "latency_p99_us": float(np.percentile(li, 99) * 1e6),
                "latency_max_us": float(li.max() * 1e6)}


def step_ranges(steps: list[int], limit: int | None = None) -> list[list[int]]:
    """Sorted steps as [first, last] runs of consecutive steps: [1, 2, 3, 7] -> [[1, 3], [7, 7]] (the first
    ``limit`` runs)."""
    out: list[list[int]] = []
    for k in steps:
        if out and k == out[-1][1] + 1:
            out[-1][1] = k
        elif limit is not None and len(out) >= limit:
            break
        else:
            out.append([k, k])
    return out

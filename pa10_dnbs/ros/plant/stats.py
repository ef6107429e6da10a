"""The plant's report: per-joint counters on /diagnostics, and the stats file written at exit.

Stats (JSON): mode, steps, completed, wall and simulated time, the achieved
real-time factor; realtime adds the target factor, tick period, deadline,
the fraction of ticks with every effort before the deadline (``on_time_fraction``,
also per simulated minute), late tick starts and the largest lateness; per
joint: misses (and their first step ranges), lockstep timeouts (ranges),
state-to-effort latency p50 / p99 / max, resends and fault counters.
"""
from __future__ import annotations

import math
import time

from .counters import FAULT_KEYS, plant_counters
from .timing import step_ranges
from ..diagnostics import status, status_name

MAX_RANGES = 100  # miss ranges kept per joint in the stats file


def joint_counters(node, i: int) -> dict:
    c = plant_counters(node.gate, node.endpoints, node.resends, i)
    link = node.endpoints.state_links[i]
    if link is not None:
        c.update({f"injected_state_{k}": v for k, v in link.counters().items()})
    return c


def diagnostics_report(node) -> list:
    return [status(status_name(node, "plant", name), node.get_name(), joint_counters(node, i), FAULT_KEYS)
            for i, name in enumerate(node.plant.joint_names)]


def plant_stats(node) -> dict:
    gate, endpoints, p = node.gate, node.endpoints, node.p
    k = gate.step
    wall = (node.wall_end if node.finished else time.perf_counter()) - node.wall_start
    joints = []
    for i, name in enumerate(node.plant.joint_names):
        link = endpoints.state_links[i]
        joints.append({
            "name": name,
            **plant_counters(gate, endpoints, node.resends, i),
            "first_missed_step": gate.miss_steps[i][0] if gate.miss_steps[i] else None,
            "miss_ranges": step_ranges(gate.miss_steps[i], MAX_RANGES),
            "stale_efforts": int(gate.stale[i]),
            "effort_publishers": node.effort_publishers[i],  # the most seen at once (1: the joint's controller)
            "ahead_efforts_dropped": int(gate.dropped_ahead[i]),
            "timeout_ranges": step_ranges(gate.timeout_steps[i]),
            "resent_step_ranges": step_ranges(node.resent_steps[i], MAX_RANGES),  # lockstep: which states were re-sent
            "injected_state_faults": link.counters() if link is not None else None,
            **node.timing.joint_summary(i, k),
        })
    wall_ok = math.isfinite(wall) and wall > 0
    stats = {
        "mode": p["mode"], "steps": int(k), "completed": node.finished,
        "sim_time_s": k * node.dt, "wall_time_s": wall if math.isfinite(wall) else None,
        "real_time_factor": (k * node.dt / wall) if wall_ok else None,
        "reliability": p["reliability"], "state_qos_depth": endpoints.state_qos.depth,
        "effort_qos_depth": endpoints.effort_qos.depth,
        "on_missing_effort": p["on_missing_effort"], "effort_timeout_s": p["effort_timeout_s"],
        "rt_priority": p["rt_priority"], "rt_priority_applied": node.rt_applied,
        "cpu": node.cpu.report(),
        # one wait set over the effort subscriptions (one per joint): how often the plant blocked / woke with efforts
        "effort_waits_per_step": endpoints.waits / k if k else None,
        "effort_wakeups_per_step": endpoints.wakeups_with_efforts / k if k else None,
        "limit_hits": node.plant.limit_hits.tolist(), "joints": joints,
        "on_time_fraction": None, "late_start_ticks": 0,
    }
    sched = node.schedule
    if p["mode"] == "realtime":
        stats.update({
            "target_real_time_factor": p["real_time_factor"], "deadline_fraction": p["deadline_fraction"],
            "tick_period_s": node.dt / p["real_time_factor"], "late_tolerance": p["late_tolerance"],
            # a tick is on time when every joint's effort answering its state came before its deadline
            "on_time_fraction": gate.ticks_all_on_time / gate.ticks if gate.ticks else None,
            "ticks": gate.ticks,
            "on_time_fraction_per_bin": [o / t for o, t in zip(gate.on_time_per_bin, gate.ticks_per_bin)],
            "bin_s": gate.bin_steps * node.dt,
            "late_start_ticks": sched.late_starts if sched is not None else 0,
            "max_start_lateness_us": sched.max_lateness_s * 1e6 if sched is not None else None,
        })
    return stats

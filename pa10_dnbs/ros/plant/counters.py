"""The plant's per-joint counters: one schema for /diagnostics, the stats file and metrics.json's faults."""
from __future__ import annotations

# non-zero means a fault: /diagnostics turns WARN and names them
FAULT_KEYS = ("effort_timeouts", "nonfinite_efforts", "out_of_range_efforts", "malformed_efforts")
# every counter, per joint (counts of steps or messages)
COUNTER_KEYS = FAULT_KEYS + ("missed_ticks", "resent_states")
# what metrics.json's faults section keeps of a joint's plant stats
REPORT_KEYS = COUNTER_KEYS + ("timeout_ranges", "injected_state_faults", "stale_efforts", "effort_publishers")


def plant_counters(gate, endpoints, resends, i: int) -> dict:
    """COUNTER_KEYS of joint ``i`` from the effort gate (timeouts, non-finite, misses), the plant's endpoints
    (out of range, malformed) and the resend counts."""
    values = (gate.timeouts[i], gate.nonfinite[i], endpoints.out_of_range[i], endpoints.malformed[i], gate.misses[i],
              resends[i])
    return {k: int(v) for k, v in zip(COUNTER_KEYS, values)}

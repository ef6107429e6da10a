"""What the launcher tells a user whose realtime run did not keep its deadlines."""
from __future__ import annotations

ON_TIME_TARGET = 0.99  # ticks with every effort before the deadline that make a factor "sustainable"
# injected faults that make an effort miss its tick by design (config faults.<direction>.<key>)
MISSING_BY_DESIGN = ("drop_fraction", "delay_ms", "jitter_ms")


def injected_misses(faults) -> list[str]:
    """The injected faults (``settings.faults``) that lose or delay messages ('efforts dropped', ...), or []."""
    words = {"drop_fraction": "dropped", "delay_ms": "delayed", "jitter_ms": "jittered"}
    out = []
    for direction in ("state", "effort"):
        for key in MISSING_BY_DESIGN:
            if any(getattr(getattr(faults, direction), key)):
                out.append(f"{direction}s {words[key]}")
    if any(t >= 0 for t in faults.kill_controller_at_s):
        out.append("a controller killed")
    return out


def realtime_hint(real_time_factor: float, priority_applied: bool, injected: list[str] | None = None) -> str:
    """One line for a run below ``ON_TIME_TARGET``: what limits it and what to try next. ``injected``: the
    faults that lose or delay messages on purpose (``injected_misses``); they miss ticks whatever the CPU."""
    head = f"realtime `real_time_factor` {real_time_factor:g}: below {100 * ON_TIME_TARGET:g} % on time"
    if injected:
        return (f"{head}, with injected faults ({', '.join(injected)}) that miss ticks by design, whatever the "
                "machine: the missed ticks per joint are in metrics.json (timing.joints); the same run without "
                "the injected faults says whether the CPU keeps up as well")
    tries = [f"a lower `real_time_factor` (e.g. {real_time_factor / 2:g})"]
    if not priority_applied:
        tries.append("`rt_priority` 50 where the OS allows SCHED_FIFO")
    return (f"{head}: this machine does not "
            f"give the graph the CPU each tick needs; try {' or '.join(tries)}; "
            "scripts/bench_graph.py measures the highest factor it sustains (docs/timing.md)")

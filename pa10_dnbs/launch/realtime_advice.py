"""What the launcher tells a user whose realtime run did not keep its deadlines."""
from __future__ import annotations

ON_TIME_TARGET = 0.99  # ticks with every effort before the deadline that make a factor "sustainable"


def realtime_hint(real_time_factor: float, priority_applied: bool) -> str:
    """One line for a run below ``ON_TIME_TARGET``: what limits it and what to try next."""
    tries = [f"a lower --rtf (e.g. {real_time_factor / 2:g})"]
    if not priority_applied:
        tries.append("--rt-priority 50 where the OS allows SCHED_FIFO")
    return (f"realtime --rtf {real_time_factor:g}: below {100 * ON_TIME_TARGET:g} % on time: this machine does not "
            f"give the graph the CPU each tick needs; try {' or '.join(tries)}; "
            "scripts/bench_graph.py measures the highest factor it sustains (docs/timing.md)")

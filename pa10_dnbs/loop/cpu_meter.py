"""CPU time a process spends per step of the loop, measured from inside (all its threads, DDS included).

``mark(step)`` at each step (or batch of steps) the process handles; the
figure is the process CPU time between the first and the last mark over
the steps between them, so start-up and teardown are left out. The clock is
read on every ``every``-th step only (a system call costs ~1 us).
"""
from __future__ import annotations

import time


class CpuMeter:
    def __init__(self, every: int = 64):
        self.every = every
        self.first: tuple[float, int] | None = None   # (process CPU time [s], step)
        self.last: tuple[float, int] | None = None

    def mark(self, step: int) -> None:
        if self.first is not None and step % self.every:
            return
        now = (time.process_time(), step)
        if self.first is None:
            self.first = now
        self.last = now

    def report(self) -> dict:
        """{'cpu_s', 'steps', 'cpu_per_step_us'} between the first and the last mark (None figures before two)."""
        if self.first is None or self.last is None or self.last[1] <= self.first[1]:
            return {"cpu_s": None, "steps": 0, "cpu_per_step_us": None}
        cpu = self.last[0] - self.first[0]
        steps = self.last[1] - self.first[1]
        return {"cpu_s": cpu, "steps": steps, "cpu_per_step_us": 1e6 * cpu / steps}

    def line(self, name: str) -> str:
        """``CPU <name> <us> us per step over <n> steps`` (what the benchmark reads from the logs)."""
        r = self.report()
        if r["cpu_per_step_us"] is None:
            return f"CPU {name} unmeasured"
        return f"CPU {name} {r['cpu_per_step_us']:.1f} us per step over {r['steps']} steps ({r['cpu_s']:.3f} s)"

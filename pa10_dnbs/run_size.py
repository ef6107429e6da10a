"""Is a run's size within what this machine holds? An estimate of its memory (and wall time), checked before any work.

A run keeps its time series in memory: about a dozen float64 arrays of shape (n_steps, n_joints) while it
runs (state, torque, the reference and its derivatives, sensor noise, then the metrics' errors), four of them
per finished run it keeps (``simulate --controller all`` keeps three). Measured on the PA10 (7 joints): 530 B
per step for one PID run, 915 B per step for three runs with figures (``/usr/bin/time -f %M``, 2 s against
42 s); the estimate below is a little above both. A graph run (``launch``) holds its record twice (the wire
record or bag, and the run rebuilt from it).
"""
from __future__ import annotations

import os
import sys

from .config_error import ConfigError
from .number_text import num

ARRAYS_WHILE_RUNNING = 12     # (n_steps, n_joints) float64 arrays while one run steps
ARRAYS_PER_KEPT_RUN = 4       # position, velocity, reference, torque of each finished run kept
STEPS_PER_S_IN_PROCESS = 10_000   # in-process steps per second of wall time, one run (PA10: 15k DNBS, 29k PID)
STEPS_PER_S_GRAPH = 1_500          # lockstep graph steps per second (PA10 main job: 20 000 steps in 12.6 s)
SAY_LONGER_THAN_S = 3600.0         # a run longer than this in wall time is announced
WORKER_BYTES = 150 * 2**20         # a worker process of its own (Python, numpy, PyBullet): ~120 MB resident


def available_bytes() -> int:
    """Memory this process may still take [bytes]: MemAvailable, capped by a cgroup v2 limit if one is set."""
    avail = None
    try:
        with open("/proc/meminfo") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    avail = int(line.split()[1]) * 1024
    except OSError:
        pass
    if avail is None:
        avail = os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    try:
        with open("/sys/fs/cgroup/memory.max") as f:
            text = f.read().strip()
        if text.isdigit():
            avail = min(avail, int(text))
    except OSError:
        pass
    return avail


def run_bytes(n_steps: int, n_joints: int, kept_runs: int = 1, at_once: int = 1, graph: bool = False) -> int:
    """Estimated peak memory [bytes] of ``at_once`` runs stepping together (parallel workers) of which this
    process keeps ``kept_runs`` finished ones; ``graph``: a node graph's run (its record held twice)."""
    per_step = 8 * n_joints * (ARRAYS_WHILE_RUNNING * at_once + ARRAYS_PER_KEPT_RUN * max(kept_runs - 1, 0))
    return int(per_step * n_steps * (2 if graph else 1))


def _size(n: float) -> str:
    for unit in ("B", "KiB", "MiB", "GiB", "TiB", "PiB"):
        if n < 1024 or unit == "PiB":
            return f"{num(n, 3)} {unit}"
        n /= 1024
    return f"{num(n, 3)} PiB"


def _duration(s: float) -> str:
    if s < 120:
        return f"{num(s, 3)} s"
    if s < 7200:
        return f"{num(s / 60, 3)} min"
    if s < 3 * 86400:
        return f"{num(s / 3600, 3)} h"
    return f"{num(s / 86400, 3)} days"


def check_run_size(duration_s: float, n_steps: int, n_joints: int, kept_runs: int = 1,
                   at_once: int = 1, total_runs: int = 1, graph: bool = False, wall_s: float | None = None,
                   say=None, setting: str = "duration_s") -> None:
    """Raise ConfigError naming ``setting`` (the duration's: ``duration_s``, the command line's --duration, or the
    config's simulation.duration_s; or ``jobs`` when one run would fit but ``at_once`` do not) when the runs need
    more memory than is available; ``say`` (a print function) announces a run whose
    estimated wall time (``wall_s``, else from the step rates) exceeds an hour."""
    need = run_bytes(n_steps, n_joints, kept_runs, at_once, graph) + WORKER_BYTES * (at_once if at_once > 1 else 0)
    rate = STEPS_PER_S_GRAPH if graph else STEPS_PER_S_IN_PROCESS * at_once
    wall = wall_s if wall_s is not None else n_steps * total_runs / rate
    have = available_bytes()
    if need > have:
        if at_once > 1 and run_bytes(n_steps, n_joints, kept_runs, 1, graph) + WORKER_BYTES <= have:
            raise ConfigError(f"jobs: {at_once} runs at once of {num(n_steps)} steps need about {_size(need)} of "
                              f"memory, more than the {_size(have)} available here; use fewer", setting="jobs")
        raise ConfigError(f"{setting}: {num(duration_s)} s is {num(n_steps)} steps: about {_size(need)} of memory "
                          f"for the time series (and about {_duration(wall)} of wall time), more than the "
                          f"{_size(have)} available here; shorten it", setting=setting)
    if say is not None and wall > SAY_LONGER_THAN_S:
        say(f"a run of {num(duration_s)} s: {num(n_steps * total_runs)} steps take about {_duration(wall)} of wall "
            f"time and {_size(need)} of memory")


def say_note(line: str) -> None:
    """A one-line note on stderr (a long run announced before it starts)."""
    print(f"pa10-dnbs: note: {line}", file=sys.stderr, flush=True)

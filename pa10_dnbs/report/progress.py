"""A one-line progress bar for long runs: simulated time, real-time factor so far, worst |e| so far.

Drawn on a terminal only (``stream.isatty()``, unless ``enabled`` says
otherwise) and redrawn at most every ``min_interval_s`` of wall time; when the
output is a pipe or a file it writes nothing, so logs stay line-based. No ROS,
no numpy. Use::

    bar = ProgressBar(n_steps, dt_s, "simulate dnbs")
    for k in range(n_steps):
        ...
        if k % 100 == 99:
            bar.update(k + 1, worst_abs_error=float(np.abs(e[k - 99:k + 1]).max()))
    bar.close()

``update(step, worst_abs_error)`` takes the steps done so far and the worst
|e| [rad] among the steps since the previous update (or so far: the bar keeps
the maximum of what it is given). The real-time factor is simulated time over
wall time since the first update. ``log(say, line)`` prints a log line
without tearing the bar.
"""
from __future__ import annotations

import math
import sys
import time
from typing import Callable, TextIO

WIDTH = 24  # characters of the bar itself


def format_progress(label: str, step: int, total_steps: int, dt_s: float, rtf: float | None,
                    worst_abs_error: float | None, width: int = WIDTH) -> str:
    """The bar's text, e.g. ``simulate dnbs [#########......]  12.0/20.0 s  RTF 5.81  worst |e| 1.0e-01 rad``."""
    frac = min(max(step / total_steps, 0.0), 1.0) if total_steps > 0 else 0.0
    filled = int(round(frac * width))
    parts = [f"{label} [{'#' * filled}{'.' * (width - filled)}] {step * dt_s:6.1f}/{total_steps * dt_s:.1f} s"]
    parts.append(f"RTF {rtf:.2f}" if rtf is not None and math.isfinite(rtf) else "RTF -")
    parts.append(f"worst |e| {worst_abs_error:.1e} rad" if worst_abs_error is not None and math.isfinite(worst_abs_error)
                 else "worst |e| -")
    return "  ".join(parts)


class ProgressBar:
    def __init__(self, total_steps: int, dt_s: float, label: str, stream: TextIO | None = None,
                 enabled: bool | None = None, min_interval_s: float = 0.2, clock: Callable[[], float] = time.monotonic):
        self.total_steps = int(total_steps)
        self.dt_s = float(dt_s)
        self.label = label
        self.stream = stream if stream is not None else sys.stderr
        if enabled is None:
            isatty = getattr(self.stream, "isatty", None)
            enabled = bool(isatty and isatty())
        self.enabled = enabled
        self.min_interval_s = min_interval_s
        self.clock = clock
        self.step = 0
        self.worst_abs_error: float | None = None
        self._t0: float | None = None
        self._step0 = 0
        self._last_draw = -math.inf
        self._drawn = False
        self.closed = False

    @property
    def real_time_factor(self) -> float | None:
        """Simulated time over wall time since the first update; None before there is any."""
        if self._t0 is None:
            return None
        wall = self.clock() - self._t0
        return (self.step - self._step0) * self.dt_s / wall if wall > 0 and self.step > self._step0 else None

    def update(self, step: int, worst_abs_error: float | None = None) -> None:
        """``step`` steps are done; ``worst_abs_error``: the worst |e| [rad] of the new steps (NaN/None: unknown)."""
        now = self.clock()
        if self._t0 is None:
            self._t0, self._step0 = now, int(step)
        self.step = max(self.step, int(step))
        if worst_abs_error is not None and math.isfinite(worst_abs_error):
            if self.worst_abs_error is None or worst_abs_error > self.worst_abs_error:
                self.worst_abs_error = float(worst_abs_error)
        if self.enabled and now - self._last_draw >= self.min_interval_s:
            self._draw(now)

    def text(self) -> str:
        return format_progress(self.label, self.step, self.total_steps, self.dt_s, self.real_time_factor,
                               self.worst_abs_error)

    def _draw(self, now: float) -> None:
        self.stream.write("\r\x1b[K" + self.text())
        self.stream.flush()
        self._last_draw = now
        self._drawn = True

    def _clear(self) -> None:
        if self._drawn:
            self.stream.write("\r\x1b[K")
            self.stream.flush()
            self._drawn = False

    def log(self, say: Callable[[str], None], line: str) -> None:
        """``say(line)`` with the bar taken off the terminal first (it comes back with the next update)."""
        if self.enabled:
            self._clear()
            self._last_draw = -math.inf
        say(line)

    def close(self) -> None:
        """Draw the final state and end the line (nothing when disabled)."""
        if self.closed:
            return
        self.closed = True
        if self.enabled:
            self._draw(self.clock())
            self.stream.write("\n")
            self.stream.flush()

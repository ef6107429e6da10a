"""Which states carry a /clock message: one per 1 / clock_hz of simulated time, as `ros2 bag play --clock`.

The plant publishes /clock with the first state of every period of ``1e9 / clock_hz`` ns of simulated
time (state 0 included) and with the last state of the run, so a recorder sees /clock reach the end.
The bag check of a lockstep run expects exactly these steps (``steps``).
"""
from __future__ import annotations

from ..config_error import ConfigError
from .steps import NS_PER_S, StepClock

DEFAULT_CLOCK_HZ = 100.0  # simulated-time Hz, the default of `ros2 bag play --clock`


def check_clock_hz(clock_hz: float, dt_s: float, off_allowed: bool = True) -> None:
    """ValueError unless 0 <= ``clock_hz`` [Hz] <= 1 / ``dt_s`` (at most one /clock per step; 0: off, where
    ``off_allowed``: a graph whose nodes run on /clock needs it)."""
    low_ok = clock_hz >= 0 if off_allowed else clock_hz > 0
    if not (clock_hz == clock_hz and low_ok and clock_hz <= 1.0 / dt_s + 1e-9):
        raise ValueError(f"must be in [0, {1.0 / dt_s:g}] Hz of simulated time (0: no /clock), got {clock_hz}"
                         if off_allowed else f"must be in (0, {1.0 / dt_s:g}] Hz of simulated time (the graph's "
                         f"nodes run on /clock), got {clock_hz}")


def checked_clock_hz(clock_hz: float | None, dt_s: float, off_allowed: bool = True) -> float:
    """The /clock rate of a run: ``clock_hz`` [Hz] as given (None: not given, DEFAULT_CLOCK_HZ), checked against
    the step ``dt_s`` as :func:`check_clock_hz` does. ConfigError naming ``clock_hz`` when it was given; when it
    was not, naming simulation.dt_s: the config's step is what the default does not fit."""
    rate = DEFAULT_CLOCK_HZ if clock_hz is None else clock_hz
    try:
        check_clock_hz(rate, dt_s, off_allowed)
    except ValueError as exc:
        if clock_hz is not None:
            raise ConfigError(f"clock_hz: {exc}", setting="clock_hz") from None
        raise ConfigError(f"simulation.dt_s: a step of {dt_s:g} s takes at most {1.0 / dt_s:g} /clock per second "
                          f"(one per step), fewer than the default `clock_hz` {DEFAULT_CLOCK_HZ:g}: give `clock_hz` "
                          f"{1.0 / dt_s:g} or less, or a simulation.dt_s of at most {1.0 / DEFAULT_CLOCK_HZ:g} s") \
            from None
    return rate


class ClockSchedule:
    def __init__(self, clock_hz: float, dt_s: float, last_step: int):
        """``clock_hz`` > 0 [Hz of simulated time]; ``last_step``: the run's last state (always carries one)."""
        self.period_ns = int(round(NS_PER_S / clock_hz))
        self.clock = StepClock(dt_s)
        self.last_step = last_step
        self._period = -1  # the period of the latest /clock

    def due(self, step: int) -> bool:
        """True when state ``step`` (states come in increasing order) carries a /clock; records it."""
        period = self.clock.ns(step) // self.period_ns
        if period > self._period or step >= self.last_step:
            self._period = period
            return True
        return False

    @classmethod
    def steps(cls, clock_hz: float, dt_s: float, last_step: int) -> set[int]:
        """Every state 0..last_step that carries a /clock."""
        s = cls(clock_hz, dt_s, last_step)
        return {k for k in range(last_step + 1) if s.due(k)}

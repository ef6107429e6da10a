"""The number of steps of a run, counted once: ``run_steps(duration_s, dt_s)``, or ConfigError in one line.

Every command that turns a duration into steps (simulate, study, tune; the rules over the config's
simulation.duration_s) counts them here, so a duration too long to count (1e308 s: an infinite step count)
or shorter than two steps is refused alike, naming the flag or key it came from.
"""
from __future__ import annotations

import math

from .config_error import ConfigError

MAX_STEPS = 2**53  # [steps] beyond it a step's time k * dt is no longer exact in a float (and memory refuses far sooner)


def countable_steps(duration_s: float, dt_s: float, setting: str = "duration_s") -> int:
    """round(duration_s / dt_s) [steps] for ``duration_s`` [s] at the step ``dt_s`` [s]; ConfigError opening
    with ``setting`` (``duration_s``: the command line names it ``--duration``; or a config key) when it is not
    finite or more than MAX_STEPS."""
    steps = duration_s / dt_s
    if not (math.isfinite(steps) and steps <= MAX_STEPS):
        raise ConfigError(f"{setting}: {duration_s:g} s is {steps:.3g} steps of {dt_s:g} s, more than can be counted "
                          f"({MAX_STEPS:.3g})", setting=setting)
    return int(round(steps))


def run_steps(duration_s: float, dt_s: float, setting: str = "duration_s") -> int:
    """:func:`countable_steps`, and ConfigError (opening with ``setting``) unless at least two."""
    n_steps = countable_steps(duration_s, dt_s, setting)
    if n_steps < 2:
        raise ConfigError(f"{setting}: {duration_s} s is shorter than two steps", setting=setting)
    return n_steps


def run_duration(given_s: float | None, config_s: float, flag: str = "duration_s") -> tuple[float, str]:
    """(the run's duration [s], the setting its errors name): the command's ``given_s`` (--duration, named
    ``flag``) or, when None, the config's ``config_s`` (named simulation.duration_s)."""
    return (config_s, "simulation.duration_s") if given_s is None else (given_s, flag)

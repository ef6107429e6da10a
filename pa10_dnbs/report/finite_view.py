"""What the figures of a diverged run draw: the run up to the step where it went non-finite, and no sample of
an absurd size (beyond PLOT_BOUND)."""
from __future__ import annotations

import dataclasses

import numpy as np

from ..run_data import RunData

PLOT_BOUND = 1e100   # |value| beyond which a sample is not drawn: matplotlib's ticks overflow near 1e308
_DRAWN = ("position_rad", "velocity_rad_s", "reference_rad", "torque_nm")


def until_step(run: RunData, step: int) -> RunData:
    """A copy of ``run`` whose samples from ``step`` on are NaN (plotted as gaps, left out of axis limits)."""
    arrays = {}
    for name in _DRAWN:
        a = np.array(getattr(run, name), dtype=float)
        a[step:] = np.nan
        arrays[name] = a
    return dataclasses.replace(run, **arrays)


def drawable(run: RunData) -> RunData:
    """``run``, or a copy whose samples beyond PLOT_BOUND in magnitude (a diverged run's huge finite values,
    1e308) are NaN: left out of the figures like non-finite ones."""
    arrays = {}
    for name in _DRAWN:
        a = np.asarray(getattr(run, name), dtype=float)
        if (np.abs(a) > PLOT_BOUND).any():
            arrays[name] = np.where(np.abs(a) > PLOT_BOUND, np.nan, a)
    return dataclasses.replace(run, **arrays) if arrays else run

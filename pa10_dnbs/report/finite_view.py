"""What the figures of a diverged run draw: the run up to the step where it went non-finite."""
from __future__ import annotations

import dataclasses

import numpy as np

from ..run_data import RunData


def until_step(run: RunData, step: int) -> RunData:
    """A copy of ``run`` whose samples from ``step`` on are NaN (plotted as gaps, left out of axis limits)."""
    arrays = {}
    for name in ("position_rad", "velocity_rad_s", "reference_rad", "torque_nm"):
        a = np.array(getattr(run, name), dtype=float)
        a[step:] = np.nan
        arrays[name] = a
    return dataclasses.replace(run, **arrays)

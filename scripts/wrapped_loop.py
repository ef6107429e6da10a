"""One in-process run of a study scenario with the run's own joint loop wrapped, for the developer scripts that
put something between the plant and the controllers (encoder_noise_filters.py, noise_scaled_r.py)."""
from __future__ import annotations

import numpy as np

from pa10_dnbs.sim import closed_loop
from pa10_dnbs.study.scenarios import scenario_settings


def second_half_worst_rms(settings, scenario: str, controller: str, seed: int, duration_s: float, wrap=None) -> float:
    """The worst joint's RMS error over the run's second half [rad]. ``wrap(loop, dt_s)`` returns what the run
    steps in the loop's place (None: the loop itself)."""
    s, dist = scenario_settings(settings, scenario, seed)
    built = closed_loop.joint_loop

    def joint_loop(*args, **kwargs):
        reference, loop = built(*args, **kwargs)
        return reference, (loop if wrap is None else wrap(loop, s.simulation.dt_s))

    closed_loop.joint_loop = joint_loop   # the in-process run's own loop, wrapped
    try:
        run = closed_loop.simulate(s, controller, duration_s, disturbances=dist)
    finally:
        closed_loop.joint_loop = built
    half = run.n_steps // 2
    err = run.reference_rad[half:] - run.position_rad[half:]
    return float(np.sqrt((err ** 2).mean(axis=0)).max())

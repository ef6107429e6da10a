"""Is a study scenario physically feasible for the arm? Checked once before the study runs.

The torque the scenario's reference asks of each joint: inverse dynamics with gravity along it on the
scenario's plant (its payload, heavier links, friction; plant/reference_torque.py, as the reference rule checks
the nominal plant), sampled every 50 ms over the run. A scenario whose peak torque exceeds a joint's limit
(100 %: the rule keeps its nominal reference within 80 %) is infeasible: no torque-limited controller can make
that arm track it, so the study reports it in one line and runs no controller on it. Sensor noise and a torque
delay change neither the plant nor the reference: such scenarios are as feasible as the nominal one.
"""
from __future__ import annotations

import numpy as np

from ..plant.from_config import opened_plant, plant_params
from ..plant.reference_torque import FIELDS as REFERENCE_FIELDS
from ..plant.reference_torque import ReferenceTorque
from ..settings import Settings
from .scenarios import scenario_settings

#: A scenario is infeasible when its reference asks more than this fraction of a joint's torque limit.
INFEASIBLE_FRACTION = 1.0


def scenario_peak_torque(settings: Settings, scenario: str, duration_s: float) -> np.ndarray:
    """(n,) the largest |tau_j| [N m] the reference of ``scenario`` asks of the plant of ``scenario`` over
    ``duration_s`` (at most reference_torque.HORIZON_S)."""
    changed, _ = scenario_settings(settings, scenario, 0)
    dt = changed.simulation.dt_s
    with opened_plant(changed.arm, plant_params(changed.plant, dt)) as plant:
        ref = changed.reference
        return ReferenceTorque(plant, duration_s, dt).peak({k: getattr(ref, k) for k in REFERENCE_FIELDS})


def infeasible_line(settings: Settings, scenario: str, duration_s: float) -> str | None:
    """None when ``scenario`` is feasible on the settings' arm; else one line naming the joint that is furthest
    over its limit, the torque it needs [N m] and its limit [N m] (and how many other joints are over)."""
    limit = np.asarray(settings.plant.torque_limit_nm, float)
    ratio = scenario_peak_torque(settings, scenario, duration_s) / limit
    over = np.flatnonzero(ratio > INFEASIBLE_FRACTION)
    if over.size == 0:
        return None
    j = int(np.argmax(ratio))
    name = settings.arm.joint_names[j]
    more = f" (and {over.size - 1} more joint{'s' if over.size > 2 else ''} over)" if over.size > 1 else ""
    return (f"{scenario}: infeasible on arm {settings.arm.name}: joint "
            f"{name} needs {ratio[j] * limit[j]:.3g} N m along the reference (inverse dynamics with gravity on the "
            f"scenario's plant), its limit is {limit[j]:g} N m{more}: no torque-limited controller can track it; "
            f"not run")


def infeasible_scenarios(settings: Settings, scenarios, duration_s: float) -> dict[str, str]:
    """{scenario: its one line} of the ``scenarios`` that are infeasible on the settings' arm (in their order)."""
    out = {}
    for sc in scenarios:
        line = infeasible_line(settings, sc, duration_s)
        if line is not None:
            out[sc] = line
    return out

"""The config values an arm gets where neither its file nor the user's config gives them (docs/arms.md).

Two rules, run in this order by ``load_config``: the reference (reference_rule.py, from the URDF limits
alone) and the gains (gain_rule.py, from the arm's mass matrix along that reference). Only the keys nobody
gave are taken from them; the PA10's arm file gives all, so nothing is derived for it.
"""
from __future__ import annotations

import math

import numpy as np

from .arm import Arm
from .arm.gain_rule import SWEEP_STEP_S, gain_rule, report_rule
from .arm.reference_rule import reference_rule
from .settings import ReferenceSettings, RunSettings

REFERENCE_KEYS = tuple(f"reference.{k}" for k in ("amplitude_rad", "envelope_rate_per_s3", "frequency_rad_s",
                                                   "centre_rad"))
GAIN_KEYS = ("dnbs.alpha_net.error_scale_rad", "dnbs.torque_net.output_scale_nm",
             "dnbs.torque_net.error_scale_rad_s", "dnbs.remedies.robust_term.alpha_gain_per_s",
             "dnbs.remedies.robust_term.torque_gain_nms_per_rad", "dnbs.remedies.slope_bound.enabled",
             "dnbs.remedies.slope_bound.fraction", "pid.kp", "pid.ki", "pid.kd")
DERIVED_KEYS = REFERENCE_KEYS + GAIN_KEYS
#: The rule layer's fixed values: the lowest layer of load_config, under the arm file's settings and the config
#: files (so an arm file can set them; config/default.yaml must not, or no arm file could).
#: ctc.on_saturation: computed torque scales its feedback to stay within the limits (sim/computed_torque.py);
#: the PA10, iiwa and Panda arm files pin ``clip``, the law their published numbers were made with.
RULE_DEFAULTS = {"ctc": {"on_saturation": "scale_feedback"},
                 # the alpha network starts near zero: its EKF (R = 1 on e1 / E1) learns an untrained output away
                 # only to about 2e-3 E1 std rad, a floor of 1.1e-5 rad at the presets' 0.01 (docs/arms.md)
                 "dnbs": {"alpha_net": {"init_weight_std": 1e-6}}}


def derived_reference(arm: Arm, tree: dict | None = None, report: bool = True) -> dict:
    """The ``reference`` fragment of the reference rule, made feasible (reference_rule.feasible_reference: the
    torque it asks along ``tree``'s simulation.duration_s, inverse dynamics with gravity, within the limits);
    ``report``: its lines on stderr. ``tree``: the config so far (unchecked; the defaults where it gives none)."""
    import sys

    from .arm.reference_rule import feasible_reference
    from .plant.reference_torque import ReferenceTorque

    fragment = reference_rule(arm.lower_rad, arm.upper_rad)
    sim, plant = (tree or {}).get("simulation", {}), (tree or {}).get("plant", {})
    try:
        duration, dt = float(sim.get("duration_s", 20.0)), float(sim.get("dt_s", 0.001))
        gravity = float(plant.get("gravity_mps2", 9.81))
    except (TypeError, ValueError):
        return {"reference": fragment}  # the config's own check names the bad key
    if not (duration > 0 and dt > 0 and math.isfinite(duration) and gravity >= 0):
        return {"reference": fragment}
    torque = ReferenceTorque(arm, duration, dt, gravity)
    try:
        fragment, lines = feasible_reference(fragment, arm.lower_rad, arm.upper_rad, arm.torque_limit_nm,
                                             torque.peak, arm.joint_names)
    finally:
        torque.close()
    if report:
        for line in lines:
            print(f"warning: arm {arm.name}: {line}", file=sys.stderr)
    return {"reference": fragment}


def inertia_sweep_along(arm: Arm, reference: ReferenceSettings, run: RunSettings):
    """The arm's effective inertias along ``reference``, every 20 ms over the run's duration_s (an
    InertiaSweep)."""
    from .core.reference import Reference
    from .plant.inertia_sweep import inertia_sweep

    dt = run.dt_s
    ref = Reference(reference.amplitude_rad, reference.envelope_rate_per_s3, reference.frequency_rad_s, dt_s=dt,
                    centre_rad=reference.centre_rad)
    steps = np.arange(0, int(round(run.duration_s / dt)) + 1, max(1, int(round(SWEEP_STEP_S / dt))))
    return inertia_sweep(arm, ref.position(steps))


def derived_gains(arm: Arm, reference: ReferenceSettings, run: RunSettings, report: bool = True,
                  sweep=None) -> dict:
    """The gain rule's fragment (a config fragment) for the arm along ``reference`` over ``run`` (``sweep``:
    :func:`inertia_sweep_along`'s, computed when None). ``report``: print the derivation (one line per joint)
    and any warning on stderr."""
    dt = run.dt_s
    sweep = inertia_sweep_along(arm, reference, run) if sweep is None else sweep
    fragment = gain_rule(arm, sweep, dt)
    if report:
        report_rule(arm, sweep, fragment, dt)
    return fragment

"""The config values an arm gets where neither its file nor the user's config gives them (docs/arms.md).

Two rules, run in this order by :func:`with_rule_values` (``run_settings.build_settings`` calls it once, after the
config is checked): the reference (reference_rule.py, from the URDF limits alone) and the gains (gain_rule.py,
from the arm's mass matrix along that reference). Only the keys nobody gave are taken from them; the PA10's arm
file gives all, so nothing is derived for it. Both rules run the settings' own plant (its ``plant`` section,
the arm's facts resolved into it): they are handed its parameters, and look nothing up.
"""
from __future__ import annotations

import sys

import numpy as np

from .arm import Arm
from .arm.gain_rule import SWEEP_STEP_S, gain_rule, report_rule
from .arm.reference_rule import feasible_reference, reference_rule
from .core.reference import Reference
from .plant.from_config import plant_params
from .plant.inertia_sweep import inertia_sweep
from .plant.pybullet_plant import PlantParams
from .plant.reference_torque import ReferenceTorque
from .settings import PlantSettings, ReferenceSettings, RunSettings

REFERENCE_KEYS = tuple(f"reference.{k}" for k in ("amplitude_rad", "envelope_rate_per_s3", "frequency_rad_s",
                                                   "centre_rad"))
GAIN_KEYS = ("dnbs.alpha_net.error_scale_rad", "dnbs.torque_net.output_scale_nm",
             "dnbs.torque_net.error_scale_rad_s", "dnbs.remedies.robust_term.alpha_gain_per_s",
             "dnbs.remedies.robust_term.torque_gain_nms_per_rad", "dnbs.remedies.slope_bound.enabled",
             "dnbs.remedies.slope_bound.fraction", "pid.kp", "pid.ki", "pid.kd")
DERIVED_KEYS = REFERENCE_KEYS + GAIN_KEYS
#: The rule layer's fixed values: the lowest layer of the settings, under the arm file's settings and the config
#: files (so an arm file can set them; config/default.yaml must not, or no arm file could).
#: ctc.on_saturation: computed torque scales its feedback to stay within the limits (sim/computed_torque.py);
#: the PA10, iiwa and Panda arm files pin ``clip``, the law their published numbers were made with.
RULE_DEFAULTS = {"ctc": {"on_saturation": "scale_feedback"}}


def with_rule_values(arm: Arm, checked: dict, absent: tuple[str, ...], report: bool = True) -> dict:
    """The ``checked`` config (placeholders standing at the dotted keys ``absent``) with the rules' values for
    ``arm`` at those keys; ``report``: the rules print their table and warnings on stderr."""
    if not absent:
        return checked
    run = RunSettings.of(checked["simulation"])
    params = plant_params(PlantSettings.of(checked["plant"]), run.dt_s)
    values: dict = {}
    reference = dict(checked["reference"])
    if any(key in absent for key in REFERENCE_KEYS):
        values = derived_reference(arm, run, params, report=report)
        reference.update({k: v for k, v in values["reference"].items() if f"reference.{k}" in absent})
    if any(key in absent for key in GAIN_KEYS):
        values = dict(values, **derived_gains(arm, ReferenceSettings.of(reference), run, params, report=report))
    return _placed(checked, values, absent)


def derived_reference(arm: Arm, run: RunSettings, params: PlantParams, report: bool = True) -> dict:
    """The ``reference`` fragment of the reference rule, made feasible (reference_rule.feasible_reference: the
    torque it asks over ``run.duration_s`` on the plant of ``params``, inverse dynamics with gravity, within the
    limits); ``report``: its lines on stderr."""
    fragment = reference_rule(arm.lower_rad, arm.upper_rad)
    torque = ReferenceTorque(arm, run.duration_s, run.dt_s, params)
    try:
        fragment, lines = feasible_reference(fragment, arm.lower_rad, arm.upper_rad, np.asarray(params.torque_limit_nm),
                                             torque.peak, arm.joint_names)
    finally:
        torque.close()
    if report:
        for line in lines:
            print(f"warning: arm {arm.name}: {line}", file=sys.stderr)
    return {"reference": fragment}


def inertia_sweep_along(arm: Arm, reference: ReferenceSettings, run: RunSettings, params: PlantParams):
    """The arm's effective inertias on the plant of ``params`` along ``reference``, every 20 ms over the run's
    duration_s (an InertiaSweep)."""
    dt = run.dt_s
    ref = Reference(reference.amplitude_rad, reference.envelope_rate_per_s3, reference.frequency_rad_s, dt_s=dt,
                    centre_rad=reference.centre_rad)
    steps = np.arange(0, int(round(run.duration_s / dt)) + 1, max(1, int(round(SWEEP_STEP_S / dt))))
    return inertia_sweep(arm, ref.position(steps), params)


def derived_gains(arm: Arm, reference: ReferenceSettings, run: RunSettings, params: PlantParams,
                  report: bool = True, sweep=None) -> dict:
    """The gain rule's fragment (a config fragment) for the arm on the plant of ``params`` along ``reference``
    over ``run`` (``sweep``: :func:`inertia_sweep_along`'s, computed when None). ``report``: print the derivation
    (one line per joint) and any warning on stderr."""
    dt = run.dt_s
    sweep = inertia_sweep_along(arm, reference, run, params) if sweep is None else sweep
    fragment = gain_rule(arm, sweep, dt)
    if report:
        report_rule(arm, sweep, fragment, dt)
    return fragment


def _placed(tree: dict, fragment: dict, keys: tuple[str, ...]) -> dict:
    """``tree`` with ``fragment``'s values at the dotted ``keys`` in place of its own."""
    out = dict(tree)
    for key in keys:
        *parents, leaf = key.split(".")
        src, node = fragment, out
        for part in parents:
            src = src[part]
            node[part] = dict(node[part])
            node = node[part]
        node[leaf] = src[leaf]
    return out

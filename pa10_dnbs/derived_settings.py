"""The config values an arm gets where neither its file nor the user's config gives them (docs/arms.md).

Two rules, run in this order by :func:`with_rule_values` (``run_settings.build_settings`` calls it once, after the
config is checked): the reference (reference_rule.py, from the URDF limits alone) and the gains (gain_rule.py,
from the arm's mass matrix along that reference). Only the keys nobody gave are taken from them; the PA10's arm
file gives all, so nothing is derived for it. Both rules read one plant, the settings' own (its ``plant``
section, the arm's facts resolved into it), opened once for them: they look nothing up.
"""
from __future__ import annotations

import sys

import numpy as np

from .arm import Arm
from .arm.gain_rule import SWEEP_STEP_S, gain_rule, report_rule
from .arm.reference_rule import feasible_reference, reference_rule
from .core.reference import Reference
from .plant.from_config import opened_plant, plant_params
from .plant.inertia_sweep import inertia_sweep
from .plant.pybullet_plant import PyBulletArmPlant
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
RULE_DEFAULTS = {"ctc": {"on_saturation": "scale_feedback"},
                 # the alpha network starts near zero: its EKF (R = 1 on e1 / E1) learns an untrained output away
                 # only to about 2e-3 E1 std rad, a floor of 1.1e-5 rad at the presets' 0.01 (docs/arms.md)
                 "dnbs": {"alpha_net": {"init_weight_std": 1e-6}}}


def with_rule_values(arm: Arm, checked: dict, absent: tuple[str, ...], report: bool = True) -> dict:
    """The ``checked`` config (placeholders standing at the dotted keys ``absent``) with the rules' values for
    ``arm`` at those keys; ``report``: the rules print their table and warnings on stderr."""
    if not absent:
        return checked
    run = RunSettings.of(checked["simulation"])
    values: dict = {}
    reference = dict(checked["reference"])
    with opened_plant(arm, plant_params(PlantSettings.of(checked["plant"]), run.dt_s)) as plant:
        if any(key in absent for key in REFERENCE_KEYS):
            values = derived_reference(plant, run, report=report)
            reference.update({k: v for k, v in values["reference"].items() if f"reference.{k}" in absent})
        if any(key in absent for key in GAIN_KEYS):
            values = dict(values, **derived_gains(plant, ReferenceSettings.of(reference), run, report=report))
    return _placed(checked, values, absent)


def derived_reference(plant: PyBulletArmPlant, run: RunSettings, report: bool = True) -> dict:
    """The ``reference`` fragment of the reference rule for the arm of ``plant``, made feasible
    (reference_rule.feasible_reference: the torque it asks of ``plant`` over ``run.duration_s``, inverse dynamics
    with gravity, within the plant's limits); ``report``: its lines on stderr."""
    arm = plant.arm
    fragment = reference_rule(arm.lower_rad, arm.upper_rad)
    torque = ReferenceTorque(plant, run.duration_s, run.dt_s)
    limit = np.asarray(plant.params.torque_limit_nm)
    fragment, lines = feasible_reference(fragment, arm.lower_rad, arm.upper_rad, limit, torque.peak, arm.joint_names)
    if report:
        for line in lines:
            print(f"warning: arm {arm.name}: {line}", file=sys.stderr)
    return {"reference": fragment}


def inertia_sweep_along(plant: PyBulletArmPlant, reference: ReferenceSettings, run: RunSettings):
    """The effective inertias of ``plant``'s arm along ``reference``, every 20 ms over the run's duration_s (an
    InertiaSweep)."""
    dt = run.dt_s
    ref = Reference(reference.amplitude_rad, reference.envelope_rate_per_s3, reference.frequency_rad_s, dt_s=dt,
                    centre_rad=reference.centre_rad)
    steps = np.arange(0, int(round(run.duration_s / dt)) + 1, max(1, int(round(SWEEP_STEP_S / dt))))
    return inertia_sweep(plant, ref.position(steps))


def derived_gains(plant: PyBulletArmPlant, reference: ReferenceSettings, run: RunSettings, report: bool = True,
                  sweep=None) -> dict:
    """The gain rule's fragment (a config fragment) for the arm of ``plant`` along ``reference`` over ``run``
    (``sweep``: :func:`inertia_sweep_along`'s, computed when None). ``report``: print the derivation (one line
    per joint) and any warning on stderr."""
    dt, arm = run.dt_s, plant.arm
    sweep = inertia_sweep_along(plant, reference, run) if sweep is None else sweep
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

"""The config values an arm gets where neither its file nor the user's config gives them (docs/arms.md).

Two rules, run in this order by :func:`with_rule_values` (``run_settings.build_settings`` calls it once, after the
config is checked): the reference (reference_rule.py, from the URDF limits alone) and the gains (gain_rule.py,
from the arm's mass matrix along that reference). Only the keys nobody gave are taken from them (an arm file that
gives all, as the PA10's does, has nothing derived). Both rules read one plant, the settings' own (its ``plant``
section, the arm's facts resolved into it), opened once for them: they look nothing up.

Around them, what the config alone cannot bound is checked against the arm and the step (ConfigError, one line
naming the key): the reference given (:func:`check_reference`) before the rules sample it, the start state
(:func:`check_start`) once every value is known.
"""
from __future__ import annotations

import math
import sys

import numpy as np

from .arm import Arm
from .arm.gain_rule import SWEEP_STEP_S, gain_rule, report_rule
from .arm.reference_rule import feasible_reference, reference_rule
from .config import ConfigError
from .core.reference import Reference
from .plant.from_config import initial_state, opened_plant, plant_params
from .plant.inertia_sweep import inertia_sweep
from .plant.pybullet_plant import PyBulletArmPlant
from .plant.reference_torque import ReferenceTorque
from .run_steps import countable_steps
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


def with_rule_values(arm: Arm, checked: dict, absent: tuple[str, ...], report: bool = True, stream=None) -> dict:
    """The ``checked`` config (placeholders standing at the dotted keys ``absent``) with the rules' values for
    ``arm`` at those keys; ``report``: the rules print their table and warnings on ``stream`` (stderr when
    None)."""
    check_reference(arm, checked, absent)
    if absent:
        checked = _with_rules(arm, checked, absent, report, stream)
    check_start(arm, checked)
    return checked


def _with_rules(arm: Arm, checked: dict, absent: tuple[str, ...], report: bool, stream=None) -> dict:
    """``checked`` with the rules' values at the dotted keys ``absent``."""
    run = RunSettings.of(checked["simulation"])
    values: dict = {}
    reference = dict(checked["reference"])
    with opened_plant(arm, plant_params(PlantSettings.of(checked["plant"]), run.dt_s)) as plant:
        if any(key in absent for key in REFERENCE_KEYS):
            values = derived_reference(plant, run, report=report, stream=stream)
            reference.update({k: v for k, v in values["reference"].items() if f"reference.{k}" in absent})
        if any(key in absent for key in GAIN_KEYS):
            values = dict(values, **derived_gains(plant, ReferenceSettings.of(reference), run, report=report,
                                                  stream=stream))
            if not checked["dnbs"]["remedies"]["robust_term"]["enabled"]:   # its bounds would all be 0
                values["dnbs"]["remedies"]["slope_bound"]["enabled"] = False
    return _placed(checked, values, absent)


def _beyond(key: str, values, bound, arm: Arm, what: str, unit: str) -> None:
    """ConfigError naming ``key`` and the first joint whose value is above ``bound`` (n,) (``what``: the bound
    in words; ``unit``: both's)."""
    values = np.asarray(values, dtype=float)
    bad = ~(values <= np.broadcast_to(bound, values.shape))
    if np.any(bad):
        j = int(np.argmax(bad))
        raise ConfigError(f"{key}: {values[j]:g} {unit} for joint {arm.joint_names[j]} is above {what} = "
                          f"{np.broadcast_to(bound, values.shape)[j]:g} {unit}")


def check_reference(arm: Arm, checked: dict, absent: tuple[str, ...] = ()) -> None:
    """The eq. 27 reference given in ``checked`` (keys in ``absent`` left to the rules) bounded so that its
    position, velocity and acceleration stay finite and it can be sampled at the step T = simulation.dt_s:
    frequency w below the Nyquist rate pi / T, envelope rate d at most 1 / T^3 (the envelope rises within a few
    steps), amplitude c at most the joint's range (upper - lower limit), centre inside the joint's limits; and
    simulation.duration_s a countable number of steps (the rules sample the reference over it). ConfigError
    naming the key and the joint."""
    dt, ref = checked["simulation"]["dt_s"], checked["reference"]
    countable_steps(checked["simulation"]["duration_s"], dt, "simulation.duration_s")
    given = lambda k: f"reference.{k}" not in absent  # noqa: E731
    if given("frequency_rad_s"):
        w = np.asarray(ref["frequency_rad_s"], dtype=float)
        nyquist = math.pi / dt
        if np.any(w >= nyquist):
            j = int(np.argmax(w >= nyquist))
            raise ConfigError(f"reference.frequency_rad_s: {w[j]:g} rad/s for joint {arm.joint_names[j]} is at or "
                              f"above the Nyquist rate pi / simulation.dt_s = {nyquist:g} rad/s")
    if given("envelope_rate_per_s3"):
        _beyond("reference.envelope_rate_per_s3", ref["envelope_rate_per_s3"], 1.0 / dt**3, arm,
                "1 / simulation.dt_s^3", "1/s^3")
    if given("amplitude_rad"):
        _beyond("reference.amplitude_rad", ref["amplitude_rad"], arm.upper_rad - arm.lower_rad, arm,
                "the joint's range, upper - lower limit,", "rad")
    if given("centre_rad"):
        _outside("reference.centre_rad", ref["centre_rad"], arm, "the centre")


def _outside(key: str, q, arm: Arm, what: str) -> None:
    """ConfigError naming ``key`` when a joint's position ``q`` (n,) [rad] lies outside its limits."""
    q = np.asarray(q, dtype=float)
    bad = ~((q >= arm.lower_rad) & (q <= arm.upper_rad))
    if np.any(bad):
        j = int(np.argmax(bad))
        raise ConfigError(f"{key}: {what} {q[j]:g} rad of joint {arm.joint_names[j]} is outside its limits "
                          f"[{arm.lower_rad[j]:g}, {arm.upper_rad[j]:g}] rad")


def check_start(arm: Arm, checked: dict) -> None:
    """The start position (plant/from_config.initial_state: the reference's centre + the offset) inside the
    arm's limits: ConfigError naming simulation.initial_position_offset_rad otherwise."""
    q0, _ = initial_state(RunSettings.of(checked["simulation"]), ReferenceSettings.of(checked["reference"]))
    _outside("simulation.initial_position_offset_rad", q0, arm, "the start position (reference.centre_rad + offset)")


def derived_reference(plant: PyBulletArmPlant, run: RunSettings, report: bool = True, stream=None) -> dict:
    """The ``reference`` fragment of the reference rule for the arm of ``plant``, made feasible
    (reference_rule.feasible_reference: the torque it asks of ``plant`` over ``run.duration_s``, inverse dynamics
    with gravity, within the plant's limits); ``report``: its lines on ``stream`` (stderr when None)."""
    arm = plant.arm
    fragment = reference_rule(arm.lower_rad, arm.upper_rad)
    torque = ReferenceTorque(plant, run.duration_s, run.dt_s)
    limit = np.asarray(plant.params.torque_limit_nm)
    fragment, lines = feasible_reference(fragment, arm.lower_rad, arm.upper_rad, limit, torque.peak, arm.joint_names,
                                         sweep=torque.sweep)
    if report:
        for line in lines:
            print(f"warning: arm {arm.name}: {line}", file=sys.stderr if stream is None else stream)
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
                  sweep=None, stream=None) -> dict:
    """The gain rule's fragment (a config fragment) for the arm of ``plant`` along ``reference`` over ``run``
    (``sweep``: :func:`inertia_sweep_along`'s, computed when None). ``report``: print the derivation (one line
    per joint) and any warning on ``stream`` (stderr when None)."""
    dt, arm = run.dt_s, plant.arm
    sweep = inertia_sweep_along(plant, reference, run) if sweep is None else sweep
    fragment = gain_rule(arm, sweep, dt)
    if report:
        report_rule(arm, sweep, fragment, dt, stream=stream)
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

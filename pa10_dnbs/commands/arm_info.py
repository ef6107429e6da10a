"""``pa10-dnbs arm [--arm A]``: what the project makes of an arm, before anything runs.

Its facts with their sources, each joint's effective inertia range along its reference (from the plant's
mass matrix), the gains the rule of docs/arms.md gives it, and the gains the arm actually runs with (its
file's settings or the config's where they differ): so that a placeholder or a missing rotor inertia shows.
"""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from ..arm.gain_rule import report_rule
from ..arm.summary import arm_line
from ..config import default_config_path
from .options import ArmInfoOptions
from ..plant.from_config import opened_plant, plant_params
from ..run_settings import build_settings


def _at(tree: dict, dotted: str):
    """``tree``'s value at the dotted key."""
    for part in dotted.split("."):
        tree = tree[part]
    return tree


def _runs_with(settings, rule: dict, light_kgm2: np.ndarray) -> str:
    """What the arm runs with: the rule's gains, or a line per gain key (GAIN_KEYS) whose value differs from the
    rule's, per joint; with k_u its discrete-time figure T k_u / J_light (stable below 2, docs/arms.md)."""
    from ..derived_settings import GAIN_KEYS

    config, names = settings.to_config(), settings.arm.joint_names
    own = []
    for key in GAIN_KEYS:
        ran, ruled = np.broadcast_to(_at(config, key), (len(names),)), np.broadcast_to(_at(rule, key), (len(names),))
        if ran.dtype == bool or ruled.dtype == bool:
            differ = bool(np.any(ran != ruled))
        else:
            differ = not np.allclose(np.asarray(ran, float), np.asarray(ruled, float), rtol=1e-12, atol=0.0)
        if differ:
            text = f"{key}: " + ", ".join(f"{n} {str(v).lower()}" if isinstance(v, bool) else f"{n} {v:g}"
                                        for n, v in zip(names, ran.tolist()))
            if key.endswith("torque_gain_nms_per_rad"):
                figure = settings.simulation.dt_s * np.asarray(ran, float) / light_kgm2
                text += f" (T k_u / J_light {', '.join(f'{x:.2f}' for x in figure)})"
            own.append(text)
    return "runs with: the rule's gains" if not own else "\n  ".join(
        ["runs with: its own values where they differ from the rule's:", *own])


def run_arm_info(options: ArmInfoOptions) -> int:
    """Print the arm's facts, sources, inertia sweep and gains; returns 0 (bad input raises ConfigError)."""
    from ..derived_settings import derived_gains, derived_reference, inertia_sweep_along

    o = options
    # the rules' own report is printed below, once and on stdout (the command's output), not while building
    settings = build_settings(Path(o.config_path) if o.config_path else default_config_path(), arm=o.arm,
                              report=False)
    the_arm, run = settings.arm, settings.simulation
    print(arm_line(the_arm).replace("; ", ";\n  "))
    print("sources:")
    for key, text in the_arm.sources.items():
        print(f"  {key}: {text}")
    with opened_plant(the_arm, plant_params(settings.plant, run.dt_s)) as plant:
        derived_reference(plant, run, stream=sys.stdout)   # what the reference rule moved or cannot fit, if any
        sweep = inertia_sweep_along(plant, settings.reference, run)
        rule = derived_gains(plant, settings.reference, run, report=False, sweep=sweep)
    report_rule(the_arm, sweep, rule, run.dt_s, stream=sys.stdout)
    print(_runs_with(settings, rule, sweep.light_kgm2))
    return 0

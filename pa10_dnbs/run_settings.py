"""The settings of one run, built once, in this order: the config file(s), the arm file, the rules' values.

A command calls :func:`build_settings` (or its three steps: ``config.load_config``, :func:`document_arm`,
:func:`with_rules`) and hands the :class:`~pa10_dnbs.settings.Settings` down; nothing below reads a config file
or looks the arm up again. A node builds its own from the params the launcher gives it (every value resolved,
so the rules derive nothing there).
"""
from __future__ import annotations

from pathlib import Path

from .arm import DEFAULT_ARM, Arm, load_arm
from .config import checked_with_placeholders, layered, load_config, merged, missing, validate
from .derived_settings import GAIN_KEYS, REFERENCE_KEYS, RULE_DEFAULTS, derived_gains, derived_reference
from .settings import ReferenceSettings, RunSettings, Settings


def document_arm(document: dict, arm: str | Path | None = None) -> Arm:
    """The arm ``arm`` names (``--arm``: a preset's name, an arm file or a URDF), else the config's ``arm``
    key, else the default (ArmError naming the file when it is bad)."""
    return load_arm(arm if arm is not None else document.get("arm", DEFAULT_ARM))


def with_rules(the_arm: Arm, document: dict, report: bool = True) -> Settings:
    """The settings of ``the_arm`` under the config ``document``: the rules' fixed values and the arm's facts,
    its ``settings``, the document over them, and the rules' values (docs/arms.md) for the keys nobody gives; ``report``: the rules
    print their table and warnings (stderr). ConfigError naming the key when a value is bad."""
    facts = {"plant": {"torque_limit_nm": the_arm.torque_limit_nm.tolist(),
                       "rotor_inertia_kgm2": the_arm.rotor_inertia_kgm2.tolist(),
                       "viscous_nms_per_rad": the_arm.viscous_nms_per_rad.tolist(),
                       "coulomb_nm": the_arm.coulomb_nm.tolist()}}
    tree = layered(dict(document, arm=str(the_arm.file)), merged(RULE_DEFAULTS, facts), the_arm.settings)
    if missing(tree, REFERENCE_KEYS):
        tree = merged(derived_reference(the_arm, tree, report=report), tree)
    if missing(tree, GAIN_KEYS):
        checked = checked_with_placeholders(tree, GAIN_KEYS, the_arm.n_joints)
        reference, run = ReferenceSettings.of(checked["reference"]), RunSettings.of(checked["simulation"])
        tree = merged(derived_gains(the_arm, reference, run, report=report), tree)
    return Settings.of(validate(tree, the_arm.n_joints), the_arm)


def build_settings(config_path: str | Path, arm: str | Path | None = None, report: bool = True) -> Settings:
    """The settings of a run: the config file at ``config_path`` (and what it extends), the arm (``arm``, else
    the config's), then the rules' values."""
    document = load_config(config_path)
    return with_rules(document_arm(document, arm), document, report=report)

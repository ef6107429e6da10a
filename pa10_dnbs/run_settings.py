"""The settings of one run, built once, going down in this order: the config file(s), the arm file, the rules'
values.

A command calls :func:`build_settings` and hands the :class:`~pa10_dnbs.settings.Settings` (or the sections a
part needs) down; nothing below reads a config file or looks the arm up again. A node builds its own from the
params the launcher gives it (every value resolved, so the rules derive nothing there).
"""
from __future__ import annotations

import io
import sys
from pathlib import Path

from .arm import DEFAULT_ARM, ArmError, load_arm
from .config import ConfigError, MissingKeyError, check_arm_settings, checked_layers, default_config_path, load_config
from .derived_settings import DERIVED_KEYS, RULE_DEFAULTS, with_rule_values
from .settings import Settings


def build_settings(config_path: str | Path, arm: str | Path | None = None, report: bool = True,
                   stream=None) -> Settings:
    """The settings of a run: the config file at ``config_path`` (and what it extends); the arm (``arm``: a
    preset's name, an arm file or a URDF; None: the config's ``arm`` key, else the default); the rules' fixed
    values and the arm's facts, its file's ``settings``, the config over them, checked once for the arm's joint
    count; then the rules' values (docs/arms.md) for the keys nobody gives (``report``: the rules print their
    table and warnings on ``stream``, stderr when None). ConfigError naming the key or file, ArmError naming the
    arm file."""
    document = load_config(config_path)
    try:
        the_arm = load_arm(arm if arm is not None else document.get("arm", DEFAULT_ARM))
    except ArmError as exc:
        if arm is not None and exc.setting is None:   # "arm: ..." is the caller's option (the CLI says --arm)
            exc.setting = "arm"
        raise
    try:
        check_arm_settings(the_arm.settings, the_arm.n_joints, load_config(default_config_path()))
    except ConfigError as exc:   # said as the arm file's key, not taken for the config's
        raise ConfigError(f"{the_arm.file}: settings.{exc}") from None
    facts = {"plant": {"torque_limit_nm": the_arm.torque_limit_nm.tolist(),
                       "rotor_inertia_kgm2": the_arm.rotor_inertia_kgm2.tolist(),
                       "viscous_nms_per_rad": the_arm.viscous_nms_per_rad.tolist(),
                       "coulomb_nm": the_arm.coulomb_nm.tolist()}}
    layers = [RULE_DEFAULTS, facts, the_arm.settings, dict(document, arm=str(the_arm.file))]
    try:
        checked, absent = checked_layers(layers, the_arm.n_joints, DERIVED_KEYS)
    except MissingKeyError as exc:   # the config file (and what it extends) is where the key belongs
        raise ConfigError(f"{config_path}: {exc} (neither it nor a file it extends gives it; a config usually "
                          f"starts with `extends: {default_config_path()}`)") from None
    return Settings.of(with_rule_values(the_arm, checked, absent, report, stream), the_arm)


def built_settings_held(config_path: str | Path, arm: str | Path | None = None) -> tuple[Settings, str]:
    """:func:`build_settings` with the rules' table and warnings held back: the settings and that text, for a
    command to say (:func:`say_rules`) once every input is accepted, so that a refused input is its one line."""
    held = io.StringIO()
    settings = build_settings(config_path, arm, report=True, stream=held)
    return settings, held.getvalue()


def say_rules(text: str) -> None:
    """The rules' table and warnings :func:`built_settings_held` held back, on stderr, as the rules print them."""
    if text:
        sys.stderr.write(text)
        sys.stderr.flush()

"""Load and validate ``config/*.yaml``.

Every key is declared once in ``SCHEMA`` with its kind; unknown keys, wrong
types and non-finite or out-of-range numbers raise :class:`ConfigError`
naming the dotted key (e.g. ``dnbs.torque_net.eta``).
"""
from __future__ import annotations

import math
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from .config_error import ConfigError, first_unknown, short, too_large  # ConfigError: the CLI and nodes catch it here
from .config_yaml import read_config_yaml
from .file_path import PathProblem, file_or_folder


@dataclass(frozen=True)
class Num:
    """A real number; ``low`` is the bound, ``strict`` makes it exclusive; ``integer`` requires an int; ``high``
    the upper bound, exclusive where ``high_strict``."""

    low: float | None = None
    strict: bool = True
    integer: bool = False
    high: float | None = None
    high_strict: bool = False


@dataclass(frozen=True)
class Joints:
    """One number per actuated joint of the arm, with the bounds of ``num``; a single number is broadcast."""

    num: Num


@dataclass(frozen=True)
class Pair:
    """Two increasing numbers >= 0, e.g. a time window [t0, t1]."""


@dataclass(frozen=True)
class Flag:
    """true or false."""


@dataclass(frozen=True)
class Text:
    """A non-empty string, optionally one of ``choices``."""

    choices: tuple[str, ...] = ()


POS = Num(0.0)
NONNEG = Num(0.0, strict=False)
ANY = Num()
FRACTION = Num(0.0, strict=False, high=1.0)
#: a fraction of messages dropped: below 1 (all dropped, a lockstep step would wait for a message that never comes)
DROP_FRACTION = Num(0.0, strict=False, high=1.0, high_strict=True)


def _net_schema(output_key: str, error_key: str, n_inputs: int) -> dict:
    return {
        "max_degree": Num(0, strict=False, integer=True, high=4),
        "input_scale": (POS,) * n_inputs,  # tuple of Num: one per input, in that input's units
        output_key: Joints(POS),           # A [rad/s] or U [N m]: output = scale * w^T S
        error_key: Joints(POS),            # E1 [rad] or E2 [rad/s]: the EKF trains on e / scale
        "init_weight_std": Joints(NONNEG),
        "p0": Joints(POS),
        "q": Joints(NONNEG),
        "r": Joints(POS),
        "eta": Joints(Num(0.0, high=1.0)),  # 0 < eta <= 1 (eq. 7)
    }


def _switch(**settings) -> dict:
    return {"enabled": Flag(), **settings}


# The longest injected delay or jitter of one message [ms]: 1 s, the default --effort-timeout. A message later than
# that is a lost one (--drop-*: the plant re-sends after the timeout); 1e308 ms made every lockstep step wait.
LINK_DELAY_MAX_MS = 1000.0


def _link_faults() -> dict:
    """Faults injected on one direction of each joint's link (plant -> controller states, or efforts back)."""
    return {
        "drop_fraction": Joints(DROP_FRACTION),
        "delay_ms": Joints(Num(0.0, strict=False, high=LINK_DELAY_MAX_MS)),
        "jitter_ms": Joints(Num(0.0, strict=False, high=LINK_DELAY_MAX_MS)),
        "corrupt_fraction": Joints(FRACTION),
        "corrupt_kind": Text(("nan", "inf", "out_of_range")),
    }



#: simulation.dt_s's lower bound [s]: 10 us, a 100 kHz loop, far below any arm's control period (1 ms on the presets)
#: and above the 1 us a lockstep robot's stamps are matched within; 1e-300 made every duration a count of steps past
#: counting, blamed on simulation.duration_s
MIN_DT_S = 1e-5


SCHEMA: dict[str, Any] = {
    "arm": Text(),  # a preset's name (urdf/<name>/) or the path of an arm file or URDF; resolved to its file
    "simulation": {
        "dt_s": Num(MIN_DT_S, strict=False, high=0.1),
        "duration_s": POS,
        "window_s": Pair(),
        "seed": Num(0, strict=False, integer=True),
        "initial_position_offset_rad": Joints(ANY),
        "initial_velocity_rad_s": Joints(ANY),
    },
    "reference": {
        "amplitude_rad": Joints(NONNEG),
        "envelope_rate_per_s3": Joints(POS),
        "frequency_rad_s": Joints(NONNEG),
        "centre_rad": Joints(ANY),
        "preview_steps": Num(0, strict=False, integer=True, high=100),
    },
    "plant": {
        "gravity_mps2": NONNEG,
        "rotor_inertia_kgm2": Joints(NONNEG),
        "viscous_nms_per_rad": Joints(NONNEG),
        "coulomb_nm": Joints(NONNEG),
        "coulomb_smoothing_rad_s": POS,
        "torque_limit_nm": Joints(POS),
        "payload_kg": NONNEG,
        "link_mass_scale": POS,
    },
    "dnbs": {
        "e2_sign": Text(("stable", "printed")),
        "kernel": Text(("auto", "numpy", "c")),
        "alpha_net": _net_schema("output_scale_rad_s", "error_scale_rad", 2),
        "torque_net": _net_schema("output_scale_nm", "error_scale_rad_s", 3),
        "remedies": {
            "robust_term": _switch(velocity_feedforward=Flag(), alpha_gain_per_s=Joints(NONNEG), torque_gain_nms_per_rad=Joints(NONNEG)),
            "anti_windup": _switch(),
            "dead_zone": _switch(alpha_rad=Joints(NONNEG), torque_rad_s=Joints(NONNEG)),
            "e_modification": _switch(sigma=NONNEG),
            "projection": _switch(weight_bound=POS),
            "slope_bound": _switch(fraction=Joints(FRACTION)),  # per arm: the gain rule (docs/arms.md)
            "learning_ramp": _switch(ramp_s=NONNEG),
            "covariance_bound": _switch(p_max=POS),
        },
    },
    "pid": {"kp": Joints(NONNEG), "ki": Joints(NONNEG), "kd": Joints(NONNEG), "anti_windup": Flag()},
    # on_saturation: what CTC does past a torque limit (sim/computed_torque.py); the rule layer gives
    # scale_feedback (derived_settings.RULE_DEFAULTS), the presets' arm files clip
    "ctc": {"kp_per_s2": Joints(NONNEG), "kd_per_s": Joints(NONNEG),
            "on_saturation": Text(("scale_feedback", "clip"))},
    "guards": {
        "position_margin_rad": NONNEG,
        "max_speed_rad_s": Joints(POS),
        "on_bad_state": Text(("hold", "zero")),
        "ekf_full_check_every": Num(0, strict=False, integer=True),
    },
    "checkpoint": {"period_s": POS},
    "metrics": {"settle_band_rad": POS, "startup_s": NONNEG},
    "faults": {
        "seed": Num(0, strict=False, integer=True),
        "state": _link_faults(),
        "effort": _link_faults(),
        "kill_controller_at_s": Joints(ANY),
    },
}


class MissingKeyError(ConfigError):
    """A key no layer of the settings gives (the message names the key; the caller who knows the file adds it)."""


def _number(key: str, value: Any, spec: Num) -> float | int:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ConfigError(f"{key}: expected a number, got {type(value).__name__} {short(value)}")
    try:
        real = float(value)
    except OverflowError:   # an int past the largest float
        raise ConfigError(f"{key}: {too_large(value)}") from None
    if spec.integer and not (isinstance(value, int) or real.is_integer()):
        raise ConfigError(f"{key}: expected an integer, got {short(value)}")
    if not math.isfinite(real):
        raise ConfigError(f"{key}: must be finite, got {short(value)}")
    if spec.low is not None and (value <= spec.low if spec.strict else value < spec.low):
        rel = ">" if spec.strict else ">="
        raise ConfigError(f"{key}: must be {rel} {spec.low:g}, got {short(value)}")
    if spec.high is not None and (value >= spec.high if spec.high_strict else value > spec.high):
        raise ConfigError(f"{key}: must be {'<' if spec.high_strict else '<='} {spec.high:g}, got {short(value)}")
    return int(value) if spec.integer else float(value)


def _check_mapping(key: str, value: Any, spec: dict) -> None:
    """``value`` is a mapping whose keys are all in ``spec`` (ConfigError naming the first unknown key, a key that
    is not a name too: ``1:``, ``~:``)."""
    if not isinstance(value, dict):
        got = "nothing (an empty section)" if value is None else type(value).__name__
        raise ConfigError(f"{key or '<root>'}: expected a mapping, got {got}")
    unknown = first_unknown(value, spec)
    if unknown is not None:
        raise ConfigError(f"{key + '.' if key else ''}{unknown}: unknown key "
                          f"(allowed: {', '.join(sorted(spec))})")


def check_value(key: str, value: Any, spec: Any, n: int | None) -> Any:
    """``value`` checked against ``spec`` (``n``: the arm's number of joints, the length of every Joints list;
    None: any length). Lists may be tuples (typed settings hold tuples). Returns the value normalised (numbers
    as float or int, lists as tuples)."""
    if isinstance(spec, dict):
        _check_mapping(key, value, spec)
        missing = sorted(set(spec) - set(value))
        if missing:
            raise MissingKeyError(f"{key + '.' if key else ''}{missing[0]}: missing key")
        return {k: check_value(f"{key}.{k}" if key else k, value[k], spec[k], n) for k in spec}
    if isinstance(spec, Num):
        return _number(key, value, spec)
    if isinstance(spec, Joints):
        if isinstance(value, (list, tuple)):
            if n is not None and len(value) != n:
                raise ConfigError(f"{key}: expected {n} values (one per joint of the arm), got {len(value)}")
            return tuple(_number(f"{key}[{i}]", v, spec.num) for i, v in enumerate(value))
        return (_number(key, value, spec.num),) * (1 if n is None else n)
    if isinstance(spec, tuple):
        if not isinstance(value, (list, tuple)) or len(value) != len(spec):
            raise ConfigError(f"{key}: expected a list of {len(spec)} numbers, got {short(value)}")
        return tuple(_number(f"{key}[{i}]", v, s) for i, (v, s) in enumerate(zip(value, spec)))
    if isinstance(spec, Pair):
        if not isinstance(value, (list, tuple)) or len(value) != 2:
            raise ConfigError(f"{key}: expected [t0, t1], got {short(value)}")
        t0, t1 = (_number(f"{key}[{i}]", v, NONNEG) for i, v in enumerate(value))
        if t1 <= t0:
            raise ConfigError(f"{key}: t1 must be greater than t0, got {short(value)}")
        return (t0, t1)
    if isinstance(spec, Flag):
        if not isinstance(value, bool):
            raise ConfigError(f"{key}: expected true or false, got {short(value)}")
        return value
    if isinstance(spec, Text):
        if not isinstance(value, str) or not value:
            raise ConfigError(f"{key}: expected a non-empty string, got {short(value)}")
        if spec.choices and value not in spec.choices:
            raise ConfigError(f"{key}: must be one of {', '.join(spec.choices)}, got {short(value)}")
        return value
    raise TypeError(f"bad schema entry at {key}")  # pragma: no cover


def validate(raw: Any, n_joints: int) -> dict:
    """Validate a parsed, merged config document for an arm of ``n_joints`` joints."""
    checked = check_value("", raw, SCHEMA, n_joints)
    sim = checked["simulation"]
    if sim["window_s"][1] > sim["duration_s"] + 1e-12:
        raise ConfigError(f"simulation.window_s: ends at {sim['window_s'][1]:g} s, after "
                          f"simulation.duration_s = {sim['duration_s']:g} s")
    return checked


def config_file(path: Path) -> Path:
    """``path`` resolved, a regular file: ConfigError naming it otherwise (missing, a folder, a pipe or a device, a
    name the OS refuses: file_path.file_or_folder)."""
    try:
        resolved, is_dir = file_or_folder(path)
    except PathProblem as exc:
        raise ConfigError(f"config file not found: {exc.path}" if exc.missing else f"config file {exc}") from None
    if is_dir:
        raise ConfigError(f"config file {path}: a folder, not a file")
    return resolved


MAX_EXTENDS = 100   # files a config's extends chain may hold above it (a real one holds 1-3)


def _read_yaml(path: Path, seen: tuple[Path, ...] = ()) -> dict:
    """The document at ``path``, merged over the file its ``extends`` key names (relative to it), recursively."""
    path = config_file(path)
    if path in seen:
        raise ConfigError(f"{path}: extends: circular ({' -> '.join(str(p) for p in seen + (path,))})")
    if len(seen) >= MAX_EXTENDS:   # else Python's recursion limit, blamed on whichever file it hit
        raise ConfigError(f"{seen[0]}: extends: a chain of more than {MAX_EXTENDS} files (at {path})")
    raw = read_config_yaml(path)  # one line for a file that is not text, not YAML, or gives a key twice
    if not isinstance(raw, dict):
        return raw
    arm = raw.get("arm")
    is_path = isinstance(arm, str) and ("/" in arm or arm.lower().endswith((".yaml", ".yml", ".urdf", ".xml")))
    if is_path and not arm.startswith("package://"):
        # a path is relative to the file that names it (made absolute, not resolved: the arm's loader resolves it
        # and names a loop of symbolic links in one line)
        raw["arm"] = os.path.abspath(path.parent / arm)
    if "extends" not in raw:
        return raw
    base = raw.pop("extends")
    if not isinstance(base, str) or not base:
        raise ConfigError(f"{path}: extends: expected the path of a config file, got {short(base)}")
    try:
        config_file(path.parent / base)
    except ConfigError as exc:
        raise ConfigError(f"{path}: extends: {base}: {exc}") from None
    parent = _read_yaml(path.parent / base, seen + (path,))
    if not isinstance(parent, dict):
        raise ConfigError(f"{path}: extends: {base} is not a mapping")
    return _merge(parent, raw)


def _merge(base: dict, over: dict) -> dict:
    """``base`` with ``over``'s keys replacing its own, mappings merged key by key."""
    out = dict(base)
    for k, v in over.items():
        out[k] = _merge(base[k], v) if isinstance(v, dict) and isinstance(base.get(k), dict) else v
    return out


def load_config(path: str | Path) -> dict:
    """The config document at ``path`` (merged over the file its ``extends`` names), parsed and validated as far
    as a config alone can be: a mapping of known keys, each value given of its kind and within its bounds (a
    per-joint list of any length: its length is the arm's, checked when the arm's settings are built). Raises
    ConfigError naming the key or file. An ``arm`` path is made absolute (relative to the file naming it).

    The settings of a run are built from it, the arm file and the rules (``run_settings.build_settings``)."""
    raw = _read_yaml(Path(path))
    if not isinstance(raw, dict):
        raise ConfigError(f"{path}: expected a mapping of config sections")
    _check_given("", raw, SCHEMA)
    return raw


def _check_given(key: str, value: Any, spec: Any, n: int | None = None, null_ok: bool = True) -> None:
    """The keys ``value`` gives checked against ``spec`` (missing keys are left to the arm and the rules; ``n``:
    the arm's joints, the length of every per-joint list, None: any length; ``null_ok``: a null passes)."""
    if isinstance(spec, dict):
        _check_mapping(key, value, spec)
        for k, v in value.items():
            _check_given(f"{key}.{k}" if key else k, v, spec[k], n, null_ok)
    elif value is not None:
        check_value(key, value, spec, n)
    elif not null_ok:
        raise ConfigError(f"{key}: null (leave the key out for the rule's or a config's value)")


def check_arm_settings(settings: dict, n_joints: int, config_gives: dict) -> None:
    """An arm file's ``settings`` for its arm of ``n_joints`` joints: config keys but ``arm``, each given (not
    null) of its kind, within its bounds and, per joint, of the arm's length, and none that ``config_gives`` (the
    default config, which a config extends) gives: the config is the layer above the arm file, so the arm file's
    value of such a key would never be used. ConfigError naming the key."""
    _check_given("", settings, {k: v for k, v in SCHEMA.items() if k != "arm"}, n_joints, null_ok=False)
    for key in _leaf_keys(settings):
        if _get(config_gives, key) is not None:
            raise ConfigError(f"{key}: the default config gives this key and overrides an arm file's value, so it "
                              f"would never be used (an arm file's settings hold what the rules would derive, "
                              f"docs/arms.md); give it in a config file")


def _leaf_keys(tree: dict, prefix: str = ""):
    """The dotted keys of ``tree``'s values that are not mappings, in the file's order."""
    for k, v in tree.items():
        key = f"{prefix}{k}"
        if isinstance(v, dict):
            yield from _leaf_keys(v, key + ".")
        else:
            yield key


def merged(base: dict, over: dict) -> dict:
    """``base`` with ``over``'s keys replacing its own, mappings merged key by key."""
    return _merge(base, over)


def checked_layers(layers: list[dict], n_joints: int, rule_keys: tuple[str, ...]) -> tuple[dict, tuple[str, ...]]:
    """(the ``layers`` merged, each over the one before, checked for an arm of ``n_joints`` joints; the dotted
    ``rule_keys`` that none of them gives). Ones (true for a switch) stand in for those keys in the checked
    config, so the rest is checked before a rule gives their values. ConfigError naming the key."""
    tree: dict = {}
    for layer in layers:
        tree = _merge(tree, layer)
    absent = tuple(key for key in rule_keys if _get(tree, key) is None)
    return validate(_merge(_placeholders(absent, n_joints), tree), n_joints), absent


def _get(tree: dict, dotted: str):
    """``tree``'s value at a dotted key, or None where any part is missing."""
    for part in dotted.split("."):
        if not isinstance(tree, dict) or part not in tree:
            return None
        tree = tree[part]
    return tree


def _placeholders(keys: tuple[str, ...], n: int) -> dict:
    """Ones (true for a switch) at ``keys`` (so the rest of a config can be checked before the rule gives their
    values)."""
    out: dict = {}
    for key in keys:
        *parents, leaf = key.split(".")
        node = out
        for part in parents:
            node = node.setdefault(part, {})
        node[leaf] = True if leaf == "enabled" else [1.0] * n  # > 0 passes every bound of these keys
    return out


def default_config_path() -> Path:
    """The shipped ``config/default.yaml`` (source tree or installed share directory)."""
    from .paths import share_path
    return share_path("config", "default.yaml")

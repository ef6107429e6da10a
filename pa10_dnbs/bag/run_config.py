"""The config a bag's run is read with (``analyse``, ``replay --live``): ``--config``, else the one stored in the bag
(custom_data ``pa10_dnbs.config``), else the shipped default; checked once, here, against the arm the bag holds.

A stored config is checked by the config schema (config.py) for the keys the readers use, so a hand-damaged one
gives one line naming the bag and the key, never a traceback from deep inside a reader. Other keys are left as
stored: a bag of an earlier version may lack a newer section (``metrics``: DEFAULT_METRICS stands in).
The readers get what they use as :class:`BagRunSettings`, never the config's mapping.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from ..config import SCHEMA, ConfigError, check_value, default_config_path
from ..config_error import short
from ..run_settings import build_settings
from ..run_size import check_run_size, run_bytes
from ..run_steps import countable_steps
from .bag_reader import Bag, BagError
from .custom_data import CUSTOM_CONFIG, CUSTOM_PREFIX

#: the stored config's keys the readers use: simulation.dt_s [s], simulation.window_s [s, s], the torque limits [N m]
USED_KEYS = ("simulation.dt_s", "simulation.window_s", "plant.torque_limit_nm")
#: the metrics section of a bag recorded before the config had one (the values every config had then)
DEFAULT_METRICS = {"settle_band_rad": 0.01, "startup_s": 0.2}


@dataclass(frozen=True)
class BagRunSettings:
    """What the readers of a bag's run (``analyse``, ``replay --live``) take from its config, checked for the bag's
    arm: the step ``dt_s`` [s], the metrics ``window_s`` (t0, t1) [s], ``torque_limit_nm`` (n_joints,) [N m],
    ``settle_band_rad`` [rad], ``startup_s`` [s], ``seed`` (None: not stored), ``arm_file`` (the arm file the run
    named, for its URDF when the bag holds none; None: not stored) and ``source`` (where the config came from,
    for the report)."""

    dt_s: float
    window_s: tuple[float, float]
    torque_limit_nm: tuple[float, ...]
    settle_band_rad: float
    startup_s: float
    seed: int | None
    arm_file: str | None
    source: str


def _from_mapping(stored: dict, source: str) -> BagRunSettings:
    """The settings of the config mapping stored in a bag, its USED_KEYS (and metrics, when there) checked by
    :func:`_checked_stored`: the one place a bag's stored config is read as a mapping."""
    sim, metrics = stored["simulation"], stored.get("metrics") or DEFAULT_METRICS
    return BagRunSettings(float(sim["dt_s"]), tuple(sim["window_s"]), tuple(stored["plant"]["torque_limit_nm"]),
                          float(metrics["settle_band_rad"]), float(metrics["startup_s"]), sim.get("seed"),
                          stored.get("arm"), source)


def _given_config(config_path: Path, joints: tuple[str, ...], bag_dt_s: float | None) -> BagRunSettings:
    """The run's config from ``config_path``: ConfigError naming it when its arm's joints are not the bag's
    ``joints`` (another arm's config would report the bag against that arm's torque limits) or its step is not
    the bag's ``bag_dt_s`` [s] (its stored config's; None: unknown), which would misread the run's steps."""
    settings = build_settings(config_path, report=False)   # a reader of a bag: the rules' table is not its to say
    if tuple(settings.arm.joint_names) != tuple(joints):
        raise ConfigError(f"`config_path` {config_path}: its arm {settings.arm.name} (joints "
                          f"{', '.join(settings.arm.joint_names)}) is not the bag's (joints {', '.join(joints)}): pass "
                          "the run's config, or leave `config_path` out for the one stored in the bag")
    if bag_dt_s is not None and settings.simulation.dt_s != bag_dt_s:
        raise ConfigError(f"`config_path` {config_path}: its simulation.dt_s {settings.simulation.dt_s:g} s is not the "
                          f"bag's step {bag_dt_s:g} s: pass the run's config, or leave `config_path` out for the one "
                          "stored in the bag")
    return _from_settings(settings, str(Path(config_path).resolve()))


def _from_settings(settings, source: str) -> BagRunSettings:
    """The readers' part of a command's ``settings`` (settings.Settings)."""
    sim = settings.simulation
    return BagRunSettings(sim.dt_s, tuple(sim.window_s), tuple(settings.plant.torque_limit_nm),
                          settings.metrics.settle_band_rad, settings.metrics.startup_s, sim.seed,
                          str(settings.arm.file), source)


def _stored_dt_s(info: dict) -> float | None:
    """The step [s] of the config stored in the bag, or None."""
    try:
        return float(info["config"]["simulation"]["dt_s"])
    except (KeyError, TypeError, ValueError):
        return None


def _checked_stored(bag: Bag, cfg) -> dict:
    """The stored config ``cfg`` with USED_KEYS checked by the schema and normalised (numbers as float, lists as
    tuples); BagError naming the bag and the key."""
    where = f"{bag.path}: the config stored in the bag ({CUSTOM_CONFIG})"
    if not isinstance(cfg, dict):
        raise BagError(f"{where} is not a mapping; pass `config_path`")
    out = dict(cfg)
    for dotted in USED_KEYS:
        section, key = dotted.split(".")
        values = out.get(section)
        if not isinstance(values, dict) or key not in values:
            raise BagError(f"{where} lacks {dotted}; pass `config_path`")
        try:
            out[section] = {**values, key: check_value(dotted, values[key], SCHEMA[section][key], None)}
        except ConfigError as exc:
            raise BagError(f"{where}: {exc}; pass `config_path`") from None
    if out.get("metrics"):   # absent in bags of runs before the section: DEFAULT_METRICS
        try:
            out["metrics"] = check_value("metrics", out["metrics"], SCHEMA["metrics"], None)
        except ConfigError as exc:
            raise BagError(f"{where}: {exc}; pass `config_path`") from None
    return out


def stored_steps(bag: Bag, info: dict, dt_s: float, n_joints: int) -> int | None:
    """The run's steps by the duration the launcher stored (custom_data ``pa10_dnbs.duration_s`` [s], as text) at
    the step ``dt_s`` [s]; None when the bag has none. BagError naming the bag and the key unless it is a positive,
    finite number of seconds and a countable number of steps whose record of ``n_joints`` joints fits in memory."""
    if "duration_s" not in info:
        return None
    raw = info["duration_s"]
    try:
        duration_s = check_value("duration_s", float(raw), SCHEMA["simulation"]["duration_s"], None)
        n = countable_steps(duration_s, dt_s)
    except (TypeError, ValueError) as exc:   # ConfigError is a ValueError
        why = exc if isinstance(exc, ConfigError) else f"duration_s: not a number: {short(raw)}"
        raise BagError(f"{bag.path}: custom_data {CUSTOM_PREFIX}{why}") from None
    try:
        check_run_size(duration_s, n, n_joints, graph=True)
    except ConfigError:   # its words name the command's duration: here the stored key is to blame
        raise BagError(f"{bag.path}: custom_data {CUSTOM_PREFIX}duration_s: {duration_s:g} s is {n:,} steps of "
                       f"{dt_s:g} s, about {run_bytes(n, n_joints, graph=True) / 2**30:,.0f} GiB to hold, more than "
                       "is available here") from None
    return n


def run_config(bag: Bag, info: dict, config_path: Path | None, joints: tuple[str, ...]) -> BagRunSettings:
    """The settings to read the bag's run with (``source``: where they came from). ``info``: ``analysis.run_info(bag)``;
    ``joints``: the bag's arm's joints (``analysis.bag_joint_names``), whose count the torque limits must match.
    ConfigError naming ``config_path``, BagError naming the bag (and the stored key)."""
    if config_path is not None:
        return _given_config(config_path, joints, _stored_dt_s(info))
    if info.get("config") is None:
        path = default_config_path()
        found = _from_settings(build_settings(path, report=False), f"{path} (the bag carries no config)")
        whose = f"the shipped default config ({path}; the bag carries none) has torque limits for"
    else:
        found = _from_mapping(_checked_stored(bag, info["config"]),
                              f"stored in the bag (recorded from {info.get('config_file', '?')})")
        whose = "the config stored in the bag has torque limits for"
    if len(found.torque_limit_nm) != len(joints):
        raise BagError(f"{bag.path}: the bag's arm has {len(joints)} joints ({', '.join(joints)}), {whose} "
                       f"{len(found.torque_limit_nm)}: pass the run's `config_path`")
    return found

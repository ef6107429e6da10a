"""The settings of a run as typed, frozen objects, validated when they are made.

One class per section of ``config/*.yaml`` (its fields are the section's keys, in the same units: see
config/default.yaml), and :class:`Settings`, the whole: the arm and every section. A command builds one
``Settings`` (``run_settings.build_settings``) and hands it, or the sections a part needs, down as arguments.
A changed copy is ``dataclasses.replace(...)``: it is validated again, so a scenario or a tuning trial cannot
hold a value a config file could not. Per-joint values are tuples of floats (one per actuated joint).
"""
from __future__ import annotations

import dataclasses
import typing
from dataclasses import dataclass, fields, is_dataclass

from .arm import Arm
from .config import SCHEMA, check_value
from .config_error import ConfigError

Joints = tuple[float, ...]  # one value per actuated joint, chain order


class _Section:
    """A section of the config: checked against its ``SCHEMA`` entry at construction (numbers normalised)."""

    KEY = ""  # the dotted config key of the section

    def __post_init__(self) -> None:
        spec = SCHEMA
        for part in self.KEY.split("."):
            spec = spec[part]
        checked = check_value(self.KEY, _plain(self), spec, None)
        for f in fields(self):
            if not is_dataclass(getattr(self, f.name)):
                object.__setattr__(self, f.name, checked[f.name])

    @classmethod
    def of(cls, mapping: dict):
        """The section from a validated config's mapping (nested sections built the same way)."""
        hints = typing.get_type_hints(cls)
        return cls(**{f.name: (hints[f.name].of(mapping[f.name]) if isinstance(hints[f.name], type)
                               and issubclass(hints[f.name], _Section) else mapping[f.name]) for f in fields(cls)})


def _plain(section) -> dict:
    """The section as the config's mapping (nested sections as mappings)."""
    return {f.name: (_plain(v) if is_dataclass(v := getattr(section, f.name)) else v) for f in fields(section)}


@dataclass(frozen=True)
class RunSettings(_Section):
    """``simulation``: step dt_s (s), duration_s (s), metrics window_s [t0, t1] (s), seed, the start offset
    from the reference (rad) and start velocity (rad/s) per joint."""

    KEY = "simulation"
    dt_s: float
    duration_s: float
    window_s: tuple[float, float]
    seed: int
    initial_position_offset_rad: Joints
    initial_velocity_rad_s: Joints


@dataclass(frozen=True)
class ReferenceSettings(_Section):
    """``reference``: eq. 27 per joint (amplitude rad, envelope rate 1/s^3, frequency rad/s, centre rad) and the
    preview (steps) a joint controller gets ahead."""

    KEY = "reference"
    amplitude_rad: Joints
    envelope_rate_per_s3: Joints
    frequency_rad_s: Joints
    centre_rad: Joints
    preview_steps: int


@dataclass(frozen=True)
class PlantSettings(_Section):
    """``plant``: gravity (m/s^2), per joint rotor inertia (kg m^2), viscous (N m s/rad) and Coulomb (N m)
    friction, the Coulomb smoothing (rad/s), torque limits (N m), a payload (kg) and a factor on link masses."""

    KEY = "plant"
    gravity_mps2: float
    rotor_inertia_kgm2: Joints
    viscous_nms_per_rad: Joints
    coulomb_nm: Joints
    coulomb_smoothing_rad_s: float
    torque_limit_nm: Joints
    payload_kg: float
    link_mass_scale: float


@dataclass(frozen=True)
class AlphaNetSettings(_Section):
    """``dnbs.alpha_net``: the virtual control's HONN (output scale A in rad/s, error scale E1 in rad)."""

    KEY = "dnbs.alpha_net"
    max_degree: int
    input_scale: tuple[float, float]
    output_scale_rad_s: Joints
    error_scale_rad: Joints
    init_weight_std: Joints
    p0: Joints
    q: Joints
    r: Joints
    eta: Joints


@dataclass(frozen=True)
class TorqueNetSettings(_Section):
    """``dnbs.torque_net``: the torque's HONN (output scale U in N m, error scale E2 in rad/s)."""

    KEY = "dnbs.torque_net"
    max_degree: int
    input_scale: tuple[float, float, float]
    output_scale_nm: Joints
    error_scale_rad_s: Joints
    init_weight_std: Joints
    p0: Joints
    q: Joints
    r: Joints
    eta: Joints


@dataclass(frozen=True)
class RobustTermSettings(_Section):
    KEY = "dnbs.remedies.robust_term"
    enabled: bool
    velocity_feedforward: bool
    alpha_gain_per_s: Joints
    torque_gain_nms_per_rad: Joints


@dataclass(frozen=True)
class SwitchSettings(_Section):
    KEY = "dnbs.remedies.anti_windup"
    enabled: bool


@dataclass(frozen=True)
class DeadZoneSettings(_Section):
    KEY = "dnbs.remedies.dead_zone"
    enabled: bool
    alpha_rad: Joints
    torque_rad_s: Joints


@dataclass(frozen=True)
class EModificationSettings(_Section):
    KEY = "dnbs.remedies.e_modification"
    enabled: bool
    sigma: float


@dataclass(frozen=True)
class ProjectionSettings(_Section):
    KEY = "dnbs.remedies.projection"
    enabled: bool
    weight_bound: float


@dataclass(frozen=True)
class SlopeBoundSettings(_Section):
    KEY = "dnbs.remedies.slope_bound"
    enabled: bool
    fraction: Joints


@dataclass(frozen=True)
class LearningRampSettings(_Section):
    KEY = "dnbs.remedies.learning_ramp"
    enabled: bool
    ramp_s: float


@dataclass(frozen=True)
class CovarianceBoundSettings(_Section):
    KEY = "dnbs.remedies.covariance_bound"
    enabled: bool
    p_max: float


@dataclass(frozen=True)
class RemediesSettings(_Section):
    """``dnbs.remedies``: each remedy of docs/controller.md, switched on or off, with its settings."""

    KEY = "dnbs.remedies"
    robust_term: RobustTermSettings
    anti_windup: SwitchSettings
    dead_zone: DeadZoneSettings
    e_modification: EModificationSettings
    projection: ProjectionSettings
    slope_bound: SlopeBoundSettings
    learning_ramp: LearningRampSettings
    covariance_bound: CovarianceBoundSettings

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.slope_bound.enabled and not self.robust_term.enabled:
            raise ConfigError("dnbs.remedies.slope_bound.enabled: true needs dnbs.remedies.robust_term.enabled: the "
                              "bounds are fractions of the robust term's gains, 0 when it is off, so every network "
                              "weight would be held at 0 (set slope_bound.enabled: false)")


@dataclass(frozen=True)
class DnbsSettings(_Section):
    """``dnbs``: the DNBS controller: the e2 sign, the kernel (auto, numpy, c), its two networks and remedies."""

    KEY = "dnbs"
    e2_sign: str
    kernel: str
    alpha_net: AlphaNetSettings
    torque_net: TorqueNetSettings
    remedies: RemediesSettings


@dataclass(frozen=True)
class PidSettings(_Section):
    """``pid``: gains per joint (kp N m/rad, ki N m/(rad s), kd N m s/rad) and the integrator's anti-windup."""

    KEY = "pid"
    kp: Joints
    ki: Joints
    kd: Joints
    anti_windup: bool


@dataclass(frozen=True)
class CtcSettings(_Section):
    """``ctc``: computed torque's gains per joint (kp 1/s^2, kd 1/s) and what it does past a torque limit
    (scale_feedback or clip: sim/computed_torque.py)."""

    KEY = "ctc"
    kp_per_s2: Joints
    kd_per_s: Joints
    on_saturation: str


@dataclass(frozen=True)
class GuardSettings(_Section):
    """``guards``: the state guard (position margin rad, max speed rad/s per joint, what a bad state gets) and
    how often (steps) the EKF's full check runs."""

    KEY = "guards"
    position_margin_rad: float
    max_speed_rad_s: Joints
    on_bad_state: str
    ekf_full_check_every: int


@dataclass(frozen=True)
class CheckpointSettings(_Section):
    KEY = "checkpoint"
    period_s: float


@dataclass(frozen=True)
class MetricsSettings(_Section):
    """``metrics``: the settling band (rad) and the start-up span (s) left out of the torque figures."""

    KEY = "metrics"
    settle_band_rad: float
    startup_s: float


@dataclass(frozen=True)
class LinkFaultSettings(_Section):
    """Faults on the states sent to the controllers (``faults.state``; per joint: drop and corrupt fractions,
    delay and jitter in ms, and what a corrupted value becomes)."""

    KEY = "faults.state"
    drop_fraction: Joints
    delay_ms: Joints
    jitter_ms: Joints
    corrupt_fraction: Joints
    corrupt_kind: str


@dataclass(frozen=True)
class EffortLinkFaultSettings(LinkFaultSettings):
    """Faults on the efforts sent back (``faults.effort``); the same keys as the states'."""

    KEY = "faults.effort"


@dataclass(frozen=True)
class FaultSettings(_Section):
    """``faults``: the injected faults of a graph run (seed, both link directions, controller kill times s)."""

    KEY = "faults"
    seed: int
    state: LinkFaultSettings
    effort: EffortLinkFaultSettings
    kill_controller_at_s: Joints


SECTIONS = {"simulation": RunSettings, "reference": ReferenceSettings, "plant": PlantSettings,
            "dnbs": DnbsSettings, "pid": PidSettings, "ctc": CtcSettings, "guards": GuardSettings,
            "checkpoint": CheckpointSettings, "metrics": MetricsSettings, "faults": FaultSettings}


@dataclass(frozen=True)
class Settings:
    """Everything a run is set by: the arm (facts and chain) and each section, checked together at
    construction (every per-joint tuple has one value per joint of the arm, the metrics window ends within the
    run)."""

    arm: Arm
    simulation: RunSettings
    reference: ReferenceSettings
    plant: PlantSettings
    dnbs: DnbsSettings
    pid: PidSettings
    ctc: CtcSettings
    guards: GuardSettings
    checkpoint: CheckpointSettings
    metrics: MetricsSettings
    faults: FaultSettings

    def __post_init__(self) -> None:
        from .config import validate
        validate(self.to_config(), self.arm.n_joints)

    @classmethod
    def of(cls, mapping: dict, arm: Arm) -> "Settings":
        """From a validated config mapping for ``arm``."""
        return cls(arm=arm, **{k: c.of(mapping[k]) for k, c in SECTIONS.items()})

    def to_config(self) -> dict:
        """The config mapping these settings are (``arm``: the arm file's path), as config_used.yaml holds it."""
        return {"arm": str(self.arm.file), **{k: _plain(getattr(self, k)) for k in SECTIONS}}

    @property
    def n_joints(self) -> int:
        return self.arm.n_joints


def replace_in(settings: Settings, dotted: str, value) -> Settings:
    """``settings`` with the value at a dotted key (``plant.payload_kg``) replaced; every section on the way is
    made again, so validated again (ConfigError naming the key)."""
    head, _, rest = dotted.partition(".")
    if not rest:
        return dataclasses.replace(settings, **{head: value})
    return dataclasses.replace(settings, **{head: replace_in(getattr(settings, head), rest, value)})


__all__ = ["Settings", "SECTIONS", "ConfigError", "replace_in"] + [c.__name__ for c in SECTIONS.values()]

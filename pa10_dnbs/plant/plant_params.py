"""The parameters every arm plant takes (:class:`PlantParams`, SI units, validated when made) and the checks of
its inputs, shared by the PyBullet and the MuJoCo plant (numpy only)."""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..arm import Arm

_VECTOR_FIELDS = (
    # name, lower bound, bound is strict
    ("rotor_inertia_kgm2", 0.0, False),
    ("viscous_nms_per_rad", 0.0, False),
    ("coulomb_nm", 0.0, False),
    ("torque_limit_nm", 0.0, True),
)


@dataclass(frozen=True)
class PlantParams:
    """Plant parameters (SI units); validated on construction. Every per-joint field has one value per actuated
    joint (checked by the plant, which refuses one left None): a run's come from its settings' ``plant``
    section (plant/from_config.py ``plant_params``), a tool's from ``arm_plant_params``.

    Attributes
    ----------
    dt_s : float
        Integration step, s (> 0).
    gravity_mps2 : float
        Gravity magnitude along -z, m/s^2 (>= 0; 0 disables gravity).
    rotor_inertia_kgm2 : tuple of n float or None
        Reflected rotor inertia added to diag(M), kg m^2 (>= 0).
    viscous_nms_per_rad : tuple of n float or None
        Viscous friction Fv, N m s/rad (>= 0).
    coulomb_nm : tuple of n float or None
        Coulomb friction Fc, N m (>= 0).
    coulomb_smoothing_rad_s : float
        eps in Fc tanh(qd / eps), rad/s (> 0).
    torque_limit_nm : tuple of n float or None
        Symmetric torque saturation, N m (> 0).
    payload_kg : float
        Point mass at the arm's flange link, kg (>= 0; the PA10's rated payload is 10 kg).
    link_mass_scale : float
        Factor on every link's mass and inertia tensor (> 0; 1 is the URDF as written): a model error
        the controllers were not tuned for. The rotor inertias are not scaled.
    """

    dt_s: float = 1e-3
    gravity_mps2: float = 9.81
    rotor_inertia_kgm2: tuple[float, ...] | None = None
    viscous_nms_per_rad: tuple[float, ...] | None = None
    coulomb_nm: tuple[float, ...] | None = None
    coulomb_smoothing_rad_s: float = 1e-2
    torque_limit_nm: tuple[float, ...] | None = None
    payload_kg: float = 0.0
    link_mass_scale: float = 1.0

    def __post_init__(self) -> None:
        _check_scalar("dt_s", self.dt_s, strict=True)
        _check_scalar("payload_kg", self.payload_kg, strict=False)
        _check_scalar("link_mass_scale", self.link_mass_scale, strict=True)
        _check_scalar("gravity_mps2", self.gravity_mps2, strict=False)
        _check_scalar("coulomb_smoothing_rad_s", self.coulomb_smoothing_rad_s, strict=True)
        for name, _, strict in _VECTOR_FIELDS:
            value = getattr(self, name)
            if value is None:
                continue
            try:
                arr = np.asarray(value, dtype=float)
            except (TypeError, ValueError) as exc:
                raise ValueError(f"{name}: expected one number per joint, got {value!r}") from exc
            if arr.ndim != 1 or arr.size == 0:
                raise ValueError(f"{name}: expected one value per joint, got shape {arr.shape}")
            if not np.all(np.isfinite(arr)):
                raise ValueError(f"{name}: values must be finite, got {value!r}")
            if np.any(arr <= 0.0) if strict else np.any(arr < 0.0):
                bound = "> 0" if strict else ">= 0"
                raise ValueError(f"{name}: values must be {bound}, got {value!r}")
            object.__setattr__(self, name, tuple(float(v) for v in arr))


def _check_scalar(name: str, value: float, strict: bool) -> None:
    try:
        v = float(value)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name}: expected a number, got {value!r}") from exc
    if not math.isfinite(v):
        raise ValueError(f"{name}: must be finite, got {value!r}")
    if (v <= 0.0) if strict else (v < 0.0):
        raise ValueError(f"{name}: must be {'> 0' if strict else '>= 0'}, got {value!r}")


def as_joint_vector(name: str, value, n: int) -> np.ndarray:
    arr = np.asarray(value, dtype=float)
    if arr.shape != (n,):
        raise ValueError(f"{name}: expected shape ({n},), got {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name}: values must be finite")
    return arr


def checked_for_arm(params: PlantParams, arm: Arm) -> PlantParams:
    """``params``, each per-joint field checked to hold one value per joint of ``arm`` (ValueError naming the
    field; one left None is refused: the settings' ``plant`` section holds every value, the arm's facts
    resolved into it)."""
    for name in ("rotor_inertia_kgm2", "viscous_nms_per_rad", "coulomb_nm", "torque_limit_nm"):
        value = getattr(params, name)
        if value is None:
            raise ValueError(f"{name}: not given (one value per joint of {arm.name}; a run's come from its "
                             "settings' plant section)")
        if len(value) != arm.n_joints:
            raise ValueError(f"{name}: expected {arm.n_joints} values (one per joint of {arm.name}), "
                             f"got {len(value)}")
    return params

"""The search space of each controller (docs/tuning.md, "Search spaces"): a few dimensionless numbers that
scale the per-joint values the arm starts from (its file's settings, or the gain rule of docs/arms.md), so one
space serves every arm and the start (every multiplier 1) is a point of it.

PID and CTC, per joint, with w the bandwidth multiplier and d the damping multiplier (the closed loop of a
joint of inertia J, ``J s^2 + Kd s + Kp``, has its natural frequency sqrt(Kp / J) times w and its damping
ratio Kd / (2 sqrt(Kp J)) times d):
    Kp = w^2 Kp0,  Kd = d w Kd0,  Ki = i w^3 Ki0  (PID only; i: the integral multiplier).
DNBS, per joint: k_u and k_a times their multipliers, E2 (the torque net's error scale) times its multiplier,
both networks' EKF q and p0 times theirs, and the learning ramp in seconds (0: no ramp).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

from ..config import merged, validate
from ..config_error import ConfigError
from ..settings import Settings


@dataclass(frozen=True)
class Param:
    """One dimension: ``name`` in [low, high], sampled on a log scale when ``log``; ``what`` says it in words."""

    name: str
    low: float
    high: float
    log: bool
    what: str


SPACES: dict[str, tuple[Param, ...]] = {
    "pid": (
        Param("bandwidth", 0.5, 8.0, True, "w: Kp x w^2, Kd x w, Ki x w^3"),
        Param("damping", 0.3, 3.0, True, "d: Kd x d (damping ratio x d)"),
        Param("integral", 0.03, 30.0, True, "i: Ki x i"),
    ),
    "dnbs": (
        Param("torque_gain", 0.25, 4.0, True, "k_u (robust_term.torque_gain_nms_per_rad) x this"),
        Param("alpha_gain", 0.25, 4.0, True, "k_a (robust_term.alpha_gain_per_s) x this"),
        Param("error_scale", 0.1, 10.0, True, "E2 (torque_net.error_scale_rad_s) x this"),
        Param("ekf_q", 0.01, 100.0, True, "q of both networks' EKF x this"),
        Param("ekf_p0", 0.01, 100.0, True, "p0 of both networks' EKF x this"),
        Param("ramp_s", 0.0, 5.0, False, "learning_ramp.ramp_s [s] (0: no ramp)"),
    ),
    "ctc": (
        Param("bandwidth", 0.25, 8.0, True, "w: kp_per_s2 x w^2, kd_per_s x w"),
        Param("damping", 0.3, 3.0, True, "d: kd_per_s x d (damping ratio x d)"),
    ),
}
CONTROLLERS = tuple(SPACES)


def select(controller: str, names: list[str] | None) -> tuple[Param, ...]:
    """The dimensions of ``controller``'s space to search (all when ``names`` is None); ConfigError on an
    unknown controller or name."""
    if controller not in SPACES:
        raise ConfigError(f"controller: unknown {controller}; valid: {', '.join(SPACES)}", setting="controller")
    space = SPACES[controller]
    if names is None:
        return space
    valid = [p.name for p in space]
    bad = [n for n in names if n not in valid]
    if bad or not names:
        raise ConfigError(f"params: unknown {', '.join(bad) if bad else '(empty list)'} for {controller}; "
                          f"valid: {', '.join(valid)}", setting="params")
    return tuple(p for p in space if p.name in names)


def start_values(controller: str, settings: Settings) -> dict[str, float]:
    """The point of the full space that is ``settings`` itself (multipliers 1; the ramp as set, clipped)."""
    values = {p.name: 1.0 for p in SPACES[controller]}
    if controller == "dnbs":
        ramp = settings.dnbs.remedies.learning_ramp
        p = next(p for p in SPACES["dnbs"] if p.name == "ramp_s")
        values["ramp_s"] = min(max(ramp.ramp_s if ramp.enabled else 0.0, p.low), p.high)
    return values


def _scaled(values, factor: float) -> list[float]:
    return [float(v) * factor for v in values]


def settings_fragment(controller: str, settings: Settings, values: dict[str, float]) -> dict:
    """The config fragment (per-joint lists) that the point ``values`` gives, from ``settings``' own values; a
    name missing from ``values`` keeps its start value."""
    v = dict(start_values(controller, settings), **values)
    if controller == "pid":
        w, d, i = v["bandwidth"], v["damping"], v["integral"]
        p = settings.pid
        return {"pid": {"kp": _scaled(p.kp, w * w), "kd": _scaled(p.kd, d * w), "ki": _scaled(p.ki, i * w ** 3)}}
    if controller == "ctc":
        w, d = v["bandwidth"], v["damping"]
        c = settings.ctc
        return {"ctc": {"kp_per_s2": _scaled(c.kp_per_s2, w * w), "kd_per_s": _scaled(c.kd_per_s, d * w)}}
    d = settings.dnbs
    rt = d.remedies.robust_term
    nets = {name: {"q": _scaled(net.q, v["ekf_q"]), "p0": _scaled(net.p0, v["ekf_p0"])}
            for name, net in (("alpha_net", d.alpha_net), ("torque_net", d.torque_net))}
    nets["torque_net"]["error_scale_rad_s"] = _scaled(d.torque_net.error_scale_rad_s, v["error_scale"])
    ramp = float(v["ramp_s"])
    return {"dnbs": {**nets, "remedies": {
        "robust_term": {"torque_gain_nms_per_rad": _scaled(rt.torque_gain_nms_per_rad, v["torque_gain"]),
                        "alpha_gain_per_s": _scaled(rt.alpha_gain_per_s, v["alpha_gain"])},
        "learning_ramp": {"enabled": ramp > 0.0, "ramp_s": ramp}}}}


def apply(settings: Settings, fragment: dict) -> Settings:
    """``settings`` with ``fragment``'s values (a config fragment), validated again."""
    return Settings.of(validate(merged(settings.to_config(), fragment), settings.n_joints), settings.arm)


def on_bound(params: tuple[Param, ...], values: dict[str, float], tol: float = 0.02) -> list[str]:
    """Names of the dimensions whose value lies within ``tol`` of the range (log range for log ones) of a bound,
    each with the bound: 'bandwidth (upper, 8)'."""
    out = []
    for p in params:
        x = values[p.name]
        lo, hi, xx = (math.log(p.low), math.log(p.high), math.log(x)) if p.log else (p.low, p.high, x)
        if p.name == "ramp_s" and p.low == 0.0 and x <= tol * (p.high - p.low):
            continue  # no ramp is a setting of its own, not a range too narrow
        if xx - lo <= tol * (hi - lo):
            out.append(f"{p.name} (lower, {p.low:g})")
        elif hi - xx <= tol * (hi - lo):
            out.append(f"{p.name} (upper, {p.high:g})")
    return out

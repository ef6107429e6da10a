"""A joint controller's gains as ROS parameters: which settings they are, their units and ranges, and the
values of one joint (no rclpy: the launcher writes them into the run's params file, the node declares them).

Each parameter is named by its config key (``pid.kp``, ``dnbs.remedies.robust_term.torque_gain_nms_per_rad``)
and holds that key's value for the node's one joint; its range is the key's bounds in ``config.SCHEMA``.
"""
from __future__ import annotations

from .config import SCHEMA, Joints
from .settings import Settings, replace_in

#: config key -> what it is, with its unit (the parameter's description)
GAINS = {
    "dnbs": {
        "dnbs.remedies.robust_term.alpha_gain_per_s": "k_a: the virtual control's gain on e1 [1/s]",
        "dnbs.remedies.robust_term.torque_gain_nms_per_rad": "k_u: the torque's gain on e2 [N m s/rad]",
        "dnbs.alpha_net.output_scale_rad_s": "A: the alpha network's output scale [rad/s]",
        "dnbs.alpha_net.error_scale_rad": "E1: the alpha network's training error scale [rad]",
        "dnbs.alpha_net.eta": "the alpha network's EKF learning rate eta (0, 1] [1]",
        "dnbs.torque_net.output_scale_nm": "U: the torque network's output scale [N m]",
        "dnbs.torque_net.error_scale_rad_s": "E2: the torque network's training error scale [rad/s]",
        "dnbs.torque_net.eta": "the torque network's EKF learning rate eta (0, 1] [1]",
    },
    "pid": {
        "pid.kp": "proportional gain [N m/rad]",
        "pid.ki": "integral gain [N m/(rad s)]",
        "pid.kd": "derivative gain [N m s/rad]",
    },
}
LIMIT = {"plant.torque_limit_nm": "the joint's symmetric torque limit [N m]"}


def gain_keys(controller: str) -> dict[str, str]:
    """The parameters of a ``controller`` ('dnbs' or 'pid') node: config key -> description with unit."""
    return {**GAINS[controller], **LIMIT}


def gain_range(key: str) -> tuple[float | None, float | None]:
    """The inclusive range [lo, hi] of ``key``'s values (None: unbounded); a strict bound (> 0) is checked
    again when the node's settings take the value."""
    spec = SCHEMA
    for part in key.split("."):
        spec = spec[part]
    assert isinstance(spec, Joints), key
    return spec.num.low, spec.num.high


def _value(settings: Settings, key: str) -> tuple[float, ...]:
    node = settings
    for part in key.split("."):
        node = getattr(node, part)
    return node


def joint_gains(settings: Settings, controller: str, row: int) -> dict[str, float]:
    """The values of joint ``row``'s parameters (config key -> float)."""
    return {key: float(_value(settings, key)[row]) for key in gain_keys(controller)}


def with_joint_gains(settings: Settings, row: int, gains: dict[str, float]) -> Settings:
    """``settings`` with joint ``row``'s values of ``gains`` (config key -> value), checked again (ConfigError
    naming the key)."""
    for key, value in gains.items():
        values = list(_value(settings, key))
        values[row] = value
        settings = replace_in(settings, key, tuple(values))
    return settings

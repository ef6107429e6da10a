"""Build one joint's controller (DNBS or PID) from a validated config dict.

Shared by the in-process simulation and the ROS joint-controller node, so
both run the same objects with the same seeds.
"""
from __future__ import annotations

from .core.dnbs_controller import DNBSJointController, DNBSParams, NetworkParams
from .core.ekf import EKFParams
from .core.pid_controller import PIDJointController, PIDParams
from .core.reference import Reference

CONTROLLER_KINDS = ("dnbs", "pid")


def _network(net: dict, joint: int) -> NetworkParams:
    return NetworkParams(
        max_degree=net["max_degree"],
        input_scale=net["input_scale"],
        init_weight_std=net["init_weight_std"][joint],
        ekf=EKFParams(p0=net["p0"][joint], q=net["q"][joint], r=net["r"][joint], eta=net["eta"][joint]),
    )


def build_controller(cfg: dict, kind: str, joint: int):
    """Controller for joint index ``joint`` (0..6); DNBS weights seeded by (simulation.seed, joint)."""
    limit = cfg["plant"]["torque_limit_nm"][joint]
    if kind == "dnbs":
        params = DNBSParams(alpha_net=_network(cfg["dnbs"]["alpha_net"], joint),
                            torque_net=_network(cfg["dnbs"]["torque_net"], joint),
                            torque_limit_nm=limit, anti_windup=cfg["dnbs"]["anti_windup"],
                            ekf_full_check_every=cfg["guards"]["ekf_full_check_every"])
        return DNBSJointController(params, seed=(cfg["simulation"]["seed"], joint))
    if kind == "pid":
        pid = cfg["pid"]
        return PIDJointController(PIDParams(kp=pid["kp"][joint], ki=pid["ki"][joint], kd=pid["kd"][joint],
                                            dt_s=cfg["simulation"]["dt_s"], torque_limit_nm=limit))
    raise ValueError(f"unknown controller kind {kind!r} (expected one of {CONTROLLER_KINDS})")


def build_reference(cfg: dict) -> Reference:
    """Eq. 27 reference from ``cfg['reference']``."""
    r = cfg["reference"]
    return Reference(r["amplitude_rad"], r["envelope_rate_per_s3"], r["frequency_rad_s"],
                     dt_s=cfg["simulation"]["dt_s"], preview_steps=r["preview_steps"])

"""Build joint controllers (DNBS or PID) and the reference from a run's typed settings.

Shared by the in-process simulation (one bank of all the arm's joints) and the
ROS joint-controller node (a bank of its one joint), so both run the same
objects with the same seeds.
"""
from __future__ import annotations

import numpy as np

from .core.controller_bank import ControllerBank
from .core.dnbs_controller import DNBSControllers, DNBSParams, NetworkParams, Remedies
from .core.pid_controller import PIDControllers, PIDParams
from .core.joint_trajectory import JointTrajectory
from .core.reference import Reference
from .core.state_guard import StateGuard
from .core.trajectory_reference import TrajectoryReference
from .loop.guarded_controllers import GuardedControllers
from .settings import AlphaNetSettings, RemediesSettings, Settings, TorqueNetSettings

CONTROLLER_KINDS = ("dnbs", "pid")


def _network(net: AlphaNetSettings | TorqueNetSettings, output_scale, error_scale) -> NetworkParams:
    a = lambda v: np.array(v, dtype=float)  # noqa: E731
    return NetworkParams(max_degree=net.max_degree, input_scale=tuple(net.input_scale),
                         output_scale=a(output_scale), error_scale=a(error_scale), init_weight_std=a(net.init_weight_std),
                         p0=a(net.p0), q=a(net.q), r=a(net.r), eta=a(net.eta))


def remedies_from_settings(rem: RemediesSettings) -> Remedies:
    """The ``dnbs.remedies`` settings as :class:`Remedies` (settings of a switched-off remedy are kept, unused)."""
    a = lambda v: np.array(v, dtype=float)  # noqa: E731
    return Remedies(
        robust_term=rem.robust_term.enabled, velocity_feedforward=rem.robust_term.velocity_feedforward,
        alpha_gain_per_s=a(rem.robust_term.alpha_gain_per_s),
        torque_gain_nms_per_rad=a(rem.robust_term.torque_gain_nms_per_rad),
        anti_windup=rem.anti_windup.enabled,
        dead_zone=rem.dead_zone.enabled, dead_zone_rad=a(rem.dead_zone.alpha_rad),
        dead_zone_rad_s=a(rem.dead_zone.torque_rad_s),
        e_modification=rem.e_modification.enabled, e_modification_sigma=rem.e_modification.sigma,
        projection=rem.projection.enabled, weight_bound=rem.projection.weight_bound,
        slope_bound=rem.slope_bound.enabled, slope_fraction=a(rem.slope_bound.fraction),
        learning_ramp=rem.learning_ramp.enabled, learning_ramp_s=rem.learning_ramp.ramp_s,
        covariance_bound=rem.covariance_bound.enabled, p_max=rem.covariance_bound.p_max)


def dnbs_params(settings: Settings) -> DNBSParams:
    """Every joint's DNBS parameters (``.select(rows)`` gives a subset)."""
    d = settings.dnbs
    return DNBSParams(alpha_net=_network(d.alpha_net, d.alpha_net.output_scale_rad_s, d.alpha_net.error_scale_rad),
                      torque_net=_network(d.torque_net, d.torque_net.output_scale_nm, d.torque_net.error_scale_rad_s),
                      torque_limit_nm=np.array(settings.plant.torque_limit_nm, dtype=float),
                      dt_s=settings.simulation.dt_s, remedies=remedies_from_settings(d.remedies),
                      e2_sign=d.e2_sign, ekf_full_check_every=settings.guards.ekf_full_check_every)


def pid_params(settings: Settings) -> PIDParams:
    pid = settings.pid
    return PIDParams(kp=np.array(pid.kp, float), ki=np.array(pid.ki, float), kd=np.array(pid.kd, float),
                     torque_limit_nm=np.array(settings.plant.torque_limit_nm, float), dt_s=settings.simulation.dt_s,
                     anti_windup=pid.anti_windup)


def build_controllers(settings: Settings, kind: str, joints=None) -> ControllerBank:
    """Controllers of joint indices ``joints`` (0..n-1; all of the arm's when None), one per row, in that order.

    ``dnbs.kernel: c`` steps a DNBS bank with the compiled kernel (the same bits; KernelBuildError when it
    cannot be built here); ``auto``: the compiled kernel where it builds, else numpy (accel/choice.py; commands
    resolve it first and say which). DNBS weights of joint j are seeded by (simulation.seed, j), whatever
    the bank it sits in.
    """
    rows = list(range(settings.n_joints)) if joints is None else [int(j) for j in joints]
    if kind == "dnbs":
        bank, kernel = DNBSControllers, settings.dnbs.kernel
        if kernel == "auto":
            from .accel.choice import auto_kernel
            kernel = auto_kernel().kernel
        if kernel == "c":  # the same step compiled (pa10_dnbs/accel): imported only when asked for
            from .accel.compiled_dnbs import CompiledDNBSControllers as bank
        return bank(dnbs_params(settings).select(rows), seed=settings.simulation.seed, joints=rows)
    if kind == "pid":
        return PIDControllers(pid_params(settings).select(rows))
    raise ValueError(f"unknown controller kind {kind!r} (expected one of {CONTROLLER_KINDS})")


def build_reference(settings: Settings, trajectory: JointTrajectory | None = None) -> Reference | TrajectoryReference:
    """Eq. 27 reference from ``settings.reference``; with ``trajectory`` (``--trajectory FILE``), that trajectory
    from step 0 on, starting from eq. 27's state at step 0 (TrajectoryError if the arm cannot follow it)."""
    r = settings.reference
    eq27 = Reference(r.amplitude_rad, r.envelope_rate_per_s3, r.frequency_rad_s,
                     dt_s=settings.simulation.dt_s, preview_steps=r.preview_steps, centre_rad=r.centre_rad)
    if trajectory is None:
        return eq27
    ref = switchable_reference(settings, eq27)
    ref.start(trajectory, 0)
    return ref


def load_reference_trajectory(settings: Settings, path, flag: str = "--trajectory") -> JointTrajectory:
    """The JointTrajectory of file ``path`` (YAML or JSON, docs/trajectories.md), checked against the config's arm
    and interpolated once from step 0 (its quintics within the joint limits); ConfigError ``<flag> <path>: <what
    is wrong>`` (one line) otherwise."""
    from .config_error import ConfigError
    from .core.joint_trajectory import TrajectoryError
    from .trajectory_file import load_trajectory_file

    traj = load_trajectory_file(path, settings.arm, flag)
    try:
        build_reference(settings, traj)
    except TrajectoryError as exc:
        raise ConfigError(f"{flag} {path}: {exc}") from None
    return traj


def switchable_reference(settings: Settings, reference: Reference | TrajectoryReference) -> TrajectoryReference:
    """``reference`` as a TrajectoryReference of the config's arm (joint names and URDF limits), which takes
    trajectories while running (the reference node's ``trajectory`` topic); itself if it is one."""
    if isinstance(reference, TrajectoryReference):
        return reference
    arm = settings.arm
    return TrajectoryReference(reference, arm.joint_names, arm.lower_rad, arm.upper_rad)


def build_state_guard(settings: Settings, joints=None) -> StateGuard:
    """The state guard of joint indices ``joints`` (all when None): the arm's URDF limits and ``settings.guards``."""
    arm = settings.arm
    rows = list(range(arm.n_joints)) if joints is None else [int(j) for j in joints]
    g = settings.guards
    return StateGuard(lower_rad=np.array([arm.lower_rad[j] for j in rows]),
                      upper_rad=np.array([arm.upper_rad[j] for j in rows]),
                      margin_rad=g.position_margin_rad,
                      max_speed_rad_s=np.array([g.max_speed_rad_s[j] for j in rows]))


def build_guarded_controllers(settings: Settings, kind: str, joints=None) -> GuardedControllers:
    """What a joint runs, in a node or in-process: its controller behind its state guard."""
    return GuardedControllers(build_controllers(settings, kind, joints), build_state_guard(settings, joints),
                              settings.guards.on_bad_state)

"""Build what a run's joints need from a run's typed settings: the reference, the state guard and the joint
controllers (DNBS or PID) behind it.

:func:`joint_loop` builds them at once from the sections they need (the in-process run, one bank of all the
arm's joints); the ``build_*`` functions take a whole ``Settings`` for the ROS nodes (a bank of one joint) and
the tests, and build the same objects with the same seeds, so both run alike.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from .arm import Arm
from .config_error import ConfigError
from .core.controller_bank import ControllerBank
from .core.dnbs_controller import DNBSControllers, DNBSParams, NetworkParams, Remedies
from .core.joint_trajectory import JointTrajectory, TrajectoryError
from .core.pid_controller import PIDControllers, PIDParams
from .core.reference import Reference
from .core.state_guard import StateGuard
from .core.trajectory_reference import TrajectoryReference
from .loop.guarded_controllers import GuardedControllers
from .settings import (AlphaNetSettings, DnbsSettings, GuardSettings, PidSettings, ReferenceSettings, RemediesSettings,
                       RunSettings, Settings, TorqueNetSettings)
from .trajectory_file import load_trajectory_file

CONTROLLER_KINDS = ("dnbs", "pid")


def joint_loop(kind: str, arm: Arm, run: RunSettings, reference: ReferenceSettings, torque_limit_nm,
               guards: GuardSettings, dnbs: DnbsSettings, pid: PidSettings, trajectory: JointTrajectory | None = None,
               bank: ControllerBank | None = None) -> tuple[Reference | TrajectoryReference, GuardedControllers]:
    """(the reference of all the arm's joints, their controllers of ``kind`` behind the state guard): eq. 27 from
    ``reference`` (with ``trajectory``: that trajectory from step 0, TrajectoryError if the arm cannot follow it);
    ``bank``: controllers built by the caller (computed torque, on its plant) in place of a DNBS or PID bank.
    ``torque_limit_nm``: (n,) the plant's limits [N m]."""
    ref = _reference(arm, reference, run.dt_s, trajectory)
    rows = list(range(arm.n_joints))
    if bank is None:
        bank = _bank(kind, rows, run, torque_limit_nm, guards, dnbs, pid)
    return ref, GuardedControllers(bank, _guard(arm, guards, rows), guards.on_bad_state)


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


def _dnbs_params(d: DnbsSettings, torque_limit_nm, dt_s: float, guards: GuardSettings) -> DNBSParams:
    return DNBSParams(alpha_net=_network(d.alpha_net, d.alpha_net.output_scale_rad_s, d.alpha_net.error_scale_rad),
                      torque_net=_network(d.torque_net, d.torque_net.output_scale_nm, d.torque_net.error_scale_rad_s),
                      torque_limit_nm=np.array(torque_limit_nm, dtype=float),
                      dt_s=dt_s, remedies=remedies_from_settings(d.remedies),
                      e2_sign=d.e2_sign, ekf_full_check_every=guards.ekf_full_check_every)


def _pid_params(pid: PidSettings, torque_limit_nm, dt_s: float) -> PIDParams:
    return PIDParams(kp=np.array(pid.kp, float), ki=np.array(pid.ki, float), kd=np.array(pid.kd, float),
                     torque_limit_nm=np.array(torque_limit_nm, float), dt_s=dt_s, anti_windup=pid.anti_windup)


def _bank(kind: str, rows: list[int], run: RunSettings, torque_limit_nm, guards: GuardSettings,
          dnbs: DnbsSettings | None, pid: PidSettings | None) -> ControllerBank:
    """Controllers of joint indices ``rows``, one per row, in that order.

    ``dnbs.kernel: c`` steps a DNBS bank with the compiled kernel (the same bits; KernelBuildError when it
    cannot be built here); ``auto``: the compiled kernel where it builds, else numpy (accel/choice.py; commands
    resolve it first and say which). DNBS weights of joint j are seeded by (simulation.seed, j), whatever
    the bank it sits in.
    """
    if kind == "dnbs":
        cls, kernel = DNBSControllers, dnbs.kernel
        if kernel == "auto":
            from .accel.choice import auto_kernel
            kernel = auto_kernel().kernel
        if kernel == "c":  # the same step compiled (pa10_dnbs/accel): imported only when asked for
            from .accel.compiled_dnbs import CompiledDNBSControllers as cls
        return cls(_dnbs_params(dnbs, torque_limit_nm, run.dt_s, guards).select(rows), seed=run.seed, joints=rows)
    if kind == "pid":
        return PIDControllers(_pid_params(pid, torque_limit_nm, run.dt_s).select(rows))
    raise ValueError(f"unknown controller kind {kind!r} (expected one of {CONTROLLER_KINDS})")


def _reference(arm: Arm, r: ReferenceSettings, dt_s: float,
               trajectory: JointTrajectory | None) -> Reference | TrajectoryReference:
    eq27 = Reference(r.amplitude_rad, r.envelope_rate_per_s3, r.frequency_rad_s,
                     dt_s=dt_s, preview_steps=r.preview_steps, centre_rad=r.centre_rad)
    if trajectory is None:
        return eq27
    ref = TrajectoryReference(eq27, arm.joint_names, arm.lower_rad, arm.upper_rad)
    ref.start(trajectory, 0)
    return ref


def _guard(arm: Arm, g: GuardSettings, rows: list[int]) -> StateGuard:
    return StateGuard(lower_rad=np.array([arm.lower_rad[j] for j in rows]),
                      upper_rad=np.array([arm.upper_rad[j] for j in rows]),
                      margin_rad=g.position_margin_rad,
                      max_speed_rad_s=np.array([g.max_speed_rad_s[j] for j in rows]))


def _rows(settings: Settings, joints) -> list[int]:
    return list(range(settings.n_joints)) if joints is None else [int(j) for j in joints]


def dnbs_params(settings: Settings) -> DNBSParams:
    """Every joint's DNBS parameters (``.select(rows)`` gives a subset)."""
    return _dnbs_params(settings.dnbs, settings.plant.torque_limit_nm, settings.simulation.dt_s, settings.guards)


def build_controllers(settings: Settings, kind: str, joints=None) -> ControllerBank:
    """Controllers of joint indices ``joints`` (0..n-1; all of the arm's when None), one per row, in that order
    (the kernels and seeds of :func:`_bank`)."""
    s = settings  # only the kind's own section is read: a joint controller node's settings hold no other
    return _bank(kind, _rows(s, joints), s.simulation, s.plant.torque_limit_nm, s.guards,
                 s.dnbs if kind == "dnbs" else None, s.pid if kind == "pid" else None)


def build_reference(settings: Settings, trajectory: JointTrajectory | None = None) -> Reference | TrajectoryReference:
    """Eq. 27 reference from ``settings.reference``; with ``trajectory`` (a JointTrajectory file), that trajectory
    from step 0 on, starting from eq. 27's state at step 0 (TrajectoryError if the arm cannot follow it)."""
    return _reference(settings.arm, settings.reference, settings.simulation.dt_s, trajectory)


def load_reference_trajectory(settings: Settings, path) -> JointTrajectory:
    """The JointTrajectory of file ``path`` (YAML or JSON, docs/trajectories.md), checked against the settings'
    arm and interpolated once from step 0 (its quintics within the joint limits); ConfigError ``trajectory
    <path>: <what is wrong>`` (one line; setting ``trajectory``: the command line names its flag) otherwise."""
    traj = load_trajectory_file(Path(path), settings.arm)
    try:
        build_reference(settings, traj)
    except TrajectoryError as exc:
        raise ConfigError(f"trajectory {path}: {exc}", setting="trajectory") from None
    return traj


def switchable_reference(settings: Settings, reference: Reference | TrajectoryReference) -> TrajectoryReference:
    """``reference`` as a TrajectoryReference of the settings' arm (joint names and URDF limits), which takes
    trajectories while running (the reference node's ``trajectory`` topic); itself if it is one."""
    if isinstance(reference, TrajectoryReference):
        return reference
    arm = settings.arm
    return TrajectoryReference(reference, arm.joint_names, arm.lower_rad, arm.upper_rad)


def build_state_guard(settings: Settings, joints=None) -> StateGuard:
    """The state guard of joint indices ``joints`` (all when None): the arm's URDF limits and ``settings.guards``."""
    return _guard(settings.arm, settings.guards, _rows(settings, joints))


def build_guarded_controllers(settings: Settings, kind: str, joints=None) -> GuardedControllers:
    """What a joint runs, in a node or in-process: its controller behind its state guard."""
    return GuardedControllers(build_controllers(settings, kind, joints), build_state_guard(settings, joints),
                              settings.guards.on_bad_state)

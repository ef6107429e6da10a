"""What ``pa10-dnbs launch`` checks and resolves before any node starts (one line, exit 2 on bad input): the
settings (built once, the fault flags applied, the DNBS kernel resolved), the graph's options, and where the run's
record goes."""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from ..accel.choice import resolve_kernel
from ..bag.bag_writer import BagExistsError, check_bag_path
from ..config import ConfigError, default_config_path
from ..controller_factory import load_reference_trajectory
from ..core.checkpoint import checkpoint_dir, load_joint_checkpoints, network_degrees
from ..live.options import check_live_options
from ..loop.scheduling import granted_priority
from ..output_lock import lock_output
from ..report.metrics_file import metrics_settings
from ..report.outputs import check_output_dir
from ..run_settings import built_settings_held, say_rules
from ..run_size import check_run_size, say_note
from ..run_steps import run_duration, run_steps
from ..settings import Settings
from ..supervisor.domain_ids import shell_domain
from .fault_flags import apply_fault_flags, check_kill_times
from ..supervisor.graph_run import GraphOptions, loop_reliability, parse_netns
from ..supervisor.node_specs import reference_batch
from ..supervisor.plant_engine import plant_robot_options
from ..supervisor.rmw_check import check_rmw
from ..supervisor.robot_options import check_robot_options
from ..wire.clock_schedule import checked_clock_hz
from ..wire.topics import MAX_BATCH_STEPS, REFERENCE_DEPTH, check_joint_name, check_namespace, default_namespace
from .options import LaunchOptions


@dataclass(frozen=True)
class LaunchPlan:
    """A checked launch: the run's ``settings``, the graph's options ``opt``, ``n_steps`` steps of ``dt_s`` [s], the
    metrics window (``measured``), the QoS ``reliability``, and what the report names (config file, trajectory
    file, warm-start folder, bag, robot)."""

    settings: Settings
    opt: GraphOptions
    config_path: Path
    n_steps: int
    dt_s: float
    measured: dict
    reliability: str
    trajectory: Path | None
    init_from: Path | None
    record: Path | None
    robot: object | None
    own_robot: bool


def plan_launch(options: LaunchOptions) -> LaunchPlan:
    """Everything ``options`` asks for, checked against the settings before anything starts (ConfigError naming
    the flag): the duration against the step, the clock rate against dt, the trajectory file (read as the
    reference node will), the checkpoints of a warm start, the robot's topics, the output and the bag's path."""
    o = options
    check_rmw()   # every node would exit 102 (rcl) on an RMW this environment does not hold
    config_path = Path(o.config_path).resolve() if o.config_path else default_config_path()
    # the settings, built once: config file(s), arm file, rules (their table said once the inputs are accepted)
    settings, rules = built_settings_held(config_path, o.arm)
    the_arm = settings.arm
    joint_names = the_arm.joint_names
    for joint in joint_names:  # the graph names nodes and topics after the joints: checked before any node starts
        try:
            check_joint_name(joint)
        except ValueError as exc:
            raise ConfigError(f"--arm {the_arm.file or the_arm.name}: {exc}") from None
    namespace = default_namespace(the_arm.name) if o.namespace is None else o.namespace
    settings = apply_fault_flags(settings, o.faults)
    try:
        check_namespace(namespace)
    except ValueError as exc:
        raise ConfigError(f"--namespace: {exc}") from None
    namespaces = parse_netns(list(o.netns))
    duration_s, given = run_duration(o.duration_s, settings.simulation.duration_s, "--duration")
    own_robot = o.plant == "mujoco"
    robot = plant_robot_options(o.plant, o.robot, o.mode)
    robot_fields = check_robot_options(robot, o.mode, namespace) if robot is not None else {}
    if own_robot:
        robot_fields["plant_engine"] = "mujoco"
    domain_id = o.domain_id
    if robot is not None and domain_id is None and not own_robot:  # the robot is running: the graph joins its domain
        domain_id = shell_domain("the robot's domain")
    dt = settings.simulation.dt_s
    clock_hz = checked_clock_hz(o.clock_hz, dt, off_allowed=False)   # None: the default, which dt may not fit
    n_steps = run_steps(duration_s, dt, given)
    check_kill_times(settings.faults, joint_names, n_steps * dt, o.faults.kill)  # before any node starts
    check_run_size(duration_s, n_steps, len(joint_names), graph=True, say=say_note, setting=given,
                   wall_s=n_steps * dt / o.real_time_factor if o.mode == "realtime" else None)
    trajectory = None
    if o.trajectory is not None:  # the file read and checked as the reference node will: one line, exit 2
        load_reference_trajectory(settings, o.trajectory)
        trajectory = Path(o.trajectory).resolve()
    if o.live_port is not None:
        check_live_options(o.live_host, o.live_port, o.live_hz)
    init_from = None
    if o.init_from is not None:
        if o.controller != "dnbs":
            raise ConfigError("--init-from: only the DNBS controllers have learned state to start from")
        try:
            load_joint_checkpoints(o.init_from, joint_names, network_degrees(settings.dnbs))  # all there and readable, before anything starts
        except ValueError as exc:
            raise ConfigError(f"--init-from: {exc}") from None
        init_from = checkpoint_dir(o.init_from).resolve()
    out, force, controller, mode, record = o.out, o.force, o.controller, o.mode, o.record
    check_output_dir(out, force, "out", inputs={"config_path": config_path, "arm": the_arm.file,
                                                "arm URDF": the_arm.urdf, "trajectory": trajectory,
                                                "init_from": init_from, "record": record})
    rt_priority, refused = granted_priority(o.rt_priority)
    if refused:  # said once here, rather than by each of the ten nodes in its log
        print(f"launch: {refused}", flush=True)
    if record is not None:
        given, record = Path(record), Path(record).resolve()
        if record == Path(out).resolve() or Path(out).resolve() in record.parents:
            raise ConfigError(f"--record: the bag {record} must not be inside the output directory {out}")
        if not record.parent.is_dir():
            raise ConfigError(f"--record: {record.parent} is not a directory (the bag's folder must exist)")
        lock_output(record, "bag")
        # the rule of --out: never the current directory, its parents, the root, a link or one of the run's
        # inputs; --force replaces only an empty folder or a bag pa10-dnbs recorded (its OUTPUT_MARK)
        check_output_dir(given, force, "record", inputs={"config_path": config_path, "arm": the_arm.file,
                                                         "arm URDF": the_arm.urdf, "trajectory": trajectory,
                                                         "init_from": init_from})
        try:
            check_bag_path(record, force)
        except BagExistsError as exc:
            raise ConfigError(f"--record: {exc}") from None
    say_rules(rules)   # every input accepted: the rules' table, as a run without refusal always said it
    if controller == "dnbs":  # auto resolved (and c built) once here, before the joint controllers start; the
        # nodes read the resolved kernel from their params (ros_params.yaml) (KernelBuildError if c cannot be built)
        settings = resolve_kernel(settings, say=lambda line: print(f"launch: {line}", flush=True))
    opt = GraphOptions(config_path=config_path, mode=mode, controller=controller, duration_s=n_steps * dt,
                       domain_id=domain_id, reliability=o.reliability, effort_timeout_s=o.effort_timeout_s,
                       on_missing_effort=o.on_missing_effort, progress=o.progress, dt_s=dt, record_bag=record,
                       force_bag=force, restart=o.restart, netns=namespaces, init_from=init_from,
                       bag_compression=o.bag_compression, live_port=o.live_port, live_host=o.live_host,
                       live_hz=o.live_hz, real_time_factor=o.real_time_factor, deadline_fraction=o.deadline_fraction,
                       rt_priority=rt_priority, sched_batch=o.sched_batch, namespace=namespace,
                       clock_hz=clock_hz, joint_names=joint_names, trajectory_file=trajectory,
                       **robot_fields)
    if reference_batch(opt) > MAX_BATCH_STEPS:   # a /clock hours apart: its lookahead, in messages the node keeps
        slowest = 1.0 / (dt * (MAX_BATCH_STEPS * (REFERENCE_DEPTH - 2) - 50))
        raise ConfigError(f"clock_hz: {clock_hz:g} Hz is one /clock per {1.0 / (clock_hz * dt):,.0f} steps: the "
                          f"reference node would send {reference_batch(opt):,} points per message (at most "
                          f"{MAX_BATCH_STEPS:,}); give at least {slowest:.3g} Hz", setting="clock_hz")
    reliability = loop_reliability(opt)
    measured = metrics_settings(settings, n_steps * dt)
    return LaunchPlan(settings=settings, opt=opt, config_path=config_path, n_steps=n_steps, dt_s=dt,
                      measured=measured, reliability=reliability, trajectory=trajectory, init_from=init_from,
                      record=record, robot=robot, own_robot=own_robot)

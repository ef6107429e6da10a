"""``pa10-dnbs launch``: the ROS 2 node graph, with the same outputs as ``simulate``."""
from __future__ import annotations

import dataclasses
import shutil
import sys
from pathlib import Path

import yaml

from ..accel.choice import resolve_kernel
from .options import LaunchOptions
from ..bag.analysis import bag_arm, bag_joint_names, wire_record_from_bag
from ..bag.bag_reader import Bag, BagError
from ..bag.bag_writer import check_bag_path
from ..config import ConfigError, default_config_path
from ..controller_factory import load_reference_trajectory
from ..core.checkpoint import checkpoint_dir, load_joint_checkpoints
from ..interrupt import outputs_written
from ..supervisor.fault_flags import apply_fault_flags, faults_active, plain
from ..supervisor.fault_report import fault_note, fault_report
from ..supervisor.graph_run import GraphFailure, GraphOptions, loop_reliability, parse_netns, run_graph
from ..supervisor.params_file import write_params_file
from ..supervisor.realtime_advice import ON_TIME_TARGET, injected_misses, realtime_hint
from ..live.options import check_live_options
from ..loop.scheduling import granted_priority
from ..number_text import interval
from ..report.metrics_file import metrics_dict, metrics_settings
from ..report.outputs import atomic_output_dir, check_creatable, check_output_dir, write_report
from ..output_lock import lock_output
from ..run_settings import build_settings
from ..run_size import check_run_size, say_note
from ..wire.wire_record import load_wire_run
from ..wire.steps import StepClock
from ..wire.clock_schedule import DEFAULT_CLOCK_HZ, ClockSchedule, check_clock_hz
from ..wire.topics import CLOCK, ArmTopics, check_namespace, default_namespace
from ..supervisor.robot_options import check_robot_options, robot_domain
from ..supervisor.plant_engine import plant_robot_options



def run_launch(options: LaunchOptions) -> int:
    """Run the graph once (``options``, checked by the command line's parsing) and write metrics, figures and
    report into ``options.out``. Returns the exit code.

    The config the nodes run with (the fault flags applied) is written to ``out/config_used.yaml``, their
    parameters to ``out/ros_params.yaml``. What depends on the settings is checked here, before anything starts
    (one line, exit 2): the duration against the step, the clock rate against dt, the trajectory file (read as
    the reference node will), the checkpoints of a warm start, the robot's topics, the bag's path.
    """
    o = options
    config_path = Path(o.config_path).resolve() if o.config_path else default_config_path()
    settings = build_settings(config_path, o.arm)  # the settings, built once: config file(s), arm file, rules
    the_arm = settings.arm
    joint_names = the_arm.joint_names
    namespace = default_namespace(the_arm.name) if o.namespace is None else o.namespace
    settings = apply_fault_flags(settings, o.faults)
    try:
        check_namespace(namespace)
    except ValueError as exc:
        raise ConfigError(f"--namespace: {exc}") from None
    namespaces = parse_netns(list(o.netns))
    duration_s = settings.simulation.duration_s if o.duration_s is None else o.duration_s
    own_robot = o.plant == "mujoco"
    robot = plant_robot_options(o.plant, o.robot, o.mode)
    robot_fields = check_robot_options(robot, o.mode) if robot is not None else {}
    if own_robot:
        robot_fields["plant_engine"] = "mujoco"
    domain_id = o.domain_id
    if robot is not None and domain_id is None and not own_robot:  # the robot is running: the graph joins its domain
        domain_id = robot_domain()
    dt = settings.simulation.dt_s
    try:
        check_clock_hz(o.clock_hz, dt)
    except ValueError as exc:
        raise ConfigError(f"--clock-hz: {exc}") from None
    n_steps = int(round(duration_s / dt))
    if n_steps < 2:
        raise ConfigError(f"--duration: {duration_s} s is shorter than two steps of {dt} s")
    check_run_size(duration_s, n_steps, len(joint_names), graph=True, say=say_note,
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
            load_joint_checkpoints(o.init_from, joint_names)  # all there and readable, before anything starts
        except ValueError as exc:
            raise ConfigError(f"--init-from: {exc}") from None
        init_from = checkpoint_dir(o.init_from).resolve()
    out, force, controller, mode, record = o.out, o.force, o.controller, o.mode, o.record
    check_output_dir(out, force, "--out")
    rt_priority, refused = granted_priority(o.rt_priority)
    if refused:  # said once here, rather than by each of the ten nodes in its log
        print(f"launch: {refused}", flush=True)
    if record is not None:
        record = Path(record).resolve()
        if record == Path(out).resolve() or Path(out).resolve() in record.parents:
            raise ConfigError(f"--record: the bag {record} must not be inside the output directory {out}")
        if not record.parent.is_dir():
            raise ConfigError(f"--record: {record.parent} is not a directory (the bag's folder must exist)")
        check_creatable(record, "--record")
        lock_output(record, "bag")
        check_bag_path(record, force)
    if controller == "dnbs":  # auto resolved (and c built) once here, before the joint controllers start; the
        # nodes read the resolved kernel from config_used.yaml (KernelBuildError if c cannot be built)
        settings = resolve_kernel(settings, say=lambda line: print(f"launch: {line}", flush=True))
    opt = GraphOptions(config_path=config_path, mode=mode, controller=controller, duration_s=n_steps * dt,
                       domain_id=domain_id, reliability=o.reliability, effort_timeout_s=o.effort_timeout_s,
                       on_missing_effort=o.on_missing_effort, progress=o.progress, dt_s=dt, record_bag=record,
                       force_bag=force, restart=o.restart, netns=namespaces, init_from=init_from,
                       bag_compression=o.bag_compression, live_port=o.live_port, live_host=o.live_host,
                       live_hz=o.live_hz, real_time_factor=o.real_time_factor, deadline_fraction=o.deadline_fraction,
                       rt_priority=rt_priority, sched_batch=o.sched_batch, namespace=namespace,
                       clock_hz=o.clock_hz, joint_names=joint_names, trajectory_file=trajectory,
                       **robot_fields)
    reliability = loop_reliability(opt)
    measured = metrics_settings(settings, n_steps * dt)
    window = measured["window_s"]

    try:
        with atomic_output_dir(out, force) as tmp:
            try:
                used = tmp / "config_used.yaml"
                used.write_text(yaml.safe_dump(plain(settings.to_config()), sort_keys=False))
                ros_params = write_params_file(tmp / "ros_params.yaml", settings, controller, namespace)
                result = run_graph(dataclasses.replace(opt, config_path=used, params_file=ros_params), tmp,
                                   say=lambda s: print(s, flush=True),
                                   on_hard_stop=lambda: _hard_stop_cleanup(tmp, out))
                stats = result.stats
                if record is None:
                    run, missing = load_wire_run(result.wire_file, controller, joint_names,
                                                 settings.plant.torque_limit_nm, stats["wall_time_s"])
                    source = (f"the wire monitor's record of {ArmTopics(namespace).joint_states} "
                              "and the reference topics")
                else:
                    run, missing = _bag_run(record, dt, n_steps, controller, settings.plant.torque_limit_nm, stats["wall_time_s"],
                                            lockstep_stats=stats if mode == "lockstep" else None, clock_hz=o.clock_hz)
                    source = f"the bag's {ArmTopics(namespace).joint_states} and reference topics ({record})"
                if missing:
                    raise GraphFailure(f"the record of the run is incomplete: {missing}")
                metrics = metrics_dict(
                    run, measured, source="ros-graph", mode=mode, config_file=str(config_path),
                    seed=settings.simulation.seed, reliability=reliability, domain_id=result.domain_id,
                    wall_time_total_s=result.wall_total_s, limit_hits=stats["limit_hits"],
                    timing=timing_summary(stats, result.controllers, o.sched_batch),
                    node_exit_codes=result.exit_codes, bag=str(record) if record else None,
                    faults=fault_report(settings, stats, result),
                    **({"warm_start_from": str(init_from)} if init_from is not None else {}))
                notes = [f"config: `{config_path}`",
                         f"arm: {the_arm.name} ({the_arm.description}), `{the_arm.file}`",
                         f"source: ROS 2 node graph, {mode} mode, {reliability} QoS, domain {result.domain_id}; "
                         f"time series rebuilt from {source}",
                         _timing_note(stats)]
                if trajectory is not None:
                    notes.append(f"reference: the trajectory of `{trajectory}` from t = 0, not eq. 27 "
                                 "(docs/trajectories.md)")
                if own_robot:
                    notes.append("plant: the arm in MuJoCo (`pa10-dnbs robot --engine mujoco`) behind the joint bus, "
                                 "lockstep (docs/engines.md)")
                elif robot is not None:
                    notes.append(f"plant: an external robot behind the joint bus ({robot.command} commands; "
                                 "docs/your_robot.md)")
                if init_from is not None:
                    notes.append(f"DNBS warm-started from the checkpoints in `{init_from}` (not a cold start)")
                if faults_active(settings.faults) or result.restarts:
                    notes.append(fault_note(metrics["faults"]))
                elif mode == "lockstep" and (nondeterministic := _unforced_timeouts(stats, o.effort_timeout_s)):
                    notes.append(nondeterministic)
                    print(f"pa10-dnbs launch: warning: {nondeterministic}", file=sys.stderr, flush=True)
                if tuple(window) != tuple(settings.simulation.window_s):
                    notes.append(f"run shorter than the configured window {interval(settings.simulation.window_s)} s: "
                                 "metrics over the second half instead")
                write_report(tmp, [run], [metrics], title=f"{the_arm.description}: node graph run ({mode})",
                             notes=notes, chain=the_arm.chain, figures=o.figures)
            except GraphFailure as exc:
                raise _keep_logs(exc, tmp, Path(out)) from None
    except GraphFailure as exc:
        print(f"pa10-dnbs launch: FAILED: {exc}", file=sys.stderr, flush=True)
        if record is not None and (record / "metadata.yaml").is_file():
            print(f"pa10-dnbs launch: the bag recorded so far is closed and readable: {record}", file=sys.stderr)
        return 130 if exc.interrupted else 1
    outputs_written(f"pa10-dnbs: interrupted as it finished: {out} is written whole ({out}/report.md)")
    m = metrics
    print(f"{controller} ({mode}): worst-joint RMS error {m['worst_rms_error_rad']:.3e} rad over "
          f"{interval(m['window_s'])} s, "
          f"real-time factor {m['real_time_factor']:.2f}")
    if mode == "realtime":
        t = m["timing"]
        print(f"realtime --rtf {t['target_real_time_factor']:g}: every effort before the deadline on "
              f"{100 * t['on_time_fraction']:.2f} % of ticks, late tick starts {t['late_start_ticks']}")
        if t["on_time_fraction"] < ON_TIME_TARGET:
            print(realtime_hint(t["target_real_time_factor"], t["rt_priority_applied"], injected_misses(settings.faults)))
    if record is not None:
        size = sum(f.stat().st_size for f in record.iterdir())
        print(f"recorded {record} ({size / 1e6:.1f} MB, {size / 1e6 / (n_steps * dt):.2f} MB per simulated second, "
              f"compression {o.bag_compression})")
    print(f"wrote {out}/report.md")
    return 0 if m["all_finite"] and m["torques_within_limits"] else 1


def _hard_stop_cleanup(tmp: Path, out: Path) -> str:
    """A second Ctrl-C (supervisor/graph_run.py): the half-written output folder goes; what to add to the line."""
    shutil.rmtree(tmp, ignore_errors=True)
    return f"; nothing written to {out}"


def _keep_logs(exc: GraphFailure, tmp: Path, out: Path) -> GraphFailure:
    """A failed run's output folder (``tmp``) is removed, so its ``logs/`` move to ``<out>.failed/logs`` (replacing
    an earlier failure's) and the message names them there; an interrupted run (Ctrl-C) keeps nothing."""
    logs = tmp / "logs"
    if exc.interrupted or not logs.is_dir():
        return exc
    kept = out.parent / f"{out.name}.failed"
    shutil.rmtree(kept, ignore_errors=True)
    kept.mkdir(parents=True)
    shutil.move(str(logs), str(kept / "logs"))
    message = str(exc).replace(str(logs), str(kept / "logs"))
    return GraphFailure(f"{message}\nthe nodes' logs and command lines are kept in {kept / 'logs'}")


def _bag_run(bag_path: Path, dt: float, n_steps: int, controller: str, torque_limit_nm, wall_time_s: float,
             lockstep_stats: dict | None, clock_hz: float = DEFAULT_CLOCK_HZ):
    """(RunData, what is missing or None) rebuilt from the bag just recorded; a bad bag is a failed run.

    With ``lockstep_stats`` (the plant's stats of a lockstep run) every step 0..n_steps must be in the bag
    on the arm's joint_states and each joint's state topic, and on each effort topic except the steps the
    plant filled in after a timeout; /clock must hold the steps of ``ClockSchedule`` at ``clock_hz``. (Resent states and repeated answers add messages; none may be lost.)
    """
    clock = StepClock(dt)
    try:
        with Bag(bag_path) as bag:
            rec = wire_record_from_bag(bag, dt, n_steps)
            arm = bag_arm(bag)
            joint_names = bag_joint_names(bag, arm)
            steps = {}
            if lockstep_stats is not None:
                per_step = [CLOCK, arm.joint_states] + [t for j in joint_names for t in (arm.state(j), arm.effort(j))]
                steps = {t: set() for t in per_step}
                for topic, _, _, data in bag.messages([t for t in per_step if t in bag.topics]):
                    if len(data) >= 12:
                        steps[topic].add(clock.step_of_cdr(data))
    except BagError as exc:
        raise GraphFailure(f"the recorded bag is not readable: {exc}") from None
    problems = [rec.missing()] if rec.missing() else []
    if rec.malformed:
        problems.append(f"{rec.malformed} undecodable messages")
    everything = set(range(n_steps + 1))
    for topic, seen in steps.items():
        expected = everything
        if topic == CLOCK:
            expected = ClockSchedule.steps(clock_hz, dt, n_steps)
        elif topic.endswith("/effort"):
            joint = joint_names.index(topic.split("/")[-2])
            filled = {k for a, b in lockstep_stats["joints"][joint]["timeout_ranges"] for k in range(a, b + 1)}
            expected = everything - filled - {n_steps}  # the answer to the last state may come after the end
        lost = expected - seen
        if lost:
            problems.append(f"{topic} lacks {len(lost)} steps (first {min(lost)})")
    run = rec.run_data(controller, joint_names, torque_limit_nm, wall_time_s)
    return run, "; ".join(problems) or None


def _unforced_timeouts(stats: dict, effort_timeout_s: float) -> str | None:
    """What to say when a lockstep run without injected faults stepped past a missing effort, else None."""
    joints = [(j["name"], j["effort_timeouts"]) for j in stats["joints"] if j["effort_timeouts"]]
    if not joints:
        return None
    return (f"the plant stepped without an answer {sum(n for _, n in joints)} times "
            f"({', '.join(f'{name}: {n}' for name, n in joints)}; --effort-timeout {effort_timeout_s:g} s of wall "
            "time): no fault was injected, so a node stalled (a loaded machine?) and this lockstep run is not "
            "the in-process run bit for bit")


TIMING_KEYS = ("on_time_fraction", "late_start_ticks", "max_start_lateness_us", "target_real_time_factor",
               "real_time_factor", "tick_period_s", "deadline_fraction", "reliability", "state_qos_depth",
               "effort_qos_depth", "effort_timeout_s", "on_missing_effort", "rt_priority", "rt_priority_applied",
               "cpu", "effort_waits_per_step", "effort_wakeups_per_step", "on_time_fraction_per_bin")


def timing_summary(stats: dict, controllers: dict, sched_batch: bool) -> dict:
    """The timing part of metrics.json: the plant's pacing figures and, per joint, misses and latency; whether
    the nodes were asked for SCHED_BATCH and the policies the controllers ended with (their stats files)."""
    policies = sorted({c["sched_policy"] for c in controllers.values() if c and "sched_policy" in c})
    return ({k: stats.get(k) for k in TIMING_KEYS}
            | {"sched_batch": sched_batch, "controller_sched_policies": policies, "joints": stats["joints"]})


def _timing_note(stats: dict) -> str:
    j = stats["joints"]
    med = max(x["latency_median_us"] or 0 for x in j)
    p99 = max(x["latency_p99_us"] or 0 for x in j)
    s = (f"plant: {stats['steps']} steps, real-time factor {stats['real_time_factor']:.2f}; state-to-effort latency "
         f"p50 up to {med:.0f} us, p99 up to {p99:.0f} us; effort timeouts "
         f"{sum(x['effort_timeouts'] for x in j)}")
    if stats["mode"] == "realtime":
        s += (f"; target real-time factor {stats['target_real_time_factor']:g} (tick {1e3 * stats['tick_period_s']:.2f}"
              f" ms, deadline {100 * stats['deadline_fraction']:.0f} %); ticks with every effort on time "
              f"{100 * stats['on_time_fraction']:.2f} %, late tick starts {stats['late_start_ticks']}, missed ticks "
              "per joint " + ", ".join(f"{x['name']} {x['missed_ticks']}" for x in j))
    return s

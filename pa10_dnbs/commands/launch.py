"""``pa10-dnbs launch``: the ROS 2 node graph, with the same outputs as ``simulate``."""
from __future__ import annotations

import contextlib
import dataclasses
import shutil
import tempfile
import sys
from pathlib import Path

import yaml

from ..atomic_file import mkdir_mode
from ..config_error import said_as
from ..interrupt import deferred, on_second_sigint, outputs_written
from ..number_text import interval
from ..report.metrics_file import diverged_text, metrics_dict, run_ok
from ..report.outputs import atomic_output_dir, write_report
from ..config_yaml import dumpable
from ..setting_flags import SETTING_FLAGS
from ..supervisor.fault_report import fault_report
from ..supervisor.graph_run import GraphFailure, run_graph
from ..supervisor.params_file import write_params_file
from ..supervisor.processes import move_commands
from ..supervisor.realtime_advice import ON_TIME_TARGET, injected_misses, realtime_hint
from ..wire.topics import ArmTopics
from ..wire.wire_record import load_wire_run
from .launch_plan import plan_launch
from .launch_record import bag_run, bag_stamp, failed_run_bag_note
from .launch_report import report_notes, second_effort_publishers, timing_summary
from .options import LaunchOptions



def run_launch(options: LaunchOptions) -> int:
    """Run the graph once (``options``, checked by the command line's parsing) and write metrics, figures and
    report into ``options.out``. Returns the exit code.

    In order: the plan (``launch_plan.py``: everything checked before a node starts, one line and exit 2 on bad
    input); the config the nodes run with (the fault flags applied) written to ``out/config_used.yaml`` and
    their parameters to ``out/ros_params.yaml``; the graph run (``supervisor/``); the time series rebuilt from
    the wire monitor's record or the bag (``launch_record.py``); the report (``launch_report.py``).
    """
    o = options
    plan = plan_launch(o)
    settings, opt, config_path, dt, n_steps = plan.settings, plan.opt, plan.config_path, plan.dt_s, plan.n_steps
    the_arm, namespace, controller, mode, out = settings.arm, opt.namespace, o.controller, o.mode, o.out
    joint_names, record, init_from = the_arm.joint_names, plan.record, plan.init_from
    bag_before = bag_stamp(record)   # an earlier run's bag that --force is to replace, if any

    try:
        with _finished(out, record), atomic_output_dir(out, o.force) as tmp:
            try:
                used = tmp / "config_used.yaml"
                used.write_text(yaml.safe_dump(dumpable(settings.to_config()), sort_keys=False))
                ros_params = write_params_file(tmp / "ros_params.yaml", settings, controller, namespace)
                result = run_graph(dataclasses.replace(opt, config_path=used, params_file=ros_params,
                                                       recorded_config=str(Path(out).absolute() / used.name)), tmp,
                                   say=lambda s: print(s, flush=True),
                                   on_hard_stop=lambda: _hard_stop_cleanup(tmp, out))
                on_second_sigint(_second_stop_line(out, record), cleanup=lambda: shutil.rmtree(tmp, ignore_errors=True))
                stats = result.stats
                if record is None:
                    run, missing = load_wire_run(result.wire_file, controller, joint_names,
                                                 settings.plant.torque_limit_nm, stats["wall_time_s"])
                    source = (f"the wire monitor's record of {ArmTopics(namespace).joint_states} "
                              "and the reference topics")
                else:
                    run, missing = bag_run(record, dt, n_steps, controller, settings.plant.torque_limit_nm,
                                           stats["wall_time_s"], lockstep_stats=stats if mode == "lockstep" else None,
                                           clock_hz=opt.clock_hz)
                    source = f"the bag's {ArmTopics(namespace).joint_states} and reference topics ({record})"
                if missing:
                    raise GraphFailure(f"the record of the run is incomplete: {missing}")
                metrics = metrics_dict(
                    run, plan.measured, source="ros-graph", mode=mode, config_file=str(config_path),
                    seed=settings.simulation.seed, reliability=plan.reliability, domain_id=result.domain_id,
                    wall_time_total_s=result.wall_total_s, limit_hits=stats["limit_hits"],
                    timing=timing_summary(stats, result.controllers, o.sched_batch),
                    node_exit_codes=result.exit_codes, bag=str(record) if record else None,
                    faults=fault_report(settings, stats, result),
                    trajectories_received=result.reference,
                    **({"warm_start_from": str(init_from)} if init_from is not None else {}))
                notes = report_notes(plan, o, stats, result, source, metrics)
                write_report(tmp, [run], [metrics], title=f"{the_arm.description}: node graph run ({mode})",
                             notes=notes, chain=the_arm.chain, figures=o.figures)
                move_commands(tmp / "logs", tmp, Path(out))   # its lines as run from the finished folder
            except GraphFailure as exc:
                raise _keep_logs(exc, tmp, Path(out)) from None
    except GraphFailure as exc:
        print(f"pa10-dnbs launch: FAILED: {said_as(str(exc), SETTING_FLAGS)}", file=sys.stderr, flush=True)
        note = failed_run_bag_note(record, bag_before)
        if note is not None:
            print(f"pa10-dnbs launch: {note}", file=sys.stderr)
        return 130 if exc.interrupted else 1
    m = metrics
    print(f"{controller} ({mode}): worst-joint RMS error {m['worst_rms_error_rad']:.3e} rad over "
          f"{interval(m['window_s'])} s, "
          f"real-time factor {m['real_time_factor']:.2f}")
    if mode == "realtime" and m["timing"].get("paced_by") == "robot":
        print(f"realtime, paced by the robot: every effort before the robot's next state on "
              f"{100 * m['timing']['on_time_fraction']:.2f} % of its states")
    elif mode == "realtime":
        t = m["timing"]
        print(f"realtime --rtf {t['target_real_time_factor']:g}: every effort before the deadline on "
              f"{100 * t['on_time_fraction']:.2f} % of ticks, late tick starts {t['late_start_ticks']}")
        if t["on_time_fraction"] < ON_TIME_TARGET:
            hint = realtime_hint(t["target_real_time_factor"], t["rt_priority_applied"], injected_misses(settings.faults))
            print(said_as(hint, SETTING_FLAGS))
    if record is not None:
        size = sum(f.stat().st_size for f in record.iterdir())
        print(f"recorded {record} ({size / 1e6:.1f} MB, {size / 1e6 / (n_steps * dt):.2f} MB per simulated second, "
              f"compression {o.bag_compression})")
    print(f"wrote {out}/report.md")
    if m.get("diverged"):
        print(f"DIVERGED: {diverged_text(m)}")
    rivals = second_effort_publishers(stats, result.restarts)  # the report and a warning said which (exit 1)
    return 0 if run_ok(m) and rivals is None else 1


@contextlib.contextmanager
def _finished(out: Path, record: Path | None):
    """Around the run and its outputs: once the graph has stopped (run_graph's own handlers gone), a Ctrl-C is
    noted, the outputs are finished and put in place, then it ends the command with the line that says so (130),
    as ``simulate`` does (report/outputs.py, finished_output_dir). A ``--record`` bag is whole by then: the
    outputs thrown away said "run the same command again", which the bag then refused (it exists; --force)."""
    with deferred():   # a Ctrl-C before the graph's handlers are set: run_graph stops at once (interrupt.take_noted)
        yield
        outputs_written(f"pa10-dnbs: interrupted as it finished: {out} is written whole ({out}/report.md)"
                        + (f"; the bag {record} is whole" if record is not None else ""))


def _second_stop_line(out: Path, record: Path | None) -> str:
    """The line of a second Ctrl-C while the outputs of a finished run are written (the first let them be)."""
    line = f"pa10-dnbs launch: interrupted again: stopped at once; nothing written to {out}"
    if record is not None:   # the recorder closed it before the graph stopped
        line += (f"; the bag {record} is whole (`pa10-dnbs analyse {record} --out DIR` makes the report from it; "
                 "a new run into it needs --force)")
    return line


def _hard_stop_cleanup(tmp: Path, out: Path) -> str:
    """A second Ctrl-C (supervisor/graph_run.py): the half-written output folder goes; what to add to the line."""
    shutil.rmtree(tmp, ignore_errors=True)
    return f"; nothing written to {out}"


#: the file that marks ``<out>.failed`` as a failed launch's kept logs (only such a folder is ever replaced)
FAILED_MARK = ".pa10-dnbs-failed-launch"


#: what the nodes' command lines read (their config and params) and the folder they write checkpoints in, kept
#: with a failed run's logs
PARAM_FILES = ("config_used.yaml", "ros_params.yaml", "checkpoints")


def _keep_logs(exc: GraphFailure, tmp: Path, out: Path) -> GraphFailure:
    """A failed run's output folder (``tmp``) is removed, so its ``logs/`` move to ``<out>.failed/logs`` (replacing
    an earlier failure's, known by its FAILED_MARK; anything else there is left alone and the logs go to a fresh
    ``<out>.failed-XXXX``), with the PARAM_FILES beside them that logs/commands.sh reads there, and the message
    names them there; an interrupted run (Ctrl-C) keeps nothing."""
    logs = tmp / "logs"
    if exc.interrupted or not logs.is_dir():
        return exc
    try:
        kept = out.parent / f"{out.name}.failed"
        if (kept / FAILED_MARK).is_file():
            shutil.rmtree(kept)
        if kept.exists() or kept.is_symlink():   # not ours: a user's file or folder
            kept = Path(tempfile.mkdtemp(prefix=f"{out.name}.failed-", dir=out.parent))
            mkdir_mode(kept)
        else:
            kept.mkdir(parents=True)
        (kept / FAILED_MARK).write_text(f"the logs of a failed pa10-dnbs launch into {out}\n")
        for name in PARAM_FILES:   # what the lines of logs/commands.sh read and write in: kept beside them
            if (tmp / name).exists():
                shutil.move(str(tmp / name), str(kept / name))
        shutil.move(str(logs), str(kept / "logs"))
        move_commands(kept / "logs", tmp, kept)
    except OSError as why:   # the failure's own line comes first, whatever happens to its logs
        return GraphFailure(f"{exc}\n(its nodes' logs could not be kept: {why})")
    message = str(exc).replace(str(logs), str(kept / "logs"))
    return GraphFailure(f"{message}\nthe nodes' logs and command lines are kept in {kept / 'logs'}")

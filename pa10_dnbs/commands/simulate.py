"""``pa10-dnbs simulate``: in-process closed loop, metrics, figures and report."""
from __future__ import annotations

import shutil
from pathlib import Path

from ..accel.choice import resolve_kernel
from .options import SimulateOptions
from ..config import ConfigError, default_config_path
from ..core.joint_trajectory import TrajectoryError
from ..core.checkpoint import load_joint_checkpoints, network_degrees, save_checkpoint
from ..interrupt import AFTER_LINE, EXIT_INTERRUPTED, on_second_sigint, outputs_written, say
from ..number_text import interval
from ..report.markdown import report_markdown
from ..report.metrics_file import diverged_text, guard_text, metrics_dict, metrics_settings, run_ok
from ..report.outputs import atomic_output_dir, check_output_dir, finished_output_dir, write_report, write_run
from ..report.partial import partial_banner, write_partial_mark
from ..run_settings import built_settings_held, say_rules
from ..run_size import check_run_size, say_note
from ..run_steps import run_duration, run_steps
from ..sim.closed_loop import simulate
from .fault_flags import IN_PROCESS_FAULTS_NOTE, faults_active
from ..trajectory_file import load_trajectory_file

CHOICES = {"dnbs": ("dnbs",), "pid": ("pid",), "ctc": ("ctc",), "both": ("dnbs", "pid"), "all": ("dnbs", "pid", "ctc")}


def run_simulate(options: SimulateOptions) -> int:
    """Run one or more controllers (``options``, checked by the command line's parsing); write everything into
    ``options.out`` atomically. Returns the exit code.

    A bad trajectory file or one the arm cannot follow, or checkpoints that do not fit: ConfigError, nothing
    written. The report says what the run was (a trajectory instead of eq. 27, a warm start, the engine).
    """
    o = options
    config_path = Path(o.config_path) if o.config_path else default_config_path()
    # the settings, built once: config file(s), arm file, rules (their table said once the inputs are accepted)
    settings, rules = built_settings_held(config_path, o.arm)
    the_arm = settings.arm
    duration_s, given = run_duration(o.duration_s, settings.simulation.duration_s)   # --duration, or the config's
    n_steps = run_steps(duration_s, settings.simulation.dt_s, given)
    duration_s = n_steps * settings.simulation.dt_s
    kinds = CHOICES[o.controller]
    traj = load_trajectory_file(Path(o.trajectory), the_arm) if o.trajectory is not None else None  # its quintics: the run's
    check_run_size(duration_s, n_steps, len(the_arm.joint_names), kept_runs=len(kinds),
                   total_runs=len(kinds), say=say_note, setting=given)
    if faults_active(settings.faults):
        say_note(IN_PROCESS_FAULTS_NOTE)
    init_states = None
    if o.init_from is not None:
        if "dnbs" not in kinds:
            raise ConfigError("--init-from: only the DNBS controllers have learned state to start from")
        try:
            init_states = load_joint_checkpoints(o.init_from, the_arm.joint_names, network_degrees(settings.dnbs))
        except ValueError as exc:
            raise ConfigError(f"--init-from: {exc}") from None
    check_output_dir(o.out, o.force, "out", inputs={"config_path": config_path, "arm": the_arm.file,
                                                    "arm URDF": the_arm.urdf, "trajectory": o.trajectory,
                                                    "init_from": o.init_from})
    say_rules(rules)
    if "dnbs" in kinds:
        settings = resolve_kernel(settings, say=print)  # dnbs.kernel: auto -> c or numpy, said in one line
    measured = metrics_settings(settings, duration_s)
    runs, metrics = [], []
    try:
        for kind in kinds:
            try:
                run = simulate(settings, kind, duration_s, progress=o.progress,
                               init_states=init_states if kind == "dnbs" else None, engine=o.engine, trajectory=traj)
            except TrajectoryError as exc:  # the arm cannot follow the file's quintics: before any run, nothing written
                raise ConfigError(f"trajectory {o.trajectory}: {exc}", setting="trajectory") from None
            extra = ({"warm_start_from": str(Path(o.init_from).resolve())}
                     if init_states is not None and kind == "dnbs" else {})
            if o.engine != "pybullet":
                extra["engine"] = o.engine
            metrics.append(metrics_dict(run, measured, source="in-process", config_file=str(config_path.resolve()),
                                        seed=settings.simulation.seed, limit_hits=run.extra["limit_hits"], **extra))
            runs.append(run)
            print(_summary_line(metrics[-1]), flush=True)   # as each controller finishes
    except KeyboardInterrupt:
        del metrics[len(runs):]   # a controller interrupted between its metrics and its run
        if not runs:
            say(f"pa10-dnbs: interrupted during the {kinds[0]} run (0 of {len(kinds)} controllers finished); "
                f"nothing written to {o.out}: run the same command again")
            return EXIT_INTERRUPTED
        if len(runs) < len(kinds):
            return _keep_partial(o.out, o.force, runs, metrics, kinds, the_arm, n_steps, o.controller, duration_s)
        # every run had finished: the whole output is written below, as without the Ctrl-C
    notes = [f"config: `{config_path}`", f"arm: {the_arm.name} ({the_arm.description}), `{the_arm.file}`",
             "source: in-process simulation (no ROS)"]
    if o.engine != "pybullet":
        notes.append(f"engine: {o.engine} (docs/engines.md); the gains are the same as on the PyBullet plant")
    if faults_active(settings.faults):
        notes.append(IN_PROCESS_FAULTS_NOTE)
    if traj is not None:
        notes.append(f"reference: the trajectory of `{o.trajectory}` from t = 0, not eq. 27 (docs/trajectories.md)")
    if init_states is not None:
        notes.append(f"DNBS warm-started from the checkpoints in `{o.init_from}` (not a cold start)")
    if "ctc" in kinds:
        notes.append("CTC: centralized computed torque with the plant's own model (the reference a decentralized "
                     "controller is compared to; in-process only)")
    if tuple(measured["window_s"]) != tuple(settings.simulation.window_s):
        notes.append(f"run shorter than the configured window {interval(settings.simulation.window_s)} s: "
                     f"metrics over the second half instead")
    with finished_output_dir(o.out, o.force, "report.md") as tmp:   # a Ctrl-C now: finished first, then said
        write_report(tmp, runs, metrics, title=f"{the_arm.description}: closed-loop run", notes=notes,
                     chain=the_arm.chain, figures=o.figures)
        for run in runs:
            if run.controller == "dnbs":
                _save_checkpoints(tmp / "checkpoints" if len(runs) == 1 else tmp / "dnbs" / "checkpoints",
                                  run.extra["controllers"], n_steps - 1, the_arm.joint_names)
    print(f"wrote {o.out}/report.md")
    return 0 if all(run_ok(m) for m in metrics) else 1


def _save_checkpoints(directory: Path, controllers, last_step: int, joint_names: tuple[str, ...]) -> None:
    """One ``<joint>.npz`` per joint, as the graph's controllers write them (``--init-from`` reads either)."""
    directory.mkdir(parents=True, exist_ok=True)
    for row, joint in enumerate(controllers.joints):
        save_checkpoint(directory / f"{joint_names[joint]}.npz", controllers.state_dict(row), last_step)


def _summary_line(m: dict) -> str:
    """One controller's result in a line (printed as it finishes)."""
    settle = m["worst_settling_time_s"]
    return (f"{m['controller']}: worst-joint RMS error {m['worst_rms_error_rad']:.3e} rad over "
            f"{interval(m['window_s'])} s; "
            f"settled (|e| < {m['settle_band_rad']:g} rad) "
            + (f"after {settle:.3f} s" if settle is not None else "never")
            + f"; max |e| {m['worst_max_abs_error_run_rad']:.4f} rad; torque variation "
            f"{m['worst_torque_variation']:.2f}; {m['real_time_factor']:.1f}x real time"
            + (f"; DIVERGED: {diverged_text(m)}" if m.get("diverged") else "")
            + (f"; guards acted: {guard_text(m)}" if m.get("guard_counters") else ""))


def _keep_partial(out: Path, force: bool, runs, metrics: list[dict], kinds: tuple[str, ...], the_arm, n_steps: int,
                  controller: str, duration_s: float) -> int:
    """After a Ctrl-C with some controllers finished: their folders (data and metrics, no figures) and a report
    marked partial naming the controllers not complete (report/partial.py), into ``out``; one line; 130.
    A second Ctrl-C meanwhile removes the half-written folder and ends at once."""
    missing = list(kinds[len(runs):])
    command = f"pa10-dnbs simulate --controller {controller} --duration {duration_s:g} --out {out}"
    with atomic_output_dir(out, force) as tmp:
        on_second_sigint(f"pa10-dnbs: interrupted again: stopped at once; nothing written to {out}",
                         cleanup=lambda: shutil.rmtree(tmp, ignore_errors=True))
        for run, m in zip(runs, metrics):
            write_run(tmp / run.controller, run, m, figures=False)
            if run.controller == "dnbs":
                _save_checkpoints(tmp / "dnbs" / "checkpoints", run.extra["controllers"], n_steps - 1,
                                  the_arm.joint_names)
        title = f"{the_arm.description}: closed-loop run, PARTIAL (interrupted)"
        notes = [f"not complete (stopped or never started): {', '.join(missing)}",
                 "figures not drawn (an interrupted run)"]
        text = report_markdown(metrics, [], title, notes)
        banner = partial_banner(len(runs), len(kinds), "controllers")
        (tmp / "report.md").write_text(text.replace(f"# {title}\n\n", f"# {title}\n\n{banner}\n\n", 1))
        write_partial_mark(tmp, command, len(runs), len(kinds), missing)
    line = (f"pa10-dnbs: interrupted during the {missing[0]} run; kept the {len(runs)} finished of {len(kinds)} "
            f"controllers ({', '.join(r.controller for r in runs)}) in {out}/report.md, marked partial (not complete: "
            f"{', '.join(missing)}): rerun with --force for the whole comparison")
    outputs_written(line)   # a Ctrl-C from here says this line, not "nothing written"
    say(line)
    outputs_written(AFTER_LINE)
    return EXIT_INTERRUPTED

"""``pa10-dnbs study``: every scenario x controller x seed in parallel, study.json / study.md / study.png."""
from __future__ import annotations

import os
import shlex
import shutil
from itertools import product
from pathlib import Path

from ..accel.choice import resolve_kernel
from .options import StudyOptions
from ..config import ConfigError, default_config_path
from ..json_text import json_text
from ..interrupt import AFTER_LINE, EXIT_INTERRUPTED, on_second_sigint, outputs_written, say
from ..report.outputs import atomic_output_dir, check_output_dir, finished_output_dir
from ..report.progress import ProgressBar
from ..run_settings import built_settings_held, say_rules
from ..run_steps import run_duration, run_steps
from ..run_size import check_run_size, say_note
from ..setting_flags import SETTING_FLAGS
from .fault_flags import IN_PROCESS_FAULTS_NOTE, faults_active
from ..sim.closed_loop import CONTROLLERS
from ..study.feasibility import infeasible_scenarios
from ..study.lost_runs import RunsLost
from ..study.partial_summary import write_partial_study
from ..study.runner import run_study
from ..study.scenarios import SCENARIOS, check_scenario_references
from .name_list import name_list
from ..study.summary import study_figure, study_markdown


def run_study_command(options: StudyOptions) -> int:
    """Run the study of ``options`` (its values checked by the command line's parsing) on its arm and write its
    outputs in ``options.out``."""
    o = options
    scen = name_list("--scenarios", o.scenarios, list(SCENARIOS))
    ctrl = name_list("--controllers", o.controllers, CONTROLLERS)
    config_path = Path(o.config_path) if o.config_path else default_config_path()
    # the settings, built once: config file(s), arm file, rules (their table said once the inputs are accepted)
    settings, rules = built_settings_held(config_path, o.arm)
    duration_s, given = run_duration(o.duration_s, settings.simulation.duration_s)   # --duration, or the config's
    n_runs, n_steps = len(scen) * len(ctrl) * o.seeds, run_steps(duration_s, settings.simulation.dt_s, given)
    at_once = 1 if o.scheduler is not None else min(n_runs, o.jobs or os.cpu_count() or 1)
    check_run_size(duration_s, n_steps, settings.n_joints, at_once=at_once,
                   total_runs=n_runs, say=say_note, setting=given)
    if faults_active(settings.faults):
        say_note(IN_PROCESS_FAULTS_NOTE)
    check_output_dir(o.out, o.force, "out", inputs={"config_path": config_path, "arm": settings.arm.file,
                                                    "arm URDF": settings.arm.urdf})
    check_scenario_references(settings, scen)   # a reference past the Nyquist rate: one line, nothing runs
    infeasible = infeasible_scenarios(settings, scen, duration_s)   # before any run: one line each, not run
    if len(infeasible) < len(scen):
        say_rules(rules)
    for line in infeasible.values():
        print(f"study: {line}")
    if len(infeasible) == len(scen):
        raise ConfigError(f"--scenarios: every scenario chosen is infeasible on arm {settings.arm.file} (lines above): "
                          "nothing to run")
    asked, scen = scen, [s for s in scen if s not in infeasible]
    if "dnbs" in ctrl and o.scheduler is None:   # on a cluster each worker resolves `auto` (the same bits): a
        settings = resolve_kernel(settings, say=print)  # worker without a compiler takes numpy; here: once, not in
        # each local worker
    n = len(scen) * len(ctrl) * o.seeds
    dt = settings.simulation.dt_s
    steps_per_run = n_steps
    bar = ProgressBar(n * steps_per_run, dt, f"study ({n} runs)", enabled=None if o.progress else False)
    done = []

    def finished(row: dict) -> None:  # simulated time of the finished runs, worst |e| among them
        done.append(row)
        bar.update(len(done) * steps_per_run, row["worst_max_abs_error_run_rad"])

    command = (f"pa10-dnbs study --scenarios {','.join(asked)} --controllers {','.join(ctrl)} --seeds {o.seeds} "
               f"--duration {duration_s:g} --out {shlex.quote(str(o.out))}"
               + (f" --config {shlex.quote(str(config_path))}" if config_path != default_config_path() else "")
               + (f" --arm {shlex.quote(str(o.arm))}" if o.arm is not None else ""))
    head = {"config_file": str(config_path.resolve()), "arm": str(settings.arm.file), "duration_s": duration_s,
            **({"infeasible": infeasible} if infeasible else {})}
    all_runs = list(product(scen, ctrl, range(o.seeds)))
    try:
        rows = run_study(settings, scen, ctrl, o.seeds, duration_s, o.jobs, on_done=finished, scheduler=o.scheduler)
    except KeyboardInterrupt:   # the workers are stopped (study/executor.py); the completed runs are kept
        bar.close()
        rows = _every_run(done, all_runs)
        if rows is None:
            return _keep_partial(o.out, o.force, done, all_runs, command, head)
        # the stop came after the last run's result, before the study returned: the study is whole
        _write_study(o.out, o.force, rows, command, head, duration_s, infeasible)
        say(f"pa10-dnbs: interrupted as it finished: {o.out} is written whole ({o.out}/study.md)")
        outputs_written(AFTER_LINE)
        return EXIT_INTERRUPTED
    except RunsLost as exc:   # a worker or the cluster lost: the completed runs are kept as for a Ctrl-C
        bar.close()
        return _keep_partial(o.out, o.force, done, all_runs, command, head, lost=exc)
    bar.close()
    _write_study(o.out, o.force, rows, command, head, duration_s, infeasible)
    diverged = sum(r["diverged"] for r in rows)
    guarded = sum(r.get("guard_events", 0) > 0 for r in rows)
    print(f"{n} runs, {diverged} diverged"
          + (f"; {guarded} with guard events (states refused, torques replaced or EKF resets: study.json's "
             "guard_events)" if guarded else "")
          + (f"; {len(infeasible)} scenario(s) infeasible on this arm, not run" if infeasible else "")
          + f"; wrote {o.out}/study.md")
    return 0


def _every_run(done: list[dict], all_runs: list) -> list[dict] | None:
    """The rows of ``done`` in the order of ``all_runs`` ((scenario, controller, seed) each), as run_study returns
    them, when every run is there; else None."""
    by_key = {(r["scenario"], r["controller"], r["seed"]): r for r in done}
    return [by_key[k] for k in all_runs] if all(k in by_key for k in all_runs) else None


def _write_study(out: Path, force: bool, rows: list[dict], command: str, head: dict, duration_s: float,
                 infeasible: dict) -> None:
    """The whole study into ``out``: study.json, study.md, study.png (a Ctrl-C meanwhile: finished first, then
    said)."""
    with finished_output_dir(out, force, "study.md") as tmp:
        (tmp / "study.json").write_text(json_text({**head, "rows": rows}))
        (tmp / "study.md").write_text(study_markdown(rows, command, duration_s,
                                                     {k: v.description for k, v in SCENARIOS.items()}, infeasible))
        study_figure(rows, tmp / "study.png")


def _keep_partial(out: Path, force: bool, done: list[dict], all_runs: list, command: str, head: dict,
                  lost: RunsLost | None = None) -> int:
    """After a Ctrl-C (or with ``lost``, a local worker process or the Dask cluster lost mid-study): the completed
    runs' rows into ``out``, marked partial (study/partial_summary.py); one line saying what is where; exit 130
    (lost: its line naming --jobs or --scheduler, exit 2, as an unreachable scheduler). Nothing completed:
    nothing written. A second Ctrl-C meanwhile removes the half-written folder and ends at once."""
    n = len(all_runs)
    kept = len({(r["scenario"], r["controller"], r["seed"]) for r in done})
    opening = (f"pa10-dnbs: error: {lost.named(SETTING_FLAGS)}; stopped " if lost is not None
               else "pa10-dnbs: interrupted ")
    code = 2 if lost is not None else EXIT_INTERRUPTED
    if not kept:
        say(f"{opening}after 0 of {n} runs; nothing written to {out}: run the same command again")
        return code
    with atomic_output_dir(out, force) as tmp:
        on_second_sigint(f"pa10-dnbs: interrupted again: stopped at once; nothing written to {out}",
                         cleanup=lambda: shutil.rmtree(tmp, ignore_errors=True))
        write_partial_study(tmp, done, all_runs, command, head)
    line = (f"{opening}after {kept} of {n} runs; kept their rows in {out}/study.partial.md (and "
            ".json), marked partial: rerun with --force for the whole study")
    outputs_written(line)   # a Ctrl-C from here says this line, not "nothing written"
    say(line)
    outputs_written(AFTER_LINE)
    return code

"""``pa10-dnbs tune``: search a controller's settings on an arm with Optuna (docs/tuning.md).

Everything is checked before anything is written (bad input: exit 2, one line): the controller, the
parameters, scenarios and numbers, the arm and config, the storage URL, the scheduler. Then DIR holds the
study's storage (``tune.db``, unless ``--storage``), and, once the trials are done, tuned.yaml, tune.md,
tune.json and the figures. Ctrl-C keeps every completed trial and says how many, where; the same command
resumes (a second Ctrl-C ends at once: pa10_dnbs/interrupt.py).
"""
from __future__ import annotations

import os
import shlex
import sys
import time
from pathlib import Path

from ..arm import load_arm, preset_names
from ..atomic_file import atomic_path
from ..config import ConfigError, default_config_path
from .options import TuneOptions
from ..json_text import json_text
from ..interrupt import EXIT_INTERRUPTED, check, deferred, immediate, on_second_sigint, say
from ..output_lock import lock_key, lock_output
from ..report.outputs import OutputExistsError, check_creatable, check_output_dir, check_tune_dir, tune_files
from ..run_size import check_run_size, say_note
from .fault_flags import IN_PROCESS_FAULTS_NOTE, faults_active
from ..study.executor import Executor
from ..study.lost_runs import RunsLost
from ..study.scenarios import SCENARIOS, check_scenario_references
from .name_list import name_list
from ..tune.report import held_out_table, held_out_verdict, tune_figures, tune_markdown, tuned_yaml
from ..tune.objective import TRAINING_SCENARIOS, TRAINING_SEEDS
from ..tune.space import select, start_values
from ..run_settings import built_settings_held, say_rules
from ..run_steps import run_duration, run_steps
from ..setting_flags import SETTING_FLAGS
from ..tune.tuner import (TrialProgress, TuneSpec, arm_digest, check_persistent, check_storage_file, completed,
                          held_out, open_storage, open_study, optimize, refusal, settings_digest, storage_key,
                          sqlite_file, stored_identity, study_lock_key)

HELD_OUT_SEED0 = 100   # held-out seeds are 100, 101, ...: never a training seed (0 .. --seeds - 1)


def _write(path: Path, text: str) -> None:
    with atomic_path(path) as tmp:
        tmp.write_text(text)


def run_tune(options: TuneOptions) -> int:
    """Tune the controller of ``options`` (its values checked by the command line's parsing) on its arm;
    returns the exit code. A Ctrl-C says how far it got (:func:`_interrupted_line`) and exits 130."""
    state = {"study": None, "phase": "checks", "bar": None, "had_storage": False, "where_kept": None}
    try:
        return _checked_tune(options, state)
    except KeyboardInterrupt:
        if state["bar"] is not None:
            state["bar"].close()
        say(_interrupted_line(state, options.trials))
        return EXIT_INTERRUPTED
    except RunsLost as exc:   # a worker or the cluster lost: what the storage keeps, as for a Ctrl-C; exit 2
        if state["bar"] is not None:
            state["bar"].close()
        say(_lost_line(exc, state, options.trials))
        return 2


def check_tune(o: TuneOptions) -> None:
    """Every check a tune of ``o`` makes before it writes anything, and the study an interrupted tune left in
    DIR/tune.db against these options; ConfigError or Refused (one line) if one fails; no note said. For a caller
    that runs several tunes and checks them all first (scripts/equal_budget.py)."""
    c = _checks(o, say=None)
    spec = c["spec"]
    if o.storage is None:
        stored = stored_identity(c["out"] / "tune.db", spec.study_name)
        if stored is not None and stored != spec.identity():
            raise ConfigError(refusal(spec.study_name, stored, spec.identity()))


def _checked_tune(o: TuneOptions, state: dict) -> int:
    """Check every input of ``o`` (nothing written), then tune; ``state`` says how far it got."""
    c = _checks(o, say=say_note)
    out, spec = c["out"], c["spec"]
    lock_output(out)  # a second tune into DIR at once is refused (the same command later resumes)
    url = o.storage if o.storage is not None else _default_storage(out)   # one tune of a study at a time, in
    lock_key(study_lock_key(url, spec.study_name),    # whichever storage, however its URL is spelled
             f"{'--storage' if o.storage is not None else '--out'}: study {spec.study_name} in {url} is being tuned "
             "by another run (pid {pid}); wait for it to end (the same command then resumes it)")
    say_rules(c["rules"])   # every input accepted, the locks taken
    where_kept = o.storage if o.storage is not None else str(out / "tune.db")
    on_second_sigint(f"pa10-dnbs: interrupted again: stopped at once; the completed trials stay in {where_kept}; "
                     "run the same command to resume")
    state.update(phase="start", where_kept=where_kept, had_storage=o.storage is not None or (out / "tune.db").exists())
    with deferred():   # a Ctrl-C stops the tune between two storage operations, never inside one
        with immediate():   # seconds of imports on a busy machine: a Ctrl-C stops them at once
            import optuna  # noqa: F401
        return _tune(state, spec, c["base"], o.trials, out, o.storage, (c["pool"], c["batch"]), o.scheduler,
                     c["train"], o.seeds, o.held_out_seeds, o.controller, c["base"].arm, c["config_path"],
                     c["command"], o.progress)


def _checks(o: TuneOptions, say) -> dict:
    """Check every input of ``o`` (nothing written; ``say``: the notes of a long run or of faults); what the tune
    needs of them."""
    param_list = select(o.controller, None if o.params is None else [n.strip() for n in o.params.split(",") if n.strip()])
    train = name_list("--scenarios", o.scenarios, list(SCENARIOS))
    out = Path(o.out)
    if out.exists() and not out.is_dir():
        raise ConfigError(f"--out: {out} exists and is not a directory")
    check_creatable(out, "out")
    if o.storage is not None:
        check_persistent(o.storage)   # an in-memory database keeps nothing: refused before any run
        check_storage_file(o.storage)   # nor a database of the user's own, which would get the tune's tables
    config_path = Path(o.config_path) if o.config_path else default_config_path()
    # the settings, built once: config file(s), arm file, rules (their table said once the inputs are accepted)
    base, rules = built_settings_held(config_path, o.arm)
    the_arm = base.arm
    check_scenario_references(base, train)   # a reference past the Nyquist rate: one line, nothing runs
    if o.held_out_seeds:
        try:
            check_scenario_references(base, [s for s in SCENARIOS if s not in train])
        except ConfigError as exc:
            raise ConfigError(f"{exc} (the held-out runs take every scenario; --held-out-seeds 0 leaves them out)") \
                from None
    duration_s, given = run_duration(o.duration_s, base.simulation.duration_s)   # --duration, or the config's
    n_steps = run_steps(duration_s, base.simulation.dt_s, given)
    runs_per_trial = len(train) * o.seeds
    jobs = o.jobs or os.cpu_count() or 1
    batch = max(1, jobs // runs_per_trial)   # trials asked at once with `jobs` workers (tune/tuner.py optimize)
    n_held = 2 * len(SCENARIOS) * o.held_out_seeds   # the start and the best settings on every scenario
    pool = min(jobs, max(runs_per_trial * min(batch, o.trials), n_held))   # the runs that ever step at once
    check_run_size(duration_s, n_steps, len(the_arm.joint_names), at_once=1 if o.scheduler is not None else pool,
                   total_runs=runs_per_trial * o.trials + n_held, say=say, setting=given)
    if faults_active(base.faults) and say is not None:
        say(IN_PROCESS_FAULTS_NOTE)
    spec = TuneSpec(the_arm.name, o.controller, param_list, train, list(range(o.seeds)), duration_s,
                    str(config_path.resolve()), o.seed, start_values(o.controller, base),
                    arm_digest(the_arm), settings_digest(base))
    command = _command(o.controller, o.trials, out, o.arm, config_path, o.storage, o.seed, o.scenarios, o.seeds, o.held_out_seeds,
                       duration_s, o.params, base.simulation.duration_s)
    check_output_dir(out, False, "out", inputs={"config_path": config_path, "arm": the_arm.file,
                                                "arm URDF": the_arm.urdf},
                     resume=tune_files(out, o.storage))
    check_tune_dir(out, spec.study_name, spec.identity(), refusal)  # only this tune's own files: it resumes
    _check_same_storage(out, o.storage)   # DIR's reports and tune.db are of this storage's study
    return {"out": out, "spec": spec, "base": base, "pool": pool, "batch": batch, "train": train,
            "config_path": config_path, "command": command, "rules": rules}


def _default_storage(out: Path) -> str:
    """The storage of a tune without --storage: DIR/tune.db."""
    return f"sqlite:///{(out / 'tune.db').resolve()}"


def _reports(out: Path) -> dict:
    """DIR/tune.json, the reports of the tune run there last ({} when there are none or they do not read)."""
    import json

    try:
        done = json.loads((out / "tune.json").read_text())
    except (OSError, ValueError):
        return {}
    return done if isinstance(done, dict) else {}


def _moved_here(stored: str, storage: str | None, out: Path) -> bool:
    """The reports name a DIR/tune.db of another folder, and this folder, given no --storage (or its own tune.db
    as --storage), holds its own tune.db: the tune's folder was copied or moved here (its study is checked by its
    stored options)."""
    own = storage is None or storage_key(storage) == storage_key(_default_storage(out))
    return own and stored.endswith("/tune.db") and stored.startswith("sqlite:///") and (out / "tune.db").is_file()


def _check_same_storage(out: Path, storage: str | None) -> None:
    """OutputExistsError (one line naming --out) if ``out`` holds another storage's tune: a tune.json written from
    another storage, or its own tune.db while the trials go to a --storage elsewhere (the reports would be
    replaced by another storage's study, and disagree with DIR/tune.db). A tune folder copied or moved whole
    (tune.json naming the tune.db of its old place) is this folder's own tune. Reports of trials whose tune.db is
    gone are refused too: the same command would start a new study over them."""
    url = storage if storage is not None else _default_storage(out)
    done = _reports(out)
    stored = done.get("storage")
    own = storage_key(_default_storage(out))
    db = sqlite_file(url)
    if isinstance(stored, str) and storage_key(stored) == storage_key(url) and isinstance(done.get("trials"), int) \
            and done["trials"] > 0 and db is not None and not db.exists():   # refused before the file is made again
        raise OutputExistsError(f"--out: {out}/tune.json reports {done['trials']} trials of study "
                                f"{done.get('study')!r}, but {db}, which held them, is gone: restore it to "
                                "resume that tune, or give another --out for a new one")
    if isinstance(stored, str) and storage_key(stored) != storage_key(url) and not _moved_here(stored, storage, out):
        that = "without --storage" if storage_key(stored) == own else f"with --storage {stored}"
        raise OutputExistsError(f"--out: {out} holds the reports of the tune in {stored}, not in {url}: give another "
                                f"--out for this tune (or rerun {that} to resume that one)")
    if storage is not None and (out / "tune.db").is_file() and storage_key(url) != own:
        raise OutputExistsError(f"--out: {out}/tune.db holds the trials of a tune without --storage, not of "
                                f"{storage}: give another --out for this tune (or leave --storage out to resume "
                                "that one)")


def _check_reports_kept(out: Path, storage_obj, study_name: str, storage: str) -> None:
    """OutputExistsError naming --out when DIR's reports count more trials of study ``study_name`` than the
    storage holds: it was replaced or lost (a new database), and the tune would start anew and write its
    reports over those of the lost trials. Read only: the study is neither made nor changed."""
    from optuna.trial import TrialState

    done = _reports(out)
    if done.get("study") != study_name or not isinstance(done.get("trials"), int):
        return
    try:
        n = len(storage_obj.get_all_trials(storage_obj.get_study_id_from_name(study_name), deepcopy=False,
                                           states=(TrialState.COMPLETE,)))
    except KeyError:   # no such study there
        n = 0
    if done["trials"] > n:
        raise OutputExistsError(f"--out: {out}/tune.json reports {done['trials']} trials of study {study_name!r}, "
                                f"but {storage} holds {n}: the storage those trials were kept in is gone or another; "
                                "restore it to resume that tune, or give another --out for a new one")


def _interrupted_line(state: dict, trials: int) -> str:
    """The truth after a Ctrl-C: how many trials the storage keeps, where, and what the same command does."""
    where_kept = state["where_kept"]
    if state["phase"] == "checks":
        return ("pa10-dnbs: interrupted while checking its input, before any trial: nothing written or changed; "
                "run the same command again")
    if state["study"] is None:
        if state["had_storage"]:
            return (f"pa10-dnbs: interrupted before this run's first trial; {where_kept} keeps the trials it held: "
                    "run the same command to resume")
        return "pa10-dnbs: interrupted before the first trial; no trial kept: run the same command to start"
    n = len(completed(state["study"]))
    if state["phase"] == "done":
        return f"pa10-dnbs: interrupted after the tune was complete: {n} trials in {where_kept}, its reports written"
    if state["phase"] == "trials":
        return (f"pa10-dnbs: interrupted: kept {n} completed trial{'s' * (n != 1)} (of --trials {trials}) in "
                f"{where_kept}; run the same command to resume")
    return (f"pa10-dnbs: interrupted after the trials ({n} kept in {where_kept}), before the held-out runs and "
            "reports were all written: run the same command to finish them")


def _lost_line(exc: RunsLost, state: dict, trials: int) -> str:
    """A local worker process or the cluster lost mid-tune: one line naming --jobs or --scheduler, how many
    trials the storage keeps, where, and that the same command resumes."""
    opening = f"pa10-dnbs: error: {exc.named(SETTING_FLAGS)}"
    if state["study"] is None:
        return f"{opening}; before this run's first trial: run the same command again"
    n, where_kept = len(completed(state["study"])), state["where_kept"]
    if state["phase"] == "trials":
        return (f"{opening}; kept {n} completed trial{'s' * (n != 1)} (of --trials {trials}) in {where_kept}; "
                "run the same command to resume")
    return (f"{opening}; after the trials ({n} kept in {where_kept}), before the held-out runs and reports were "
            "written: run the same command to finish them")


def _tune(state, spec, base, trials, out, storage, pool_batch, scheduler, train, seeds, held_out_seeds, controller,
          the_arm, config_path, command, progress) -> int:
    """The search, the held-out runs and the reports; ``state`` says how far it got (for an interruption)."""
    pool, batch = pool_batch   # local: the processes (no more than ever run at once) and the trials asked at once
    with Executor(pool if scheduler is None else None, scheduler) as ex:   # an unreachable scheduler stops here,
        # before any storage is touched
        storage_obj = open_storage(storage) if storage is not None else None
        if storage is None:
            out.mkdir(parents=True, exist_ok=True)
            storage = _default_storage(out)
            storage_obj = open_storage(storage, default_file=out / "tune.db")
        if scheduler is not None:
            batch = max(1, ex.jobs // (len(train) * seeds))   # the cluster's workers
        _check_reports_kept(out, storage_obj, spec.study_name, storage)   # before the study is made or changed
        study = open_study(storage_obj, spec, batch)
        state["study"], state["phase"] = study, "trials"
        t0 = time.monotonic()
        bar = state["bar"] = TrialProgress(study, trials, f"tune {controller} on {the_arm.name}", progress)
        optimize(study, spec, base, trials, ex, bar, batch=batch)
        bar.close()
        state["bar"], state["phase"] = None, "reports"
        trials_done = completed(study)
        best = min(trials_done, key=lambda t: t.value)
        start = next((t for t in trials_done if t.user_attrs.get("start")), None)
        held_scen, held_seeds = list(SCENARIOS), list(range(HELD_OUT_SEED0, HELD_OUT_SEED0 + held_out_seeds))
        held = held_out(base, spec, best.params, held_scen, held_seeds, ex) if held_out_seeds else None
        where = ex.where
    wall = time.monotonic() - t0
    check()
    out.mkdir(parents=True, exist_ok=True)
    arm_value = the_arm.name if the_arm.name in preset_names() and load_arm(the_arm.name).file == the_arm.file \
        else str(the_arm.file)
    _write(out / "tuned.yaml", tuned_yaml(spec, base, best.params, arm_value, config_path, [
        f"{controller} on {the_arm.name} tuned by: {command}",
        f"trial {best.number} of study {spec.study_name}, objective {best.value:.4f} (docs/tuning.md)",
        f"run it: pa10-dnbs simulate --config {out / 'tuned.yaml'} --controller {controller} --out DIR"]))
    figures = tune_figures(study, out)
    check()
    _write(out / "tune.md", tune_markdown(spec, study, best, start, command, where, wall, held, held_scen, held_seeds,
                                          storage, figures))
    _write(out / "tune.json", json_text({
        "arm": the_arm.name, "controller": controller, "study": spec.study_name, "storage": storage,
        "options": spec.identity(), "trials": len(trials_done), "best_trial": best.number,
        "best_objective": best.value, "best_params": dict(spec.fixed, **best.params), "start_params": spec.start,
        "start_objective": start.value if start is not None else None,
        "held_out_seeds": held_seeds if held else [], "held_out": held}))
    state["phase"] = "done"
    print(f"{len(trials_done)} trials; best trial {best.number}: objective {best.value:.3f}"
          + (f" (start {start.value:.3f})" if start is not None else "") + f"; wrote {out}/tuned.yaml, {out}/tune.md")
    if held:
        print("\n".join(held_out_table(held, held_scen)[-1:]))
        verdict = held_out_verdict(held)
        if verdict:
            print(f"warning: {verdict}", file=sys.stderr)
    return 0


def _command(controller, trials, out, arm, config_path, storage, seed, scenarios, seeds, held_out_seeds, duration_s,
             params, config_duration_s) -> str:
    parts = ["pa10-dnbs tune", f"--controller {controller}", f"--trials {trials}", f"--out {shlex.quote(str(out))}"]
    if arm is not None:
        parts.append(f"--arm {shlex.quote(str(arm))}")
    if config_path != default_config_path():
        parts.append(f"--config {shlex.quote(str(config_path))}")
    if storage is not None:
        parts.append(f"--storage {shlex.quote(storage)}")
    for flag, v, default in (("--seed", seed, 0), ("--scenarios", scenarios, TRAINING_SCENARIOS),
                             ("--seeds", seeds, TRAINING_SEEDS), ("--held-out-seeds", held_out_seeds, 3),
                             ("--duration", duration_s, config_duration_s),
                             ("--params", params, None)):
        if v != default:
            parts.append(f"{flag} {v:g}" if isinstance(v, float) else f"{flag} {v}")
    return " ".join(parts)

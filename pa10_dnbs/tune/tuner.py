"""The search: an Optuna study in a storage, trials asked here and their runs executed by an Executor (this
process, local processes or a Dask cluster), told back here. The storage is only ever touched by this process,
so cluster workers need no database (docs/tuning.md).

Determinism: the sampler is TPE seeded with ``seed`` (plus the number of trials already in the storage, so a
resumed tune does not redraw the points it already tried). Trials are asked in batches of
``max(1, workers // runs per trial)`` and told in trial order, so the same command with the same number of
workers gives the same trials; with at most one trial per batch (the default: 8 scenarios x 1 seed = 8 runs,
fewer than 16 workers) the trials do not depend on the number of workers either. ``--jobs`` sets the batch; the
local pool has no more processes than the runs that step at once (commands/tune.py).
"""
from __future__ import annotations

import logging
import time
import warnings
from dataclasses import dataclass, field

from ..config_error import ConfigError
from ..interrupt import check
from ..output_lock import OutputInUseError, waiting_for
from ..settings import Settings
from ..study.executor import Executor
from .objective import objective, tune_run
from .space import Param, apply, settings_fragment, start_values

STUDY_ATTR = "pa10_dnbs_tune"   # the study's user attribute holding the options that define its objective


@dataclass
class TuneSpec:
    """What one tune searches and scores: controller, its searched dimensions, the training runs."""

    arm_name: str
    controller: str
    params: tuple[Param, ...]
    scenarios: list[str]
    seeds: list[int]
    duration_s: float
    config_file: str
    seed: int = 0
    start: dict = field(default_factory=dict)  # the start point of the full space (space.start_values)
    arm_digest: str = ""        # sha256 of the arm file's and its URDF's content (:func:`arm_digest`)
    settings_digest: str = ""   # sha256 of the merged settings the trials start from (:func:`settings_digest`)

    @property
    def fixed(self) -> dict:
        """The dimensions not searched, at their start values."""
        searched = {p.name for p in self.params}
        return {k: v for k, v in self.start.items() if k not in searched}

    @property
    def study_name(self) -> str:
        return f"{self.arm_name}-{self.controller}"

    def identity(self) -> dict:
        """The options a resumed study must share with the one in the storage."""
        return {"arm": self.arm_name, "controller": self.controller, "params": [p.name for p in self.params],
                "scenarios": self.scenarios, "seeds": self.seeds, "duration_s": self.duration_s,
                "config_file": self.config_file, "seed": self.seed, "arm_digest": self.arm_digest,
                "settings_digest": self.settings_digest}


def arm_digest(arm) -> str:
    """sha256 (hex) of what an arm is: its arm file's content and its URDF's (one file for a bare URDF); two arm
    files of one name, or an arm file edited in place, differ."""
    import hashlib

    h = hashlib.sha256()
    for path in dict.fromkeys([arm.file, arm.urdf]):   # in order, once each
        h.update(path.read_bytes())
        h.update(b"\0")
    return h.hexdigest()


def settings_digest(settings: Settings) -> str:
    """sha256 (hex) of the merged settings (config files, arm file, rules: everything a trial's run is set by but
    the searched point), the arm file's path left out (the arm is :func:`arm_digest`): a config edited in place
    differs."""
    import hashlib
    import json

    mapping = {k: v for k, v in settings.to_config().items() if k != "arm"}
    return hashlib.sha256(json.dumps(mapping, sort_keys=True, default=repr).encode()).hexdigest()


def quiet_optuna() -> None:
    import optuna

    optuna.logging.set_verbosity(optuna.logging.WARNING)
    warnings.filterwarnings("ignore", category=optuna.exceptions.ExperimentalWarning)
    logging.getLogger("alembic").setLevel(logging.WARNING)


def storage_key(url: str) -> str:
    """What names the storage at ``url``: an SQLite file as ``sqlite:///`` and its resolved path (a relative
    path, ``//`` in it, or a tune's default ``DIR/tune.db`` name the same file alike); any other URL as given."""
    from ..output_lock import path_key

    file = sqlite_file(url)
    return url if file is None else f"sqlite:///{path_key(file)}"


def sqlite_file(url: str):
    """The file (a Path, ``~`` expanded) of an SQLite URL, or None: another database, in memory, a ``file:`` URI,
    or not a URL (open_storage says so)."""
    from pathlib import Path

    from sqlalchemy.engine import make_url

    try:
        u = make_url(url)
    except Exception:   # noqa: BLE001 - not a URL
        return None
    db = u.database or ""
    if u.get_backend_name() != "sqlite" or db in ("", ":memory:") or db.startswith("file:"):
        return None
    return Path(db).expanduser()


def study_lock_key(url: str, study_name: str) -> str:
    """The name of the lock a tune holds on its study in the storage at ``url`` (output_lock.lock_key): two tunes
    of one study at once would each mark the other's running trial failed. An SQLite file by its resolved path
    (:func:`storage_key`); a server by its URL as given (one server reached by two names is not caught)."""
    return f"optuna study {study_name} in {storage_key(url)}"


STORAGE_OPEN_WAIT_S = 60.0   # how long a tune waits for another to finish opening the same storage [s]


def check_persistent(url: str) -> None:
    """ConfigError naming ``storage`` for an in-memory SQLite URL (``sqlite://``, ``sqlite:///:memory:``, a
    ``file::memory:`` or ``mode=memory`` URI with ``uri=true``): its trials end with the process, so nothing
    could be kept or resumed. Other URLs are opened (and said wrong) by :func:`open_storage`."""
    from sqlalchemy.engine import make_url

    try:
        u = make_url(url)
    except Exception:   # noqa: BLE001 - not a URL: open_storage says so
        return
    db, uri = u.database or "", str(u.query.get("uri", "")).lower() == "true"   # uri=true: a file: URI (pysqlite)
    if u.get_backend_name() == "sqlite" and (db in ("", ":memory:") or uri and (
            db.startswith("file::memory:") or str(u.query.get("mode", "")) == "memory")):
        raise ConfigError(f"storage: {url} is an in-memory database: its trials would end with this run, nothing "
                          "kept or resumed; give a file (sqlite:///PATH.db), a database server, or leave `storage` "
                          "out (DIR/tune.db)", setting="storage")


def check_storage_file(url: str) -> None:
    """ConfigError naming ``storage`` for an SQLite file that exists and is no Optuna storage (not SQLite, or a
    database with tables of its own): the tune would add its tables to a file of the user's."""
    from ..report.outputs import not_optuna_storage

    path = sqlite_file(url)
    if path is not None and path.is_file() and (why := not_optuna_storage(path)):
        raise ConfigError(f"storage: {path} is not a tune's storage ({why}): a tune would add its tables to it; give "
                          "a new file or the storage of a tune", setting="storage")


def open_storage(url: str, default_file=None):
    """An Optuna RDB storage at ``url`` (sqlite:///file.db, postgresql://..., ...); ConfigError if it does not
    open, naming ``storage``, or ``out`` and the file for a tune's own ``default_file`` (DIR/tune.db: no
    ``storage`` given). Two tunes opening one new storage at once would both create its tables (sqlite: "table studies
    already exists", 4 of 10 tries): one opens it at a time, the other waits (a lock named by the URL as given)."""
    import optuna
    from sqlalchemy.exc import SAWarning

    quiet_optuna()
    where = f"`storage`: {url}" if default_file is None else f"`out`: {default_file} (the tune's storage)"
    try:
        with waiting_for(f"optuna storage {storage_key(url)}",
                         f"{where} is being opened by another run (pid {{pid}}) "
                         f"for over {STORAGE_OPEN_WAIT_S:g} s", STORAGE_OPEN_WAIT_S, between=check), \
                warnings.catch_warnings():
            # what SQLAlchemy would only warn of (a query argument the driver ignores) is a refused URL, in one line
            warnings.filterwarnings("error", "Query string argument", SAWarning)
            return optuna.storages.RDBStorage(url)
    except OutputInUseError:
        raise
    except Exception as exc:  # sqlalchemy's errors for bad URLs, missing drivers, unreachable servers
        text = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        if default_file is not None:
            raise ConfigError(f"`out`: cannot open {default_file} (the tune's storage): {text}") from None
        if "://" not in url:
            text += f" (a database URL; for a file: sqlite:///{url})"
        raise ConfigError(f"storage: cannot open {url}: {text}", setting="storage") from None


def open_study(storage, spec: TuneSpec, batch: int):
    """The spec's study in ``storage``: created, or loaded if it exists with the same options (ConfigError if
    not); the start point enqueued as its first trial."""
    import optuna

    study = optuna.create_study(storage=storage, study_name=spec.study_name, direction="minimize",
                                load_if_exists=True)
    from optuna.trial import TrialState

    stored = study.user_attrs.get(STUDY_ATTR)
    if stored is None and not study.trials:
        study.set_user_attr(STUDY_ATTR, spec.identity())
    elif stored != spec.identity():
        raise ConfigError(refusal(spec.study_name, stored or {}, spec.identity()))
    for t in study.get_trials(deepcopy=False, states=(TrialState.RUNNING,)):
        study.tell(t.number, state=TrialState.FAIL)   # left by a tune that was killed: one coordinator per study
    if not any(t.user_attrs.get("start") for t in study.get_trials(
            deepcopy=False, states=(TrialState.COMPLETE, TrialState.WAITING))):
        study.enqueue_trial({p.name: spec.start[p.name] for p in spec.params}, user_attrs={"start": True})
    study.sampler = optuna.samplers.TPESampler(seed=spec.seed + len(study.trials), multivariate=True,
                                               constant_liar=batch > 1)
    return study


def stored_identity(db, study_name: str) -> dict | None:
    """The options stored with study ``study_name`` in the SQLite file ``db`` (read only, no Optuna), or None (no
    file, no such study, not an Optuna storage)."""
    import json
    import sqlite3
    from pathlib import Path

    db = Path(db)
    if not db.is_file():
        return None
    try:
        con = sqlite3.connect(f"{db.resolve().as_uri()}?mode=ro", uri=True)
        try:
            row = con.execute("SELECT a.value_json FROM study_user_attributes a JOIN studies s ON a.study_id = "
                              "s.study_id WHERE s.study_name = ? AND a.key = ?", (study_name, STUDY_ATTR)).fetchone()
        finally:
            con.close()
        return json.loads(row[0]) if row else None
    except (sqlite3.Error, ValueError):
        return None


#: the setting that gives each part of a study's identity (its name for the others)
IDENTITY_SETTINGS = {"config_file": "config_path", "arm_digest": "arm", "settings_digest": "config_path"}
DIGESTS = {"arm_digest": "the arm file's and URDF's content", "settings_digest": "the merged settings"}


def refusal(study_name: str, stored: dict, given: dict) -> str:
    """Why a stored study cannot go on with these options, and what to do: one line naming each setting that
    differs (config_error.SETTING_MARK), as stored and as given."""
    def shown(key, v):
        if key in DIGESTS:
            return f"sha256 {v[:12]}" if isinstance(v, str) and v else "not recorded (an older pa10-dnbs's study)"
        if key == "seeds" and isinstance(v, list):
            return str(len(v))          # seeds N means seeds 0..N-1
        return ",".join(map(str, v)) if isinstance(v, list) else f"{v:g}" if isinstance(v, float) else str(v)
    def differs(k):
        name = f"`{IDENTITY_SETTINGS.get(k, k)}`"
        what = f"{name}: {DIGESTS[k]}," if k in DIGESTS else name
        return f"{what} {shown(k, given.get(k))} (stored: {shown(k, stored.get(k))})"
    diff = [differs(k) for k in given if stored.get(k) != given[k]]
    return (f"`out`/`storage`: study {study_name!r} there was run with other options, so its trials do not "
            f"score the same objective: {'; '.join(diff)}; rerun with the stored options to resume it, or give "
            "another `out` (or `storage`) to start a new study")


def completed(study) -> list:
    from optuna.trial import TrialState

    return study.get_trials(deepcopy=False, states=(TrialState.COMPLETE,))


def trial_settings(base: Settings, spec: TuneSpec, values: dict) -> Settings:
    """The validated config of a trial's point (the dimensions not searched at their start values)."""
    return apply(base, settings_fragment(spec.controller, base, dict(spec.fixed, **values)))


def optimize(study, spec: TuneSpec, base: Settings, n_trials: int, executor: Executor, progress=None,
             batch: int | None = None) -> None:
    """Run trials until the study holds ``n_trials`` completed ones, ``batch`` at a time (default: as many as
    the executor's workers run at once). ``progress(done, best, runs_done, runs)`` after every run.
    Interrupted (Ctrl-C, an error): the trials of the batch are marked failed, the completed ones stay in the
    storage, and the exception goes on."""
    from optuna.trial import TrialState

    runs_per_trial = len(spec.scenarios) * len(spec.seeds)
    batch = batch or max(1, executor.jobs // runs_per_trial)
    while (done := len(completed(study))) < n_trials:
        asked = [study.ask() for _ in range(min(batch, n_trials - done))]
        tasks = {}
        for t in asked:
            values = {p.name: t.suggest_float(p.name, p.low, p.high, log=p.log) for p in spec.params}
            trial = trial_settings(base, spec, values)
            for sc in spec.scenarios:
                for seed in spec.seeds:
                    tasks[(t.number, sc, seed)] = (trial, sc, spec.controller, seed, spec.duration_s)
        n_runs = [0]

        def on_run(key, row):
            n_runs[0] += 1
            if progress is not None:
                progress(done, n_runs[0], len(tasks))
        try:
            rows = executor.run(tune_run, tasks, on_run)
        except BaseException:
            for t in asked:
                study.tell(t, state=TrialState.FAIL)
            raise
        for t in asked:
            trial_rows = [rows[k] for k in tasks if k[0] == t.number]
            t.set_user_attr("rows", trial_rows)
            study.tell(t, objective(trial_rows))
    if progress is not None:
        progress(len(completed(study)), 0, 0)


def held_out(base: Settings, spec: TuneSpec, best_values: dict, scenarios: list[str], seeds: list[int],
             executor: Executor) -> dict[str, list[dict]]:
    """Rows of the start settings and of ``best_values`` on every (scenario, seed): {'start': [...], 'tuned': [...]}."""
    trials = {"start": trial_settings(base, spec, start_values(spec.controller, base)),
              "tuned": trial_settings(base, spec, best_values)}
    tasks = {(which, sc, seed): (trial, sc, spec.controller, seed, spec.duration_s)
             for which, trial in trials.items() for sc in scenarios for seed in seeds}
    rows = executor.run(tune_run, tasks)
    return {which: [rows[k] for k in tasks if k[0] == which] for which in trials}


class TrialProgress:
    """One line on a terminal: trials done, best so far, the current batch's runs, elapsed wall time; nothing
    when ``enabled`` is False (not a terminal)."""

    def __init__(self, study, total: int, label: str, enabled: bool, stream=None, clock=time.monotonic):
        import sys

        self.study, self.total, self.label, self.enabled = study, total, label, enabled
        self.stream = stream if stream is not None else sys.stderr
        self.clock, self.t0, self._last = clock, clock(), -1e9

    def text(self, done: int, runs_done: int, runs: int, now: float | None = None) -> str:
        trials = completed(self.study)
        best = min(trials, key=lambda t: t.value, default=None)
        el = int((self.clock() if now is None else now) - self.t0)
        parts = [f"{self.label}: {done}/{self.total} trials",
                 f"best {best.value:.3f} (trial {best.number})" if best is not None else "best -",
                 f"elapsed {el // 3600:d}:{el // 60 % 60:02d}:{el % 60:02d}"]
        if runs:
            parts.insert(1, f"runs {runs_done}/{runs}")
        return "  ".join(parts)

    def __call__(self, done: int, runs_done: int, runs: int) -> None:
        now = self.clock()
        if self.enabled and (now - self._last >= 0.5 or runs == 0):
            self.stream.write("\r\x1b[K" + self.text(done, runs_done, runs, now))
            self.stream.flush()
            self._last = now

    def close(self) -> None:
        if self.enabled:
            self.stream.write("\n")
            self.stream.flush()

"""Write a run's outputs into a directory atomically: all files or none.

Files go to a temporary sibling directory that is renamed into place only
when everything was written; an existing directory is replaced only with
``force``, and only if it is empty or a previous pa10-dnbs output (it holds
OUTPUT_MARK); never the current directory, its parents, the root, or a path
that is, holds or lies in one of the run's inputs (check_output_dir). A folder
that something else makes at ``out`` while the run goes on is left as it was:
the finished outputs go to ``<out>.finished-<pid>`` beside it, and the
one-line error says so.

matplotlib (about 0.25 s to import) is loaded only when figures are drawn: the output checks every command
makes first, a run without figures (``--no-figures``) and the CLI never load it.
"""
from __future__ import annotations

import contextlib
import json
import os
import shutil
import sqlite3
import tempfile
from contextlib import contextmanager
from pathlib import Path

import yaml

from ..interrupt import deferred, on_second_sigint, outputs_written
from ..file_path import shown
from ..atomic_file import mkdir_mode
from ..json_text import json_text
from ..kinematics.urdf_chain import UrdfChain
from ..output_lock import holds_output, lock_output, path_key, release_output
from ..output_mark import OUTPUT_MARK, OUTPUT_MARK_TEXT, is_previous_output
from ..refused import Refused
from ..run_data import RunData
from .finite_view import until_step
from .markdown import report_markdown
from .partial import partial_mark


class OutputExistsError(FileExistsError, Refused):
    """The output directory exists and ``force`` was not given, or cannot be written, or another run uses it."""


# OUTPUT_MARK (output_mark.py): atomic_output_dir writes it into every output (simulate, study, launch, analyse;
# their interrupted partial outputs too) before the folder is renamed into place; the bag writer into every bag.

# The longest file name (bytes) a folder may have: its temporary siblings ``.NAME.partial-XXXXXXXX`` and
# ``.NAME.old-PID`` (atomic_output_dir) must fit in the filesystem's 255.
NAME_MAX = 255
NAME_ROOM = NAME_MAX - len(".") - max(len(".partial-") + 8, len(".old-") + 10)

# What ``tune`` keeps in its DIR (tune/report.py, commands/tune.py; SQLite's journal beside tune.db): a tune
# resumes into a folder holding nothing else.
TUNE_FILES = frozenset({"tune.db", "tune.db-journal", "tune.db-wal", "tune.db-shm", "tuned.yaml", "tune.md",
                        "tune.json", "history.png", "importance.png"})


def tune_files(out: Path, storage: str | None) -> frozenset[str]:
    """TUNE_FILES, and the names of a ``--storage sqlite:///FILE`` that lies directly in ``out`` (and its
    journals): what a tune's DIR may hold when it resumes."""
    if not storage or not storage.startswith("sqlite:///"):
        return TUNE_FILES
    file = Path(path_key(storage[len("sqlite:///"):]))
    if file.parent != Path(path_key(out)):
        return TUNE_FILES
    return TUNE_FILES | {file.name + end for end in ("", "-journal", "-wal", "-shm")}


def check_output_dir(out: Path, force: bool, setting: str = "out", inputs: dict | None = None,
                     resume: frozenset[str] | None = None) -> None:
    """:func:`_check_output_dir`; a path the system cannot look at (too long, a folder that cannot be searched,
    a loop of symbolic links) is refused in one line naming ``setting``, as the other refusals. Checked again by the
    same run (its outputs about to be written) after something else made or swapped ``out`` meanwhile: not
    refused, :func:`atomic_output_dir` then keeps the finished outputs beside it."""
    key = os.path.abspath(out)
    with _one_line(out, setting):
        if not holds_output(out):   # a new run (a command called again in one process): a first look
            _checked.pop(key, None)
        elif key in _checked and _identity(out) != _checked[key]:
            return
        _check_output_dir(out, force, setting, inputs, resume)
        _checked.setdefault(key, _identity(out))


@contextmanager
def _one_line(out: Path, setting: str):
    """Within: an OSError (a path too long, a folder that cannot be searched) or a loop of symbolic links while
    looking at ``out`` becomes an OutputExistsError, one line naming ``setting``."""
    try:
        yield
    except OutputExistsError:
        raise
    except RuntimeError:   # Path.resolve's "Symlink loop from ..."
        raise OutputExistsError(f"`{setting}`: {shown(out)}: a loop of symbolic links in the path") from None
    except OSError as exc:
        where = f" ({shown(exc.filename)})" if exc.filename and str(exc.filename) != str(out) else ""
        raise OutputExistsError(f"`{setting}`: {shown(out)}: {exc.strerror or exc}{where}") from None


#: abspath -> what was there ((device, inode) or None) when the run holding its lock first checked that folder
_checked: dict[str, tuple[int, int] | None] = {}


def _check_output_dir(out: Path, force: bool, setting: str, inputs: dict | None,
                      resume: frozenset[str] | None) -> None:
    """Fail early, before any work, if ``out`` is in use by another run (output_lock.py: this process then
    holds it until the output is in place), exists and may not be replaced, or cannot be created. ``setting``:
    the setting that names the output (``out``, ``record``), as the message names it (config_error.SETTING_MARK).

    Never an output, even with ``force``: the current directory, one of its parents or the root; a path equal
    to, inside, or holding one of ``inputs`` ({setting or name: path or None}: the run's config, arm file, bag,
    checkpoints, ...; each compared as given, made absolute, and resolved). ``force`` replaces only an empty
    folder or a previous pa10-dnbs output (OUTPUT_MARK). Refused up front too: an ``out`` that is a symbolic
    link, ends in '.' or '..', or whose name is too long for its temporary siblings.
    ``resume`` (tune): an existing ``out`` holding only these names is accepted without ``force`` (the command
    then checks it is its own run's)."""
    out = Path(out)
    check_name(out, setting)
    if out.exists() and not out.is_dir():
        raise OutputExistsError(f"`{setting}`: {out} exists and is not a directory")
    check_not_cwd(out, setting)
    if (last := os.path.basename(str(out).rstrip("/"))) in (".", ".."):
        raise OutputExistsError(f"`{setting}`: {out} ends in {last!r}: name the folder itself")
    check_apart(out, inputs or {}, setting)
    check_creatable(out, setting)
    lock_output(out)
    if not out.exists():
        return
    if resume is not None:
        if foreign := sorted(p.name for p in out.iterdir() if p.name not in resume):
            raise OutputExistsError(f"`{setting}`: {out} holds files that are not this command's outputs "
                                    f"({', '.join(foreign[:3])}{', ...' if len(foreign) > 3 else ''}): "
                                    "choose another folder")
        return
    if not force:
        if (mark := partial_mark(out)) is not None:
            raise OutputExistsError(f"output directory exists: {out} holds the partial outputs of an interrupted "
                                    f"run ({mark.get('completed')} of {mark.get('total')} done; use `force` to "
                                    "replace it with a complete run)")
        raise OutputExistsError(f"output directory exists: {out} (use `force` to replace it)" if setting == "out" else
                                f"`{setting}`: {out} exists; pass `force` to replace it")
    if any(out.iterdir()) and not is_previous_output(out):
        if "tune.db" in {p.name for p in out.iterdir()}:   # a tune's folder (its storage: trials, never replaced)
            raise OutputExistsError(f"`{setting}`: {out} is a tune's folder (its storage tune.db holds the trials): "
                                    "`force` never replaces one; remove it yourself or choose another folder")
        raise OutputExistsError(f"`{setting}`: {out} holds files that are not a pa10-dnbs output: `force` replaces only "
                                "an empty folder or a previous output; remove it yourself or choose another folder")


def check_name(out: Path, setting: str) -> None:
    """``out`` names a folder that atomic_output_dir can replace: every component at most NAME_MAX bytes and
    its last one at most NAME_ROOM (its temporary siblings must fit); not a symbolic link (the link would be
    replaced, not the folder it points to)."""
    text = str(out)
    last = os.path.basename(text.rstrip("/"))
    for part in Path(out).parts[:-1]:
        if len(os.fsencode(part)) > NAME_MAX:
            raise OutputExistsError(f"`{setting}`: a folder name in the path is too long ({len(os.fsencode(part))} "
                                    f"bytes; at most {NAME_MAX})")
    if (size := len(os.fsencode(last))) > NAME_ROOM:
        raise OutputExistsError(f"`{setting}`: the name is too long ({size} bytes; at most {NAME_ROOM} so that its "
                                "temporary sibling fits)")
    if os.path.islink(text.rstrip("/") or text):
        raise OutputExistsError(f"`{setting}`: {out} is a symbolic link: give the folder itself")


def check_not_cwd(out: Path, setting: str) -> None:
    """``out`` is not the current directory, one of its parents or the root (an empty path is ``.``)."""
    where, cwd = Path(out).resolve(), Path.cwd().resolve()
    if where == cwd or where in cwd.parents or where == Path(where.anchor):
        raise OutputExistsError(f"`{setting}`: {str(out) or '(empty)'!s} is "
                                + ("the filesystem root" if where == Path(where.anchor) else
                                   "the current directory" if where == cwd else "a parent of the current directory")
                                + ": give a folder of its own for the outputs")


def check_apart(out: Path, inputs: dict, setting: str) -> None:
    """``out`` is neither one of ``inputs`` ({setting or words: path or None}; a config's (``config_path``)
    ``extends`` files count too) nor
    holds one nor lies inside one: an output never replaces or mixes with what its run reads. Each path is
    compared both as given (made absolute, not resolved: a symbolic link inside ``out`` counts as inside) and
    resolved (what it points to)."""
    wheres = sorted(_both(out))
    for name, path in inputs.items():
        if path is None:
            continue
        given = config_files(path) + [Path(os.path.abspath(path))] if name == "config_path" else [Path(path)]
        for used in sorted({u for g in given for u in _both(g)}):
            for where in wheres:
                how = "is" if used == where else "holds" if where in used.parents else \
                    "lies inside" if used in where.parents else None
                if how is not None:
                    raise OutputExistsError(f"`{setting}`: {out} {how} this run's {_said(name)} {used}: an output never "
                                            "replaces or mixes with what its run uses; choose another output folder")


def _said(name: str) -> str:
    """An input's name in a message: a setting (``config_path``) marked as one, other words (``arm URDF``) as
    they are."""
    return f"`{name}`" if name.isidentifier() else name


def _both(path) -> set[Path]:
    """``path`` made absolute and normalised (os.path.abspath: links kept) and resolved (links followed)."""
    return {Path(os.path.abspath(path)), Path(path_key(path))}


def config_files(path: Path) -> list[Path]:
    """The config file ``path`` and the files its ``extends`` keys name, in turn (unreadable ones end the list:
    loading the config reports them)."""
    files: list[Path] = []
    path = Path(path)
    while path.resolve() not in files:
        files.append(path.resolve())
        if not path.is_file():   # a FIFO would block the read: loading the config refuses it
            break
        try:
            base = yaml.safe_load(path.read_text()).get("extends")
        except (OSError, ValueError, AttributeError, RecursionError, yaml.YAMLError):
            break
        if not isinstance(base, str) or not base:
            break
        path = path.resolve().parent / base
    return files


def check_tune_dir(out: Path, study_name: str, identity: dict, refusal) -> None:
    """``out`` holds no tune but this one: its tune.json (a finished tune) and tune.db (any tune) were made with
    the options ``identity`` of study ``study_name``; ``refusal(name, stored, given)`` words a mismatch.
    Raises OutputExistsError (one line), also for a tune file (tune.db, tune.json, ...) that is a symbolic link:
    the tune would resume into (and write its reports through it to) another folder's files."""
    out = Path(out)
    for name in sorted(TUNE_FILES):
        if (out / name).is_symlink():
            raise OutputExistsError(f"`out`: {out}/{name} is a symbolic link (to {os.readlink(out / name)}): a tune "
                                    "resumes only the files in its own folder; remove the link or give another `out`")
    try:
        done = json.loads((out / "tune.json").read_text())
    except (OSError, ValueError):
        done = None
    if isinstance(done, dict) and (done.get("study"), done.get("options")) != (study_name, identity):
        raise OutputExistsError(refusal(done.get("study", "?"), done.get("options") or {}, identity)
                                if done.get("study") == study_name else
                                f"`out`: {out} holds the tune {done.get('study')!r}, not {study_name!r}: "
                                "give another `out` for this tune")
    if (out / "tune.db").exists() and not (out / "tune.db").is_file():
        raise OutputExistsError(f"`out`: {out}/tune.db is not a file (a folder or another kind of file): a tune keeps "
                                "its trials in DIR/tune.db; move it or give another `out`")
    if (out / "tune.db").is_file():
        why = not_optuna_storage(out / "tune.db")
        if why:   # a file of the user's, which the tune would write its tables into
            raise OutputExistsError(f"`out`: {out}/tune.db is not a tune's storage ({why}): a tune keeps its trials "
                                    "in DIR/tune.db; move the file or give another `out`")
        others = [n for n in _sqlite_study_names(out / "tune.db") if n != study_name]
        if others:
            raise OutputExistsError(f"`out`: {out}/tune.db holds the tune {others[0]!r}, not {study_name!r}: "
                                    "give another `out` for this tune")


def _read_only(db: Path):
    """The SQLite database ``db`` opened read only (a context manager that closes it)."""
    return contextlib.closing(sqlite3.connect(f"{Path(db).resolve().as_uri()}?mode=ro", uri=True))


def not_optuna_storage(db: Path) -> str | None:
    """Why the file ``db`` is no Optuna SQLite storage (not SQLite; tables of its own), or None: an Optuna storage,
    or an empty file or database (a storage not yet made, which the tune makes)."""
    try:
        with _read_only(db) as con:
            tables = {row[0] for row in con.execute("SELECT name FROM sqlite_master WHERE type = 'table'")}
    except sqlite3.Error as exc:
        return f"not an SQLite database: {exc}"
    if tables and not {"studies", "trials", "alembic_version"} <= tables:
        return f"an SQLite database with other tables: {', '.join(sorted(tables)[:3])}"
    return None


def _sqlite_study_names(db: Path) -> list[str]:
    """The Optuna study names in the SQLite storage ``db`` (read only; none if it is not one)."""
    try:
        with _read_only(db) as con:
            return [row[0] for row in con.execute("SELECT study_name FROM studies")]
    except sqlite3.Error:
        return []


def check_creatable(path: Path, setting: str) -> None:
    """``path`` can be made: its nearest existing ancestor is a directory in which a folder can be created
    (tried with a temporary one, removed at once: a check that holds for root and read-only mounts too)."""
    with _one_line(path, setting):
        _check_creatable(path, setting)


def _check_creatable(path: Path, setting: str) -> None:
    for above in Path(os.path.abspath(path)).parents:   # the nearest existing folder above, links not followed
        if os.path.lexists(above):
            if above.is_symlink() and not above.exists():   # a link to nothing: the run's end could not make it
                raise OutputExistsError(f"`{setting}`: {above} is a symbolic link to {os.readlink(above)}, which does "
                                        f"not exist (output {shown(path)})")
            break
    parent = Path(path).resolve().parent
    while not parent.exists():
        parent = parent.parent
    if not parent.is_dir():
        raise OutputExistsError(f"`{setting}`: {parent} is not a directory (output {path})")
    try:
        os.rmdir(tempfile.mkdtemp(prefix=".pa10_dnbs-probe-", dir=parent))
    except OSError as exc:
        raise OutputExistsError(f"`{setting}`: cannot create {path}: {exc.strerror} in {parent}") from None


@contextmanager
def atomic_output_dir(out: Path, force: bool):
    """Yield a temporary directory; on success it replaces ``out``, on error it is removed (with the folders above
    ``out`` it made: an interrupted or failed command leaves nothing)."""
    out = Path(out)
    check_output_dir(out, force)
    checked = _checked.get(os.path.abspath(out))   # what --force may replace: the folder this run checked first
    made = [p for p in (out.parent, *out.parent.parents) if not p.exists()][::-1]   # outermost first
    try:
        out.parent.mkdir(parents=True, exist_ok=True)
        tmp = Path(tempfile.mkdtemp(prefix=f".{out.name}.partial-", dir=out.parent))
        mkdir_mode(tmp)   # the output is renamed into place: not mkdtemp's owner-only 0700
    except BaseException:
        _remove_empty(made)
        _release(out)
        raise
    try:
        yield tmp
        (tmp / OUTPUT_MARK).write_text(OUTPUT_MARK_TEXT)   # what --force may later replace (is_previous_output)
        old = None
        if os.path.lexists(out):
            if checked is None or _identity(out) != checked:   # made (or swapped) by someone else meanwhile
                raise _appeared(out, tmp)
            old = out.with_name(f".{out.name}.old-{os.getpid()}")
            out.rename(old)
        try:
            tmp.rename(out)
        except BaseException as exc:
            if old is not None:
                old.rename(out)  # put the previous output back
            elif isinstance(exc, OSError) and os.path.lexists(out):   # made in the instant since the look above
                raise _appeared(out, tmp) from None
            raise
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        _remove_empty(made)
        _release(out)
        raise
    if old is not None:
        _remove_tree(old)
    _release(out)


def _remove_tree(folder: Path) -> None:
    """Remove ``folder`` (the output --force replaced), also where the user had made it or a folder in it
    read-only (write permission given back to its owner first; what still resists is left)."""
    def writable_parent(func, path, exc_info):
        parent = os.path.dirname(path)
        with contextlib.suppress(OSError):
            os.chmod(parent, os.stat(parent).st_mode | 0o700)
            func(path)

    shutil.rmtree(folder, onerror=writable_parent)


def _release(out: Path) -> None:
    """The run is done with ``out``: its lock dropped and its first look forgotten."""
    _checked.pop(os.path.abspath(out), None)
    release_output(out)


@contextmanager
def finished_output_dir(out: Path, force: bool, main_file: str):
    """:func:`atomic_output_dir` for the outputs of a command whose runs are all done: a Ctrl-C (or SIGTERM)
    meanwhile lets them be finished (seconds), then ends the command with the line that says so; a second one
    removes the half-written folder and ends at once (pa10_dnbs/interrupt.py). ``main_file``: the file the line
    names (report.md, study.md)."""
    with deferred():
        with atomic_output_dir(out, force) as tmp:
            on_second_sigint(f"pa10-dnbs: interrupted again: stopped at once; nothing written to {out}",
                             cleanup=lambda: shutil.rmtree(tmp, ignore_errors=True))
            yield tmp
        outputs_written(f"pa10-dnbs: interrupted as it finished: {out} is written whole ({out}/{main_file})")


def _identity(path: Path) -> tuple[int, int] | None:
    """(device, inode) of ``path`` itself (a link not followed), or None when nothing is there."""
    try:
        st = os.lstat(path)
    except FileNotFoundError:
        return None
    return st.st_dev, st.st_ino


def _appeared(out: Path, tmp: Path) -> OutputExistsError:
    """``out`` was made while the run went on: left as it is; the finished outputs renamed from ``tmp`` to a
    visible sibling, which the error names (they are whole: never deleted for a folder not ours)."""
    kept = out.with_name(f"{out.name}.finished-{os.getpid()}")
    tmp.rename(kept)
    return OutputExistsError(f"`out`: {out} was created by something else while this run went on; it is left as "
                             f"it was, and this run's finished outputs are in {kept}")


def _remove_empty(folders: list[Path]) -> None:
    """Remove ``folders`` (outermost first) innermost first, each only while it is empty."""
    for folder in reversed(folders):
        try:
            folder.rmdir()
        except OSError:   # not empty (something else was written there meanwhile), or gone
            return


def write_run(directory: Path, run: RunData, metrics: dict, chain: UrdfChain | None = None,
              figures: bool = True) -> list[tuple[str, str]]:
    """metrics.json, timeseries.npz and (unless ``figures`` is False) the figures of one run (the arm in 3D
    when ``chain`` is given); returns (caption, file) pairs."""
    directory.mkdir(parents=True, exist_ok=True)
    (directory / "metrics.json").write_text(json_text(metrics))
    run.save_npz(directory / "timeseries.npz")
    if not figures:
        return []
    from .arm_figure import arm_figure   # matplotlib: only when drawing (module docstring)
    from .figures import error_figure, startup_figure, torque_figure, tracking_figure

    run = _shown(run, metrics)
    tag = run.controller.upper()
    settling = [j["settling_time_s"] for j in metrics["joints"]]
    figs = [(f"{tag}: reference (solid) and actual (dashed) angles, Figs. 4-10", "tracking.png"),
            (f"{tag}: tracking errors, Fig. 11 (metrics window shaded, settling time dotted)", "errors.png"),
            (f"{tag}: start-up, errors with the settling band and torques with their limits", "startup.png"),
            (f"{tag}: applied torques and their limits", "torques.png")]
    tracking_figure(run, directory / "tracking.png")
    error_figure([run], directory / "errors.png", tuple(metrics["window_s"]), [settling])
    startup_figure(run, directory / "startup.png", metrics["settle_band_rad"], settling)
    torque_figure(run, directory / "torques.png")
    if chain is not None:
        arm_figure(run, chain, directory / "arm.png")
        figs.insert(0, (f"{tag}: the arm at six instants and its flange path (forward kinematics of the URDF)",
                        "arm.png"))
    return figs


def _shown(run: RunData, metrics: dict) -> RunData:
    """What a run's figures draw: the run itself, or a run that went non-finite up to that step."""
    step = metrics.get("non_finite_from_step")
    return until_step(run, step) if step is not None else run


def write_report(directory: Path, runs: list[RunData], metrics: list[dict], title: str,
                 notes: list[str], chain: UrdfChain | None = None, figures: bool = True) -> None:
    """A single run's files at the top of ``directory``; several runs in sub-directories plus a comparison.
    ``figures=False`` (``--no-figures``): data and report.md only, no PNG (about 3 s less per run)."""
    if not figures:
        notes = notes + ["Figures not drawn (--no-figures); `pa10-dnbs analyse` of a bag, or a run without "
                         "the flag, draws them."]
    if len(runs) == 1:
        figs = write_run(directory, runs[0], metrics[0], chain, figures)
    else:
        figs = []
        for run, m in zip(runs, metrics):
            sub = run.controller
            figs += [(c, f"{sub}/{f}") for c, f in write_run(directory / sub, run, m, chain, figures)]
    if len(runs) > 1:
        if figures:
            from .figures import error_figure

            error_figure([_shown(r, m) for r, m in zip(runs, metrics)], directory / "errors_compare.png",
                         tuple(metrics[0]["window_s"]),
                         [[j["settling_time_s"] for j in m["joints"]] for m in metrics])
            figs.insert(0, ("Tracking errors of " + " and ".join(r.controller.upper() for r in runs)
                            + " overlaid (metrics window shaded)", "errors_compare.png"))
        (directory / "summary.json").write_text(json_text(
            {m["controller"]: {"worst_rms_error_rad": m["worst_rms_error_rad"],
                               "metrics": f"{m['controller']}/metrics.json"} for m in metrics}))
    (directory / "report.md").write_text(report_markdown(metrics, figs, title, notes))

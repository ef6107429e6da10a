"""Write a run's outputs into a directory atomically: all files or none.

Files go to a temporary sibling directory that is renamed into place only
when everything was written; an existing directory is replaced only with
``force``.
"""
from __future__ import annotations

import os
import shutil
import tempfile
from contextlib import contextmanager
from pathlib import Path

from ..json_text import json_text
from ..kinematics.urdf_chain import UrdfChain
from ..output_lock import lock_output, release_output
from ..run_data import RunData
from .arm_figure import arm_figure
from .figures import error_figure, startup_figure, torque_figure, tracking_figure
from .finite_view import until_step
from .markdown import report_markdown
from .partial import partial_mark


class OutputExistsError(FileExistsError):
    """The output directory exists and ``--force`` was not given, or cannot be written, or another run uses it."""


def check_output_dir(out: Path, force: bool, flag: str = "out") -> None:
    """Fail early, before any work, if ``out`` is in use by another run (output_lock.py: this process then
    holds it until the output is in place), exists and may not be replaced, or cannot be created. ``flag``:
    how the message names the output (a command passes its flag)."""
    out = Path(out)
    if out.exists() and not out.is_dir():
        raise OutputExistsError(f"{flag}: {out} exists and is not a directory")
    check_creatable(out, flag)
    lock_output(out)
    if out.exists() and not force:
        if (mark := partial_mark(out)) is not None:
            raise OutputExistsError(f"output directory exists: {out} holds the partial outputs of an interrupted "
                                    f"run ({mark.get('completed')} of {mark.get('total')} done; use --force to "
                                    "replace it with a complete run)")
        raise OutputExistsError(f"output directory exists: {out} (use --force to replace it)")


def check_creatable(path: Path, flag: str) -> None:
    """``path`` can be made: its nearest existing ancestor is a directory in which a folder can be created
    (tried with a temporary one, removed at once: a check that holds for root and read-only mounts too)."""
    parent = Path(path).resolve().parent
    while not parent.exists():
        parent = parent.parent
    if not parent.is_dir():
        raise OutputExistsError(f"{flag}: {parent} is not a directory (output {path})")
    try:
        os.rmdir(tempfile.mkdtemp(prefix=".pa10_dnbs-probe-", dir=parent))
    except OSError as exc:
        raise OutputExistsError(f"{flag}: cannot create {path}: {exc.strerror} in {parent}") from None


@contextmanager
def atomic_output_dir(out: Path, force: bool):
    """Yield a temporary directory; on success it replaces ``out``, on error it is removed."""
    out = Path(out)
    check_output_dir(out, force)
    try:
        out.parent.mkdir(parents=True, exist_ok=True)
        tmp = Path(tempfile.mkdtemp(prefix=f".{out.name}.partial-", dir=out.parent))
    except BaseException:
        release_output(out)
        raise
    try:
        yield tmp
        old = None
        if out.exists():
            old = out.with_name(f".{out.name}.old-{os.getpid()}")
            out.rename(old)
        try:
            tmp.rename(out)
        except BaseException:
            if old is not None:
                old.rename(out)  # put the previous output back
            raise
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        release_output(out)
        raise
    if old is not None:
        shutil.rmtree(old, ignore_errors=True)
    release_output(out)


def write_run(directory: Path, run: RunData, metrics: dict, chain: UrdfChain | None = None,
              figures: bool = True) -> list[tuple[str, str]]:
    """metrics.json, timeseries.npz and (unless ``figures`` is False) the figures of one run (the arm in 3D
    when ``chain`` is given); returns (caption, file) pairs."""
    directory.mkdir(parents=True, exist_ok=True)
    (directory / "metrics.json").write_text(json_text(metrics))
    run.save_npz(directory / "timeseries.npz")
    if not figures:
        return []
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
    """What a run's figures draw: the run itself, or a diverged run up to the step where it went non-finite."""
    diverged = metrics.get("diverged")
    return until_step(run, diverged["step"]) if diverged else run


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
            error_figure([_shown(r, m) for r, m in zip(runs, metrics)], directory / "errors_compare.png",
                         tuple(metrics[0]["window_s"]),
                         [[j["settling_time_s"] for j in m["joints"]] for m in metrics])
            figs.insert(0, ("Tracking errors of " + " and ".join(r.controller.upper() for r in runs)
                            + " overlaid (metrics window shaded)", "errors_compare.png"))
        (directory / "summary.json").write_text(json_text(
            {m["controller"]: {"worst_rms_error_rad": m["worst_rms_error_rad"],
                               "metrics": f"{m['controller']}/metrics.json"} for m in metrics}))
    (directory / "report.md").write_text(report_markdown(metrics, figs, title, notes))

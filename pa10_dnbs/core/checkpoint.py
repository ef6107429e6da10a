"""Save and load a controller's learned state (``state_dict()`` arrays) as one .npz file, atomically.

The file holds the arrays plus ``step`` (the last step answered). Written to
a temporary sibling and renamed, so a process killed mid-write leaves the
previous checkpoint intact. The archive is built in memory and written in
one call (~0.3 ms of CPU, against ~0.5 ms for ``np.savez`` on the file).
Periodic saves of the joints are spread over the period
(``checkpoint_phase``): the joint controllers all saving on one step put a few ms
of CPU into one tick.
"""
from __future__ import annotations

import io
import zipfile
import zlib
from pathlib import Path

import numpy as np

from ..atomic_file import atomic_path
from .honn import monomial_exponents

_NETWORKS = (("alpha", 2), ("torque", 3))   # each network's name in a state dict and its number of inputs


def save_checkpoint(path: Path, state: dict, step: int) -> None:
    """Write one joint's controller ``state`` (its ``state_dict``: each network's weights (L,) and EKF covariance
    (L, L)) and the ``step`` it was taken at, as one .npz at ``path``, atomically (never a half-written file)."""
    buf = io.BytesIO()
    np.savez(buf, step=np.array(step), **state)
    with atomic_path(path, ".tmp.npz") as tmp:
        tmp.write_bytes(buf.getbuffer())


def checkpoint_phase(joint: int, n_joints: int, every: int) -> int:
    """The step within each period of ``every`` steps at which joint ``joint`` (of ``n_joints``) saves: the
    joints' saves spread evenly over the period (joint 0 at its start)."""
    return (joint * every) // n_joints


def checkpoint_due(step: int, every: int, phase: int) -> bool:
    """True at the periodic save steps phase + m * every (m >= 0), step 0 excepted."""
    return step > 0 and step % every == phase


def load_checkpoint(path: Path) -> tuple[dict, int]:
    """(state dict, step) from ``save_checkpoint``; ValueError if the file is not a readable checkpoint."""
    try:
        not_zip = _not_zip(path)
        if not not_zip:
            with np.load(Path(path), allow_pickle=False) as z:
                state = {k: z[k] for k in z.files}
    except (OSError, ValueError, EOFError, KeyError, zipfile.BadZipFile, zlib.error) as exc:
        why = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise ValueError(f"{path}: not a readable checkpoint (truncated or not an .npz file: {why})") from None
    if not_zip:
        raise ValueError(f"{path}: not a checkpoint (.npz): not a zip archive: {not_zip}")
    if "step" not in state:
        raise ValueError(f"{path}: not a checkpoint (no step)")
    return state, _whole_number(path, state.pop("step"), "step")


def _not_zip(path: Path) -> str:
    """What ``path`` is when it does not start like a zip archive (an .npz), else "": ``np.load`` would return a
    .npy file's array (no archive) or advise ``allow_pickle`` on any other file."""
    with open(path, "rb") as f:
        head = f.read(6)
    if head.startswith(b"PK"):
        return ""
    if head.startswith(b"\x93NUMPY"):
        return "a single array (.npy, np.save's output)"
    return f"it starts with {head!r}" if head else "an empty file"


def _whole_number(path: Path, value: np.ndarray, what: str) -> int:
    """``value`` (a stored array) as an int if it is one finite whole number, else ValueError naming ``path``."""
    ok = np.shape(value) == () and value.dtype.kind in "iuf"
    if ok and value.dtype.kind == "f":
        ok = bool(np.isfinite(value)) and float(value) == int(value)
    if not ok:
        shown = np.array2string(np.asarray(value), threshold=6)[:60]
        raise ValueError(f"{path}: not a checkpoint: its {what} is not a whole number ({shown}, {value.dtype})")
    return int(value)


def checkpoint_dir(path: Path) -> Path:
    """The directory holding ``<joint>.npz`` files: ``path`` itself, ``path/checkpoints`` (a run's output), or
    ``path/dnbs/checkpoints`` (the output of a run of several controllers: ``simulate --controller all``)."""
    path = Path(path)
    for inside in (path / "checkpoints", path / "dnbs" / "checkpoints"):
        if inside.is_dir():
            return inside
    return path


def network_degrees(dnbs) -> tuple[int, int]:
    """(alpha, torque) ``max_degree`` of the ``dnbs`` settings (``DnbsSettings``): what a checkpoint must fit."""
    return int(dnbs.alpha_net.max_degree), int(dnbs.torque_net.max_degree)


def check_controller_state(f: Path, state: dict, joint: int, degrees: tuple[int, int]) -> None:
    """ValueError naming ``f`` unless ``state`` is a DNBS state of joint index ``joint`` for networks of
    ``degrees`` (alpha, torque ``max_degree``): weights (L,), covariances (L, L), initial weights (L,), finite."""
    missing = [f"{name}_{k}" for name, _ in _NETWORKS for k in ("w", "P", "w0") if f"{name}_{k}" not in state]
    if missing:
        raise ValueError(f"{f}: not a DNBS checkpoint (no {', '.join(missing)})")
    if "joint" in state and _whole_number(f, state["joint"], "joint index") != joint:
        raise ValueError(f"{f}: the checkpoint of joint index {state['joint']}, expected {joint}")
    for (name, n_inputs), degree in zip(_NETWORKS, degrees):
        n = len(monomial_exponents(n_inputs, degree))
        shapes = tuple(np.shape(state[f"{name}_{k}"]) for k in ("w", "P", "w0"))
        if shapes != ((n,), (n, n), (n,)):
            raise ValueError(f"{f}: its {name} network has weights {shapes[0]} and covariance {shapes[1]}, "
                             f"this config's dnbs.{name}_net (max_degree {degree}) has {n} weight{'s' * (n != 1)}: a checkpoint "
                             "of another network")
        for k, what in (("w", "weights"), ("P", "covariance"), ("w0", "initial weights")):
            value = state[f"{name}_{k}"]
            if value.dtype.kind not in "fiu":
                raise ValueError(f"{f}: its {name} network's {what} are not numbers ({value.dtype})")
            if not np.isfinite(value).all():
                raise ValueError(f"{f}: its {name} network's {what} are not all finite (NaN or inf)")
        if not _symmetric_positive_definite(np.asarray(state[f"{name}_P"], dtype=float)):
            raise ValueError(f"{f}: its {name} network's covariance is not symmetric positive definite (the EKF "
                             "keeps it so; the guard would reset it at the first step, dropping the warm start)")


def _symmetric_positive_definite(P: np.ndarray) -> bool:
    """P (L, L) symmetric (to 1e-12 of its largest entry) with a Cholesky factor (every eigenvalue > 0)."""
    if P.size == 0:
        return True
    if np.abs(P - P.T).max() > 1e-12 * np.abs(P).max():
        return False
    try:
        np.linalg.cholesky(P)
    except np.linalg.LinAlgError:
        return False
    return True


def load_joint_checkpoints(path: Path, joint_names, degrees: tuple[int, int] | None = None) -> list[dict]:
    """One controller state per joint from ``<dir>/<joint>.npz`` (see :func:`checkpoint_dir`).

    ``degrees``: the (alpha, torque) ``max_degree`` the states must fit (:func:`check_controller_state`).
    ValueError naming the file when one is missing, unreadable or does not fit.
    """
    try:
        d = checkpoint_dir(path)
        there = d.is_dir()
    except OSError as exc:   # a name too long for the OS
        raise ValueError(f"{path}: {exc.strerror or exc}") from None
    if not there:
        if d.is_file():   # one joint's file, say: the folder holds the arm's
            raise ValueError(f"{path}: a file; give the folder that holds every joint's <joint>.npz "
                             f"({d.parent} here), or the run's output folder")
        raise ValueError(f"{path}: no such checkpoint directory")
    states = []
    for name in joint_names:
        f = d / f"{name}.npz"
        if not f.is_file():
            held = sorted(g.stem for g in d.glob("*.npz"))
            other = f"; the folder holds joints {', '.join(held)}: another arm's run?" \
                if held and not set(held) & set(joint_names) else ""
            raise ValueError(f"{f}: missing (a warm start needs one checkpoint per joint: {', '.join(joint_names)})"
                             f"{other}")
        state = load_checkpoint(f)[0]
        if degrees is not None:
            check_controller_state(f, state, len(states), degrees)
        states.append(state)
    return states

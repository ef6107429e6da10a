"""One run per output path at a time: an advisory ``flock`` on a lock file named after the path's resolved form.

A run takes the lock of its ``--out`` (and ``--record`` bag) before any work and holds it until its outputs are
in place (or the process ends); a second run into the same path is refused at once with one line, even with
``--force`` (which replaces a finished run's output, never a running one's). The lock files live in
``$TMPDIR/pa10_dnbs-locks-<uid>/`` (not next to the output: its folder may not exist yet) and are removed on
release; the kernel drops a lock when its holder dies, so a killed run never blocks the next.
"""
from __future__ import annotations

import atexit
import fcntl
import hashlib
import os
import tempfile
from pathlib import Path

from .refused import Refused


class OutputInUseError(FileExistsError, Refused):
    """Another run holds the output path."""


_held: dict[str, tuple[int, int]] = {}  # resolved path -> (the open lock file's descriptor, the holder's pid)


def _lock_file(key: str) -> Path:
    d = Path(tempfile.gettempdir()) / f"pa10_dnbs-locks-{os.getuid()}"
    d.mkdir(mode=0o700, exist_ok=True)
    return d / (hashlib.sha256(key.encode()).hexdigest()[:24] + ".lock")


def _sweep_stale(directory: Path) -> None:
    """Remove the lock files no process holds (their holders were killed before they could): each is taken and
    unlinked; a run opening it at that moment sees its file gone and makes a new one (the inode check below)."""
    for file in directory.glob("*.lock"):
        try:
            fd = os.open(file, os.O_RDWR)
        except OSError:
            continue
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            if os.fstat(fd).st_ino == os.stat(file).st_ino:
                os.unlink(file)
        except OSError:  # held (BlockingIOError), or gone meanwhile
            pass
        finally:
            os.close(fd)


def lock_output(path: Path, what: str = "output directory") -> None:
    """Hold the lock of ``path`` for this process (again: no-op); raises OutputInUseError if another run holds it."""
    lock_key(str(Path(path).resolve()), f"{what} {path} is in use by another run (pid {{pid}}); wait for it to end or "
                                        "choose another path")


def lock_key(key: str, in_use: str) -> None:
    """Hold the lock named ``key`` (a resolved path, or any text naming one shared thing, e.g. an Optuna study in a
    storage) for this process (again: no-op); OutputInUseError with ``in_use`` (``{pid}``: the holder's) if another
    run holds it."""
    if key in _held:
        return
    file = _lock_file(key)
    _sweep_stale(file.parent)
    while True:
        fd = os.open(file, os.O_RDWR | os.O_CREAT, 0o600)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            holder = (os.read(fd, 64).decode(errors="replace").split() or ["?"])[0]
            os.close(fd)
            raise OutputInUseError(in_use.format(pid=holder)) from None
        try:
            same = os.fstat(fd).st_ino == os.stat(file).st_ino
        except FileNotFoundError:
            same = False
        if same:  # not a file its previous holder unlinked while we opened it
            break
        os.close(fd)
    os.ftruncate(fd, 0)
    os.write(fd, f"{os.getpid()} {key}\n".encode())
    _held[key] = (fd, os.getpid())


def release_output(path: Path) -> None:
    """Drop the lock of ``path`` if this process holds it (its lock file is removed)."""
    release_key(str(Path(path).resolve()))


def release_key(key: str) -> None:
    """Drop the lock named ``key`` if this process holds it (its lock file is removed)."""
    fd, pid = _held.pop(key, (None, None))
    if fd is None:
        return
    if pid != os.getpid():  # a forked child: its copy of the descriptor closes with it, the parent keeps the lock
        return
    try:
        os.unlink(_lock_file(key))
    except FileNotFoundError:
        pass
    os.close(fd)


def held() -> set[str]:
    """The keys (resolved paths) whose locks this process holds."""
    return set(_held)


def release_all(keep: set[str] = frozenset()) -> None:
    """Drop every lock this process holds but those of ``keep`` (end of a command run inside another)."""
    for key in list(_held):
        if key not in keep:
            release_key(key)


atexit.register(release_all)

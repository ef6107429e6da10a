"""One run per output path at a time: an advisory ``flock`` on a lock file named after the path's resolved form.

A run takes the lock of its ``--out`` (and ``--record`` bag) before any work and holds it until its outputs are
in place (or the process ends); a second run into the same path is refused at once with one line, even with
``--force`` (which replaces a finished run's output, never a running one's). The lock files live in
``$TMPDIR/pa10_dnbs-locks-<uid>/`` (not next to the output: its folder may not exist yet) and are removed on
release; the kernel drops a lock when its holder dies, so a killed run never blocks the next.

Readers share: a run that only reads a path (analyse or replay of a bag) takes the lock shared (``lock_input``),
so any number of readers hold it at once; a reader is refused only while a writer holds the path, a writer while
anyone does. A shared holder removes the lock file on release only if it can then take the lock alone (no other
reader holds it); else the last one out, or the next run's sweep of stale files, removes it.
"""
from __future__ import annotations

import atexit
import fcntl
import hashlib
import os
import tempfile
import time
from contextlib import contextmanager
from pathlib import Path

from .file_path import absolute
from .refused import Refused


class OutputInUseError(FileExistsError, Refused):
    """Another run holds the output path."""


_held: dict[str, tuple[int, int]] = {}  # resolved path -> (the open lock file's descriptor, the holder's pid)
_shared: set[str] = set()               # the keys of _held this process holds shared (as a reader)
SWEEP_RETRY_S = 0.2  # how long a refused lock is tried again: another run's sweep holds a stale file an instant [s]


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


def path_key(path: Path) -> str:
    """The lock's name for ``path``: its resolved form; made absolute only, where links loop or the path is too
    long to resolve (nothing can be read or written there: the command's own check says so)."""
    return str(absolute(Path(path)))


def lock_output(path: Path, what: str = "output directory") -> None:
    """Hold the lock of ``path`` for this process, alone (again: no-op); raises OutputInUseError if another run
    holds it (writing or reading)."""
    lock_key(path_key(path), f"{what} {path} is in use by another run (pid {{pid}}); wait for it to end or "
                                        "choose another path")


def lock_input(path: Path, what: str = "bag") -> None:
    """Hold the lock of ``path`` for this process, shared with other readers (again: no-op); raises
    OutputInUseError if a run that writes it holds it."""
    lock_key(path_key(path), f"{what} {path} is in use by another run (pid {{pid}}), which writes it; "
                                        "wait for it to end", shared=True)


def lock_key(key: str, in_use: str, shared: bool = False) -> None:
    """Hold the lock named ``key`` (a resolved path, or any text naming one shared thing, e.g. an Optuna study in a
    storage) for this process (again: no-op; held shared and asked alone: made exclusive if no other run holds it);
    OutputInUseError with ``in_use`` (``{pid}``: the holder's, for readers the last one's to take it) if another
    run holds it (``shared``: if a writer does)."""
    if key in _held:
        if not shared and key in _shared:
            _upgrade(key, in_use)
        return
    file = _lock_file(key)
    _sweep_stale(file.parent)
    give_up = time.monotonic() + SWEEP_RETRY_S
    while True:
        fd = os.open(file, os.O_RDWR | os.O_CREAT, 0o600)
        try:
            fcntl.flock(fd, (fcntl.LOCK_SH if shared else fcntl.LOCK_EX) | fcntl.LOCK_NB)
        except BlockingIOError:
            holder = _holder(fd)
            os.close(fd)
            if time.monotonic() < give_up:  # perhaps another run's sweep, about to unlink a stale file
                time.sleep(0.01)
                continue
            raise OutputInUseError(in_use.format(pid=holder)) from None
        try:
            same = os.fstat(fd).st_ino == os.stat(file).st_ino
        except FileNotFoundError:
            same = False
        if same:  # not a file its previous holder unlinked while we opened it
            break
        os.close(fd)
    if not shared:
        os.ftruncate(fd, 0)
    os.pwrite(fd, f"{os.getpid()} {key}\n".encode(), 0)  # readers overwrite each other: the first word stays a pid
    _held[key] = (fd, os.getpid())
    if shared:
        _shared.add(key)


def _holder(fd: int) -> str:
    """The pid written in an open lock file (``?``: none yet)."""
    return (os.pread(fd, 64, 0).decode(errors="replace").split() or ["?"])[0]


def _upgrade(key: str, in_use: str) -> None:
    """Make this process's shared lock of ``key`` exclusive; OutputInUseError if another run holds it too (the
    shared lock is then taken again: flock drops it while it tries)."""
    fd, _ = _held[key]
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except BlockingIOError:
        try:
            fcntl.flock(fd, fcntl.LOCK_SH | fcntl.LOCK_NB)
        except BlockingIOError:  # a writer took it in that instant: this process no longer holds it
            _held.pop(key)
            _shared.discard(key)
            os.close(fd)
        raise OutputInUseError(in_use.format(pid=_holder(fd) if key in _held else "?")) from None
    _shared.discard(key)
    os.ftruncate(fd, 0)
    os.pwrite(fd, f"{os.getpid()} {key}\n".encode(), 0)


def holds_output(path: Path) -> bool:
    """Whether this process holds the lock of ``path`` alone (as a run writing it)."""
    key = path_key(path)
    return key in _held and key not in _shared


def release_output(path: Path) -> None:
    """Drop the lock of ``path`` if this process holds it (its lock file is removed)."""
    release_key(path_key(path))


def release_key(key: str) -> None:
    """Drop the lock named ``key`` if this process holds it (its lock file is removed; held shared: only if no other
    reader holds it, which this process checks by taking it alone first)."""
    fd, pid = _held.pop(key, (None, None))
    shared = key in _shared
    _shared.discard(key)
    if fd is None:
        return
    if pid != os.getpid():  # a forked child: its copy of the descriptor closes with it, the parent keeps the lock
        return
    try:
        if shared:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)  # BlockingIOError: other readers hold it, they remove it
        file = _lock_file(key)
        if os.fstat(fd).st_ino == os.stat(file).st_ino:
            os.unlink(file)
    except (BlockingIOError, FileNotFoundError):
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


@contextmanager
def waiting_for(key: str, in_use: str, wait_s: float, between=None):
    """Hold the lock named ``key`` (not held by this process yet) while the block runs, waiting up to ``wait_s`` [s]
    for another run to drop it: for a step of a few seconds two runs must not take at once (creating one
    storage's tables). OutputInUseError with ``in_use`` (``{pid}``: the holder's) past the wait; ``between``:
    called between two tries (e.g. interrupt.check, so that a Ctrl-C ends the wait)."""
    give_up = time.monotonic() + wait_s
    while True:
        try:
            lock_key(key, in_use)
            break
        except OutputInUseError:
            if time.monotonic() >= give_up:
                raise
            if between is not None:
                between()
            time.sleep(0.02)
    try:
        yield
    finally:
        release_key(key)


atexit.register(release_all)

"""Keep PyBullet's C-level prints ("pybullet build time", "argv[0]=") off stdout and stderr.

They are written with C stdio (the build time to stderr in the pinned
wheel), fully buffered when the stream is a pipe, so the buffers are
flushed into /dev/null before file descriptors 1 and 2 are restored. (A
node's one error line on stderr must stay one line.)
"""
from __future__ import annotations

import ctypes
import os
import sys
import tempfile
import threading
from contextlib import contextmanager

_libc = ctypes.CDLL(None)
_redirecting = threading.RLock()   # one redirection of descriptors 1 and 2 at a time: each restores what it saved


def flush_std_streams() -> None:
    """Flush sys.stdout and sys.stderr; either is None when its descriptor was closed at start (``>&-``)."""
    for stream in (sys.stdout, sys.stderr):
        if stream is not None:
            stream.flush()


def fill_closed_std_fds() -> None:
    """A closed descriptor 1 or 2 (``>&-``) opened on /dev/null for good: else the next file opened takes its
    number and C-level prints (PyBullet's "argv[0]=") land in that file."""
    for fd in (1, 2):
        try:
            os.fstat(fd)
        except OSError:
            null = os.open(os.devnull, os.O_WRONLY)
            if null != fd:
                os.dup2(null, fd)
                os.close(null)


@contextmanager
def quiet_c_stdout():
    """Send file descriptors 1 and 2 to /dev/null for the duration of the block."""
    fill_closed_std_fds()   # before the target is opened: it would take a closed descriptor's number
    with open(os.devnull, "wb") as null, _redirected(null.fileno()):
        yield


@contextmanager
def _redirected(target: int):
    """File descriptors 1 and 2 on ``target`` for the duration of the block, C stdio flushed before they return."""
    with _redirecting:
        flush_std_streams()
        saved = {fd: os.dup(fd) for fd in (1, 2)}
        try:
            for fd in saved:
                os.dup2(target, fd)
            yield
        finally:
            _libc.fflush(None)
            for fd, copy in saved.items():
                os.dup2(copy, fd)
                os.close(copy)


@contextmanager
def c_output_into(sink: list[str]):
    """Send file descriptors 1 and 2 into a temporary file for the duration of the block; what was written there
    (C-level prints: PyBullet's b3Error, whose text ends without a newline) is appended to ``sink`` at its end."""
    fill_closed_std_fds()
    with tempfile.TemporaryFile() as f:
        try:
            with _redirected(f.fileno()):
                yield
        finally:
            f.seek(0)
            sink.append(f.read().decode("utf-8", errors="replace"))

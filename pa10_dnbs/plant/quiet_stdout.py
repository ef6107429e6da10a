"""Keep PyBullet's C-level prints ("pybullet build time", "argv[0]=") off stdout.

They are written with C stdio, fully buffered when stdout is a pipe, so the
buffer is flushed into /dev/null before file descriptor 1 is restored.
"""
from __future__ import annotations

import ctypes
import os
import sys
from contextlib import contextmanager

_libc = ctypes.CDLL(None)


@contextmanager
def quiet_c_stdout():
    """Send file descriptor 1 to /dev/null for the duration of the block."""
    sys.stdout.flush()
    saved = os.dup(1)
    try:
        with open(os.devnull, "wb") as null:
            os.dup2(null.fileno(), 1)
        yield
    finally:
        _libc.fflush(None)
        os.dup2(saved, 1)
        os.close(saved)

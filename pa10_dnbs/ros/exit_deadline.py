"""An exit deadline that works while the main thread holds the GIL: after ``seconds``, ``_exit(code)``.

A node's ``close()`` (and, before the nodes stopped tearing rclpy down,
destroying endpoints and ``rclpy_logging_fini``: a graph update stuck on a
shared-memory port, ``runtime.py``) can block in C with the GIL held. Then
no Python thread and no Python signal handler can run, and ``signal.alarm``
can only kill the process (exit -14). A POSIX
timer with SIGEV_THREAD makes glibc call libc's ``_exit(code)`` on a thread of
its own: no Python, no GIL. Linux with glibc; elsewhere ``arm`` returns None
and the caller falls back to ``signal.alarm``.
"""
from __future__ import annotations

import ctypes
import ctypes.util

CLOCK_MONOTONIC = 1
SIGEV_THREAD = 2


class _SigEvent(ctypes.Structure):  # struct sigevent (glibc, 64 bytes)
    _fields_ = [("sigev_value", ctypes.c_void_p), ("sigev_signo", ctypes.c_int), ("sigev_notify", ctypes.c_int),
                ("sigev_notify_function", ctypes.c_void_p), ("sigev_notify_attributes", ctypes.c_void_p),
                ("_pad", ctypes.c_int * 8)]


class _TimeSpec(ctypes.Structure):
    _fields_ = [("tv_sec", ctypes.c_long), ("tv_nsec", ctypes.c_long)]


class _ITimerSpec(ctypes.Structure):
    _fields_ = [("it_interval", _TimeSpec), ("it_value", _TimeSpec)]


def _libc():
    """The C library holding timer_create: the process's own (glibc >= 2.34), else librt; None if neither."""
    libc = ctypes.CDLL(None, use_errno=True)
    if hasattr(libc, "timer_create"):
        return libc
    rt = ctypes.util.find_library("rt")
    lib = ctypes.CDLL(rt) if rt else None
    return lib if lib is not None and hasattr(lib, "timer_create") else None


class ExitDeadline:
    """One armed deadline; ``cancel()`` disarms it."""

    def __init__(self, libc, timer: ctypes.c_void_p):
        self._libc, self._timer = libc, timer

    def cancel(self) -> None:
        if self._timer is not None:
            self._libc.timer_delete(self._timer)
            self._timer = None


def arm(seconds: float, code: int) -> ExitDeadline | None:
    """End the process with exit status ``code`` (0..255) after ``seconds`` [s] unless cancelled first;
    None where POSIX SIGEV_THREAD timers are not available."""
    if not 0 <= code <= 255 or not seconds > 0:
        raise ValueError(f"need 0 <= code <= 255 and seconds > 0, got {code}, {seconds}")
    try:
        libc = _libc()
    except OSError:
        return None
    if libc is None or ctypes.sizeof(_SigEvent) != 64:
        return None
    ev = _SigEvent(sigev_value=code or None, sigev_notify=SIGEV_THREAD,  # _exit(int) reads the value's low bits
                   sigev_notify_function=ctypes.cast(libc._exit, ctypes.c_void_p).value)
    timer = ctypes.c_void_p()
    if libc.timer_create(CLOCK_MONOTONIC, ctypes.byref(ev), ctypes.byref(timer)) != 0:
        return None
    whole = int(seconds)
    spec = _ITimerSpec(it_value=_TimeSpec(whole, int(round((seconds - whole) * 1e9))))
    if libc.timer_settime(timer, 0, ctypes.byref(spec), None) != 0:
        libc.timer_delete(timer)
        return None
    return ExitDeadline(libc, timer)

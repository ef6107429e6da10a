"""A CPython 3.11 race in the local process pool, kept off the user's screen.

When a worker dies, the pool's manager thread fails every pending future with BrokenProcessPool
(``terminate_broken``). A stop that cancelled some of them just before (Ctrl-C, or ``timeout``'s signal to the
command an instant ahead of the one to its group, which ends the workers) makes that ``set_exception`` raise
InvalidStateError in the thread, and Python prints its traceback on stderr under the stop's one line. CPython
fixed it in 3.12 (gh-107219: the error is ignored there). The future is done either way; the traceback is noise.
"""
from __future__ import annotations

import threading
from concurrent.futures import InvalidStateError
from concurrent.futures.process import _ExecutorManagerThread

_installed: list = []   # the hook this one passes everything else to, once installed


def quiet_cancelled_future_race() -> None:
    """Install (once per process) a ``threading.excepthook`` that drops that InvalidStateError of a process pool's
    manager thread and hands every other exception to the hook it replaced."""
    if not _installed:
        _installed.append(threading.excepthook)
        threading.excepthook = _hook


def _hook(args) -> None:
    if issubclass(args.exc_type, InvalidStateError) and isinstance(args.thread, _ExecutorManagerThread):
        return
    _installed[0](args)

"""CPython 3.11's process-pool manager thread raises InvalidStateError when it fails a future a stop cancelled
meanwhile (gh-107219, fixed in 3.12): its traceback came under `study`'s one stop line once in the full suite
(test_timeout_signal.py). The study's hook drops exactly that, and hands anything else on."""
from __future__ import annotations

import threading
from concurrent.futures import InvalidStateError, ProcessPoolExecutor

from pa10_dnbs.study import pool_race


def _args(exc: BaseException, thread: threading.Thread):
    return threading.ExceptHookArgs((type(exc), exc, None, thread))


def test_the_race_in_the_managers_thread_is_dropped_and_the_rest_handed_on(monkeypatch):
    handed_on = []
    monkeypatch.setattr(pool_race, "_installed", [])
    monkeypatch.setattr(threading, "excepthook", lambda args: handed_on.append(str(args.exc_value)))
    with ProcessPoolExecutor(max_workers=1) as pool:
        assert pool.submit(abs, -1).result() == 1
        manager = pool._executor_manager_thread
        pool_race.quiet_cancelled_future_race()
        pool_race.quiet_cancelled_future_race()   # once per process: the hook it hands on to is not itself
        assert threading.excepthook is pool_race._hook
        threading.excepthook(_args(InvalidStateError("CANCELLED: <Future state=cancelled>"), manager))
        threading.excepthook(_args(ValueError("a real fault"), manager))       # another error of that thread
        threading.excepthook(_args(InvalidStateError("elsewhere"), threading.current_thread()))  # another thread
    assert handed_on == ["a real fault", "elsewhere"]

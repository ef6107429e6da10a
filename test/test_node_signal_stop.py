"""A node's SIGINT / SIGTERM handler takes no lock (``ros/runtime.py``: ``SignalStop``, ``stop_on_signal``).

A Python signal handler runs between two bytecodes of the main thread; when that thread is inside
``remove_done_callback`` of the stop future (``spin_until_future_complete`` adds and removes one on every
slice), the future's lock is held, and a handler that called ``set_result`` waited for it for ever: a wire
monitor that had completed hung in its handler until the launcher's SIGKILL (CI, once)."""
from __future__ import annotations

import signal
import threading
import time

import pytest

rclpy = pytest.importorskip("rclpy")

from pa10_dnbs.ros.runtime import SignalStop, spin_until, stop_on_signal  # noqa: E402


def test_the_handler_returns_while_the_stop_futures_lock_is_held():
    stop = SignalStop()
    handler = stop_on_signal(stop)
    returned = threading.Event()

    def main_thread_inside_remove_done_callback():
        with stop._lock:  # what rclpy's Future.remove_done_callback holds when the signal arrives
            handler(signal.SIGINT, None)
        returned.set()

    threading.Thread(target=main_thread_inside_remove_done_callback, daemon=True).start()
    assert returned.wait(5.0), "the handler waited for the future's lock"
    assert stop.done() and stop.result() == "SIGINT"
    handler(signal.SIGTERM, None)  # a second signal changes nothing
    assert stop.result() == "SIGINT"


def test_a_spin_loop_sees_the_request_within_a_slice():
    from rclpy.experimental import EventsExecutor

    context = rclpy.Context()
    rclpy.init(context=context)
    try:
        executor = EventsExecutor(context=context)
        stop = SignalStop()
        t0 = time.monotonic()
        timer = threading.Timer(0.3, stop_on_signal(stop), args=(signal.SIGTERM, None))
        timer.start()
        spin_until(executor, stop, stop)
        assert 0.25 < time.monotonic() - t0 < 2.0
        assert stop.result() == "SIGTERM"
        executor.shutdown()
    finally:
        rclpy.shutdown(context=context)

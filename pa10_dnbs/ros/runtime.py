"""Process plumbing shared by the nodes: init, spin, READY line, clean exit.

Two workarounds for the rclpy 7.1.6 wheel:
- ``EventsExecutor.spin()`` busy-loops, so nodes spin with
  ``spin_until_future_complete`` in short slices instead;
- ``Node.destroy_node()`` sometimes never returns under load (see
  ``_release_entities``), so teardown releases the endpoints itself and a
  node process leaves with ``exit_process``: no interpreter finalization,
  where the node handle would be destroyed the same way.
A node's rclpy teardown (after ``close()`` wrote its files) that hangs in C
is cut short after 5 s by ``exit_deadline`` with the node's own exit code,
its stacks in the log.
rclpy's own signal handling is off (it raises KeyboardInterrupt wherever the
interpreter is, including inside callbacks run by the C++ executor): SIGINT
and SIGTERM complete a ``stop`` future that every spin loop checks; the node
then tears down and exits 0. A Python handler runs only when the main thread
is back in Python, so a node stuck in C code ignores SIGINT: SIGUSR1 makes
``faulthandler`` (C level, no GIL needed) write every thread's Python stack
into the node's log, and the launcher sends it to a node that is still
running 5 s after SIGINT, before SIGTERM (``kill -USR1 PID`` does it by hand).
"""
from __future__ import annotations

import faulthandler
import gc
import os
import signal
import sys
import threading
from typing import Callable, NoReturn

import rclpy
from rclpy.executors import ExternalShutdownException
from rclpy.experimental import EventsExecutor
from rclpy.task import Future

from . import exit_deadline
from .params import ParameterError

SLICE_S = 0.2  # longest a spin call runs before the stop future is checked again
# Exceptions that ended run_node. A failed start-up's traceback holds the half-built node; freeing it
# destroys its rcl handle, which can spin forever with the GIL held: it is kept until the teardown has armed
# its exit deadline (``_rclpy_teardown``). Those of a built node are kept until the process ends, as the
# node is (see ``exit_process``).
_KEPT_EXCEPTIONS: list[BaseException] = []
TEARDOWN_LIMIT_S = 5.0  # a close() or an rclpy teardown that takes longer is cut short
TEARDOWN_DUMP_LEAD_S = 0.5  # the stacks of a hung rclpy teardown are written this long before it is cut short


def spin_until(executor, future: Future, stop: Future) -> None:
    """Spin until ``future`` or ``stop`` is done."""
    while not future.done() and not stop.done():
        executor.spin_until_future_complete(future, timeout_sec=SLICE_S)


def announce_ready(name: str) -> None:
    """The line launchers and tests wait for."""
    print(f"READY {name}", flush=True)


def run_node(make_node: Callable[[], "rclpy.node.Node"], args=None) -> int:
    """Create the node and spin it until SIGINT or SIGTERM (or its own ``loop`` returns); return the exit code.

    ``make_node`` builds the node after ``rclpy.init``; the node may define
    ``exit_code`` (int), ``loop(executor, stop)`` (its own spin loop, which
    must return once ``stop`` is done) and ``close()`` (write files, report).
    """
    rclpy.init(args=args, signal_handler_options=rclpy.signals.SignalHandlerOptions.NO)
    stop = Future()

    def on_signal(signum, _frame):
        if not stop.done():
            stop.set_result(signal.Signals(signum).name)

    signal.signal(signal.SIGINT, on_signal)
    signal.signal(signal.SIGTERM, on_signal)
    faulthandler.register(signal.SIGUSR1, file=sys.stderr, all_threads=True)  # where a stuck node is stuck
    node = None
    executor = EventsExecutor()
    code = 0
    try:
        node = make_node()
        executor.add_node(node)
        if hasattr(node, "loop"):
            node.loop(executor, stop)
        else:
            spin_until(executor, stop, stop)
        code = getattr(node, "exit_code", 0)
    except (KeyboardInterrupt, ExternalShutdownException) as exc:
        _KEPT_EXCEPTIONS.append(exc)
        code = 0
    except (ParameterError, FileExistsError) as exc:  # the user's input: one line, no traceback
        # kept, not freed at the end of this clause: a half-built node's handle must not be destroyed before
        # the exit deadline is armed (seen once: a plant that rejected a parameter spun here for 10 min)
        _KEPT_EXCEPTIONS.append(exc)
        print(f"FAILED {exc}", file=sys.stderr, flush=True)
        code = 2
    except Exception as exc:  # a node that fails says why and exits non-zero
        _KEPT_EXCEPTIONS.append(exc)
        print(f"FAILED {type(exc).__name__}: {exc}", file=sys.stderr, flush=True)
        import traceback

        traceback.print_exc()
        code = 1
    finally:
        # close(): the node's own files and report. A hang there is a failure: the watchdog thread exits 3
        # (it needs the GIL), SIGALRM (default action: terminate) backs it up.
        watchdog = _arm_teardown_watchdog(code)
        signal.alarm(int(TEARDOWN_LIMIT_S) + 2)
        if node is not None and hasattr(node, "close"):
            try:
                node.close()
            except Exception as exc:  # pragma: no cover
                print(f"close failed: {exc}", file=sys.stderr)
                code = code or 1
        signal.alarm(0)
        watchdog.cancel()
        _rclpy_teardown(node, executor, code)
    return code


def exit_process(code: int) -> NoReturn:
    """End a node's process with ``code`` once ``run_node`` has torn it down, skipping the interpreter's
    finalization.

    The node handle is never destroyed: ``destroy_node()``, and the garbage collection of the handle at
    finalization, can spin forever in ``destroy_when_not_in_use()`` with the GIL held (the rclpy 7.1.6
    wheel; seen as a node killed by the teardown's SIGALRM, and, at finalization where the signal handlers
    are back to their defaults, as a controller SIGTERMed by the launcher after its STATS). Files are
    written and closed by ``close()``, the endpoints released and the context shut down before this is
    called. The DDS participant's shared-memory files in /dev/shm stay behind: the launcher removes them
    (``launch/shm_cleanup.py``), as it does for a killed node.
    """
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(code)


def _release_entities(node) -> None:
    """Destroy the node's endpoints one by one instead of ``Node.destroy_node()``.

    Under load, ``destroy_node()`` sometimes never returns in the rclpy 7.1.6
    wheel: its final ``destroy_when_not_in_use()`` on the node handle spins
    with the GIL held. The endpoints (and so the DDS readers and writers) are
    released here; the node handle itself goes with the process.
    """
    for pub in list(node.publishers):
        node.destroy_publisher(pub)
    for sub in list(node.subscriptions):
        node.destroy_subscription(sub)
    for timer in list(node.timers):
        node.destroy_timer(timer)
    for srv in list(node.services):
        node.destroy_service(srv)
    for sub in getattr(node, "polled", []):  # polled.py: subscriptions outside the executor
        sub.destroy()


def _rclpy_teardown(node, executor, code: int) -> None:
    """Release the executor, the endpoints and the context, within TEARDOWN_LIMIT_S.

    The node's work is done and written by now. Under load these rclpy calls can block in C with the GIL
    held (seen: ``rclpy_logging_fini`` in ``try_shutdown``, ``destroy_service``, a subscription's
    ``destroy``), where neither a Python thread nor a Python signal handler can run. So the limit is an
    ``exit_deadline`` (a libc thread calls ``_exit(code)``: the node keeps its own exit code), and
    ``faulthandler`` writes every thread's stack into the log just before it ("Timeout (...)!" and the
    stacks: where the teardown hung).
    """
    deadline = exit_deadline.arm(TEARDOWN_LIMIT_S, code if 0 <= code <= 255 else 1)
    if deadline is None:  # no POSIX timer threads here: SIGALRM ends a hung teardown (exit -14)
        signal.alarm(int(TEARDOWN_LIMIT_S) + 2)
    faulthandler.dump_traceback_later(TEARDOWN_LIMIT_S - TEARDOWN_DUMP_LEAD_S, file=sys.stderr)
    if node is None and _KEPT_EXCEPTIONS:
        # the constructor failed: its half-built node goes now, under the deadline. Freeing it destroys the
        # DDS participant (the context's last node) and so its shared-memory files, and can hang in C.
        _KEPT_EXCEPTIONS.clear()
        gc.collect()
    if node is not None:
        executor.remove_node(node)
    executor.shutdown()
    if node is not None:
        _release_entities(node)
    rclpy.try_shutdown()
    faulthandler.cancel_dump_traceback_later()
    if deadline is None:
        signal.alarm(0)
    else:
        deadline.cancel()


def _arm_teardown_watchdog(code: int) -> threading.Timer:
    def expire():
        print(f"teardown hung for {TEARDOWN_LIMIT_S:g} s; exiting", file=sys.stderr, flush=True)
        os._exit(code if code else 3)

    timer = threading.Timer(TEARDOWN_LIMIT_S, expire)
    timer.daemon = True
    timer.start()
    return timer

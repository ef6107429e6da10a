"""Process plumbing shared by the nodes: init, spin, READY line, clean exit.

``EventsExecutor.spin()`` busy-loops in the rclpy 7.1.6 wheel, so nodes spin
with ``spin_until_future_complete`` and a long timeout instead (1e10 s
overflows and returns at once). rclpy's own signal handlers wake the executor:
SIGINT raises KeyboardInterrupt, SIGTERM ExternalShutdownException; the node
then exits 0.
"""
from __future__ import annotations

import os
import sys
import threading
from typing import Callable

import rclpy
from rclpy.executors import ExternalShutdownException
from rclpy.experimental import EventsExecutor
from rclpy.task import Future

FOREVER_S = 1e9


def announce_ready(name: str) -> None:
    """The line launchers and tests wait for."""
    print(f"READY {name}", flush=True)


def run_node(make_node: Callable[[], "rclpy.node.Node"], args=None) -> int:
    """Create the node, spin until it sets ``node.done`` or a signal arrives; return the exit code.

    ``make_node`` builds the node after ``rclpy.init``; the node may define
    ``done`` (a Future), ``exit_code`` (int), ``loop(executor)`` (its own spin
    loop) and ``close()`` (flush files before shutdown).
    """
    rclpy.init(args=args)
    stop = Future()
    node = None
    executor = EventsExecutor()
    code = 0
    try:
        node = make_node()
        executor.add_node(node)
        done = getattr(node, "done", None) or Future()
        done.add_done_callback(lambda _: stop.set_result("done") if not stop.done() else None)
        if hasattr(node, "loop"):
            node.loop(executor, stop)
        else:
            executor.spin_until_future_complete(stop, timeout_sec=FOREVER_S)
        code = getattr(node, "exit_code", 0)
    except (KeyboardInterrupt, ExternalShutdownException):
        code = 0
    except Exception as exc:  # a node that fails says why and exits non-zero
        print(f"FAILED {type(exc).__name__}: {exc}", file=sys.stderr, flush=True)
        import traceback

        traceback.print_exc()
        code = 1
    finally:
        # Teardown can spin forever inside Node.destroy_node() when the events
        # executor still holds a handle (seen with the 7.1.6 wheel): detach the
        # node first, and hard-exit if teardown still hangs.
        _arm_teardown_watchdog(code)
        if node is not None and hasattr(node, "close"):
            try:
                node.close()
            except Exception as exc:  # pragma: no cover
                print(f"close failed: {exc}", file=sys.stderr)
                code = code or 1
        if node is not None:
            executor.remove_node(node)
        executor.shutdown()
        if node is not None:
            node.destroy_node()
        rclpy.try_shutdown()
    return code


TEARDOWN_LIMIT_S = 5.0


def _arm_teardown_watchdog(code: int) -> None:
    def expire():
        print(f"teardown hung for {TEARDOWN_LIMIT_S:g} s; exiting", file=sys.stderr, flush=True)
        os._exit(code if code else 3)

    timer = threading.Timer(TEARDOWN_LIMIT_S, expire)
    timer.daemon = True
    timer.start()

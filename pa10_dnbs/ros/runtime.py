"""Process plumbing shared by the nodes: init, spin, READY line, clean exit.

A workaround for the rclpy 7.1.6 wheel: ``EventsExecutor.spin()`` busy-loops, so nodes spin with
``spin_until_future_complete`` in short slices instead.

No rclpy or DDS call after ``close()``: once the node has written its files, the process leaves with
``exit_process`` (``os._exit``), without destroying its endpoints, its node or its context, and without
interpreter finalization. Each of those calls publishes a graph update (``ros_discovery_info``) to every
other participant through Fast DDS's shared-memory ports, with the GIL held; a port whose interprocess
mutex was left locked by a process that ended while one of its threads held it (every node ends with
``_exit``, its Fast DDS threads still running) costs each such publish a 1 s lock timeout. With ~20
endpoints per node that was the "hang" of ``destroy_node()``, of ``destroy_service``, of a subscription's
``destroy`` and of ``rclpy_logging_fini`` (which destroys the node's /rosout publisher) seen under load
(caught with gdb: the main thread in ``SharedMemManager::Port::try_push`` on a mutex whose owner thread no
longer existed; docs/architecture.md). ``close()`` runs under an ``exit_deadline`` (5 s, then ``_exit`` with
the node's code, or 3 when it was 0: a hung close() is a failure), ``faulthandler`` writing the stacks just
before; the launcher names such a node.
rclpy's own signal handling is off (it raises KeyboardInterrupt wherever the
interpreter is, including inside callbacks run by the C++ executor): SIGINT,
SIGTERM and SIGHUP (a hung-up terminal, unless ``nohup`` ignores it:
interrupt.stop_signals) mark a ``stop`` future (``SignalStop``) that every spin loop checks;
the node then closes and exits 0. The handler only sets an attribute: it runs
between two bytecodes of the main thread, which may hold the future's lock
(``spin_until_future_complete`` adds and removes a done callback), and
``set_result`` there waited for that lock for ever (seen once in a fresh-clone
CI run: a wire monitor that had completed, stuck in its SIGINT handler until
SIGKILL). A Python handler runs only when the main thread
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
from typing import Callable, NoReturn

import rclpy
from rclpy.exceptions import InvalidParameterTypeException, InvalidParameterValueException
from rclpy.executors import ExternalShutdownException
from rclpy.experimental import EventsExecutor
from rclpy.task import Future

from . import exit_deadline
from ..interrupt import LAUNCHER_PID_ENV, signal_on_parent_death, stop_signals
from ..wire.robot_interface import RobotFault
from .param_overrides import bad_param_override, param_rules
from .params import ParameterError, params_help
from .shm_cleanup import remove_stale, shm_files
from .ready import GraphNotReady

SLICE_S = 0.2  # longest a spin call runs before the stop future is checked again
# Exceptions that ended run_node. A failed start-up's traceback holds the half-built node; freeing it
# destroys its rcl handle (and DDS participant), which can block in C with the GIL held: it is kept until
# ``_close`` has armed its exit deadline. Those of a built node are kept until the process ends, as the
# node is (see ``exit_process``).
_KEPT_EXCEPTIONS: list[BaseException] = []
TEARDOWN_LIMIT_S = 5.0  # a close() (or the freeing of a half-built node) that takes longer is cut short
TEARDOWN_DUMP_LEAD_S = 0.5  # the stacks of a hung close() are written this long before it is cut short


def _init_rcl(args) -> str | None:
    """rclpy.init with ``args``; None, or why rcl refused its ``--ros-args`` (one line: a ``-p`` value that is not
    YAML, an unknown argument). rcl's own log line about it is kept off stderr: the caller says it once."""
    from rclpy._rclpy_pybind11 import RCLError, UnknownROSArgsError

    saved, quiet = os.dup(2), os.open(os.devnull, os.O_WRONLY)
    os.dup2(quiet, 2)
    try:
        rclpy.init(args=args, signal_handler_options=rclpy.signals.SignalHandlerOptions.NO)
    except UnknownROSArgsError as exc:
        return f"unknown ROS arguments {exc}"
    except RCLError as exc:
        why = str(exc).removeprefix("failed to initialize rcl: ").split(". Error:")[0].split(", at /")[0]
        if "parameter override" in why:
            why += " (not a YAML value: quote it, e.g. -p 'name:=\"text:\"')"
        return why
    finally:
        os.dup2(saved, 2)
        os.close(saved)
        os.close(quiet)
    return None


def bad_remap(argv) -> str | None:
    """Why a ``-r __ns:=NS`` or ``-r __node:=NAME`` rule of ``argv`` names no valid namespace or node name, else
    None: rcl takes ``/pa10/`` and fails only when the node is made, as a traceback saying "node name must not
    start with a number" (rclpy's own validators say what is wrong)."""
    from rclpy.exceptions import NameValidationException
    from rclpy.validate_namespace import validate_namespace
    from rclpy.validate_node_name import validate_node_name

    for flag, rule in param_rules(argv, ("-r", "--remap")):
        name, sep, value = rule.rpartition(":=")
        check = {"__ns": validate_namespace, "__node": validate_node_name, "__name": validate_node_name}.get(
            name.rpartition(":")[2])
        if sep and check is not None:
            try:
                check(value)
            except NameValidationException as exc:
                return f"remapping '{flag} {rule}': {' '.join(str(exc).split()).removesuffix(' ^')}"
    return None


class SignalStop(Future):
    """The stop request of ``run_node``: done once a signal handler has called ``request`` (lock-free: a plain
    attribute) or ``set_result`` was called. Spin loops see it within ``SLICE_S``."""

    def __init__(self):
        super().__init__()
        self.signal_name: str | None = None

    def request(self, signal_name: str) -> None:
        """From a signal handler: no lock, no callback."""
        self.signal_name = signal_name

    def done(self) -> bool:
        return self.signal_name is not None or super().done()

    def result(self):
        return self.signal_name if self.signal_name is not None else super().result()


def stop_on_signal(stop: SignalStop) -> Callable:
    """The SIGINT / SIGTERM / SIGHUP handler of ``run_node``: marks ``stop`` with the signal's name, taking no lock."""

    def on_signal(signum, _frame):
        if not stop.done():
            stop.request(signal.Signals(signum).name)

    return on_signal


_STOP: list[Future] = []  # the stop future of run_node, for code that runs before a node has its loop


def stop_requested() -> bool:
    """True once SIGINT, SIGTERM or SIGHUP asked the process to stop (usable while a node is being built)."""
    return bool(_STOP) and _STOP[-1].done()


def spin_until(executor, future: Future, stop: Future) -> None:
    """Spin until ``future`` or ``stop`` is done."""
    while not future.done() and not stop.done():
        executor.spin_until_future_complete(future, timeout_sec=SLICE_S)


def _stop_with_launcher(stop: SignalStop) -> None:
    """A node a launcher started (its pid in LAUNCHER_PID_ENV) stops as on Ctrl-C once that launcher dies, also
    by SIGKILL (interrupt.signal_on_parent_death: SIGINT); one whose launcher is gone already stops at once. A
    node started by hand (commands.sh) has no such variable and runs on its own."""
    launcher = os.environ.get(LAUNCHER_PID_ENV, "")
    if launcher.isdigit() and not signal_on_parent_death(signal.SIGINT, int(launcher)):
        stop.request(signal.SIGINT.name)


def announce_ready(name: str) -> None:
    """The line launchers and tests wait for."""
    print(f"READY {name}", flush=True)


def run_node(make_node: Callable[[], "rclpy.node.Node"], args=None, params: dict | None = None) -> int:
    """Create the node and spin it until SIGINT, SIGTERM or SIGHUP (or its own ``loop`` returns); return the exit code.

    ``make_node`` builds the node after ``rclpy.init``; the node may define
    ``exit_code`` (int), ``loop(executor, stop)`` (its own spin loop, which
    must return once ``stop`` is done) and ``close()`` (write files, report).
    ``params``: the node's ``PARAMS``, which ``-h``/``--help`` (before any ``--ros-args``) prints, exit 0, no node
    started.
    """
    argv = list(sys.argv[1:] if args is None else args)
    own = argv[:argv.index("--ros-args")] if "--ros-args" in argv else argv
    if params is not None and ("-h" in own or "--help" in own):
        module = sys.modules[getattr(make_node, "func", make_node).__module__]   # __main__ under python -m
        # importing rclpy made LTTng-UST's /dev/shm/lttng-ust-wait-* (ros/shm_cleanup.py): gone if no one maps them
        remove_stale({f for f in shm_files() if f.startswith("lttng-ust-wait-")}, frozenset({os.getpid()}))
        try:
            print(params_help(f"python -m {getattr(module.__spec__, 'name', module.__name__)}", params), flush=True)
        except BrokenPipeError:   # its reader gone (| head): quiet, as Python's own rule for EPIPE, exit 1
            os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
            return 1
        return 0
    # a -p value rcl cannot read: named before rclpy.init (ros/param_overrides.py); anything else rcl refuses in
    # its --ros-args (an unknown argument): from rclpy.init itself. The user's input: one line, exit 2
    line = list(sys.argv if args is None else args)
    refused = bad_param_override(line) or bad_remap(line) or _init_rcl(args)
    if refused is not None:
        print(f"FAILED {refused}", file=sys.stderr, flush=True)
        return 2
    stop = SignalStop()
    _STOP.append(stop)
    on_signal = stop_on_signal(stop)
    for sig in stop_signals():   # SIGHUP too (the terminal's hang-up reaches every node), unless nohup ignores it
        signal.signal(sig, on_signal)
    _stop_with_launcher(stop)
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
    except (InvalidParameterTypeException, InvalidParameterValueException) as exc:   # rclpy refused a value of its
        # own parameters (-p use_sim_time:=maybe)
        _KEPT_EXCEPTIONS.append(exc)
        print(f"FAILED {' '.join(str(exc).split())}", file=sys.stderr, flush=True)
        code = 2
    except (ParameterError, FileExistsError) as exc:  # the user's input: one line, no traceback
        # kept, not freed at the end of this clause: a half-built node's handle must not be destroyed before
        # the exit deadline is armed (seen once: a plant that rejected a parameter spun here for 10 min)
        _KEPT_EXCEPTIONS.append(exc)
        print(f"FAILED {exc}", file=sys.stderr, flush=True)
        code = 2
    except RobotFault as exc:  # the joint bus's robot broke the interface: one line (docs/your_robot.md)
        _KEPT_EXCEPTIONS.append(exc)
        print(f"ROBOT FAULT: {exc}", file=sys.stderr, flush=True)
        code = 1
    except GraphNotReady as exc:  # what was lacking is the whole story: one line
        _KEPT_EXCEPTIONS.append(exc)
        print(f"FAILED {exc}", file=sys.stderr, flush=True)
        code = 1
    except Exception as exc:  # a node that fails says why and exits non-zero
        _KEPT_EXCEPTIONS.append(exc)
        print(f"FAILED {type(exc).__name__}: {exc}", file=sys.stderr, flush=True)
        import traceback

        traceback.print_exc()
        code = 1
    finally:
        code = _close(node, code)
    return code


def exit_process(code: int) -> NoReturn:
    """End a node's process with ``code`` once ``run_node`` has closed it, skipping the interpreter's
    finalization.

    Nothing of rclpy or DDS is torn down (see the module docstring): destroying an endpoint, the node or the
    context (also at finalization, by the garbage collection of their handles) publishes graph updates
    through the shared-memory ports and can block there with the GIL held. Files are written and closed by
    ``close()`` before this is called. The DDS participant's shared-memory files in /dev/shm stay behind: a
    launcher (its pid in LAUNCHER_PID_ENV) removes them once its nodes are gone (``ros/shm_cleanup.py``), as it
    does for a killed node. A node started without one (by hand, or from the user's own launch file) sweeps as a
    launcher does, its own process not counted: every file whose owner is gone (or is this process) and that no
    other live process maps: no DDS call, non-blocking locks, and an exit deadline in case reading another
    process's /proc maps stalls. A file another node still maps is left to whoever sweeps after it (nodes
    that leave together can each leave some: the next sweep takes them).
    """
    if not os.environ.get(LAUNCHER_PID_ENV):
        sweep_deadline = exit_deadline.arm(TEARDOWN_LIMIT_S, code if 0 <= code <= 255 else 1)
        if sweep_deadline is None:
            signal.alarm(int(TEARDOWN_LIMIT_S) + 2)
        try:
            remove_stale(shm_files(), frozenset({os.getpid()}))
        except (Exception, KeyboardInterrupt) as exc:   # a sweep that fails must not keep the process from leaving
            print(f"shared-memory sweep not finished: {type(exc).__name__} {exc}", file=sys.stderr)
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(code)


def _close(node, code: int) -> int:
    """``node.close()`` (its files and report) under an exit deadline; then nothing more of rclpy or DDS.

    A close() that outlives TEARDOWN_LIMIT_S ends the process (a libc timer thread calls ``_exit``: it works
    while the main thread holds the GIL in C) with ``code``, or 3 when that was 0; ``faulthandler`` writes
    every thread's stack just before ("Timeout (...)!" and the stacks, in the node's log). A node whose
    constructor failed has its half-built node freed here, under the same deadline: that removes its DDS
    participant and so its shared-memory files (the one DDS teardown left; a failed start has no run to lose,
    so no stacks either: under load the freeing can outlast the limit, and the user's one line stays alone).
    Returns the exit code (1 when close() raised).
    """
    limit_code = code if 0 < code <= 255 else (1 if code else 3)
    deadline = exit_deadline.arm(TEARDOWN_LIMIT_S, limit_code)
    if deadline is None:  # no POSIX timer threads here: SIGALRM (default action: terminate) ends a hang
        signal.alarm(int(TEARDOWN_LIMIT_S) + 2)
    if node is not None:  # a failed start's freeing cut short loses nothing: its one line stays the only one
        faulthandler.dump_traceback_later(TEARDOWN_LIMIT_S - TEARDOWN_DUMP_LEAD_S, file=sys.stderr)
    if node is not None and hasattr(node, "close"):
        try:
            node.close()
        except Exception as exc:  # pragma: no cover
            print(f"close failed: {exc}", file=sys.stderr)
            code = code or 1
    if node is None and _KEPT_EXCEPTIONS:
        _KEPT_EXCEPTIONS.clear()
        gc.collect()
    faulthandler.cancel_dump_traceback_later()  # a no-op when none was armed
    if deadline is None:
        signal.alarm(0)
    else:
        deadline.cancel()
    return code

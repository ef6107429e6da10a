"""Ctrl-C for the long commands (docs/tuning.md, "Interrupting"): the command alone decides, its workers do not.

A terminal's Ctrl-C sends SIGINT to every process of the foreground group: the command and its pool workers.

- Pool workers ignore SIGINT (:func:`pool_worker_start`, their pool's initializer; :func:`sigint_blocked` closes
  the window between fork and initializer). A worker interrupted inside multiprocessing's queues can leave a half
  message in a pipe the pool reads forever (the rare hang the old pool had); the parent stops them itself. They
  also die with the command, however it ends (a plain ``kill``, SIGKILL), so none is left behind.
- The command: the first SIGINT raises KeyboardInterrupt (the command stops its work, keeps what is complete,
  says where, exits 130); from then on a second SIGINT ends at once (:func:`two_stage_sigint`): every child is
  killed and reaped, one line (:func:`on_second_sigint` sets it), exit 130, no clean-up that could wait (but
  :func:`before_second_kill`'s: a developer script lets its child command stop its own children first, at most
  about 5 s; a third SIGINT then ends at once). The same
  signal again within ``SAME_STOP_S`` is the same stop (``timeout`` signals the command, then its group).
  SIGTERM (``kill``, ``timeout``, a batch scheduler's cancel) and SIGHUP (the terminal closed, an ssh session
  dropped) are taken as a Ctrl-C (STOP_SIGNALS): no half-written output folder is left behind by them.
- Code that talks to a database (the tune's Optuna storage) or waits on a pool's or a cluster's futures runs
  :func:`deferred`: there the first SIGINT is only noted, and :func:`check` raises KeyboardInterrupt at the next
  safe point (the executor checks every ``POLL_S``), never inside a SQL statement (an interrupted cursor prints
  SQLAlchemy's traceback and can leave the connection unusable) nor inside concurrent.futures' locks (one left
  taken blocks the pool's manager thread, which the interpreter's exit then waits for forever). Pure computation
  may run :func:`immediate` inside it.
- The end: once a command's outputs are in place (:func:`outputs_written`) a Ctrl-C says where they are; after it
  returned (:func:`quiet_end`) one line; once the interpreter finalizes, SIGINT is ignored and the command's exit
  code stands (:func:`_hold_sigint_to_the_end`).
"""
from __future__ import annotations

import atexit
import contextlib
import os
import signal
import sys
import time

EXIT_INTERRUPTED = 130   # 128 + SIGINT, as a shell reports a command ended by Ctrl-C
POLL_S = 0.1            # how often a waiting executor looks at a deferred Ctrl-C
PR_SET_PDEATHSIG = 1    # prctl(2): the signal a process gets when its parent dies (linux/prctl.h)
LAUNCHER_PID_ENV = "PA10_DNBS_LAUNCHER_PID"   # a node's launcher: the node stops when it dies (ros/runtime.py)
#: what stops a command: Ctrl-C, SIGTERM (``kill``, ``timeout``, a batch scheduler's cancel) and SIGHUP (its
#: terminal closed, its ssh session dropped: the shell hangs up its jobs, the command and its children), taken alike
STOP_SIGNALS = (signal.SIGINT, signal.SIGTERM, signal.SIGHUP)
#: the same signal again this soon [s] after the first is the same stop, not a second Ctrl-C: GNU timeout sends
#: its signal (SIGTERM, or SIGINT with ``-s INT``) to the command and then to the command's whole group, two
#: system calls in a row (the handlers' calls 0.015 ms apart at most in 160 tries here, 2 cores loaded; most
#: tries see one call). A terminal sends each Ctrl-C to the group once: a second press 0.1 s or more after the
#: first is a second Ctrl-C.
SAME_STOP_S = 0.1


def stop_signals() -> tuple[int, ...]:
    """The STOP_SIGNALS to catch now: SIGHUP not where it is ignored (``nohup``: the command is to outlive its
    terminal; a launcher leaves it ignored, so its nodes inherit that)."""
    return tuple(sig for sig in STOP_SIGNALS
                 if not (sig == signal.SIGHUP and signal.getsignal(sig) == signal.SIG_IGN))

_second_line = "pa10-dnbs: interrupted again: stopped at once"
_state = {"deferred": 0, "requested": False, "raised": False, "cleanup": None, "before_kill": None}


def pool_worker_start(parent_pid: int) -> None:
    """A pool worker's initializer: it ignores Ctrl-C and SIGHUP (the group's, as the terminal hangs up: the parent
    stops the workers itself), ends on SIGTERM (how the parent stops one; not the handler it inherited) and dies
    with its parent (Linux's PR_SET_PDEATHSIG: SIGKILL
    once the parent is gone), so a command ended by any signal leaves no worker behind; ``parent_pid``: the
    parent's, to catch a parent that died before the request."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGHUP, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    signal.pthread_sigmask(signal.SIG_UNBLOCK, set(STOP_SIGNALS))   # held back while it was forked
    if not signal_on_parent_death(signal.SIGKILL, parent_pid):
        os._exit(0)


def signal_on_parent_death(sig: int, parent_pid: int) -> bool:
    """Have Linux send ``sig`` to this process once its parent dies, by any signal, SIGKILL and the OOM killer
    too (PR_SET_PDEATHSIG; the parent is the thread that forked it: every command forks from its main thread);
    False when the parent, ``parent_pid``, is gone already (it died before the request). True where the
    request is not available (not Linux)."""
    try:
        import ctypes

        libc = ctypes.CDLL(None, use_errno=True)
        libc.prctl(PR_SET_PDEATHSIG, int(sig), 0, 0, 0)
    except (OSError, AttributeError):  # pragma: no cover - not Linux
        return True
    return os.getppid() == parent_pid


@contextlib.contextmanager
def sigint_blocked():
    """The stop signals (SIGINT, SIGTERM, SIGHUP) held back in this thread while workers are forked (they inherit
    the mask, then set their own dispositions); one that came meanwhile is delivered on exit."""
    try:
        old = signal.pthread_sigmask(signal.SIG_BLOCK, set(STOP_SIGNALS))
    except (AttributeError, OSError, ValueError):  # pragma: no cover - not POSIX
        yield
        return
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, old)


def on_second_sigint(line: str, cleanup=None) -> None:
    """The line a second Ctrl-C prints (what stays where); set by a command once it knows. ``cleanup()``: run
    first (after the children are killed), e.g. to remove a half-written output folder; its errors are ignored."""
    global _second_line
    _second_line = line
    _state["cleanup"] = cleanup


def before_second_kill(stop) -> None:
    """``stop()``: run on a second Ctrl-C before the children are killed (errors ignored), for the rest of
    :func:`two_stage_sigint`: a child that has children of its own (a launcher and its nodes) gets to stop them
    its own quick way first."""
    _state["before_kill"] = stop


def child_pids(parent: int | None = None) -> list[int]:
    """Living direct children of ``parent`` (default: this process), from /proc."""
    parent = os.getpid() if parent is None else parent
    pids = []
    for name in os.listdir("/proc"):
        if not name.isdigit():
            continue
        try:
            with open(f"/proc/{name}/stat") as f:
                stat = f.read()
        except OSError:
            continue
        fields = stat[stat.rfind(")") + 2:].split()   # state, ppid, pgrp, ...
        if int(fields[1]) == parent and fields[0] != "Z":
            pids.append(int(name))
    return pids


def kill_children(wait_s: float = 2.0) -> None:
    """SIGKILL every child and reap it (a killed worker must not stay a zombie or an orphan); at most ``wait_s``."""
    deadline = time.monotonic() + wait_s
    while True:
        for pid in child_pids():
            with contextlib.suppress(OSError):
                os.kill(pid, signal.SIGKILL)
        try:
            while (pid := os.waitpid(-1, os.WNOHANG)[0]) != 0:
                pass
        except ChildProcessError:
            return
        if time.monotonic() > deadline:
            return
        time.sleep(0.01)


def _on_stop(handler) -> None:
    """``handler`` for every stop signal (main thread only: ValueError elsewhere)."""
    for sig in stop_signals():
        signal.signal(sig, handler)


def same_stop(first: tuple[int, float] | None, signum: int) -> bool:
    """Whether ``signum`` now is the stop ``first`` = (signal, time.monotonic() [s]) sent again: the same signal
    within ``SAME_STOP_S`` (timeout: to the command, then to its group)."""
    return first is not None and first[0] == signum and time.monotonic() - first[1] < SAME_STOP_S


def _same_stop(signum) -> bool:
    return same_stop(_state.get("first"), signum)


def _second(signum, frame) -> None:
    if _same_stop(signum):
        return   # the same stop sent twice: the first goes on
    stop_first, _state["before_kill"] = _state.get("before_kill"), None   # once: a third Ctrl-C waits for nothing
    if stop_first is not None:
        with contextlib.suppress(Exception):
            stop_first()
    kill_children()
    if _state.get("cleanup") is not None:
        with contextlib.suppress(Exception):
            _state["cleanup"]()
    with contextlib.suppress(Exception):
        os.write(2, ("\n" + _second_line + "\n").encode())
    os._exit(EXIT_INTERRUPTED)


def _first(signum, frame) -> None:
    _on_stop(_second)
    _state["first"] = (signum, time.monotonic())
    _state["requested"] = True
    if not _state["deferred"]:
        _state["raised"] = True
        raise KeyboardInterrupt


def check() -> None:
    """Raise the KeyboardInterrupt of a Ctrl-C noted in :func:`deferred` (once)."""
    if _state["requested"] and not _state["raised"]:
        _state["raised"] = True
        raise KeyboardInterrupt


def take_noted() -> int | None:
    """The signal of a stop noted in :func:`deferred` and not raised yet, taken (:func:`check` raises it no more):
    for code that stops on it its own way (the launcher: its graph not started). None when there is none."""
    if _state["requested"] and not _state["raised"]:
        _state["raised"] = True
        return (_state.get("first") or (signal.SIGINT, 0.0))[0]
    return None


@contextlib.contextmanager
def deferred():
    """Within: the first SIGINT is noted, raised by the next :func:`check` (and at the end of the block)."""
    _state["deferred"] += 1
    try:
        yield
    finally:
        _state["deferred"] -= 1
    check()


@contextlib.contextmanager
def immediate():
    """Within (pure computation inside :func:`deferred`): the first SIGINT raises at once, as outside."""
    depth, _state["deferred"] = _state["deferred"], 0
    try:
        check()
        yield
    finally:
        _state["deferred"] = depth


@contextlib.contextmanager
def two_stage_sigint():
    """Within: the first SIGINT raises KeyboardInterrupt, the second ends the process at once (see the module).
    Outside the main thread: nothing changes."""
    global _second_line
    try:
        previous = {sig: signal.signal(sig, _first) for sig in stop_signals()}
    except ValueError:   # not the main thread
        yield
        return
    _second_line = "pa10-dnbs: interrupted again: stopped at once"
    _state.update(deferred=0, requested=False, raised=False, cleanup=None, before_kill=None, written=None, first=None)
    try:
        yield
    finally:
        for sig, handler in previous.items():
            signal.signal(sig, handler)
        _state.update(deferred=0, requested=False, raised=False, cleanup=None, before_kill=None)


def quiet_start(prog: str = "pa10-dnbs") -> object:
    """While the command's modules load (before it can say anything useful): a SIGINT ends at once with one
    line opening with ``prog`` and exit 130 instead of an import traceback. Returns the previous handler for
    :func:`end_quiet_start`."""
    line = f"{prog}: interrupted while starting, before any work: nothing changed\n".encode()

    def stop(signum, frame):
        with contextlib.suppress(Exception):
            os.write(2, line)
        os._exit(EXIT_INTERRUPTED)
    try:
        return signal.signal(signal.SIGINT, stop)
    except ValueError:   # not the main thread
        return None


def end_quiet_start(previous) -> None:
    if previous is not None:
        with contextlib.suppress(ValueError):
            signal.signal(signal.SIGINT, previous)


def _hold_sigint_to_the_end() -> None:
    """The last exit function (registered when this module loads, before the command's libraries register
    theirs; they run in reverse order): once the command has returned (:func:`quiet_end`) and every exit function
    has run, SIGINT is ignored. The interpreter then resets the handlers it set to the default (``_PySignal_Fini``,
    which leaves an ignored signal ignored) and frees its modules, tens of milliseconds in which a Ctrl-C would end
    the process by the signal itself, without a line (any thread takes a process's signal, so blocking it in this
    one is not enough). Ignored, the command's own exit code stands: its work and its output are complete, as its
    lines said."""
    if _state.get("ended"):
        with contextlib.suppress(ValueError):
            for sig in STOP_SIGNALS:   # SIGTERM and SIGHUP as SIGINT
                signal.signal(sig, signal.SIG_IGN)


atexit.register(_hold_sigint_to_the_end)


AFTER_LINE = ("pa10-dnbs: interrupted while exiting, after the command had finished (the lines above say what it "
              "wrote)")


def _after_output(signum, frame) -> None:
    """A Ctrl-C once the command's outputs are in place: the line that says so (``outputs_written``), 130."""
    if _same_stop(signum):
        return   # the stop that made these outputs, sent twice: its line is said
    for stream in (sys.stdout, sys.stderr):
        with contextlib.suppress(Exception):
            stream.flush()
    kill_children(0.5)
    with contextlib.suppress(Exception):
        os.write(2, ((_state.get("written") or AFTER_LINE) + "\n").encode())
    os._exit(EXIT_INTERRUPTED)


def outputs_written(line: str) -> None:
    """A command's outputs are in place: a Ctrl-C from now on ends it at once with ``line`` (what was written
    where), not with a line that says nothing was written. Outside the main thread: only the line is kept."""
    _state["written"] = line
    with contextlib.suppress(ValueError):
        _on_stop(_after_output)


def written_line() -> str | None:
    """The line of :func:`outputs_written` if the command has called it (cli.py's fallback for a Ctrl-C)."""
    return _state.get("written")


def quiet_end(line: str | None = None) -> None:
    """Once the command has returned: a SIGINT while Python code still runs (threads joined, exit functions)
    ends it at once with one line and exit 130 instead of a traceback from the interpreter's own clean-up; after
    the exit functions it is ignored (:func:`_hold_sigint_to_the_end`) and the command's exit code stands.
    ``line``: that line (default: the outputs' line of :func:`outputs_written`, else ``AFTER_LINE``)."""
    _state["ended"] = True
    if line is not None:
        _state["written"] = line
    with contextlib.suppress(ValueError):
        for sig in stop_signals():   # SIGTERM, SIGHUP too, as a Ctrl-C (their default action: death by the signal)
            signal.signal(sig, _after_output)


def say(line: str) -> None:
    """One line on stderr (the interruption's verdict); none where stderr leads nowhere (a hung-up terminal)."""
    with contextlib.suppress(OSError):
        print(line, file=sys.stderr, flush=True)

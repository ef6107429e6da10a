"""How a developer script ends, whatever stops it: the CLI's rules (pa10_dnbs/interrupt.py) for scripts/*.py.

- Ctrl-C, SIGTERM or SIGHUP: one line, exit 130 (a second Ctrl-C: at once, a child command after its own quick
  stop, 5 s at most; a third: at once); a Ctrl-C also while the modules
  load, once this module is imported (import it before anything heavy, when the script is the process), and
  while the script exits.
- A setting the library refuses (ConfigError): one line naming the script's flag for it, exit 2.
- Its standard output closed early (``| head``): no traceback, exit 1 (Python's own rule for EPIPE).
- A child command (:func:`start_child`): stopped by the script alone, first (:func:`stop_child`,
  :func:`wait_child`; at a second Ctrl-C it gets a second stop before it is killed), and by Linux if the script
  dies.

    import script_main  # noqa: E402  (first)
    ...
    if __name__ == "__main__":
        sys.exit(script_main.run(main, "bench_sim", {"duration_s": "--duration"}))
"""
from __future__ import annotations

import ctypes  # noqa: F401  (loaded before any fork: start_child's preexec_fn then imports nothing)
import os
import signal
import subprocess
import sys
import time
from collections.abc import Callable, Mapping
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from pa10_dnbs import interrupt  # noqa: E402  (the standard library only)

SCRIPTS = Path(__file__).resolve().parent
NOTHING_WRITTEN = "nothing written: run the same command again"


def _prog() -> str | None:
    """The script this process runs (scripts/NAME.py -> NAME), or None (imported by a test or a tool)."""
    main = Path(sys.argv[0]) if sys.argv and sys.argv[0] else None
    return main.stem if main is not None and main.suffix == ".py" and main.resolve().parent == SCRIPTS else None


if (_PROG := _prog()) is not None:   # the script is this process: a Ctrl-C while its modules load is one line too
    interrupt.quiet_start(_PROG)


_children: list[subprocess.Popen] = []   # what start_child started that takes a second stop of its own
_signalled: dict[int, float] = {}        # pid -> time.monotonic() [s] of the last SIGINT this script sent it
FRESH_GAP_S = interrupt.SAME_STOP_S + 0.4   # first and second stop sent together: the child's handler may run late


def start_child(argv: list[str], second_stop: bool = True, **popen) -> subprocess.Popen:
    """``subprocess.Popen(argv, **popen)`` in a process group of its own, so that the script alone stops it
    (:func:`stop_child`: one SIGINT, a first stop to the child, never taken for its second), and sent SIGINT by
    Linux if the script dies (even by SIGKILL), so that it never outlives the script. ``second_stop``: at the
    script's second Ctrl-C the child gets a second SIGINT before it is killed (:func:`_stop_at_once`: a launcher
    stops its nodes and sweeps /dev/shm itself); False: killed at once (pytest, whose second KeyboardInterrupt
    is a traceback)."""
    parent = os.getpid()
    proc = subprocess.Popen(argv, process_group=0, preexec_fn=lambda: _die_with(parent), **popen)
    _signalled.pop(proc.pid, None)   # a pid used again
    if second_stop:
        _children.append(proc)
    return proc


def _sigint(pid: int) -> None:
    try:
        os.kill(pid, signal.SIGINT)
    except OSError:   # gone already
        return
    _signalled[pid] = time.monotonic()


def _stop_at_once(wait_s: float = 5.0) -> None:
    """The script's second Ctrl-C, before its children are killed: each living child of :func:`start_child`
    with ``second_stop`` gets a second stop (a second SIGINT, at least ``SAME_STOP_S`` after the first so that it
    is not taken for the same one), so that a launcher kills its nodes and removes their shared memory itself;
    waits at most ``wait_s`` for them to end. Runs in a signal handler, maybe while the main thread holds a
    Popen's wait lock: reads ``returncode`` and /proc, calls no Popen method."""
    living = sorted({p.pid for p in _children if p.returncode is None} & set(interrupt.child_pids()))
    send_at = {}
    for pid in living:
        if pid in _signalled:   # stopped once already (stop_child): the second stop is due
            send_at[pid] = _signalled[pid] + 1.5 * interrupt.SAME_STOP_S
        else:                   # not stopped yet: this SIGINT is its first stop
            _sigint(pid)
            send_at[pid] = time.monotonic() + FRESH_GAP_S
    for pid in living:
        time.sleep(max(0.0, send_at[pid] - time.monotonic()))
        _sigint(pid)
    deadline = time.monotonic() + wait_s
    while set(living) & set(interrupt.child_pids()) and time.monotonic() < deadline:
        time.sleep(0.02)


def _die_with(parent: int) -> None:
    if not interrupt.signal_on_parent_death(signal.SIGINT, parent):
        os._exit(interrupt.EXIT_INTERRUPTED)   # the script died before the child could ask: it stops at once


def stop_child(*procs: subprocess.Popen, grace_s: float = 60.0) -> None:
    """The script stopped (Ctrl-C, SIGTERM): its children (:func:`start_child`) stopped as by a Ctrl-C, one SIGINT
    each, then SIGKILL to what is left after ``grace_s`` (a launcher stops its graph within it); all reaped."""
    for proc in procs:
        if proc.poll() is None:
            _sigint(proc.pid)
    deadline = time.monotonic() + grace_s
    for proc in procs:
        try:
            proc.wait(timeout=max(0.0, deadline - time.monotonic()))
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()


def wait_child(proc: subprocess.Popen) -> int:
    """``proc``'s exit code; stopped while waiting (KeyboardInterrupt), the child first (:func:`stop_child`)."""
    try:
        return proc.wait()
    except KeyboardInterrupt:
        stop_child(proc)
        raise


def run(main: Callable[[], int], prog: str, names: Mapping[str, str] | None = None,
        interrupted: str = NOTHING_WRITTEN) -> int:
    """``main()``'s exit code, or the one line and code of how it was stopped (the module's list); ``names``:
    the library's setting -> this script's flag (``{"duration_s": "--duration"}``); ``interrupted``: what the
    Ctrl-C line says after "PROG: interrupted; "."""
    from pa10_dnbs.config_error import ConfigError

    again = f"{prog}: interrupted again: stopped at once"
    after = again   # a Ctrl-C while it exits: after its own, or after it finished (below)
    try:   # two_stage_sigint takes over from quiet_start's handler, and gives it back on leaving
        with interrupt.two_stage_sigint():
            interrupt.on_second_sigint(again)
            interrupt.before_second_kill(_stop_at_once)
            try:
                rc = main()
            finally:   # a reader gone (| head) is found here, not in the interpreter's last flush (also --help)
                sys.stdout.flush()
        after = f"{prog}: interrupted while exiting, after the script had finished (the lines above say what it did)"
        return rc
    except KeyboardInterrupt:
        interrupt.say(f"{prog}: interrupted; {interrupted}")
        return interrupt.EXIT_INTERRUPTED
    except ConfigError as exc:
        interrupt.say(f"{prog}: error: {exc.named(names or {})}")
        return 2
    except BrokenPipeError:   # the reader is gone: nothing more to say, and nothing left to flush at exit
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 1
    finally:
        interrupt.quiet_end(after)

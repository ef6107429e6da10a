"""Child processes of the launcher: start, watch their output, stop them politely.

Each child's stdout and stderr go to one log file; a reader thread also
remembers the READY / RUNNING lines the nodes print. Each child's command line
(with the environment that places it on the run's domain) is appended to
``commands.sh`` beside the logs, so a node can be started again by hand as the
launcher started it (docs/graph.md), from the folder where the run's files end
up (:func:`move_commands`). Stopping escalates: SIGINT, then SIGUSR1 (a node
writes its threads' stacks to its log) and SIGTERM after ``grace_int_s``, then
SIGKILL after ``grace_term_s``.
"""
from __future__ import annotations

import os
import shlex
import signal
import subprocess
import threading
import time
from pathlib import Path

from .domain_ids import occupy


COMMANDS_FILE = "commands.sh"
ENV_SHOWN = ("ROS_DOMAIN_ID", "ROS_AUTOMATIC_DISCOVERY_RANGE")  # what places a child on the run's graph


def command_line(argv: list[str], env: dict) -> str:
    """``argv`` as one shell line, prefixed with the ``ENV_SHOWN`` variables of ``env``."""
    prefix = [f"{k}={shlex.quote(env[k])}" for k in ENV_SHOWN if k in env]
    return " ".join(prefix + [shlex.join(argv)])


def move_commands(logs: Path, staged: Path, final: Path) -> None:
    """``logs``'s COMMANDS_FILE with the run folder ``staged`` (where the nodes ran: the output's temporary
    folder) said as ``final`` (where the run's files end up), so that its lines start the nodes again from there."""
    path = logs / COMMANDS_FILE
    if path.is_file():
        path.write_text(path.read_text().replace(str(staged), str(final)))


class ManagedProcess:
    def __init__(self, name: str, argv: list[str], env: dict, log_path: Path):
        self.name = name
        self.argv = argv
        self.log_path = log_path
        self.lines: list[str] = []
        self.progress = 0
        self.progress_lines = 0
        self.worst_abs_error: float | None = None  # from PROGRESS lines that carry it
        with open(log_path.parent / COMMANDS_FILE, "a") as fh:
            fh.write(f"# {name} (log: {log_path.name})\n{command_line(argv, env)} &\n")
        self._log = open(log_path, "w", buffering=1)
        # the domain is no one else's while this process lives (domain_ids.py)
        occupied = (occupy(int(env["ROS_DOMAIN_ID"])),) if "ROS_DOMAIN_ID" in env else ()
        try:
            self.proc = subprocess.Popen(argv, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                                         stdin=subprocess.DEVNULL, text=True, errors="replace", bufsize=1,
                                         pass_fds=occupied)
        finally:
            for fd in occupied:
                os.close(fd)
        self._reader = threading.Thread(target=self._read, name=f"log-{name}", daemon=True)
        self._reader.start()

    def _read(self) -> None:
        # This thread must keep draining the pipe whatever arrives, or the child blocks on a full pipe.
        for line in self.proc.stdout:
            self._log.write(line)
            if line.startswith("PROGRESS "):
                self._on_progress(line.split())
            elif line.startswith(("READY", "RUNNING", "FAILED", "COMPLETE", "RESUMED", "KILLED", "LIVE ")):
                self.lines.append(line.strip())

    def _on_progress(self, fields: list[str]) -> None:
        """``PROGRESS k [worst_abs_error_rad]``: the step the observer has reached, and the worst |e| so far."""
        try:
            self.progress = int(fields[1])
        except (IndexError, ValueError):
            return
        self.progress_lines += 1
        if len(fields) > 2:
            try:
                self.worst_abs_error = float(fields[2])
            except ValueError:
                pass

    def saw(self, prefix: str) -> bool:
        return any(line.startswith(prefix) for line in self.lines)

    def line(self, prefix: str) -> str | None:
        """The first remembered line starting with ``prefix``, or None."""
        return next((line for line in self.lines if line.startswith(prefix)), None)

    @property
    def pid(self) -> int:
        return self.proc.pid

    @property
    def returncode(self) -> int | None:
        return self.proc.poll()

    def tail(self, n: int = 12) -> str:
        if not self._log.closed:
            self._log.flush()
        try:
            return "".join(self.log_path.read_text(errors="replace").splitlines(True)[-n:])
        except OSError:
            return ""

    def close_log(self) -> None:
        self._reader.join(timeout=2)
        self._log.close()


def stop_all(procs: list[ManagedProcess], grace_int_s: float = 5.0, grace_term_s: float = 3.0) -> dict[str, int]:
    """SIGINT every running child, escalate for the stragglers; return each child's exit code.

    A straggler gets SIGUSR1 before SIGTERM: a node then writes every thread's stack into its log
    (``ros/runtime.py``), which says where a node that ignored SIGINT is stuck."""
    for sig, grace in ((signal.SIGINT, grace_int_s), (signal.SIGTERM, grace_term_s), (signal.SIGKILL, 5.0)):
        running = [p for p in procs if p.returncode is None]
        if not running:
            break
        if sig == signal.SIGTERM:
            for p in running:
                try:
                    os.kill(p.pid, signal.SIGUSR1)
                except ProcessLookupError:
                    pass
            time.sleep(0.2)  # the dump is written by a C handler at once
        for p in running:
            try:
                os.kill(p.pid, sig)
            except ProcessLookupError:
                pass
        deadline = time.monotonic() + grace
        while time.monotonic() < deadline and any(p.returncode is None for p in running):
            time.sleep(0.02)
    for p in procs:
        p.proc.wait()
        p.close_log()
    return {p.name: p.returncode for p in procs}


def _descendants(pids: set[int]) -> set[int]:
    """``pids`` and every living process below them (from /proc; a node's own children, if it started any)."""
    parent_of = {}
    for name in os.listdir("/proc"):
        if name.isdigit():
            try:
                with open(f"/proc/{name}/stat") as f:
                    stat = f.read()
            except OSError:
                continue
            parent_of[int(name)] = int(stat[stat.rfind(")") + 2:].split()[1])
    found, grew = set(pids), True
    while grew:
        more = {pid for pid, ppid in parent_of.items() if ppid in found and pid not in found}
        found |= more
        grew = bool(more)
    return found


def kill_now(procs: list[ManagedProcess], wait_s: float = 2.0) -> int:
    """SIGKILL every child and whatever it started, then reap the children (at most ``wait_s``); no grace, no
    logs closed: for a second Ctrl-C, whose process ends right after. Safe inside a signal handler that
    interrupted ``stop_all`` (it reaps with ``os.waitpid``, not with Popen's lock). Returns how many were killed."""
    targets = _descendants({p.pid for p in procs if p.proc.returncode is None})
    for pid in targets:
        try:
            os.kill(pid, signal.SIGKILL)
        except (ProcessLookupError, PermissionError):
            pass
    pending = {p.pid for p in procs if p.proc.returncode is None}
    deadline = time.monotonic() + wait_s
    while pending and time.monotonic() < deadline:
        for pid in list(pending):
            try:
                if os.waitpid(pid, os.WNOHANG)[0] == pid:
                    pending.discard(pid)
            except ChildProcessError:   # reaped already
                pending.discard(pid)
        time.sleep(0.005)
    return len(targets)

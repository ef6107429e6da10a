"""launch_testing-style helpers without the launch package: start the launcher or a node, wait for lines, stop it."""
from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

from pa10_dnbs.supervisor.domain_ids import occupy

REPO = Path(__file__).resolve().parent.parent


def ros_env(domain_id: int) -> dict:
    """Environment of a test's ROS process: its own domain, discovery on this host only."""
    env = {**os.environ, "PYTHONPATH": str(REPO), "PYTHONUNBUFFERED": "1", "ROS_DOMAIN_ID": str(domain_id),
           "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST"}
    env.pop("ROS_LOCALHOST_ONLY", None)
    return env


class Proc:
    """A child process (stdout and stderr merged) whose output lines can be awaited."""

    def __init__(self, argv: list, domain_id: int):
        self.lines: list[str] = []
        self._cond = threading.Condition()
        occupied = occupy(domain_id)  # no lease is granted on the domain while this process (or a child) lives
        try:
            self.proc = subprocess.Popen([str(a) for a in argv], stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                                         text=True, env=ros_env(domain_id), cwd=REPO, pass_fds=(occupied,))
        finally:
            os.close(occupied)
        self._t = threading.Thread(target=self._read, daemon=True)
        self._t.start()

    def _read(self):
        for line in self.proc.stdout:
            with self._cond:
                self.lines.append(line.rstrip("\n"))
                self._cond.notify_all()

    def wait_for(self, pattern: str, timeout: float) -> re.Match:
        rx = re.compile(pattern)
        deadline = time.monotonic() + timeout
        with self._cond:
            while True:
                for line in self.lines:
                    m = rx.search(line)
                    if m:
                        return m
                left = deadline - time.monotonic()
                if left <= 0 or (self.proc.poll() is not None and not self._t.is_alive()):
                    raise AssertionError(f"no line matching {pattern!r}; output:\n" + "\n".join(self.lines))
                self._cond.wait(min(left, 0.2))

    def wait(self, timeout: float) -> int:
        """The exit code; an AssertionError with the output so far when the process outlives ``timeout`` [s]."""
        try:
            rc = self.proc.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            raise AssertionError(f"still running after {timeout:g} s: {' '.join(self.proc.args)}; output so far:\n"
                                 + self.output) from None
        self._t.join(timeout=5)
        return rc

    @property
    def output(self) -> str:
        return "\n".join(self.lines)

    def interrupt(self):
        self.proc.send_signal(signal.SIGINT)

    def kill(self, grace_s: float = 10.0):
        """Stop the process if it still runs: SIGINT first, SIGKILL after ``grace_s`` s."""
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGINT)
            try:
                self.proc.wait(timeout=grace_s)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()


class Launcher(Proc):
    """``pa10-dnbs launch`` as a child process; without figures unless ``figures`` (they cost ~3 s a run;
    the report's figures are tested through ``simulate`` and ``analyse``, which share the writer)."""

    def __init__(self, *args, domain_id: int, figures: bool = False):
        extra = () if figures else ("--no-figures",)
        super().__init__([sys.executable, "-m", "pa10_dnbs.cli", "launch", "--domain-id", domain_id, "--no-progress",
                          *extra, *args], domain_id)

    @classmethod
    def to_end(cls, *args, domain_id: int, timeout: float = 300) -> tuple[int, "Launcher"]:
        """``launch ARGS`` run to its end (stopped whatever happens): (its exit code, the launcher)."""
        la = cls(*args, domain_id=domain_id)
        try:
            rc = la.wait(timeout=timeout)
        finally:
            la.kill()
        return rc, la

    @classmethod
    def beside(cls, other: Proc, *args, domain_id: int, then=None) -> tuple[int, "Launcher", dict, int]:
        """``launch ARGS`` run to its end beside ``other`` (a robot or a rival publisher, started and ready);
        ``then()`` after the launch ended; both stopped whatever happens (``other`` by SIGINT). Returns (the
        launch's exit code, the launcher, its nodes' pids, ``other``'s exit code)."""
        la = cls(*args, domain_id=domain_id)
        try:
            pids = la.node_pids()
            rc = la.wait(timeout=300)
            if then is not None:
                then()
        finally:
            la.kill()
            other.interrupt()
            other_rc = other.wait(timeout=30)
        return rc, la, pids, other_rc

    def node_pids(self) -> dict[str, int]:
        m = self.wait_for(r"launch: domain \d+, \d+ nodes: (.*); observer (\w+)=(\d+)", 60)
        pids = {k: int(v) for k, v in (kv.split("=") for kv in m.group(1).split(", "))}
        pids[m.group(2)] = int(m.group(3))
        return pids

    def wait_running(self, timeout: float = 60) -> dict[str, int]:
        """Wait until the plant is stepping; return the PIDs of the nodes and the observer (wire monitor or recorder)."""
        pids = self.node_pids()
        self.wait_for("launch: plant running", timeout)
        return pids


def alive(pid: int) -> bool:
    try:
        with open(f"/proc/{pid}/stat") as f:
            return f.read().split()[2] != "Z"
    except FileNotFoundError:
        return False


def exit_codes(output: str) -> dict[str, int]:
    m = re.search(r"launch: stopped: ([^;\n]*)", output)
    assert m, output
    return {k: int(v) for k, v in (kv.split("=") for kv in m.group(1).split())}


def assert_no_leftovers(pids, shm_before: set[str], settle_s: float = 20.0) -> None:
    """Post-shutdown check: every child process is gone and no shared-memory file it created is left behind.

    Only new files whose owner is gone count: another graph running on the host at the same time keeps its
    own segments locked and mapped, and is none of this test's business. Its nodes' files between their exit
    and its launcher's clean-up a moment later are not either: a leftover is one still there after
    ``settle_s`` [s].
    """
    from pa10_dnbs.ros.shm_cleanup import shm_files, unused

    alive_now = sorted(str(p) for p in pids if alive(p))
    assert not alive_now, f"processes still alive: {alive_now}"
    deadline = time.monotonic() + settle_s
    # LTTng-UST's lttng-ust-wait-* are the host's, made by the first process that loads rclpy (any ROS process,
    # another test's too) and shared by all: a launcher removes them when no process maps them
    # (test_shm_cleanup.py), but one that another test's process mapped at that moment is none of this test's.
    ours = lambda: {f for f in unused(shm_files() - shm_before) if not f.startswith("lttng-ust-wait-")}  # noqa: E731
    while (leaked := ours()) and time.monotonic() < deadline:
        time.sleep(0.5)
    assert not leaked, f"shared-memory files left behind: {sorted(leaked)}"

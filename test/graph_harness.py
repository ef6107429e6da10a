"""launch_testing-style helpers without the launch package: start the launcher, wait for lines, stop it."""
from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent


class Launcher:
    """``pa10-dnbs launch`` as a child process whose output lines can be awaited."""

    def __init__(self, *args, domain_id: int):
        self.lines: list[str] = []
        self._cond = threading.Condition()
        env = {**os.environ, "PYTHONPATH": str(REPO), "PYTHONUNBUFFERED": "1"}
        self.proc = subprocess.Popen(
            [sys.executable, "-m", "pa10_dnbs.cli", "launch", "--domain-id", str(domain_id), "--no-progress",
             *map(str, args)], stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, env=env, cwd=REPO)
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
        rc = self.proc.wait(timeout=timeout)
        self._t.join(timeout=5)
        return rc

    @property
    def output(self) -> str:
        return "\n".join(self.lines)

    def node_pids(self) -> dict[str, int]:
        m = self.wait_for(r"launch: domain \d+, 9 nodes: (.*); wire_monitor=(\d+)", 60)
        pids = {k: int(v) for k, v in (kv.split("=") for kv in m.group(1).split(", "))}
        pids["wire_monitor"] = int(m.group(2))
        return pids

    def wait_running(self, timeout: float = 60) -> dict[str, int]:
        """Wait until the plant is stepping; return the PIDs of the nodes and the wire monitor."""
        pids = self.node_pids()
        self.wait_for("launch: plant running", timeout)
        return pids

    def interrupt(self):
        self.proc.send_signal(signal.SIGINT)

    def kill(self):
        if self.proc.poll() is None:
            self.proc.kill()
            self.proc.wait()


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

"""A launcher killed outright (SIGKILL: the OOM killer, a CI job's hard stop) takes its nodes with it: each node
stops as on Ctrl-C once its launcher dies (interrupt.signal_on_parent_death, ros/runtime.py). Before, the wire
monitor and the seven joint controllers ran on, orphaned, under SCHED_FIFO where granted."""
from __future__ import annotations

import os
import signal
import sys
import time
from pathlib import Path

import pytest

from graph_harness import Launcher, Proc, alive

pytestmark = pytest.mark.graph  # starts ROS processes

STOPPED_WITHIN_S = 30.0   # a node's close() is cut at 5 s (ros/runtime.py); the rest is a loaded machine's margin


def _children(pid: int) -> list[int]:
    """The processes whose parent is ``pid`` (from /proc)."""
    out = []
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                stat = (entry / "stat").read_text()
            except OSError:
                continue
            if int(stat.rsplit(")", 1)[1].split()[1]) == pid:
                out.append(int(entry.name))
    return out


def _left_running(pids, within_s: float = STOPPED_WITHIN_S) -> list[int]:
    """Those of ``pids`` still alive after ``within_s`` [s] (each then killed, so that none outlives the test)."""
    deadline = time.monotonic() + within_s
    while any(alive(p) for p in pids) and time.monotonic() < deadline:
        time.sleep(0.2)
    left = [p for p in pids if alive(p)]
    for p in left:
        os.kill(p, signal.SIGKILL)
    return left


def test_the_graph_stops_when_its_launcher_is_killed(tmp_path, domain):
    la = Launcher("--mode", "lockstep", "--duration", 60.0, "--out", tmp_path / "run", domain_id=domain)
    pids = {}
    try:
        pids = la.wait_running(timeout=120)
        la.proc.kill()
        la.proc.wait(timeout=10)
    finally:
        left = _left_running(list(pids.values()))
        la.kill()
    assert len(pids) >= 9 and not left, {n: p for n, p in pids.items() if p in left}


def test_the_robot_node_stops_when_its_command_is_killed(domain):
    robot = Proc([sys.executable, "-m", "pa10_dnbs.cli", "robot", "--engine", "mujoco"], domain)
    nodes = []
    try:
        robot.wait_for(r"READY mujoco_robot", 60)
        nodes = _children(robot.proc.pid)
        robot.proc.kill()
        robot.proc.wait(timeout=10)
    finally:
        left = _left_running(nodes)
        robot.kill()
    assert len(nodes) == 1 and not left, (nodes, left)

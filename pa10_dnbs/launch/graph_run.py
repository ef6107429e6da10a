"""Run the whole node graph once: start, wait until ready, run, stop, collect.

Nine node processes (reference, seven joint controllers, plant) and a wire
monitor that records what they send, on a private ROS_DOMAIN_ID with
discovery limited to this host. The launcher only supervises: it never joins
DDS itself, so once its children have exited, every shared-memory segment of
the run is unmapped and a leftover (from a killed node) can be removed.
"""
from __future__ import annotations

import json
import os
import signal
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

from .. import JOINT_NAMES
from .processes import ManagedProcess, stop_all
from .shm_cleanup import fastdds_segments, remove_stale

READY_TIMEOUT_S = 60.0


class GraphFailure(RuntimeError):
    """A node failed, exited early, or the run did not complete."""

    def __init__(self, message: str, interrupted: bool = False):
        super().__init__(message)
        self.interrupted = interrupted


@dataclass
class GraphOptions:
    config_path: Path
    mode: str = "lockstep"
    controller: str = "dnbs"
    duration_s: float = 20.0
    domain_id: int | None = None
    reliability: str = "reliable"
    effort_timeout_s: float = 1.0
    on_missing_effort: str = "hold"
    progress: bool = False
    extra_env: dict = field(default_factory=dict)


@dataclass
class GraphResult:
    stats: dict
    exit_codes: dict[str, int]
    pids: dict[str, int]
    domain_id: int
    wall_total_s: float
    shm_removed: list[str]
    wire_file: Path


class _Stop(BaseException):
    """Raised in the launcher's main thread by SIGINT or SIGTERM."""


def _stop_on_signals() -> dict:
    """SIGINT and SIGTERM stop the graph cleanly, even where the parent shell left SIGINT ignored."""
    def handler(signum, _frame):
        raise _Stop(signal.Signals(signum).name)

    previous = {}
    for signum in (signal.SIGINT, signal.SIGTERM):
        previous[signum] = signal.getsignal(signum)
        signal.signal(signum, handler)
    return previous


def pick_domain_id() -> int:
    """A domain id in 1..101 (valid on every platform), different for concurrent launchers."""
    return 1 + os.getpid() % 101


def node_env(domain_id: int, extra: dict) -> dict:
    env = {**os.environ, "ROS_DOMAIN_ID": str(domain_id), "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST",
           "PYTHONUNBUFFERED": "1", **extra}
    env.pop("ROS_LOCALHOST_ONLY", None)  # deprecated in Jazzy; conflicts with the discovery range
    return env


def _ros_args(node: str, params: dict) -> list[str]:
    args = ["--ros-args", "-r", f"__node:={node}", "-r", "__ns:=/pa10"]
    for k, v in params.items():
        args += ["-p", f"{k}:={v}"]
    return args


def node_commands(opt: GraphOptions, stats_file: Path, wire_file: Path) -> list[tuple[str, list[str]]]:
    """(name, argv) of every process: the wire monitor, the nine nodes, the plant last (it starts
    stepping once the others are matched)."""
    py = [sys.executable, "-m"]
    cfg = str(opt.config_path)
    cmds = [("wire_monitor", py + ["pa10_dnbs.ros.wire_monitor"] + _ros_args("wire_monitor", {
                "config_file": cfg, "duration_s": opt.duration_s, "out_file": str(wire_file)})),
            ("reference", py + ["pa10_dnbs.ros.reference_node"] + _ros_args("reference", {"config_file": cfg}))]
    for j in JOINT_NAMES:
        cmds.append((f"joint_controller_{j}", py + ["pa10_dnbs.ros.joint_controller_node"] + _ros_args(
            f"joint_controller_{j}", {"config_file": cfg, "joint": j, "controller": opt.controller,
                                      "reliability": opt.reliability,
                                      "queue_depth": 1 if opt.mode == "realtime" else 10})))
    cmds.append(("plant", py + ["pa10_dnbs.ros.plant_node"] + _ros_args("plant", {
        "config_file": cfg, "mode": opt.mode, "duration_s": opt.duration_s, "reliability": opt.reliability,
        "effort_timeout_s": opt.effort_timeout_s, "on_missing_effort": opt.on_missing_effort,
        "stats_file": str(stats_file), "min_joint_states_subscribers": 1})))
    return cmds


def run_graph(opt: GraphOptions, workdir: Path, say=print) -> GraphResult:
    """Run the graph; logs go to ``workdir/logs``, the wire record to ``workdir/wire.npz``. Raises GraphFailure.

    The launcher itself never joins DDS: the wire monitor is one of its child processes.
    """
    domain = opt.domain_id if opt.domain_id is not None else pick_domain_id()
    env = node_env(domain, opt.extra_env)
    logs = workdir / "logs"
    logs.mkdir(parents=True, exist_ok=True)
    stats_file = workdir / "plant_stats.json"
    wire_file = workdir / "wire.npz"
    shm_before = fastdds_segments()
    t_start = time.monotonic()
    procs: list[ManagedProcess] = []
    failure: str | None = None
    previous = _stop_on_signals()
    try:
        for name, argv in node_commands(opt, stats_file, wire_file):
            procs.append(ManagedProcess(name, argv, env, logs / f"{name}.log"))
        say(f"launch: domain {domain}, {len(procs) - 1} nodes: " + ", ".join(f"{p.name}={p.pid}" for p in procs[1:])
            + f"; wire_monitor={procs[0].pid}")
        failure = _wait_ready(procs)
        if failure is None:
            say("launch: graph ready (every node printed READY)")
            failure = _watch(procs, opt, say)
    except _Stop as sig:
        failure = f"interrupted ({sig})"
    finally:
        codes = stop_all(procs)
        for signum, handler in previous.items():
            signal.signal(signum, handler)
        shm_removed = remove_stale(fastdds_segments() - shm_before)
    say("launch: stopped: " + " ".join(f"{n}={c}" for n, c in codes.items())
        + (f"; removed {len(shm_removed)} stale shared-memory segments" if shm_removed else ""))
    bad = {n: c for n, c in codes.items() if c != 0}
    if failure is None and bad:
        failure = "nodes exited with non-zero codes: " + ", ".join(f"{n}={c}" for n, c in bad.items())
        for p in procs:
            if p.name in bad:
                failure += f"\n--- last lines of {p.name}'s log ---\n{p.tail(20)}"
    if failure is not None:
        raise GraphFailure(failure, interrupted=failure.startswith("interrupted"))
    stats = json.loads(stats_file.read_text())
    return GraphResult(stats=stats, exit_codes=codes, pids={p.name: p.pid for p in procs}, domain_id=domain,
                       wall_total_s=time.monotonic() - t_start, shm_removed=shm_removed, wire_file=wire_file)


def _describe(p: ManagedProcess) -> str:
    what = f"joint {p.name.rsplit('_', 1)[1]} controller ({p.name})" if p.name.startswith("joint_controller_") else p.name
    return f"{what} exited early with code {p.returncode}\n--- last lines of {p.log_path} ---\n{p.tail()}"


def _wait_ready(procs: list[ManagedProcess]) -> str | None:
    deadline = time.monotonic() + READY_TIMEOUT_S
    while time.monotonic() < deadline:
        for p in procs:
            if p.returncode is not None:
                return _describe(p)
        if all(p.saw("READY") for p in procs):
            return None
        time.sleep(0.05)
    late = [p.name for p in procs if not p.saw("READY")]
    return f"not ready after {READY_TIMEOUT_S:g} s: {', '.join(late)}"


def _watch(procs: list[ManagedProcess], opt: GraphOptions, say) -> str | None:
    monitor, plant = procs[0], procs[-1]
    limit_s = 120.0 + 50.0 * opt.duration_s  # generous: a run slower than 1/50 real time is broken
    deadline = time.monotonic() + limit_s
    bar = None
    n_steps = int(round(opt.duration_s * 1000))
    if opt.progress:
        from tqdm import tqdm

        bar = tqdm(total=n_steps, desc=f"launch {opt.mode} {opt.controller}", unit="step", unit_scale=True)
    announced = False
    try:
        while time.monotonic() < deadline:
            if not announced and plant.saw("RUNNING"):
                say("launch: plant running")
                announced = True
            for p in procs:
                rc = p.returncode
                if rc is None or (p is plant and rc == 0):
                    continue
                return _describe(p)
            if plant.returncode == 0:
                break
            if bar is not None:
                bar.update(max(0, monitor.progress - bar.n))
            time.sleep(0.05)
        else:
            return f"run did not finish within {limit_s:g} s"
        end = time.monotonic() + 10.0  # the last messages may still be in flight
        while not monitor.saw("COMPLETE") and time.monotonic() < end:
            time.sleep(0.05)
        if not monitor.saw("COMPLETE"):
            return "the wire monitor did not receive the whole run (see logs/wire_monitor.log)"
        return None
    finally:
        if bar is not None:
            bar.update(max(0, n_steps - bar.n))
            bar.close()

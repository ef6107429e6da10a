"""Run the whole node graph once: start, wait until ready, run, stop, collect.

Nine processes (reference, seven joint controllers, plant) on a private
ROS_DOMAIN_ID with discovery limited to this host; the launcher's own wire
monitor collects the run from the messages.
"""
from __future__ import annotations

import json
import os
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


def node_commands(opt: GraphOptions, stats_file: Path) -> list[tuple[str, list[str]]]:
    """(name, argv) of every node, the plant last (it starts stepping once the others are matched)."""
    py = [sys.executable, "-m"]
    cfg = str(opt.config_path)
    cmds = [("reference", py + ["pa10_dnbs.ros.reference_node"] + _ros_args("reference", {"config_file": cfg}))]
    for j in JOINT_NAMES:
        cmds.append((f"joint_controller_{j}", py + ["pa10_dnbs.ros.joint_controller_node"] + _ros_args(
            f"joint_controller_{j}", {"config_file": cfg, "joint": j, "controller": opt.controller,
                                      "reliability": opt.reliability})))
    cmds.append(("plant", py + ["pa10_dnbs.ros.plant_node"] + _ros_args("plant", {
        "config_file": cfg, "mode": opt.mode, "duration_s": opt.duration_s, "reliability": opt.reliability,
        "effort_timeout_s": opt.effort_timeout_s, "on_missing_effort": opt.on_missing_effort,
        "stats_file": str(stats_file), "min_joint_states_subscribers": 1})))
    return cmds


def run_graph(opt: GraphOptions, workdir: Path, monitor_factory, say=print) -> tuple[GraphResult, object]:
    """Run the graph; logs go to ``workdir/logs``. Returns (result, monitor). Raises GraphFailure."""
    domain = opt.domain_id if opt.domain_id is not None else pick_domain_id()
    env = node_env(domain, opt.extra_env)
    os.environ["ROS_DOMAIN_ID"] = env["ROS_DOMAIN_ID"]  # the in-process monitor joins the same domain
    os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
    os.environ.pop("ROS_LOCALHOST_ONLY", None)
    logs = workdir / "logs"
    logs.mkdir(parents=True, exist_ok=True)
    stats_file = workdir / "plant_stats.json"
    shm_before = fastdds_segments()
    t_start = time.monotonic()
    monitor = monitor_factory()
    procs: list[ManagedProcess] = []
    failure: str | None = None
    try:
        for name, argv in node_commands(opt, stats_file):
            procs.append(ManagedProcess(name, argv, env, logs / f"{name}.log"))
        say(f"launch: domain {domain}, {len(procs)} nodes: " + ", ".join(f"{p.name}={p.pid}" for p in procs))
        failure = _wait_ready(procs)
        if failure is None:
            say("launch: graph ready (every node printed READY)")
            failure = _watch(procs, opt, monitor, say)
    except KeyboardInterrupt:
        failure = "interrupted (SIGINT)"
    finally:
        codes = stop_all(procs)
        monitor.stop()
        shm_removed = remove_stale(fastdds_segments() - shm_before)
    say("launch: stopped: " + " ".join(f"{n}={c}" for n, c in codes.items())
        + (f"; removed {len(shm_removed)} stale shared-memory segments" if shm_removed else ""))
    bad = {n: c for n, c in codes.items() if c != 0}
    if failure is None and bad:
        failure = "nodes exited with non-zero codes: " + ", ".join(f"{n}={c}" for n, c in bad.items())
    if failure is not None:
        raise GraphFailure(failure)
    stats = json.loads(stats_file.read_text())
    result = GraphResult(stats=stats, exit_codes=codes, pids={p.name: p.pid for p in procs}, domain_id=domain,
                         wall_total_s=time.monotonic() - t_start, shm_removed=shm_removed)
    return result, monitor


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


def _watch(procs: list[ManagedProcess], opt: GraphOptions, monitor, say) -> str | None:
    plant = procs[-1]
    limit_s = 120.0 + 50.0 * opt.duration_s  # generous: a run slower than 1/50 real time is broken
    deadline = time.monotonic() + limit_s
    bar = None
    if opt.progress:
        from tqdm import tqdm

        bar = tqdm(total=monitor.n, desc=f"launch {opt.mode} {opt.controller}", unit="step", unit_scale=True)
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
                bar.update(max(0, monitor.latest_step - bar.n))
            time.sleep(0.05)
        else:
            return f"run did not finish within {limit_s:g} s"
        end = time.monotonic() + 10.0  # the last messages may still be in flight
        while not monitor.complete() and time.monotonic() < end:
            time.sleep(0.05)
        monitor.stop()
        if not monitor.complete():
            return "the wire monitor did not receive the whole run: " + monitor.missing_summary()
        return None
    finally:
        if bar is not None:
            bar.update(max(0, monitor.latest_step - bar.n))
            bar.close()

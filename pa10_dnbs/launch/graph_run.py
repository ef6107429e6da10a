"""Run the whole node graph once: start, wait until ready, run, stop, collect.

Nine node processes (reference, seven joint controllers, plant) and one
observer that records what they send (the wire monitor, or with a bag the
recorder), on a private ROS_DOMAIN_ID with
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
from dataclasses import dataclass
from pathlib import Path

from .. import JOINT_NAMES
from ..topics import CLOCK, JOINT_STATES, ROBOT_DESCRIPTION, effort_topic, reference_topic, state_topic
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
    dt_s: float = 1e-3
    record_bag: Path | None = None   # record every topic into this rosbag2 MCAP bag directory
    force_bag: bool = False


@dataclass
class GraphResult:
    stats: dict
    exit_codes: dict[str, int]
    domain_id: int
    wall_total_s: float
    wire_file: Path | None   # the wire monitor's record; None when the run went into the bag
    bag: Path | None = None


class _StopRequest:
    """Set by SIGINT or SIGTERM; the launcher's loops check it (no exception at an arbitrary point,
    so a signal can neither orphan a child being started nor interrupt the shutdown)."""

    def __init__(self):
        self.signal_name: str | None = None

    def __call__(self, signum, _frame):
        if self.signal_name is None:
            self.signal_name = signal.Signals(signum).name


def _catch_signals(stop: _StopRequest) -> dict:
    """Route SIGINT and SIGTERM to ``stop``, even where the parent shell left SIGINT ignored."""
    previous = {}
    for signum in (signal.SIGINT, signal.SIGTERM):
        previous[signum] = signal.getsignal(signum)
        signal.signal(signum, stop)
    return previous


def pick_domain_id() -> int:
    """A domain id in 1..101 (valid on every platform), different for concurrent launchers."""
    return 1 + os.getpid() % 101


def node_env(domain_id: int) -> dict:
    env = {**os.environ, "ROS_DOMAIN_ID": str(domain_id), "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST",
           "PYTHONUNBUFFERED": "1"}
    env.pop("ROS_LOCALHOST_ONLY", None)  # deprecated in Jazzy; conflicts with the discovery range
    return env


def _ros_args(node: str, params: dict) -> list[str]:
    args = ["--ros-args", "-r", f"__node:={node}", "-r", "__ns:=/pa10"]
    for k, v in params.items():
        args += ["-p", f"{k}:={v}"]
    return args


def graph_topics() -> list[str]:
    """Every topic of the graph as recorder specs ('/name:pkg/msg/Type')."""
    specs = [f"{CLOCK}:rosgraph_msgs/msg/Clock", f"{JOINT_STATES}:sensor_msgs/msg/JointState",
             f"{ROBOT_DESCRIPTION}:std_msgs/msg/String"]
    for j in JOINT_NAMES:
        specs += [f"{state_topic(j)}:sensor_msgs/msg/JointState", f"{effort_topic(j)}:sensor_msgs/msg/JointState",
                  f"{reference_topic(j)}:trajectory_msgs/msg/JointTrajectory"]
    return specs


def _yaml_list(items: list[str]) -> str:
    return "[" + ",".join(f"'{i}'" for i in items) + "]"


def node_commands(opt: GraphOptions, stats_file: Path, wire_file: Path) -> list[tuple[str, list[str]]]:
    """(name, argv) of every process: the wire monitor, the recorder (with --record), the nine nodes,
    the plant last (it starts stepping once the others are matched)."""
    py = [sys.executable, "-m"]
    cfg = str(opt.config_path)
    if opt.record_bag is None:
        cmds = [("wire_monitor", py + ["pa10_dnbs.ros.wire_monitor"] + _ros_args("wire_monitor", {
                    "config_file": cfg, "duration_s": opt.duration_s, "out_file": str(wire_file)}))]
    else:  # the recorder is the observer: the run is rebuilt from the bag
        end_ns = int(round(opt.duration_s / opt.dt_s)) * int(round(opt.dt_s * 1e9))
        custom = [f"controller={opt.controller}", f"mode={opt.mode}", f"duration_s={opt.duration_s!r}",
                  f"reliability={opt.reliability}", f"config_file={cfg}"]
        cmds = [("recorder", py + ["pa10_dnbs.ros.recorder_node"] + _ros_args("recorder", {
            "config_file": cfg, "bag": str(opt.record_bag), "force": str(opt.force_bag).lower(),
            "topics": _yaml_list(graph_topics()), "custom_data": _yaml_list(custom), "end_stamp_ns": end_ns}))]
    cmds.append(("reference", py + ["pa10_dnbs.ros.reference_node"] + _ros_args(
        "reference", {"config_file": cfg, "duration_s": opt.duration_s})))
    for j in JOINT_NAMES:
        cmds.append((f"joint_controller_{j}", py + ["pa10_dnbs.ros.joint_controller_node"] + _ros_args(
            f"joint_controller_{j}", {"config_file": cfg, "joint": j, "controller": opt.controller,
                                      "reliability": opt.reliability,
                                      "queue_depth": 1 if opt.mode == "realtime" else 2000})))
    cmds.append(("plant", py + ["pa10_dnbs.ros.plant_node"] + _ros_args("plant", {
        "config_file": cfg, "mode": opt.mode, "duration_s": opt.duration_s, "reliability": opt.reliability,
        "effort_timeout_s": opt.effort_timeout_s, "on_missing_effort": opt.on_missing_effort,
        "stats_file": str(stats_file), "min_joint_states_subscribers": int(opt.record_bag is None),
        "recorders": int(opt.record_bag is not None)})))
    return cmds


def run_graph(opt: GraphOptions, workdir: Path, say=print) -> GraphResult:
    """Run the graph; logs go to ``workdir/logs``, the wire record to ``workdir/wire.npz`` (or, with
    ``opt.record_bag``, everything into the bag). Raises GraphFailure.

    The launcher itself never joins DDS: the observer is one of its child processes.
    """
    domain = opt.domain_id if opt.domain_id is not None else pick_domain_id()
    env = node_env(domain)
    logs = workdir / "logs"
    logs.mkdir(parents=True, exist_ok=True)
    stats_file = workdir / "plant_stats.json"
    wire_file = workdir / "wire.npz"
    shm_before = fastdds_segments()
    t_start = time.monotonic()
    procs: list[ManagedProcess] = []
    failure: str | None = None
    stop = _StopRequest()
    previous = _catch_signals(stop)
    try:
        for name, argv in node_commands(opt, stats_file, wire_file):
            if stop.signal_name:
                break
            procs.append(ManagedProcess(name, argv, env, logs / f"{name}.log"))
        if not stop.signal_name:
            say(f"launch: domain {domain}, {len(procs) - 1} nodes: "
                + ", ".join(f"{p.name}={p.pid}" for p in procs[1:]) + f"; observer {procs[0].name}={procs[0].pid}")
            failure = _wait_ready(procs, stop)
        if failure is None and not stop.signal_name:
            say("launch: graph ready (every node printed READY)")
            failure = _watch(procs, opt, say, stop)
    finally:
        codes = stop_all(procs)
        shm_removed = remove_stale(fastdds_segments() - shm_before)
        for signum, handler in previous.items():
            signal.signal(signum, handler)
    if stop.signal_name:
        failure = f"interrupted ({stop.signal_name})"
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
    return GraphResult(stats=stats, exit_codes=codes, domain_id=domain, wall_total_s=time.monotonic() - t_start,
                       wire_file=wire_file if opt.record_bag is None else None, bag=opt.record_bag)


def _describe(p: ManagedProcess) -> str:
    what = f"joint {p.name.rsplit('_', 1)[1]} controller ({p.name})" if p.name.startswith("joint_controller_") else p.name
    return f"{what} exited early with code {p.returncode}\n--- last lines of {p.log_path} ---\n{p.tail()}"


def _wait_ready(procs: list[ManagedProcess], stop: _StopRequest) -> str | None:
    deadline = time.monotonic() + READY_TIMEOUT_S
    while time.monotonic() < deadline and not stop.signal_name:
        for p in procs:
            if p.returncode is not None:
                return _describe(p)
        if all(p.saw("READY") for p in procs):
            return None
        time.sleep(0.05)
    if stop.signal_name:
        return None
    late = [p.name for p in procs if not p.saw("READY")]
    return f"not ready after {READY_TIMEOUT_S:g} s: {', '.join(late)}"


def _watch(procs: list[ManagedProcess], opt: GraphOptions, say, stop: _StopRequest) -> str | None:
    monitor, plant = procs[0], procs[-1]
    limit_s = 120.0 + 50.0 * opt.duration_s  # generous: a run slower than 1/50 real time is broken
    deadline = time.monotonic() + limit_s
    bar = None
    n_steps = int(round(opt.duration_s / opt.dt_s))
    if opt.progress:
        from tqdm import tqdm

        bar = tqdm(total=n_steps, desc=f"launch {opt.mode} {opt.controller}", unit="step", unit_scale=True)
    announced = False
    try:
        while time.monotonic() < deadline:
            if stop.signal_name:
                return None
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
        while not monitor.saw("COMPLETE") and time.monotonic() < end and not stop.signal_name:
            time.sleep(0.05)
        if not monitor.saw("COMPLETE") and not stop.signal_name:
            return (f"the {monitor.name} did not receive the whole run\n--- last lines of its log ---\n"
                    + monitor.tail())
        return None
    finally:
        if bar is not None:
            bar.update(max(0, n_steps - bar.n))
            bar.close()

"""Run the whole node graph once: start, wait until ready, run, stop, collect.

Nine node processes (reference, seven joint controllers, plant) and one
observer that records what they send (the wire monitor, or with a bag the
recorder), on a private ROS_DOMAIN_ID with
discovery limited to this host. The launcher only supervises: it never joins
DDS nor loads rclpy, so once its children have exited every shared-memory file
of the run is unmapped, and a leftover (a killed node's Fast DDS segment, the
LTTng-UST wait files) can be removed.
"""
from __future__ import annotations

import json
import math
import os
import signal
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

from .. import JOINT_NAMES
from ..wire.topics import CLOCK, DEFAULT_NS, DIAGNOSTICS, ArmTopics
from ..wire.clock_schedule import DEFAULT_CLOCK_HZ
from .domain_ids import lease_domain
from .processes import ManagedProcess, stop_all
from .shm_cleanup import remove_stale, shm_files

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
    reliability: str | None = None   # per-joint state/effort QoS; None: best_effort in realtime, reliable in lockstep
    real_time_factor: float = 1.0    # realtime: a step of dt_s takes dt_s / real_time_factor of wall time
    deadline_fraction: float = 0.9   # realtime: efforts must arrive within this fraction of the tick
    rt_priority: int = 0             # SCHED_FIFO priority of plant and controllers (0: off)
    effort_timeout_s: float = 1.0
    on_missing_effort: str = "hold"
    progress: bool = False
    dt_s: float = 1e-3
    record_bag: Path | None = None   # record every topic into this rosbag2 MCAP bag directory
    force_bag: bool = False
    restart: str | None = None       # 'resume' or 'fresh': restart a joint controller that died
    max_restarts: int = 3            # per joint
    netns: dict[str, str] = field(default_factory=dict)  # node group -> network namespace (multi-host)
    init_from: Path | None = None    # warm start: a directory of <joint>.npz controller checkpoints
    bag_compression: str = "zstd"    # 'zstd' (MCAP chunks, as `ros2 bag record -s mcap`) or 'none'
    live_port: int | None = None     # serve the live view (Foxglove WebSocket) on this port; 0: a free one
    live_host: str = "127.0.0.1"
    live_hz: float = 50.0            # live view frames per second of wall time, at most
    namespace: str = DEFAULT_NS      # the arm's ROS namespace: every node runs in it (topics relative to it)
    clock_hz: float = DEFAULT_CLOCK_HZ  # /clock rate [Hz of simulated time]; every node but the plant uses it


@dataclass
class GraphResult:
    stats: dict
    exit_codes: dict[str, int]
    domain_id: int
    wall_total_s: float
    wire_file: Path | None   # the wire monitor's record; None when the run went into the bag
    bag: Path | None = None
    restarts: list[dict] = field(default_factory=list)   # joint, exit code, wall time, resumed step
    controllers: dict[str, dict] = field(default_factory=dict)  # joint -> counters of its last incarnation


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


NODE_GROUPS = ("observer", "reference", "controllers", "plant")
LIVE_VIEW = "live_view"  # the live observer: display only, its failure does not fail the run


def node_group(name: str) -> str:
    if name.startswith("joint_controller_"):
        return "controllers"
    return name if name in ("reference", "plant") else "observer"


def node_env(domain_id: int, discovery_range: str = "LOCALHOST") -> dict:
    """Children's environment: ``discovery_range`` LOCALHOST on one host, SUBNET across (network namespaces)."""
    env = {**os.environ, "ROS_DOMAIN_ID": str(domain_id), "ROS_AUTOMATIC_DISCOVERY_RANGE": discovery_range,
           "PYTHONUNBUFFERED": "1"}
    env.pop("ROS_LOCALHOST_ONLY", None)  # deprecated in Jazzy; conflicts with the discovery range
    return env


def _ros_args(node: str, params: dict, ns: str = DEFAULT_NS) -> list[str]:
    args = ["--ros-args", "-r", f"__node:={node}", "-r", f"__ns:={ns}"]
    for k, v in params.items():
        args += ["-p", f"{k}:={v}"]
    return args


def graph_topics(ns: str = DEFAULT_NS) -> list[str]:
    """Every topic of the graph of the arm in ``ns`` as recorder specs ('/name:pkg/msg/Type', resolved)."""
    arm = ArmTopics(ns)
    specs = [f"{CLOCK}:rosgraph_msgs/msg/Clock", f"{arm.joint_states}:sensor_msgs/msg/JointState",
             f"{arm.robot_description}:std_msgs/msg/String", f"{DIAGNOSTICS}:diagnostic_msgs/msg/DiagnosticArray"]
    for j in JOINT_NAMES:
        specs += [f"{arm.state(j)}:sensor_msgs/msg/JointState", f"{arm.effort(j)}:sensor_msgs/msg/JointState",
                  f"{arm.reference(j)}:trajectory_msgs/msg/JointTrajectory"]
    return specs


REALTIME_REFERENCE_BATCH = 20  # reference points per message in realtime (smaller bursts of work in the controllers)


def loop_reliability(opt: GraphOptions) -> str:
    """QoS reliability of the per-joint state/effort topics: as given, else the mode's default (realtime:
    best effort, the sensor-data convention, so a late sample is overwritten, not re-sent; lockstep:
    reliable, so nothing has to be re-requested)."""
    if opt.reliability is not None:
        return opt.reliability
    return "best_effort" if opt.mode == "realtime" else "reliable"


def reference_lookahead(opt: GraphOptions) -> int:
    """Steps the reference node keeps published beyond the latest /clock: 150, or more when /clock comes less
    often than every 100 steps (the plant must never need a reference past the next /clock)."""
    every = math.ceil(1.0 / (opt.clock_hz * opt.dt_s) - 1e-9)
    return max(150, every + 50)


def _yaml_list(items: list[str]) -> str:
    return "[" + ",".join(f"'{i}'" for i in items) + "]"


def controller_command(opt: GraphOptions, workdir: Path, joint: str, incarnation: int = 0) -> list[str]:
    """argv of joint ``joint``'s controller; a restarted one (incarnation > 0) resumes unless opt.restart is
    'fresh', and is not killed again by faults.kill_controller_at_s."""
    params = {"config_file": str(opt.config_path), "joint": joint, "controller": opt.controller,
              "reliability": loop_reliability(opt), "queue_depth": 1 if opt.mode == "realtime" else 2000,
              "rt_priority": opt.rt_priority,
              "stats_file": str(workdir / f"controller_{joint}.json"), "incarnation": incarnation,
              "resume": str(incarnation > 0 and opt.restart != "fresh").lower(),
              "effort_subscribers": 1 + int(opt.record_bag is not None),  # the plant and the recorder
              "use_sim_time": "true"}
    if opt.controller == "dnbs":
        params["checkpoint_file"] = str(workdir / "checkpoints" / f"{joint}.npz")
        if opt.init_from is not None:
            params["init_file"] = str(opt.init_from / f"{joint}.npz")
    return [sys.executable, "-m", "pa10_dnbs.ros.joint_controller_node"] + _ros_args(f"joint_controller_{joint}",
                                                                                    params, opt.namespace)


def node_commands(opt: GraphOptions, stats_file: Path, wire_file: Path) -> list[tuple[str, list[str]]]:
    """(name, argv) of every process: the wire monitor, the recorder (with --record), the nine nodes,
    the plant last (it starts stepping once the others are matched)."""
    py = [sys.executable, "-m"]

    def ros(node: str, params: dict) -> list[str]:
        return _ros_args(node, {**params, "use_sim_time": "true"}, opt.namespace)

    cfg = str(opt.config_path)
    if opt.record_bag is None:
        cmds = [("wire_monitor", py + ["pa10_dnbs.ros.wire_monitor"] + ros("wire_monitor", {
                    "config_file": cfg, "duration_s": opt.duration_s, "out_file": str(wire_file)}))]
    else:  # the recorder is the observer: the run is rebuilt from the bag
        end_ns = int(round(opt.duration_s / opt.dt_s)) * int(round(opt.dt_s * 1e9))
        custom = [f"controller={opt.controller}", f"mode={opt.mode}", f"duration_s={opt.duration_s!r}",
                  f"reliability={loop_reliability(opt)}", f"config_file={cfg}", f"clock_hz={opt.clock_hz!r}",
                  f"namespace={opt.namespace}"]
        cmds = [("recorder", py + ["pa10_dnbs.ros.recorder_node"] + ros("recorder", {
            "config_file": cfg, "bag": str(opt.record_bag), "force": str(opt.force_bag).lower(),
            "topics": _yaml_list(graph_topics(opt.namespace)), "custom_data": _yaml_list(custom), "end_stamp_ns": end_ns,
            "compression": opt.bag_compression}))]
    if opt.live_port is not None:  # display only: started after the observer, never waited for by the plant
        cmds.append((LIVE_VIEW, py + ["pa10_dnbs.ros.live_observer_node"] + ros(LIVE_VIEW, {
            "config_file": cfg, "host": opt.live_host, "port": opt.live_port, "display_hz": opt.live_hz})))
    # realtime: smaller reference batches, so that decoding one (in each controller) never costs a tick its
    # deadline; lockstep keeps 100 points per message (fewer messages, and timing does not matter there)
    batch = REALTIME_REFERENCE_BATCH if opt.mode == "realtime" else 100
    cmds.append(("reference", py + ["pa10_dnbs.ros.reference_node"] + ros(
        "reference", {"config_file": cfg, "duration_s": opt.duration_s, "batch_steps": batch,
                      "lookahead_steps": reference_lookahead(opt)})))
    for j in JOINT_NAMES:
        cmds.append((f"joint_controller_{j}", controller_command(opt, stats_file.parent, j)))
    cmds.append(("plant", py + ["pa10_dnbs.ros.plant_node"] + _ros_args("plant", {
        "config_file": cfg, "mode": opt.mode, "duration_s": opt.duration_s, "reliability": loop_reliability(opt),
        "effort_timeout_s": opt.effort_timeout_s, "on_missing_effort": opt.on_missing_effort,
        "real_time_factor": opt.real_time_factor, "deadline_fraction": opt.deadline_fraction,
        "rt_priority": opt.rt_priority,
        "stats_file": str(stats_file), "min_joint_states_subscribers": int(opt.record_bag is None),
        "recorders": int(opt.record_bag is not None), "clock_hz": opt.clock_hz}, opt.namespace)))
    return cmds


def run_graph(opt: GraphOptions, workdir: Path, say=print) -> GraphResult:
    """Run the graph; logs go to ``workdir/logs``, the wire record to ``workdir/wire.npz`` (or, with
    ``opt.record_bag``, everything into the bag). Raises GraphFailure.

    The launcher itself never joins DDS: the observer is one of its child processes.
    """
    lease = lease_domain() if opt.domain_id is None else None  # held until the run is over
    domain = opt.domain_id if lease is None else lease.domain_id
    env = node_env(domain, "SUBNET" if opt.netns else "LOCALHOST")
    logs = workdir / "logs"
    logs.mkdir(parents=True, exist_ok=True)
    (workdir / "checkpoints").mkdir(exist_ok=True)
    restarts: list[dict] = []
    stats_file = workdir / "plant_stats.json"
    wire_file = workdir / "wire.npz"
    shm_before = shm_files()
    t_start = time.monotonic()
    procs: list[ManagedProcess] = []
    failure: str | None = None
    stop = _StopRequest()
    previous = _catch_signals(stop)
    try:
        for name, argv in node_commands(opt, stats_file, wire_file):
            if stop.signal_name:
                break
            procs.append(ManagedProcess(name, _in_netns(opt, name, argv), env, logs / f"{name}.log"))
        if not stop.signal_name:
            nodes = [p for p in procs[1:] if p.name != LIVE_VIEW]
            live = [p for p in procs if p.name == LIVE_VIEW]
            say(f"launch: domain {domain}, {len(nodes)} nodes: "
                + ", ".join(f"{p.name}={p.pid}" for p in nodes) + f"; observer {procs[0].name}={procs[0].pid}"
                + "".join(f"; live view {p.name}={p.pid}" for p in live))
            failure = _wait_ready(procs, stop)
        if failure is None and not stop.signal_name:
            say("launch: graph ready (every node printed READY)")
            for p in procs:
                url = p.line("LIVE ")
                if p.name == LIVE_VIEW and url:
                    say(f"launch: live view at {url.split()[1]} (Foxglove: Open connection, Foxglove WebSocket)")
            failure = _watch(procs, opt, say, stop, _Restarter(opt, workdir, env, restarts, say))
    finally:
        codes = stop_all(procs)
        shm_removed = remove_stale(shm_files() - shm_before)
        for signum, handler in previous.items():
            signal.signal(signum, handler)
        if lease is not None:
            lease.release()
    if stop.signal_name:
        failure = f"interrupted ({stop.signal_name})"
    say("launch: stopped: " + " ".join(f"{n}={c}" for n, c in codes.items())
        + (f"; removed {len(shm_removed)} shared-memory files the nodes left in /dev/shm" if shm_removed else ""))
    bad = {n: c for n, c in codes.items() if c != 0 and n != LIVE_VIEW}
    if codes.get(LIVE_VIEW, 0) != 0:
        say(f"launch: the live view exited with code {codes[LIVE_VIEW]}; the run itself is not affected")
    if failure is None and bad:
        failure = "nodes exited with non-zero codes: " + ", ".join(f"{n}={c}" for n, c in bad.items())
        for p in procs:
            if p.name in bad:
                failure += f"\n--- last lines of {p.name}'s log ---\n{p.tail(20)}"
    if failure is not None:
        raise GraphFailure(failure, interrupted=failure.startswith("interrupted"))
    stats = json.loads(stats_file.read_text())
    controllers = {}
    for j in JOINT_NAMES:
        f = workdir / f"controller_{j}.json"
        controllers[j] = json.loads(f.read_text()) if f.is_file() else None
    return GraphResult(stats=stats, exit_codes=codes, domain_id=domain, wall_total_s=time.monotonic() - t_start,
                       wire_file=wire_file if opt.record_bag is None else None, bag=opt.record_bag,
                       restarts=restarts, controllers=controllers)


def parse_netns(specs: list[str]) -> dict[str, str]:
    """['controllers=hostb', ...] -> {'controllers': 'hostb'}; ConfigError naming --netns on bad input."""
    from ..config import ConfigError

    out = {}
    for spec in specs:
        group, sep, ns = spec.partition("=")
        if not sep or group not in NODE_GROUPS or not ns:
            raise ConfigError(f"--netns: expected GROUP=NAMESPACE with GROUP one of {', '.join(NODE_GROUPS)}, "
                              f"got {spec!r}")
        if not Path(f"/var/run/netns/{ns}").exists():
            raise ConfigError(f"--netns: no network namespace {ns!r} (see `ip netns list`)")
        out[group] = ns
    return out


def _in_netns(opt: GraphOptions, name: str, argv: list[str]) -> list[str]:
    ns = opt.netns.get(node_group(name))
    return ["ip", "netns", "exec", ns] + argv if ns else argv


class _Restarter:
    """Starts a dead joint controller again (``opt.restart``), at most ``opt.max_restarts`` times per joint."""

    def __init__(self, opt: GraphOptions, workdir: Path, env: dict, log: list[dict], say):
        self.opt, self.workdir, self.env, self.log, self.say = opt, workdir, env, log, say
        self.count: dict[str, int] = {}

    def __call__(self, procs: list[ManagedProcess], dead: ManagedProcess) -> bool:
        """Replace ``dead`` in ``procs`` by a new incarnation; False when restarts are off or used up."""
        if self.opt.restart is None or not dead.name.startswith("joint_controller_"):
            return False
        joint = dead.name.rsplit("_", 1)[1]
        n = self.count.get(joint, 0) + 1
        if n > self.opt.max_restarts:
            return False
        self.count[joint] = n
        argv = _in_netns(self.opt, dead.name, controller_command(self.opt, self.workdir, joint, incarnation=n))
        new = ManagedProcess(dead.name, argv, self.env, self.workdir / "logs" / f"{dead.name}.restart{n}.log")
        procs[procs.index(dead)] = new
        dead.close_log()
        self.log.append({"joint": joint, "incarnation": n, "exit_code": dead.returncode,
                         "wall_time": time.time(), "mode": self.opt.restart, "pid": new.pid})
        self.say(f"launch: joint {joint} controller exited with code {dead.returncode}; restarted "
                 f"({self.opt.restart}, restart {n} of at most {self.opt.max_restarts}), pid {new.pid}")
        return True


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


def _watch(procs: list[ManagedProcess], opt: GraphOptions, say, stop: _StopRequest, restart=None) -> str | None:
    monitor, plant = procs[0], procs[-1]
    limit_s = 120.0 + 50.0 * opt.duration_s  # generous: a run slower than 1/50 real time is broken
    deadline = time.monotonic() + limit_s
    bar = None
    n_steps = int(round(opt.duration_s / opt.dt_s))
    if opt.progress:  # on a terminal only; the log lines stay whole (ProgressBar.log)
        from ..report.progress import ProgressBar

        bar = ProgressBar(n_steps, opt.dt_s, f"launch {opt.mode} {opt.controller}")
        plain_say = say
        say = lambda line: bar.log(plain_say, line)  # noqa: E731
    announced = False
    live_gone = False
    try:
        while time.monotonic() < deadline:
            if stop.signal_name:
                return None
            if not announced and plant.saw("RUNNING"):
                say("launch: plant running")
                announced = True
            for p in list(procs):
                rc = p.returncode
                if rc is None or (p is plant and rc == 0):
                    continue
                if p.name == LIVE_VIEW:  # display only: the run goes on without it
                    if not live_gone:
                        live_gone = True
                        say(f"launch: the live view exited with code {rc}; the run goes on without it\n"
                            f"--- last lines of {p.log_path} ---\n{p.tail()}")
                    continue
                if plant.returncode is None and restart is not None and restart(procs, p):
                    continue
                return _describe(p)
            if plant.returncode == 0:
                if bar is not None:
                    bar.update(n_steps)
                break
            if bar is not None and monitor.progress_lines:
                bar.update(monitor.progress, monitor.worst_abs_error)
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
            bar.close()

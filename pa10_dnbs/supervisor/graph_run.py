"""Run the whole node graph once: start, wait until ready, run, stop, collect.

The node processes (reference, one controller per joint, plant) and one
observer that records what they send (the wire monitor, or with a bag the
recorder), on a private ROS_DOMAIN_ID with
discovery limited to this host. The launcher only supervises: it never joins
DDS nor loads rclpy, so once its children have exited every shared-memory file
of the run is unmapped, and a leftover (a killed node's Fast DDS segment, the
LTTng-UST wait files) can be removed.

What to start: ``node_specs.py``; supervision (signals, READY, restarts, exit codes): ``supervision.py``;
network namespaces and the children's environment: ``netns.py``; options and result: ``graph_options.py``.
"""
from __future__ import annotations

import json
import os
import signal
import time
from pathlib import Path

from ..interrupt import EXIT_INTERRUPTED, take_noted
from .domain_ids import lease_domain
from .graph_options import GraphFailure, GraphOptions, GraphResult, loop_reliability
from .netns import in_netns, netns_hint, node_env, parse_netns
from .node_specs import LIVE_VIEW, REFERENCE_STATS, graph_topics, node_commands
from .processes import ManagedProcess, kill_now, stop_all
from ..ros.shm_cleanup import remove_stale, shm_files
from .supervision import Restarter, StopRequest, catch_signals, wait_ready, watch

# faulthandler's header when a node's close() outlives its limit and the exit deadline ends it (ros/runtime.py)
TEARDOWN_HUNG_MARK = "Timeout ("

__all__ = ["GraphFailure", "GraphOptions", "GraphResult", "LIVE_VIEW", "graph_topics", "loop_reliability",
           "node_commands", "parse_netns", "run_graph"]


def run_graph(opt: GraphOptions, workdir: Path, say=print, on_hard_stop=None) -> GraphResult:
    """Run the graph; logs go to ``workdir/logs``, the wire record to ``workdir/wire.npz`` (or, with
    ``opt.record_bag``, everything into the bag). Raises GraphFailure.

    The launcher itself never joins DDS: the observer is one of its child processes.
    A second Ctrl-C (or SIGTERM) while the first is handled ends at once (:func:`_hard_stop`); ``on_hard_stop()``
    then runs last (the caller removes its half-written output) and returns what to add to the line. A caller
    may run it inside ``interrupt.deferred()`` (a Ctrl-C once the graph has stopped lets it finish its outputs):
    one noted there before the run's handlers are set stops the run at once.
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
    t_start = time.monotonic()
    procs: list[ManagedProcess] = []
    failure: str | None = None
    stop = StopRequest()
    stop.hard_stop = lambda: _hard_stop(procs, lease, opt, on_hard_stop)
    previous = catch_signals(stop)
    if (noted := take_noted()) is not None:   # a Ctrl-C the caller noted (interrupt.deferred) before these handlers
        stop(noted, None)
    try:
        for name, argv in node_commands(opt, stats_file, wire_file):
            if stop.signal_name:
                break
            procs.append(ManagedProcess(name, in_netns(opt, name, argv), env, logs / f"{name}.log"))
        if not stop.signal_name:
            nodes = [p for p in procs[1:] if p.name != LIVE_VIEW]
            live = [p for p in procs if p.name == LIVE_VIEW]
            say(f"launch: domain {domain}, {len(nodes)} nodes: "
                + ", ".join(f"{p.name}={p.pid}" for p in nodes) + f"; observer {procs[0].name}={procs[0].pid}"
                + "".join(f"; live view {p.name}={p.pid}" for p in live))
            failure = wait_ready(procs, stop)
        if failure is None and not stop.signal_name:
            say("launch: graph ready (every node printed READY)")
            for p in procs:
                url = p.line("LIVE ")
                if p.name == LIVE_VIEW and url:
                    say(f"launch: live view at {url.split()[1]} (Foxglove: Open connection, Foxglove WebSocket)")
            failure = watch(procs, opt, say, stop, Restarter(opt, workdir, env, restarts, say))
    finally:
        codes = stop_all(procs)
        shm_removed = remove_stale(shm_files())  # the nodes' files, and any other dead process's
        for signum, handler in previous.items():
            signal.signal(signum, handler)
        if lease is not None:
            lease.release()
    if stop.signal_name:
        failure = f"interrupted ({stop.signal_name})"
    say("launch: stopped: " + " ".join(f"{n}={c}" for n, c in codes.items())
        + (f"; removed {len(shm_removed)} unused shared-memory files from /dev/shm" if shm_removed else ""))
    hung = [p.name for p in procs
            if p.log_path.is_file() and TEARDOWN_HUNG_MARK in p.log_path.read_text(errors="replace")]
    if hung:
        say(f"launch: {', '.join(hung)} did not close within its limit and was cut short by its exit deadline "
            "(where it hung: the stacks in its log)")
    bad = {n: c for n, c in codes.items() if c != 0 and n != LIVE_VIEW}
    if codes.get(LIVE_VIEW, 0) != 0:
        say(f"launch: the live view exited with code {codes[LIVE_VIEW]}; the run itself is not affected")
    if failure is None and bad:
        failure = "nodes exited with non-zero codes: " + ", ".join(f"{n}={c}" for n, c in bad.items())
        for p in procs:
            if p.name in bad:
                failure += f"\n--- last lines of {p.name}'s log ---\n{p.tail(40)}"  # room for a stack dump
    if failure is not None:
        failure += netns_hint(failure, opt.netns)
        raise GraphFailure(failure, interrupted=failure.startswith("interrupted"))
    stats = json.loads(stats_file.read_text())
    controllers = {}
    for j in opt.joint_names:
        f = workdir / f"controller_{j}.json"
        controllers[j] = json.loads(f.read_text()) if f.is_file() else None
    reference = workdir / REFERENCE_STATS
    return GraphResult(stats=stats, exit_codes=codes, domain_id=domain, wall_total_s=time.monotonic() - t_start,
                       wire_file=wire_file if opt.record_bag is None else None, bag=opt.record_bag,
                       restarts=restarts, controllers=controllers,
                       reference=json.loads(reference.read_text()) if reference.is_file() else None)


def _hard_stop(procs: list[ManagedProcess], lease, opt: GraphOptions, on_hard_stop) -> None:
    """A second Ctrl-C: SIGKILL every node (and whatever it started) and reap it, remove the shared-memory files
    they left, drop the domain lease, one line, exit 130 (no grace, no report)."""
    killed = kill_now(procs)
    removed = remove_stale(shm_files())
    if lease is not None:
        lease.release()
    extra = ""
    if on_hard_stop is not None:
        try:
            extra = on_hard_stop() or ""
        except Exception:  # noqa: BLE001 - the process ends now whatever the clean-up met
            pass
    bag = ""
    if opt.record_bag is not None:   # the recorder creates the folder once it has subscribed
        bag = (f"; the bag {opt.record_bag} was cut short (its recorder was killed): it may not be readable"
               if os.path.exists(opt.record_bag) else f"; no bag was written ({opt.record_bag})")
    line = (f"\npa10-dnbs launch: interrupted again: killed the {killed} of its {len(procs)} processes still "
            f"running at once, removed {len(removed)} shared-memory files from /dev/shm{extra}{bag}\n")
    try:
        os.write(2, line.encode())
    except OSError:
        pass
    os._exit(EXIT_INTERRUPTED)

"""Supervision of a running graph: signals, waiting for READY, watching until the plant is done, restarts.

Exit codes of the children are collected by ``processes.stop_all``; a child that dies early fails the run
(``GraphFailure`` with its log's last lines), unless it is a joint controller and restarts are on, or the
live view (display only).
"""
from __future__ import annotations

import signal
import time
from pathlib import Path

from ..interrupt import same_stop, stop_signals
from .graph_options import GraphOptions
from .netns import in_netns
from .node_specs import LIVE_VIEW, controller_command
from .processes import ManagedProcess

READY_TIMEOUT_S = 60.0
OBSERVER_CATCH_UP_S = 10.0  # wall time the observer has after the plant's end to report COMPLETE


class StopRequest:
    """Set by SIGINT, SIGTERM or SIGHUP (interrupt.stop_signals); the launcher's loops check it (no exception at an
    arbitrary point, so a signal can neither orphan a child being started nor interrupt the shutdown).

    A second signal while the first is handled (a second Ctrl-C during the nodes' graces) calls ``hard_stop``
    (set by the launcher once its children exist: it kills them, cleans up and ends the process at once); the
    same signal again within ``interrupt.SAME_STOP_S`` is the first one sent twice (GNU timeout: to the command,
    then to its group), not a second Ctrl-C."""

    def __init__(self):
        self.signal_name: str | None = None
        self.hard_stop = None
        self._first: tuple[int, float] | None = None

    def __call__(self, signum, _frame):
        if self.signal_name is None:
            self.signal_name = signal.Signals(signum).name
            self._first = (signum, time.monotonic())
        elif self.hard_stop is not None and not same_stop(self._first, signum):
            self.hard_stop()


def catch_signals(stop: StopRequest) -> dict:
    """Route the stop signals (SIGINT, SIGTERM, SIGHUP unless ``nohup`` ignores it: interrupt.stop_signals) to
    ``stop``, even where the parent shell left SIGINT ignored."""
    previous = {}
    for signum in stop_signals():
        previous[signum] = signal.getsignal(signum)
        signal.signal(signum, stop)
    return previous


class Restarter:
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
        argv = in_netns(self.opt, dead.name, controller_command(self.opt, self.workdir, joint, incarnation=n))
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


def wait_ready(procs: list[ManagedProcess], stop: StopRequest) -> str | None:
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


def watch(procs: list[ManagedProcess], opt: GraphOptions, say, stop: StopRequest, restart=None) -> str | None:
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
        end = time.monotonic() + OBSERVER_CATCH_UP_S  # the last messages may still be in flight
        while not monitor.saw("COMPLETE") and time.monotonic() < end and not stop.signal_name:
            time.sleep(0.05)
        if not monitor.saw("COMPLETE") and not stop.signal_name:
            hint = (" (every node ran under SCHED_FIFO (`rt_priority`): where the loop needs the whole machine "
                    "the observer can still fall behind it; try a lower `real_time_factor`, or `rt_priority` 0)"
                    if opt.rt_priority else "")
            return (f"the {monitor.name} did not receive the whole run{hint}\n--- last lines of its log ---\n"
                    + monitor.tail())
        return None
    finally:
        if bar is not None:
            bar.close()

"""plant_node: the PyBullet plant of the arm on the ROS graph.

Before step 0, the start handshake (``wait_for_graph``, ``ros/ready.py``): its own endpoints matched, /clock
at time 0 out, and every node of ``ready_nodes`` ready on the ``ready`` topic (one timeout, naming the nodes
that are not).

What it publishes and how it takes efforts: ``endpoints.py``. How it
paces the steps (``mode``):

- lockstep (``lockstep.py``): state k+1 is computed once every
  effort answering state k has arrived; a missing one is re-requested after
  ``resend_s`` and replaced (held or zeroed, counted) after
  ``effort_timeout_s``. Deterministic: the in-process simulation, bit for bit.
- realtime (``realtime.py``): deadline-synchronous ticks of
  ``dt / real_time_factor`` wall seconds; at the start of tick k state k goes
  out, the efforts answering it that arrive before ``deadline_fraction`` of
  the tick are applied, a missing one is held or zeroed and counted as a
  miss; late tick starts are counted and not caught up.

/clock goes out with the states of ``wire/clock_schedule.py``: one per
1 / ``clock_hz`` of simulated time (default 100 Hz, as ``ros2 bag play
--clock``; 0: none); in realtime it and joint_states follow at the tick's
deadline (``realtime.py``). The plant itself runs on wall time (no use_sim_time).

Defensive: a non-finite effort counts as missing (hold or zero, counted), an
out-of-range one is saturated at its torque limit and counted. A second
publisher on a joint's effort topic (another controller answering its
states: whichever answer comes first is applied) is looked for every
``EFFORT_PUBLISHERS_CHECK_S`` of wall time, warned about once per joint and
its count kept (``effort_publishers`` in the stats: the most seen at once). Faults configured in
``faults.state`` are injected on each joint's state link. Fault counters go
to /diagnostics every second; timing figures and counters go to
``stats_file`` (JSON, ``stats.py``) at exit.
"""
from __future__ import annotations

import math
import time
from typing import NoReturn

from rclpy.node import Node
from rclpy.task import Future

from ...arm.summary import arm_line
from ...atomic_file import write_json
from ...loop.cpu_meter import CpuMeter
from ...loop.effort_gate import EffortGate
from ...loop.endpoint_match import MatchWait
from .timing import PlantTiming
from ...loop.scheduling import apply_fifo, check_priority
from ...plant.from_config import open_client, plant_from_settings
from ...wire.clock_schedule import DEFAULT_CLOCK_HZ, check_clock_hz
from ...wire.robot_interface import default_state_topic, parse_robot_command
from ...settings import Settings
from ..diagnostics import DiagnosticsReporter
from ..params import (MAX_QOS_DEPTH, RT_PRIORITY, SETTINGS_DEFAULTS, Param, ParameterError, check_choice, declare,
                      declare_settings, duration_steps)
from .lockstep import run_lockstep
from .realtime import run_realtime
from .stats import diagnostics_report, plant_stats
from .standard_endpoints import StandardPlantEndpoints
from .endpoints import PlantEndpoints
from ..ready import GraphNotReady, ReadyListener
from ..wall_timer import wall_timer
from ..runtime import announce_ready
from ..settings_params import NODE_SECTIONS
from ..endpoints import StepClock, record_qos


PARAMS = {
    "config_file": SETTINGS_DEFAULTS,
    "mode": Param("lockstep", "lockstep (step once every effort is in) or realtime (wall-clock ticks)"),
    "duration_s": Param(0.0, "simulated time to run [s]; 0 = simulation.duration_s of the config", 0.0),
    "clock_hz": Param(DEFAULT_CLOCK_HZ, "/clock rate [Hz of simulated time]; 0 = no /clock", 0.0, 1e6),
    "effort_timeout_s": Param(1.0, "lockstep: wall time to wait for an effort before replacing it [s]", 0.0),
    "resend_s": Param(0.25, "lockstep (and a robot's realtime handshake): wall time before a missing effort's state "
                            "is sent again [s]", 0.0),
    "on_missing_effort": Param("hold", "what replaces a missing effort: hold (last torque) or zero"),
    "reliability": Param("", "per-joint state/effort QoS: reliable, best_effort; '' = the mode's default"),
    "stats_file": Param("", "JSON file for timing figures and counters at exit; '' = none", writes=True),
    "min_joint_states_subscribers": Param(0, "joint_states subscribers to wait for before stepping", 0),
    "start_timeout_s": Param(30.0, "wall time to wait for the graph to be matched [s]", 0.0),
    "settle_s": Param(0.3, "wall time to wait after the graph is matched [s]", 0.0),
    "state_subscribers": Param(1, "subscribers of each <joint>/state to wait for (besides recorders)", 0),
    "clock_subscribers": Param(1, "/clock subscribers to wait for (besides recorders)", 0),
    "recorders": Param(0, "recorders to wait for on every topic", 0),
    "effort_queue_depth": Param(1000, "lockstep: keep_last depth of the effort subscriptions [messages]", 1,
                                MAX_QOS_DEPTH),
    "real_time_factor": Param(1.0, "realtime: a step of dt takes dt / real_time_factor of wall time", 0.0, 100.0),
    "deadline_fraction": Param(0.9, "realtime: efforts count within this fraction of the tick, in (0, 1]", 0.0, 1.0),
    "late_tolerance": Param(0.1, "realtime: a tick starting later than this fraction of a tick is late, in [0, 1)",
                            0.0, 1.0),
    "rt_priority": RT_PRIORITY,
    "warn_period_s": Param(1.0, "wall time between two warnings of the same kind [s]", 0.0),
    "handshake_steps": Param(3, "realtime: first steps that wait for every effort before the tick schedule starts [steps]", 1),
    "ready_nodes": Param([""], "nodes that must say ready on the ready topic before step 0 (the start handshake); "
                         "none: no handshake, settle_s instead"),
    "interface": Param("", "'' = the per-joint topics of the graph; standard = one JointState state and commands, "
                       "as a robot behind the joint bus (docs/your_robot.md; lockstep waits for every command)"),
    "robot_state_topic": Param("", "standard interface: the state topic; '' = /robot_joint_states (/joint_states "
                               "with a forward command)", topics=True),
    "robot_command": Param("joint_state", "standard interface: joint_state (stamped JointState efforts) or "
                           "forward:<controller> (Float64MultiArray on /<controller>/commands)"),
    "robot_command_topic": Param("", "standard interface, joint_state form: the command topic; '' = "
                                 "/robot_joint_command", topics=True),
}


EFFORT_PUBLISHERS_CHECK_S = 0.2  # wall time between two counts of each effort topic's publishers
FINAL_FLUSH_S = 10.0  # wall seconds the finished plant waits for every reliable subscriber to acknowledge


class PlantNode(Node):
    NODE_NAME = "plant"
    PARAMS = PARAMS

    def __init__(self):
        super().__init__(self.NODE_NAME)
        p = declare(self, self.PARAMS)
        check_choice("mode", p["mode"], ("lockstep", "realtime"))
        check_choice("on_missing_effort", p["on_missing_effort"], ("hold", "zero"))
        if p.setdefault("interface", "") not in ("", "standard"):
            raise ParameterError(f"parameter interface must be '' (the per-joint topics) or standard, got "
                                 f"{p['interface']!r}")
        if p["interface"] == "standard":  # before anything is logged: a refusal is the node's one line
            self._robot_topics = self._checked_robot_topics(p)
        realtime = p["mode"] == "realtime"
        if not p["reliability"]:  # realtime: the sensor-data convention; lockstep: lossless
            p["reliability"] = "best_effort" if realtime else "reliable"
        check_choice("reliability", p["reliability"], ("reliable", "best_effort"))
        _check_positive(p, "real_time_factor", "effort_timeout_s", "resend_s", "warn_period_s")
        if not 0 < p["deadline_fraction"] <= 1:
            raise ParameterError(f"parameter deadline_fraction must be in (0, 1], got {p['deadline_fraction']}")
        if p["handshake_steps"] < 1:
            raise ParameterError(f"parameter handshake_steps must be >= 1, got {p['handshake_steps']}")
        if not 0 <= p["late_tolerance"] < 1:
            raise ParameterError(f"parameter late_tolerance must be in [0, 1), got {p['late_tolerance']}")
        try:
            check_priority(p["rt_priority"])
        except ValueError as exc:
            raise ParameterError(f"parameter {exc}") from None
        self.p = p
        # its settings (physics, initial state, state faults): read-only parameters, the run's params file
        settings = declare_settings(self, NODE_SECTIONS[self.NODE_NAME], p["config_file"])
        self.dt = settings.simulation.dt_s
        try:
            check_clock_hz(p["clock_hz"], self.dt)
        except ValueError as exc:
            raise ParameterError(f"parameter clock_hz {exc}") from None
        duration = p["duration_s"] if p["duration_s"] > 0 else settings.simulation.duration_s
        self.n_steps = duration_steps(duration, self.dt)
        self.clock_ = StepClock(self.dt)
        self.plant = self._open_plant(settings)
        n = self.plant.n_joints
        self.get_logger().info(arm_line(self.plant.arm))
        self.gate = EffortGate(n, p["on_missing_effort"])
        self.gate.bin_steps = max(1, int(round(60.0 / self.dt)))  # realtime on-time fraction per simulated minute
        # realtime: latest value only (depth 1), a late reader skips stale states. lockstep: a deep
        # history, so a recorder that falls behind for a while still gets every message.
        self.endpoints = self._make_endpoints(settings, realtime)
        self.timing = PlantTiming(self.n_steps, n)
        self.cpu = CpuMeter()
        self.resends = [0] * n
        self.resent_steps: list[list[int]] = [[] for _ in range(n)]  # lockstep: the steps re-sent, per joint
        self.schedule = None  # realtime: the TickSchedule
        self.finished = False
        self._stop = None   # the stop Future, once loop() runs
        self._observed = None  # (k, q, qd, applied) of a state whose joint_states and /clock are still to go out
        self.exit_code = 0  # a signal before the end is a clean stop; "completed" in the stats says if it ran out
        self.wall_start = self.wall_end = math.nan
        expected = [n for n in p["ready_nodes"] if n]
        self.ready = ReadyListener(self, expected) if expected else None  # the start handshake
        self.diagnostics = DiagnosticsReporter(self, lambda: diagnostics_report(self),
                                               lambda: self.clock_.stamp(self.gate.step))
        self.effort_publishers = [0] * n  # the most publishers seen at once on each joint's effort topic
        self._effort_publishers_warned: set[str] = set()  # topics whose second publisher was named in the log
        self._effort_publishers_timer = wall_timer(self, EFFORT_PUBLISHERS_CHECK_S, self.count_effort_publishers)
        self.rt_applied, self.rt_message = apply_fifo(p["rt_priority"])
        if p["rt_priority"]:
            print(self.rt_message, flush=True)
        announce_ready("plant")

    def _checked_robot_topics(self, p: dict):
        """interface:=standard: (the command, the state topic); ParameterError when the command form is bad or the
        state and command topics are one (resolved): the robot would read its own states as commands."""
        try:
            command = parse_robot_command(p["robot_command"], p["robot_command_topic"] or None)
        except ValueError as exc:
            raise ParameterError(f"parameter robot_command: {exc}") from None
        state_topic = p["robot_state_topic"] or default_state_topic(command)
        state = self.resolve_topic_name(state_topic)
        if state == self.resolve_topic_name(command.topic):
            raise ParameterError(f"parameter robot_command_topic: must differ from robot_state_topic (both {state}): "
                                 "the robot would read its own states as commands")
        return command, state_topic

    def _open_plant(self, settings: Settings):
        """The physics: the PyBullet plant of the config's arm, at its initial state."""
        self._client = open_client()
        return plant_from_settings(settings, self._client)

    def _close_plant(self) -> None:
        self._client.disconnect()

    def _make_endpoints(self, settings: Settings, realtime: bool):
        """The per-joint topics (``endpoints.py``), or with ``interface:=standard`` the standard robot interface
        (``standard_endpoints.py``): there the plant waits for every command (no effort timeout)."""
        p = self.p
        if p["interface"] == "standard":
            command, state_topic = self._robot_topics   # checked in __init__
            p["effort_timeout_s"] = math.inf  # a robot in lockstep waits for its command (docs/your_robot.md)
            return StandardPlantEndpoints(self, settings, self.clock_, state_topic,
                                          command, p["clock_hz"], self.n_steps, lambda: self.gate.step)
        return PlantEndpoints(self, settings, self.clock_, p["reliability"],
                              state_depth=1 if realtime else record_qos().depth,
                              effort_depth=1 if realtime else p["effort_queue_depth"], clock_hz=p["clock_hz"],
                              last_step=self.n_steps)

    def count_effort_publishers(self) -> None:
        """Count each effort topic's publishers (``effort_publishers``: the most seen); a second one is warned
        about once per topic (the standard interface's one command topic serves every joint): another controller
        answers the states, and whichever answer comes first counts."""
        for j, (topic, count) in enumerate(self.endpoints.effort_publishers()):
            self.effort_publishers[j] = max(self.effort_publishers[j], count)
            if count > 1 and topic not in self._effort_publishers_warned:
                who = sorted(f"{i.node_namespace.rstrip('/')}/{i.node_name}"
                             for i in self.get_publishers_info_by_topic(topic))
                if any("_UNKNOWN_" in w for w in who):
                    continue  # its node's name is not discovered yet: the next count names it
                self._effort_publishers_warned.add(topic)
                self.get_logger().warning(
                    f"SECOND EFFORT PUBLISHER at step {self.gate.step}: {count} publishers on {topic} "
                    f"({', '.join(who)}): whichever answer comes first is applied")

    # ---------------------------------------------------------------- stepping
    def publish_state(self, k: int, joints=None, observed: bool = True) -> None:
        """State ``k`` (to ``joints`` only: a resend); ``observed=False`` keeps joint_states and /clock for
        ``publish_observed`` (realtime: after the tick's deadline, out of the controllers' window)."""
        q, qd = self.plant.state
        t_ns = self.endpoints.publish_state(k, q, qd, self.gate.applied, joints, observed)
        if joints is None:
            self.timing.published(k, t_ns)
            if not observed:
                self._observed = (k, q.tolist(), qd.tolist(), self.gate.applied.tolist())

    def resend_state(self, k: int) -> None:
        """State ``k`` again to the joints whose effort for it is missing, counted per joint (``resends``, and
        ``resent_steps`` once per step)."""
        missing = self.gate.missing
        for j in missing:
            self.resends[j] += 1
            if not self.resent_steps[j] or self.resent_steps[j][-1] != k:
                self.resent_steps[j].append(k)
        self.publish_state(k, joints=missing)

    def publish_observed(self) -> None:
        """joint_states and /clock of the last state published with ``observed=False`` (once)."""
        if self._observed is not None:
            self.endpoints.publish_observed(*self._observed)
            self._observed = None

    def take_efforts(self, joints=None) -> bool:
        """Offer every queued effort (of ``joints``, default all) to the gate; True when the current step is
        complete."""
        for joint, k, u, received_ns in self.endpoints.take_efforts(joints):
            self.timing.answered(k, joint, received_ns)
            self.gate.offer(joint, k, u)
        return self.gate.ready

    def step(self, tau) -> None:
        """Advance the physics by one step with ``tau`` (the gate's torques for it)."""
        self.plant.step(tau)
        self.cpu.mark(self.gate.step)
        if self.gate.step >= self.n_steps:
            self.finished = True
            self.wall_end = time.perf_counter()

    def wait_for_graph(self, executor, stop: Future) -> bool:
        """Spin until every endpoint has matched on the plant's side and every node in ``ready_nodes`` said it is
        ready for the first steps (the start handshake, ``ros/ready.py``), or, with no ``ready_nodes``, until the
        endpoints have matched and ``settle_s`` has passed; False when stopped first. /clock at time 0 goes out
        first (latched): the reference node and the recorder are ready only once they have received it, which
        proves the /clock match from both sides. One timeout, ``start_timeout_s``: then a RuntimeError naming
        what is missing and every node that is not ready, with what it waits for."""
        # each recorder subscribes to every topic, efforts included (the wire adds them to each count)
        wait = MatchWait(self.endpoints.needs(self.p["state_subscribers"], self.p["clock_subscribers"],
                                         self.p["min_joint_states_subscribers"], self.p["recorders"]),
                         self.p["start_timeout_s"])
        self.endpoints.publish_start_clock()
        board = self.ready.board if self.ready is not None else None
        while not stop.done():
            matched = wait.poll() == "met"
            if matched and (board is None or board.complete):
                if board is None:
                    settle_end = time.perf_counter() + self.p["settle_s"]
                    while time.perf_counter() < settle_end and not stop.done():
                        executor.spin_once(timeout_sec=0.02)
                else:  # the ready subscription stays: destroying it now would send every node a graph update
                    print(f"HANDSHAKE every node ready after {wait.waited_s:.3f} s: {', '.join(board.expected)}",
                          flush=True)
                return not stop.done()
            if time.monotonic() >= wait.deadline:
                lacking = wait.lacking + (board.lacking if board is not None else [])
                raise GraphNotReady(f"graph not ready after start_timeout_s = {self.p['start_timeout_s']:g} s: "
                                    + "; ".join(lacking))
            executor.spin_once(timeout_sec=0.02)
        return False

    def loop(self, executor, stop: Future) -> None:
        self._stop = stop   # close() waits for no acknowledgement once the graph is being stopped
        if not self.wait_for_graph(executor, stop):
            return
        print("RUNNING plant", flush=True)
        self.wall_start = time.perf_counter()
        if self.p["mode"] == "lockstep":
            run_lockstep(self, executor, stop)
        else:
            run_realtime(self, executor, stop)
        if self.finished:   # once more at the end: the timer may have been starved, or a match come late
            self.count_effort_publishers()
        if self.finished and not stop.done() and not self.endpoints.flush(FINAL_FLUSH_S, stop) and not stop.done():
            # the observer lags on a loaded machine: give it the run's last states before the writers go
            self.get_logger().warning(f"not every subscriber acknowledged the last states within {FINAL_FLUSH_S:g} s")

    # ---------------------------------------------------------------- report
    def stats(self) -> dict:
        return plant_stats(self)

    def close(self) -> None:
        self.endpoints.close(self._stop)
        path = self.p["stats_file"]
        if path:
            write_json(path, self.stats())
        print(self.cpu.line(self.NODE_NAME), flush=True)
        self._close_plant()


def _check_positive(p: dict, *keys: str) -> None:
    for k in keys:
        if not (math.isfinite(p[k]) and p[k] > 0):
            raise ParameterError(f"parameter {k} must be a positive number, got {p[k]}")


def main(args=None) -> NoReturn:
    from ..runtime import exit_process, run_node

    exit_process(run_node(PlantNode, args, params=PARAMS))


if __name__ == "__main__":
    main()

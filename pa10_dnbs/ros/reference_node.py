"""reference_node: publishes each joint's desired trajectory (eq. 27, Table 1) ahead of time.

On <ns>/<joint>/reference (<ns>: the arm's namespace, /<arm name> by default; trajectory_msgs/JointTrajectory, one joint,
reliable + transient-local) in batches of ``batch_steps`` points; header.stamp
is the time of the first point, time_from_start counts from it. Paced by
/clock (the plant's, 100 Hz of simulated time by default): it keeps at least
``lookahead_steps`` published beyond the latest /clock step, which must cover
the steps between two /clock messages (the launcher sees to it)
(and, given ``duration_s``, stops lookahead_steps past the run's last step).
Reports on /diagnostics the /clock messages it saw and those that went back
in time (a fault: the reference it already sent cannot be taken back).
/clock is taken every ``poll_period_s`` (``polled.Inbox``), not one wake-up
per message: the lookahead covers many polls.

Trajectories (docs/trajectories.md): ``trajectory_file`` (YAML or JSON) is followed from step 0 instead of
eq. 27; a trajectory_msgs/JointTrajectory on <ns>/trajectory is followed while running, from the first step
not yet published (or from its header stamp when that is non-zero and later), starting from the desired state
there (``core/trajectory_reference.py``). A wrong one is refused with one line and changes nothing. What came
goes to ``stats_file`` at exit (JSON: each accepted trajectory's steps, the refused count and the first
reasons), for the launcher's report.
"""
from __future__ import annotations

import struct
from typing import NoReturn

import numpy as np
from rclpy.duration import Duration
from rclpy.node import Node
from rosgraph_msgs.msg import Clock
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy
from trajectory_msgs.msg import JointTrajectory

from ..atomic_file import write_json
from ..config_error import ConfigError
from ..controller_factory import build_reference, load_reference_trajectory, switchable_reference
from ..core.joint_trajectory import TrajectoryError, trajectory_from_lists
from ..core.trajectory_reference import received_start
from ..wire.topics import MAX_BATCH_STEPS, TRAJECTORY
from ..wire.trajectory_cdr import encode_one_joint
from .diagnostics import DiagnosticsReporter, status, status_name
from ..loop.scheduling import apply_batch, apply_fifo
from .params import (RT_PRIORITY, SCHED_BATCH, SETTINGS_DEFAULTS, Param, ParameterError, declare, declare_settings,
                     duration_steps)
from ..loop.cpu_meter import CpuMeter
from .polled import Inbox
from .ready import announce_when_ready
from .runtime import announce_ready, exit_process, run_node, stop_requested
from .settings_params import NODE_SECTIONS
from .endpoints import CLOCK, StepClock, record_qos, reference_qos, reference_topic


FAULT_KEYS = ("clock_backwards",)
MAX_KEPT = 100  # accepted trajectories and refusal reasons kept for the stats file
CLOCK_DEPTH = 1000  # /clock messages kept between two polls
NOW = Duration(seconds=0)  # wait_for_all_acked: just look


PARAMS = {
    "config_file": SETTINGS_DEFAULTS,
    "sched_batch": SCHED_BATCH,
    "rt_priority": RT_PRIORITY,
    "batch_steps": Param(100, "reference points per message [steps]", 1, MAX_BATCH_STEPS),
    "lookahead_steps": Param(150, "steps kept published beyond the latest /clock (> reference.preview_steps)", 1),
    "duration_s": Param(0.0, "the run's simulated time [s]: nothing past its end + lookahead; 0 = open-ended", 0.0),
    "poll_period_s": Param(0.01, "wall time between two drains of /clock [s]", 0.0),
    "reference_subscribers": Param(1, "start handshake: subscribers of each reference topic that must hold the first "
                                   "batches (its controller, the observers) before the node says ready", 0),
    "trajectory_file": Param("", "a JointTrajectory (YAML or JSON) followed from step 0 instead of eq. 27 "
                             "(docs/trajectories.md); '' = eq. 27"),
    "stats_file": Param("", "JSON file at exit: the trajectories received on the trajectory topic, accepted (their "
                        "steps) and refused (why); '' = none", writes=True),
}
TRAJECTORY_QOS = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=10, reliability=ReliabilityPolicy.RELIABLE,
                            durability=DurabilityPolicy.VOLATILE)  # as `ros2 topic pub` and JTC's clients offer


class ReferenceNode(Node):
    def __init__(self):
        super().__init__("reference")
        p = declare(self, PARAMS)
        settings = declare_settings(self, NODE_SECTIONS["reference"], p["config_file"])  # eq. 27 at dt: read-only
        preview = settings.reference.preview_steps
        if p["batch_steps"] < 1 or p["lookahead_steps"] <= preview:
            raise ParameterError(f"batch_steps must be >= 1 and lookahead_steps > reference.preview_steps = {preview}")
        if not p["poll_period_s"] > 0:
            raise ParameterError(f"parameter poll_period_s must be > 0 s, got {p['poll_period_s']}")
        trajectory = None
        if p["trajectory_file"]:
            try:
                trajectory = load_reference_trajectory(settings, p["trajectory_file"])
            except ConfigError as exc:
                raise ParameterError(exc.named({"trajectory": "parameter trajectory_file:"})) from None
        self.reference = switchable_reference(settings, build_reference(settings, trajectory))
        self.trajectories = {"accepted": 0, "refused": 0}
        self.accepted: list[dict] = []  # the first MAX_KEPT accepted: steps, points, knots
        self.refusals: list[str] = []   # the first MAX_KEPT refusals' reasons
        self.clock_ = StepClock(settings.simulation.dt_s)
        self.p = p
        self.batch = p["batch_steps"]
        self.lookahead = p["lookahead_steps"]
        self.published_until = 0  # steps [0, published_until) are out
        self.clock_step = -1  # the latest step seen on /clock
        self.clock_messages = 0
        self.clock_backwards = 0
        dt = settings.simulation.dt_s
        # a run of known length: nothing past its last step + lookahead (so a bag's count is fixed)
        self.run_steps = duration_steps(p["duration_s"], dt) if p["duration_s"] > 0 else None  # None: open-ended
        self.last_step = self.run_steps + self.lookahead if self.run_steps is not None else None
        self.joint_names = settings.arm.joint_names
        self._pubs = [self.create_publisher(JointTrajectory, reference_topic(j), reference_qos())
                      for j in self.joint_names]
        self.cpu = CpuMeter()
        self.inbox = Inbox(self, p["poll_period_s"])
        self.inbox.subscribe(Clock, CLOCK, record_qos(CLOCK_DEPTH), self._on_clock)
        self.create_subscription(JointTrajectory, TRAJECTORY, self._on_trajectory, TRAJECTORY_QOS)
        self._publish_through(self.lookahead)
        self.diagnostics = DiagnosticsReporter(self, self._diagnostics,
                                               lambda: self.clock_.stamp(max(0, self.clock_step)))
        if p["sched_batch"]:
            print(apply_batch()[1], flush=True)
        if p["rt_priority"]:  # after SCHED_BATCH: a granted priority replaces it
            print(apply_fifo(p["rt_priority"])[1], flush=True)
        announce_ready("reference")
        announce_when_ready(self, self._ready_for_steps)

    def _ready_for_steps(self) -> str | None:
        """The start handshake (``ros/ready.py``): None once a /clock has come in (the plant's /clock at time 0:
        the /clock match works both ways) and every reference topic has ``reference_subscribers`` subscribers
        that acknowledged every batch published so far (the first steps' references: ``lookahead_steps``, sent
        at start); else what is missing."""
        if self.clock_messages == 0:
            return "no /clock received yet"
        want = self.p["reference_subscribers"]
        for pub in self._pubs:
            have = pub.get_subscription_count()
            if have < want:
                return f"{pub.topic_name} has {have} of {want} subscribers"
            if not pub.wait_for_all_acked(NOW):
                return f"not every subscriber of {pub.topic_name} has acknowledged the first batches"
        return None

    def _on_clock(self, data: bytes) -> None:
        """A /clock message (CDR bytes)."""
        try:
            step = self.clock_.step_of_cdr(data)
        except struct.error:
            return
        self.clock_messages += 1
        if step < self.clock_step:
            self.clock_backwards += 1
        if step > self.clock_step:
            self.cpu.mark(step)
        self.clock_step = max(self.clock_step, step)
        self._publish_through(step + self.lookahead)

    def _on_trajectory(self, msg: JointTrajectory) -> None:
        """Follow a trajectory from the first step not yet published (or its header stamp, when non-zero and
        later), or refuse it with one line; nothing changes then."""
        dt = self.reference.dt_s
        start, origin = received_start(self.published_until,
                                       msg.header.stamp.sec + msg.header.stamp.nanosec * 1e-9, dt)
        try:
            if not msg.points:
                raise TrajectoryError("no points")
            traj = trajectory_from_lists(list(msg.joint_names),
                                         [p.time_from_start.sec + p.time_from_start.nanosec * 1e-9 for p in msg.points],
                                         [list(p.positions) for p in msg.points],
                                         [list(p.velocities) for p in msg.points],
                                         [list(p.accelerations) for p in msg.points])
            if any(len(p.effort) for p in msg.points):
                raise TrajectoryError("points carry efforts: only positions are followed")
            if self.run_steps is not None and start >= self.run_steps:  # nothing of it would be followed
                raise TrajectoryError(f"it would start at step {start} (t = {start * dt:.3f} s), at or after the "
                                      f"run's end at step {self.run_steps} (t = {self.run_steps * dt:.3f} s): "
                                      "nothing of it would be followed")
            s = self.reference.start(traj, start, origin)
        except TrajectoryError as exc:
            self.trajectories["refused"] += 1
            if len(self.refusals) < MAX_KEPT:
                self.refusals.append(str(exc))
            print(f"TRAJECTORY refused: {exc}", flush=True)
            return
        self.trajectories["accepted"] += 1
        if len(self.accepted) < MAX_KEPT:
            self.accepted.append({"start_step": s.start_step, "end_step": s.end_step, "points": len(msg.points),
                                  "knots": s.knots, "dropped_points": s.dropped})
        print(f"TRAJECTORY accepted: {len(msg.points)} points, {s.knots} knots from step {s.start_step} "
              f"(t = {s.start_step * dt:.3f} s) to step {s.end_step} (t = {s.end_step * dt:.3f} s), then the last "
              f"point held" + (f"; {s.dropped} points before the start left out" if s.dropped else ""), flush=True)

    def close(self) -> None:
        print(self.cpu.line("reference"), flush=True)
        if self.p["stats_file"]:
            write_json(self.p["stats_file"], self.stats())

    def stats(self) -> dict:
        """The trajectories received on the trajectory topic (resolved name): counts, each accepted one's steps
        (first MAX_KEPT), the first MAX_KEPT refusals' reasons."""
        return {"trajectory_topic": self.resolve_topic_name(TRAJECTORY), "trajectories_accepted":
                self.trajectories["accepted"], "trajectories_refused": self.trajectories["refused"],
                "accepted": self.accepted, "refused_reasons": self.refusals}

    def _diagnostics(self) -> list:
        counters = {"clock_messages": self.clock_messages, "clock_backwards": self.clock_backwards,
                    "clock_step": self.clock_step, "published_through_step": self.published_until - 1,
                    "trajectories_accepted": self.trajectories["accepted"],
                    "trajectories_refused": self.trajectories["refused"]}
        return [status(status_name(self, "reference"), self.get_name(), counters, FAULT_KEYS)]

    def _publish_through(self, last_step: int) -> None:
        if self.last_step is not None:
            last_step = min(last_step, self.last_step)
        while self.published_until <= last_step:
            if stop_requested():   # a Ctrl-C while a long lookahead is encoded (also while the node is built)
                return
            k0 = self.published_until
            steps = np.arange(k0, k0 + self.batch)
            pos = self.reference.position(steps)  # (batch, n_joints)
            vel = self.reference.velocity(steps)
            sec, nanosec = self.clock_.sec_nanosec(k0)
            for j, (name, pub) in enumerate(zip(self.joint_names, self._pubs)):
                # raw CDR (wire/trajectory_cdr.py): rclpy's message objects cost ~20x more per batch
                pub.publish(encode_one_joint(sec, nanosec, name, pos[:, j].tolist(), vel[:, j].tolist(),
                                             self.clock_.dt_ns))
            self.published_until = k0 + self.batch


def main(args=None) -> NoReturn:
    exit_process(run_node(ReferenceNode, args, params=PARAMS))


if __name__ == "__main__":
    main()

"""The plant's wire in the standard robot interface (``interface:=standard``): the PyBullet plant as a robot
the joint bus drives (docs/your_robot.md), instead of the per-joint topics of ``endpoints.py``.

Publishes every joint's state as one ``sensor_msgs/JointState`` (name, position [rad], velocity [rad/s], and as
effort the torque applied over the step before [N m]; stamped with the robot's time k T) on ``state_topic``,
and /clock (``ClockSchedule``, latched at time 0, as ``endpoints.py``). Takes commands in the form of
``RobotCommand``: a JointState of efforts stamped with the state it answers (matched by joint name), or a
Float64MultiArray in the arm's joint order (no stamp: it answers the current step). A command gives every
joint's effort at once: the plant's lockstep and realtime loops run unchanged on top. Same methods as
``PlantEndpoints``; no per-joint topics, no joint_states of its own (the bus publishes the graph's).
"""
from __future__ import annotations

import math
import struct
import time

import numpy as np
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray

from ...loop.endpoint_match import Need
from ..acked import wait_acked
from ...wire import joint_state_cdr
from ...wire.clock_schedule import ClockSchedule
from ...wire.robot_interface import JointMatcher, RobotCommand
from ...settings import Settings
from .endpoints import CLOCK_CDR
from ..polled import PolledSubscription, SubscriptionWaitSet
from ..endpoints import CLOCK, StepClock, record_qos

ROBOT_QOS_DEPTH = 10  # the standard topics: reliable, volatile, keep-last 10 (matches a best-effort reader too)


def robot_qos(reliability: str = "reliable", depth: int = ROBOT_QOS_DEPTH) -> QoSProfile:
    rel = {"reliable": ReliabilityPolicy.RELIABLE, "best_effort": ReliabilityPolicy.BEST_EFFORT}[reliability]
    return QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=depth, reliability=rel,
                      durability=DurabilityPolicy.VOLATILE)


class StandardPlantEndpoints:
    def __init__(self, node, settings: Settings, clock: StepClock, state_topic: str, command: RobotCommand, clock_hz: float,
                 last_step: int, current_step):
        """``current_step()``: the plant's current step (what a Float64MultiArray command answers)."""
        self.node = node
        self.clock = clock
        arm = settings.arm
        self.joint_names = arm.joint_names
        n = len(self.joint_names)
        self.command = command
        self._current_step = current_step
        self._matcher = JointMatcher(self.joint_names)
        self.state_qos = self.effort_qos = robot_qos()
        self._state_pub = node.create_publisher(JointState, state_topic, self.state_qos)
        self._clock_pub = None
        if clock_hz > 0:
            self._clock_pub = node.create_publisher(Clock, CLOCK, record_qos())
            self._clock_schedule = ClockSchedule(clock_hz, clock.dt_ns / 1e9, last_step)
        forward = command.form == "forward"
        self._command_sub = PolledSubscription(node, Float64MultiArray if forward else JointState, command.topic,
                                               robot_qos(depth=100), raw=not forward)
        self._wait_set = SubscriptionWaitSet(node, [self._command_sub])
        self.state_links = [None] * n  # no state faults are injected on this interface
        self._limits = np.array(settings.plant.torque_limit_nm, dtype=float).tolist()
        self.waits = 0
        self.wakeups_with_efforts = 0
        self.malformed = np.zeros(n, dtype=np.int64)
        self.out_of_range = np.zeros(n, dtype=np.int64)
        self.commands = 0

    # ------------------------------------------------------------- out
    def publish_state(self, k: int, q: np.ndarray, qd: np.ndarray, applied: np.ndarray, joints=None,
                      observed: bool = True) -> int:
        """State ``k`` (a resend when ``joints`` is given: the whole state again) and, with ``observed``, /clock
        when due. Returns the wall time [ns] just before it went out."""
        sec, nanosec = self.clock.sec_nanosec(k)
        t_ns = time.time_ns()
        self._state_pub.publish(joint_state_cdr.encode(sec, nanosec, self.joint_names, q.tolist(), qd.tolist(),
                                                       applied.tolist()))
        if joints is None and observed:
            self.publish_observed(k, None, None, None)
        return t_ns

    def publish_start_clock(self) -> None:
        if self._clock_pub is not None and self._clock_schedule.due(0):
            self._clock_pub.publish(CLOCK_CDR.pack(0x0100, 0, 0, 0))

    def publish_observed(self, k: int, q, qd, applied) -> None:
        """/clock of state ``k`` when due (the state itself went out with ``publish_state``)."""
        if self._clock_pub is not None and self._clock_schedule.due(k):
            sec, nanosec = self.clock.sec_nanosec(k)
            self._clock_pub.publish(CLOCK_CDR.pack(0x0100, 0, sec, nanosec))

    # ------------------------------------------------------------- in
    def effort_publishers(self) -> list[tuple[str, int]]:
        """Per joint: the command topic (resolved) and how many publishers it has (one: the bus, the robot's one
        commander), the same for every joint."""
        topic = self.node.resolve_topic_name(self._command_sub.topic)
        return [(topic, self._command_sub.get_publisher_count())] * len(self.joint_names)

    def wait(self, timeout_s: float) -> list[int]:
        """Block until a command is queued or ``timeout_s`` passed; every joint when one is (a command carries
        them all)."""
        ready = self._wait_set.wait(timeout_s)
        self.waits += 1
        self.wakeups_with_efforts += bool(ready)
        return list(range(len(self.joint_names))) if ready else []

    def take_efforts(self, joints=None) -> list[tuple[int, int, float, int]]:
        """Every queued command as (joint, step, torque [N m], received [ns]) per joint, saturated at the torque limit."""
        out = []
        while (got := self._command_sub.take()) is not None:
            data, received_ns = got
            try:
                if self.command.form == "forward":
                    efforts = [float(u) for u in data.data]
                    if len(efforts) != len(self.joint_names):
                        raise ValueError(f"{len(efforts)} efforts for {len(self.joint_names)} joints")
                    step = self._current_step()
                else:
                    sec, nanosec, names, _, _, effort = joint_state_cdr.decode(data)
                    efforts = self._matcher.efforts(names, effort)
                    step = self.clock.step_of_sec_nanosec(sec, nanosec)
            except (ValueError, IndexError, struct.error, UnicodeDecodeError):
                self.malformed += 1
                continue
            self.commands += 1
            for joint, u in enumerate(efforts):
                lim = self._limits[joint]
                if math.isfinite(u) and abs(u) > lim:
                    self.out_of_range[joint] += 1
                    u = lim if u > 0 else -lim
                out.append((joint, step, u, received_ns))
        return out

    # ------------------------------------------------------------- graph
    def needs(self, state_subscribers: int, clock_subscribers: int, joint_states_subscribers: int,
              recorders: int) -> list[Need]:
        """Before state 0: a reader of the state topic (the bus), a command writer, and the /clock readers."""
        node = self.node
        out = [Need(self._state_pub.topic_name, "subscribers", max(1, state_subscribers),
                    self._state_pub.get_subscription_count, "the joint bus (state_subscribers)"),
               Need(node.resolve_topic_name(self.command.topic), "publishers", 1,
                    self._command_sub.get_publisher_count, "the joint bus's commands")]
        if self._clock_pub is not None:
            out.append(Need(CLOCK, "subscribers", clock_subscribers, self._clock_pub.get_subscription_count,
                            f"the graph's nodes (clock_subscribers:={clock_subscribers})"))
        return out

    def flush(self, timeout_s: float = 2.0, stop=None) -> bool:
        """As :meth:`PlantEndpoints.flush`, for the state publisher alone (as the MuJoCo robot's): /clock's reliable
        readers are the graph's nodes (the reference), which their launcher stops once the bus has finished,
        without waiting for the robot, so the last ticks' acknowledgements never came and the robot waited out
        the whole timeout (10 s at every run's end)."""
        return wait_acked([self._state_pub], timeout_s, stop)

    def close(self, stop=None) -> None:
        """As :meth:`PlantEndpoints.close`."""
        self.flush(stop=stop)
        self._wait_set.destroy()

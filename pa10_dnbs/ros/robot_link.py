"""The robot behind the joint bus, seen by the plant's loops as a plant: ``state`` and ``step(tau)``.

Subscribes the robot's ``sensor_msgs/JointState`` (best effort, so a reliable or a best-effort publisher
matches; polled, raw CDR) and publishes its commands (reliable, volatile, depth 10): stamped JointState
efforts, or a Float64MultiArray in the arm's joint order (``RobotCommand``). ``step(tau)`` sends the command
answering the current state and blocks until the robot's next state (a newer stamp): lockstep, the robot
waits for it. While waiting, a re-sent copy of the current state means the command was lost: it goes out
again (JointState form only: a Float64MultiArray has no stamp, so a copy could be applied twice).
Faults (``RobotFault``, one line): a joint missing or named twice, a non-finite position or velocity, no new
state within ``timeout_s`` of wall time, another publisher on the command topic (a second commander: another
graph or controller driving the same robot, which would take whichever command came first; checked once the
first state is in, then every ``COMMANDERS_CHECK_S`` of wall time, as ros2_control refuses a second
controller claiming a joint) or on the state topic (a second robot, whose states would be taken as this one's,
checked alike); before raising, one command of zero effort on every joint goes out
(``send_safe``). Joints are matched by name (``wire/robot_interface.py``).
"""
from __future__ import annotations

import struct
import time

import numpy as np
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray

from ..wire import joint_state_cdr
from ..wire.robot_interface import JointMatcher, RobotCommand, RobotFault, RobotTimeline
from ..wire.steps import NS_PER_S
from .plant.standard_endpoints import robot_qos
from .acked import wait_acked
from .polled import PolledSubscription, SubscriptionWaitSet

SLICE_S = 0.05  # longest single wait for a robot state: the stop request is checked at least this often
STATE_DEPTH = 100  # robot states kept between two takes
SAFE_WAIT_S = 1.0   # wall time [s] a fault's safe command waits for a matched robot, then for its acknowledgement
OFF_GRID_TOLERANCE_NS = 1000  # lockstep: a new state's stamp may differ from the last one + dt by this much [ns]
COMMANDERS_CHECK_S = 0.2  # wall time between two looks for another publisher on the command topic


class RemoteRobot:
    def __init__(self, node, arm, dt_ns: int, state_topic: str, command: RobotCommand, timeout_s: float,
                 stopped=lambda: False, lockstep: bool = False):
        """``arm``: the arm whose joints are matched by name; ``dt_ns``: the graph's step [ns];
        ``timeout_s``: wall time without a new state that makes the robot stale; ``stopped()``: True once the
        node is asked to stop (a wait then returns); ``lockstep``: the robot must wait for each command and step
        by ``dt_ns`` (a new state before the command of the previous one, or a stamp more than
        OFF_GRID_TOLERANCE_NS off the last one + ``dt_ns``, is a RobotFault)."""
        self.arm = arm
        self.lockstep = lockstep
        self.dt_ns = dt_ns
        self._node = node
        self.joint_names = arm.joint_names
        self.n_joints = len(self.joint_names)
        self.limit_hits = np.zeros(self.n_joints, dtype=np.int64)  # the robot's own: not seen from here
        self.command = command
        self.state_topic = state_topic
        self.timeout_s = timeout_s
        self._stopped = stopped
        self._matcher = JointMatcher(self.joint_names)
        self.timeline = RobotTimeline(dt_ns)
        self._sub = PolledSubscription(node, JointState, state_topic, robot_qos("best_effort", STATE_DEPTH))
        self._wait_set = SubscriptionWaitSet(node, [self._sub])
        forward = command.form == "forward"
        self._pub = node.create_publisher(Float64MultiArray if forward else JointState, command.topic, robot_qos())
        self._forward_msg = Float64MultiArray() if forward else None
        self.q = self.qd = None           # the current state, arm order [rad], [rad/s]
        self.stamp = (0, 0)               # its robot stamp (sec, nanosec)
        self._next = None                 # a newer state that came before its command went out
        self.duplicates = 0               # copies of the current state (the robot re-sent it)
        self.old_states = 0               # states older than the current one (ignored)
        self.commands_sent = 0
        self.commands_resent = 0
        self.unanswered_states = 0        # new states that came before the command of the previous one
        self.last_was_safe = False        # the last command sent was the safe one (a fault's)
        self._next_commanders_check = 0.0  # time.monotonic() of the next look at the command topic
        self._copies_since_new = 0        # states since the last new one with its stamp (the stale fault says)
        self._old_since_new = 0           # ... and with an earlier one

    @property
    def state(self) -> tuple[np.ndarray, np.ndarray]:
        return np.array(self.q), np.array(self.qd)

    @property
    def publisher_count(self) -> int:
        return self._sub.get_publisher_count()

    @property
    def subscription(self):
        """The polled subscription of the robot's states (for a wait set over it and the efforts)."""
        return self._sub

    # ------------------------------------------------------------- states
    def _decode(self, data: bytes):
        """(kind, stamp, q, qd) of a robot state; RobotFault (after the safe command) when it is bad."""
        try:
            sec, nanosec, names, position, velocity, _ = joint_state_cdr.decode(data)
        except (ValueError, IndexError, struct.error, UnicodeDecodeError) as exc:
            self.fault(f"undecodable JointState on {self.state_topic}: {exc}")
        stamp_ns = sec * NS_PER_S + nanosec
        last_ns = self.timeline.last_ns
        kind = self.timeline.classify(stamp_ns)
        if kind != "new":
            return kind, None, None, None
        if self.lockstep and last_ns is not None and abs(stamp_ns - last_ns - self.dt_ns) > OFF_GRID_TOLERANCE_NS:
            self.stamp = (sec, nanosec)  # the safe command answers it
            self.fault(f"lockstep: the robot's state at robot time {stamp_ns / NS_PER_S:.6f} s comes "
                       f"{(stamp_ns - last_ns) / 1e6:g} ms after the previous one, not simulation.dt_s = "
                       f"{self.dt_ns / 1e6:g} ms: a lockstep robot steps by the graph's dt (set the robot's step, or "
                       "simulation.dt_s, to match; docs/your_robot.md)")
        try:
            q, qd = self._matcher.read(names, position, velocity)
        except RobotFault as exc:
            self.stamp = (sec, nanosec)  # the safe command answers the bad state
            self.fault(f"{exc} (state at robot time {sec + nanosec / NS_PER_S:.6f} s on {self.state_topic})")
        return kind, (sec, nanosec), q, qd

    def _take_new(self) -> bool:
        """Take every queued state; the first new one becomes ``_next``. Re-sent copies of the current state are
        counted; True when one came (the caller may re-send its command)."""
        copy = False
        while (got := self._sub.take()) is not None:
            kind, stamp, q, qd = self._decode(got[0])
            if kind == "duplicate":
                self.duplicates += 1
                self._copies_since_new += 1
                copy = True
            elif kind == "old":
                self.old_states += 1
                self._old_since_new += 1
            elif self._next is None:
                self._next = (stamp, q, qd)
                self._copies_since_new = self._old_since_new = 0
            else:  # two new states before we answered one: the robot does not wait for commands
                self.unanswered_states += 1
                self._next = (stamp, q, qd)
                self._copies_since_new = self._old_since_new = 0
                if self.lockstep:
                    self._not_waiting()
        return copy

    def _not_waiting(self):
        """Lockstep: the safe command answering the newest state (``_next``), then RobotFault: the robot sent it
        before the command answering the previous one."""
        self.stamp = self._next[0]
        sec, nanosec = self.stamp
        self.fault(f"lockstep: the robot sent its state at robot time {sec + nanosec / NS_PER_S:.6f} s before the "
                   "command answering the previous one: it does not wait for commands (a paced robot: `mode` "
                   "realtime; docs/your_robot.md)")

    def wait_first(self, timeout_s: float) -> bool:
        """Block until the robot's first state (it becomes the current state, step 0); False when stopped.
        RobotFault when none came within ``timeout_s``."""
        end = time.monotonic() + timeout_s
        while self._next is None:
            if self._stopped():
                return False
            left = end - time.monotonic()
            if left <= 0:
                raise RobotFault(f"no state from the robot on {self.state_topic} within {timeout_s:g} s "
                                 f"({self.publisher_count} publishers matched): is it running, on this "
                                 "ROS_DOMAIN_ID, publishing sensor_msgs/JointState?")
            if self._wait_set.wait(min(SLICE_S, left)):
                self._take_new()
        self._advance()
        self.check_commanders(force=True)
        return True

    def check_commanders(self, force: bool = False) -> None:
        """RobotFault (after the safe command) when the command topic has a publisher besides this bus (another
        commander of the robot) or the state topic has more than one (another robot). Looks at most every
        COMMANDERS_CHECK_S of wall time unless ``force``."""
        now = time.monotonic()
        if not force and now < self._next_commanders_check:
            return
        self._next_commanders_check = now + COMMANDERS_CHECK_S
        topic = self._pub.topic_name
        if self._node.count_publishers(topic) > 1:
            self.fault(f"another publisher on the robot's command topic {topic} besides this bus (publishers: "
                       f"{self._publishers(topic)}): a robot takes commands from one controller, and this one "
                       "would get whichever came first (another graph or controller driving it? stop it)")
        if self._node.count_publishers(self.state_topic) > 1:
            self.fault(f"more than one publisher on the robot's state topic {self.state_topic} (publishers: "
                       f"{self._publishers(self.state_topic)}): this bus would take the states of two robots "
                       "as one, and command both (a second robot, or a bag replayed on it? stop it)")

    def _publishers(self, topic: str) -> str:
        """The publishers of ``topic``, by node name (one that discovery has not named yet, as such)."""
        return ", ".join(sorted(f"{i.node_namespace.rstrip('/')}/{i.node_name}" if "_UNKNOWN_" not in i.node_name
                                else "a node not known by name yet"
                                for i in self._node.get_publishers_info_by_topic(topic)))

    def take_state(self) -> bool:
        """Paced: take what is queued; True when a new state became the current one (a newer one that came
        meanwhile replaces it: the robot does not wait, the latest state is what counts)."""
        self._take_new()
        if self._next is None:
            return False
        self._advance()
        return True

    def stale(self, waited_s: float):
        """The safe command and RobotFault: no new state for ``waited_s`` [s of wall time]."""
        sec, nanosec = self.stamp
        why = ""
        if self._copies_since_new:
            why += (f"; meanwhile {self._copies_since_new} states with that same stamp (does its header.stamp "
                    "advance? each state carries the robot's time, later at every step: docs/your_robot.md)")
        if self._old_since_new:
            why += (f"; meanwhile {self._old_since_new} states stamped earlier (the robot's time went back: a "
                    "restarted simulation? restart the graph with it)")
        self.fault(f"no state from the robot on {self.state_topic} for {waited_s:.3g} s after robot time "
                   f"{sec + nanosec / NS_PER_S:.6f} s (stale robot){why}")

    def _advance(self) -> None:
        self.stamp, self.q, self.qd = self._next
        self._next = None

    # ------------------------------------------------------------- commands
    def _send(self, tau) -> None:
        self.last_was_safe = False
        if self._forward_msg is not None:
            self._forward_msg.data = [float(u) for u in tau]
            self._pub.publish(self._forward_msg)
        else:
            self._pub.publish(joint_state_cdr.encode(*self.stamp, self.joint_names, (), (), [float(u) for u in tau]))

    def send(self, tau) -> None:
        """Paced: the command ``tau`` [N m] (arm order) answering the current state."""
        self.check_commanders()
        self._send(tau)
        self.commands_sent += 1

    def send_safe(self) -> None:
        """The safe command: zero effort on every joint, answering the current state."""
        self._send([0.0] * self.n_joints)
        self.last_was_safe = True

    def stop_command(self, timeout_s: float = 1.0) -> bool:
        """The safe command as the bus's last act (a paced robot goes on applying the last command it got), waiting
        at most ``timeout_s`` [s of wall time] for the robot to acknowledge it; True when it did."""
        self.send_safe()
        return wait_acked([self._pub], timeout_s)

    def fault(self, message: str):
        """Send the safe command, then raise RobotFault(``message``). A fault at the start (a rival seen with the
        first state) can come before discovery has matched the robot's command subscriber, and the bus exits right
        after: the command is sent once one is matched and waited on until acknowledged, SAFE_WAIT_S each at most
        (once in 3 full test runs the robot never got it)."""
        end = time.monotonic() + SAFE_WAIT_S
        while self._pub.get_subscription_count() == 0 and time.monotonic() < end:
            time.sleep(0.01)
        self.send_safe()
        wait_acked([self._pub], SAFE_WAIT_S)
        raise RobotFault(message)

    def step(self, tau) -> None:
        """Send ``tau`` [N m] (arm order) answering the current state, then wait for the robot's next state."""
        self._take_new()  # copies queued before this command are not a lost command
        if self.lockstep and self._next is not None:  # the next state came before this command: it did not wait
            self._not_waiting()
        self.check_commanders()
        self._send(tau)
        self.commands_sent += 1
        end = time.monotonic() + self.timeout_s
        while self._next is None:
            if self._stopped():
                return
            left = end - time.monotonic()
            if left <= 0:
                self.stale(self.timeout_s)
            if self._wait_set.wait(min(SLICE_S, left)) and self._take_new() and self._next is None \
                    and self._forward_msg is None:
                self._send(tau)  # the robot sent its state again: our command was lost
                self.commands_resent += 1
        self._advance()

    def counters(self) -> dict:
        return {"robot_duplicate_states": self.duplicates, "robot_old_states": self.old_states,
                "robot_commands": self.commands_sent, "robot_commands_resent": self.commands_resent,
                "robot_unanswered_states": self.unanswered_states, "robot_off_grid_states": self.timeline.off_grid}

    def close(self) -> None:
        """The subscription's wait set destroyed, and the command publisher: its endpoint leaves the robot's
        domain now, not when the participant's lease runs out (~20 s; the node exits without destroying it), so a
        next run against the same robot does not see it as a second commander."""
        self._wait_set.destroy()
        self._node.destroy_publisher(self._pub)

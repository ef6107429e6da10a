"""The standard robot interface (docs/your_robot.md), without ROS: command forms, joint matching by name, the
checks that turn a robot's bad state into a ``RobotFault``, and the robot's time line.

A robot publishes ``sensor_msgs/JointState`` (name, position [rad], velocity [rad/s]) on its state topic and
takes either ``sensor_msgs/JointState`` efforts [N m] on its command topic, stamped with the state they answer
(form ``joint_state``), or ``std_msgs/Float64MultiArray`` on ``/<controller>/commands`` in the arm's joint
order (form ``forward``). No rclpy here: the joint bus (``ros/joint_bus_node.py``) and the plant's standard
wire (``ros/plant/standard_endpoints.py``) use it, the unit tests (test/test_robot_interface.py) too.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

DEFAULT_STATE_TOPIC = "/robot_joint_states"      # topic_based_ros2_control's joint_states_topic
DEFAULT_COMMAND_TOPIC = "/robot_joint_command"   # ... and its joint_commands_topic
FORWARD_STATE_TOPIC = "/joint_states"            # joint_state_broadcaster, beside a forward command controller


class RobotFault(RuntimeError):
    """The robot broke the interface (a joint missing or named twice, a non-finite value, no state in time, another
    commander on its command topic): one line."""


@dataclass(frozen=True)
class RobotCommand:
    """How commands go to the robot: ``form`` 'joint_state' (stamped JointState efforts on ``topic``) or
    'forward' (Float64MultiArray on ``topic`` = /<controller>/commands, in the arm's joint order)."""

    form: str
    topic: str


class CommandTopicError(ValueError):
    """A command topic given with a form that has its own (the forward form): the topic's setting is at fault."""


def parse_robot_command(spec: str, command_topic: str | None = None) -> RobotCommand:
    """``--robot-command`` (``joint_state`` or ``forward:<controller name>``) and ``--robot-command-topic``
    (the JointState form's topic; None: /robot_joint_command) as a RobotCommand; ValueError saying why."""
    if spec == "joint_state":
        return RobotCommand("joint_state", command_topic or DEFAULT_COMMAND_TOPIC)
    if spec.startswith("forward:"):
        name = spec[len("forward:"):].strip("/")
        if not name or any(not (part and (part[0].isalpha() or part[0] == "_")
                                    and all(c.isalnum() or c == "_" for c in part)) for part in name.split("/")):
            raise ValueError(f"expected forward:<controller name> (a ROS name, e.g. forward:effort_controller), "
                             f"got {spec!r}")
        if command_topic is not None:
            raise CommandTopicError(f"only the JointState form takes a command topic; the forward form publishes on "
                                    f"/{name}/commands")
        return RobotCommand("forward", f"/{name}/commands")
    raise ValueError(f"expected joint_state or forward:<controller name>, got {spec!r}")


def default_state_topic(command: RobotCommand) -> str:
    """The robot's state topic when none is given: /robot_joint_states, or /joint_states beside a forward
    command controller (joint_state_broadcaster's)."""
    return FORWARD_STATE_TOPIC if command.form == "forward" else DEFAULT_STATE_TOPIC


class JointMatcher:
    """The arm's joints (``joint_names``, chain order) found by name in a robot's JointState."""

    def __init__(self, joint_names):
        self.joint_names = tuple(joint_names)
        self._cache: dict[tuple, list[int]] = {}

    def indices(self, names) -> list[int]:
        """For each arm joint, its index in ``names`` (a state's name list); RobotFault naming the joints
        that are not there, or those named more than once (which of the values would be the joint's?)."""
        key = tuple(names)
        found = self._cache.get(key)
        if found is None:
            where = {n: i for i, n in enumerate(key)}
            lacking = [j for j in self.joint_names if j not in where]
            if lacking:
                raise RobotFault(f"joint_states lacks {', '.join(lacking)} (it names {', '.join(key) or 'none'}; "
                                 f"the arm's joints: {', '.join(self.joint_names)})")
            twice = [j for j in self.joint_names if key.count(j) > 1]
            if twice:
                raise RobotFault(f"joint_states names {', '.join(twice)} more than once (it names {', '.join(key)}; "
                                 "each of the arm's joints must be named once)")
            found = self._cache[key] = [where[j] for j in self.joint_names]
        return found

    def read(self, names, position, velocity) -> tuple[list[float], list[float]]:
        """(q [rad], qd [rad/s]) of the arm's joints in chain order from a state's fields; RobotFault when a
        joint is missing, a field is too short or a value is not finite."""
        idx = self.indices(names)
        if len(position) < len(names) or len(velocity) < len(names):
            raise RobotFault(f"joint_states has {len(names)} names but {len(position)} positions and "
                             f"{len(velocity)} velocities (both are needed)")
        q = [float(position[i]) for i in idx]
        qd = [float(velocity[i]) for i in idx]
        for name, a, b in zip(self.joint_names, q, qd):
            if not (math.isfinite(a) and math.isfinite(b)):
                raise RobotFault(f"non-finite state of joint {name}: position {a}, velocity {b}")
        return q, qd

    def efforts(self, names, effort) -> list[float]:
        """A JointState command's efforts [N m] in chain order (the robot side); ValueError when a joint or
        its effort is missing."""
        try:
            idx = self.indices(names)
        except RobotFault as exc:
            raise ValueError(str(exc)) from None
        if len(effort) < len(names):
            raise ValueError(f"a command with {len(names)} names but {len(effort)} efforts")
        return [float(effort[i]) for i in idx]


class RobotTimeline:
    """The robot's stamps [ns] against the graph's steps: step 0 is the first state the bus forwards; a state
    is new when its stamp is later than the last one's, a duplicate (the robot re-sent it) when equal, old when
    earlier. ``off_grid`` counts new states whose stamp is not the last one + ``dt_ns`` (lockstep: a robot on
    another step than simulation.dt_s)."""

    def __init__(self, dt_ns: int):
        self.dt_ns = dt_ns
        self.first_ns: int | None = None
        self.last_ns: int | None = None
        self.off_grid = 0

    def classify(self, stamp_ns: int) -> str:
        """'new', 'duplicate' or 'old' (and remember a new stamp)."""
        if self.last_ns is None:
            self.first_ns = self.last_ns = stamp_ns
            return "new"
        if stamp_ns == self.last_ns:
            return "duplicate"
        if stamp_ns < self.last_ns:
            return "old"
        if stamp_ns - self.last_ns != self.dt_ns:
            self.off_grid += 1
        self.last_ns = stamp_ns
        return "new"

    def graph_ns(self, stamp_ns: int) -> int:
        """The graph's time [ns] of a robot stamp: counted from the first state."""
        return stamp_ns - (self.first_ns or 0)

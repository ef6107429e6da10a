"""``pa10-dnbs launch --robot external``: the flags of the joint bus, checked before anything starts.

No ROS here. The joint bus (``ros/joint_bus_node.py``) takes the plant's place in the graph; the robot is
already running, so the graph joins its ROS domain (``--domain-id``, default this shell's ROS_DOMAIN_ID, 0 when
unset) instead of leasing a private one. docs/your_robot.md has the interface.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

from ..config import ConfigError
from ..wire.robot_interface import CommandTopicError, default_state_topic, parse_robot_command
from ..wire.topics import DEFAULT_NS, check_free_topic, check_not_the_graphs, check_topic_name, resolve

ROBOTS = ("external",)


@dataclass(frozen=True)
class RobotOptions:
    robot: str = "external"
    command: str = "joint_state"        # --robot-command: joint_state or forward:<controller>
    state_topic: str | None = None      # --robot-state-topic; None: the command form's default
    command_topic: str | None = None    # --robot-command-topic (joint_state form); None: /robot_joint_command
    timeout_s: float = 1.0              # --robot-timeout [s of wall time]


def _check_topic(flag: str, topic: str, namespace: str) -> None:
    """A topic flag: an absolute ROS name (/a/b) or a relative one (resolved in the arm's ``namespace``), not one
    the graph holds with another type (/clock: the joint bus would wait for states that never come), nor one of
    the arm's graph's own (its joint_states: the joint bus would take its own states for a second robot's)."""
    try:
        check_not_the_graphs(check_free_topic(check_topic_name(topic), namespace), namespace)
    except ValueError as exc:
        raise ConfigError(f"{flag}: {exc}", setting=flag) from None


def check_robot_options(opt: RobotOptions, mode: str, namespace: str = DEFAULT_NS) -> dict:
    """The GraphOptions fields of ``opt``; ConfigError (one line, naming the setting: robot, robot_command, ...;
    the command line names its flag) when one is wrong. ``namespace``: the arm's, where the joint bus runs and a
    relative topic resolves (the state and command topics are compared so: ``x`` in /pa10 is ``/pa10/x``)."""
    if opt.robot not in ROBOTS:
        raise ConfigError(f"robot: expected {' or '.join(ROBOTS)}, got {opt.robot!r}", setting="robot")
    for flag, topic in (("robot_state_topic", opt.state_topic), ("robot_command_topic", opt.command_topic)):
        if topic is not None:
            _check_topic(flag, topic, namespace)
    try:
        command = parse_robot_command(opt.command, opt.command_topic)
    except ValueError as exc:
        setting = "robot_command_topic" if isinstance(exc, CommandTopicError) else "robot_command"
        raise ConfigError(f"{setting}: {exc}", setting=setting) from None
    state = opt.state_topic or default_state_topic(command)
    if resolve(state, namespace) == resolve(command.topic, namespace):  # it would read its own commands as states
        same = "" if state == command.topic else f" (both {resolve(state, namespace)} in the namespace {namespace})"
        raise ConfigError(f"robot_state_topic: the robot's state topic {state!r} must differ from its command topic "
                          f"{command.topic!r}{same}", setting="robot_state_topic")
    if not (math.isfinite(opt.timeout_s) and opt.timeout_s > 0):
        raise ConfigError(f"robot_timeout: must be a positive number of seconds, got {opt.timeout_s}",
                          setting="robot_timeout")
    return {"robot": opt.robot, "robot_command": opt.command, "robot_state_topic": opt.state_topic or "",
            "robot_command_topic": opt.command_topic or "", "robot_timeout_s": opt.timeout_s}

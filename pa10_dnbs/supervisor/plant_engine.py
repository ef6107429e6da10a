"""``pa10-dnbs launch --plant mujoco``: the MuJoCo robot node (``ros/mujoco_robot_node.py``) started with the graph,
behind the joint bus, as an external robot would be (docs/engines.md). No ROS here.

The graph is then the ``--robot external`` graph (the joint bus in the plant's place, docs/your_robot.md) plus
the robot node, in the launcher's own leased domain. The robot runs until the launcher stops it (SIGINT), so it
never ends before the bus has its last state; it is not in the start handshake (it publishes /clock at time 0,
latched, and its first state once the bus has matched).
"""
from __future__ import annotations

import sys
from pathlib import Path

from ..config import ConfigError
from .robot_options import RobotOptions

PLANTS = ("pybullet", "mujoco")
MUJOCO_ROBOT = "mujoco_robot"


def plant_robot_options(plant: str, robot: RobotOptions | None, mode: str) -> RobotOptions | None:
    """The joint bus's options for ``plant`` (None and ``robot`` unchanged for pybullet); ConfigError naming the
    setting when ``plant`` mujoco is combined with what it cannot run."""
    if plant not in PLANTS:
        raise ConfigError(f"plant: expected one of {', '.join(PLANTS)}, got {plant!r}", setting="plant")
    if plant == "pybullet":
        return robot
    if robot is not None:
        raise ConfigError("plant mujoco: not with an external robot (`robot` external; it starts its own robot, "
                          "behind the joint bus)", setting="plant")
    if mode != "lockstep":
        raise ConfigError("plant mujoco: only in lockstep mode so far (`mode` lockstep; the joint bus runs lockstep)",
                          setting="plant")
    return RobotOptions()


def mujoco_robot_command(opt, ros_args) -> tuple[str, list[str]]:
    """(name, argv) of the MuJoCo robot node of the graph ``opt`` (a GraphOptions); ``ros_args(node, params)``:
    node_specs' ROS arguments."""
    return MUJOCO_ROBOT, [sys.executable, "-m", "pa10_dnbs.ros.mujoco_robot_node"] + ros_args(MUJOCO_ROBOT, {
        "config_file": Path(opt.config_path), "mode": "lockstep", "duration_s": 0.0, "clock_hz": opt.clock_hz,
        "state_topic": opt.robot_state_topic or "/robot_joint_states",
        "command_topic": opt.robot_command_topic or "/robot_joint_command"})

"""joint_controller_node: one joint's DNBS (or PID) controller.

Subscribes only to /pa10/<joint>/state and /pa10/<joint>/reference; publishes
/pa10/<joint>/effort (sensor_msgs/JointState, effort only) stamped with the
stamp of the state it answers.
"""
from __future__ import annotations

import sys

from rclpy.node import Node
from sensor_msgs.msg import JointState
from trajectory_msgs.msg import JointTrajectory

from .. import JOINT_NAMES
from ..controller_factory import CONTROLLER_KINDS, build_controller
from .joint_loop import JointLoop
from .params import check_choice, declare, load_node_config
from .runtime import announce_ready, run_node
from .wire import StepClock, effort_topic, loop_qos, reference_qos, reference_topic, state_topic


class JointControllerNode(Node):
    def __init__(self):
        super().__init__("joint_controller")
        p = declare(self, {"config_file": "", "joint": "", "controller": "dnbs", "reliability": "reliable"})
        check_choice("joint", p["joint"], JOINT_NAMES)
        check_choice("controller", p["controller"], CONTROLLER_KINDS)
        cfg = load_node_config(p["config_file"])
        self.joint = p["joint"]
        index = JOINT_NAMES.index(self.joint)
        self.clock_ = StepClock(cfg["simulation"]["dt_s"])
        self.loop_ = JointLoop(build_controller(cfg, p["controller"], index), cfg["reference"]["preview_steps"])
        self._out = JointState()
        self._out.name = [self.joint]
        self._pub = self.create_publisher(JointState, effort_topic(self.joint), loop_qos(p["reliability"]))
        self.create_subscription(JointState, state_topic(self.joint), self._on_state, loop_qos(p["reliability"]))
        self.create_subscription(JointTrajectory, reference_topic(self.joint), self._on_reference, reference_qos())
        announce_ready(f"joint_controller {self.joint}")

    def _on_state(self, msg: JointState) -> None:
        self._publish(self.loop_.on_state(self.clock_.step_of(msg.header.stamp), msg.position[0], msg.velocity[0]))

    def _on_reference(self, msg: JointTrajectory) -> None:
        first = self.clock_.step_of(msg.header.stamp)
        pts = msg.points
        self._publish(self.loop_.add_reference(first, [pt.positions[0] for pt in pts],
                                               [pt.velocities[0] for pt in pts]))

    def _publish(self, answers) -> None:
        out = self._out
        for step, effort in answers:
            self.clock_.stamp(step, out.header.stamp)
            out.effort = [effort]
            self._pub.publish(out)


def main(args=None) -> int:
    return run_node(JointControllerNode, args)


if __name__ == "__main__":
    sys.exit(main())

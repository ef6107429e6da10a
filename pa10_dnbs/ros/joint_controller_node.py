"""joint_controller_node: one joint's DNBS (or PID) controller.

Subscribes only to /pa10/<joint>/state and /pa10/<joint>/reference; publishes
/pa10/<joint>/effort (sensor_msgs/JointState, effort only) stamped with the
stamp of the state it answers.
"""
from __future__ import annotations

import struct
import sys

from rclpy.node import Node
from sensor_msgs.msg import JointState
from trajectory_msgs.msg import JointTrajectory

from .. import JOINT_NAMES
from ..controller_factory import CONTROLLER_KINDS, build_controller
from . import joint_state_cdr
from .joint_loop import JointLoop
from .params import check_choice, declare, load_node_config
from .runtime import announce_ready, run_node
from .wire import StepClock, effort_topic, loop_qos, reference_qos, reference_topic, state_topic


class JointControllerNode(Node):
    def __init__(self):
        super().__init__("joint_controller")
        p = declare(self, {"config_file": "", "joint": "", "controller": "dnbs", "reliability": "reliable",
                           "queue_depth": 10})
        check_choice("joint", p["joint"], JOINT_NAMES)
        check_choice("controller", p["controller"], CONTROLLER_KINDS)
        cfg = load_node_config(p["config_file"])
        self.joint = p["joint"]
        index = JOINT_NAMES.index(self.joint)
        self.clock_ = StepClock(cfg["simulation"]["dt_s"])
        self.loop_ = JointLoop(build_controller(cfg, p["controller"], index), cfg["reference"]["preview_steps"])
        self.malformed = 0
        self.states_received = 0
        self.efforts_sent = 0
        self._names = [self.joint]
        qos = loop_qos(p["reliability"], depth=p["queue_depth"])
        self._pub = self.create_publisher(JointState, effort_topic(self.joint), qos)
        self.create_subscription(JointState, state_topic(self.joint), self._on_state, qos, raw=True)
        self.create_subscription(JointTrajectory, reference_topic(self.joint), self._on_reference, reference_qos())
        announce_ready(f"joint_controller {self.joint}")

    def _on_state(self, data: bytes) -> None:
        try:
            sec, nanosec, _, pos, vel, _ = joint_state_cdr.decode(data)
            q, qd = pos[0], vel[0]
        except (ValueError, IndexError, struct.error, UnicodeDecodeError):
            self.malformed += 1
            return
        self.states_received += 1
        self._publish(self.loop_.on_state(self.clock_.step_of_sec_nanosec(sec, nanosec), q, qd))

    def _on_reference(self, msg: JointTrajectory) -> None:
        first = self.clock_.step_of(msg.header.stamp)
        pts = msg.points
        self._publish(self.loop_.add_reference(first, [pt.positions[0] for pt in pts],
                                               [pt.velocities[0] for pt in pts]))

    def _publish(self, answers) -> None:
        for step, effort in answers:
            sec, nanosec = self.clock_.sec_nanosec(step)
            self._pub.publish(joint_state_cdr.encode(sec, nanosec, self._names, (), (), (effort,)))
            self.efforts_sent += 1

    def close(self) -> None:
        loop = self.loop_
        print(f"STATS joint_controller {self.joint}: states {self.states_received}, efforts {self.efforts_sent}, "
              f"last answered step {loop.last_step}, waiting for references {len(loop.pending_steps)}, "
              f"duplicates {loop.duplicates}, out of order {loop.out_of_order}, malformed {self.malformed}, "
              f"reference steps buffered {loop.reference_span}", flush=True)


def main(args=None) -> int:
    return run_node(JointControllerNode, args)


if __name__ == "__main__":
    sys.exit(main())

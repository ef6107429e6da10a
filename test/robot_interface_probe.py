"""A minimal client of the standard robot interface (docs/your_robot.md), for the robot node's tests: answers
every new state on /robot_joint_states with a JointState command on /robot_joint_command stamped like it, the
efforts a fixed function of the step (in reversed joint order, to prove matching by name), for ``steps`` states;
then writes every state it saw as JSON and exits.

    python test/robot_interface_probe.py JOINTS(comma-separated) STEPS OUT.json
"""
import json
import math
import sys

import rclpy
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import JointState


def effort(k: int, j: int) -> float:
    """The probe's effort for step k, joint j [N m]: small, smooth, different per joint."""
    return 2.0 * math.sin(0.01 * k + j)


def main():
    joints, steps, out = sys.argv[1].split(","), int(sys.argv[2]), sys.argv[3]
    rclpy.init()
    node = Node("robot_interface_probe")
    qos = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=100, reliability=ReliabilityPolicy.RELIABLE,
                     durability=DurabilityPolicy.VOLATILE)
    pub = node.create_publisher(JointState, "/robot_joint_command", qos)
    seen, clocks = {}, []

    def on_state(msg: JointState):
        if not clocks:  # answer nothing before the latched /clock 0 is in: the robot's first step would publish
            return      # /clock 1 ms, and a late clock reader gets only that (the robot re-sends its state)
        stamp = msg.header.stamp.sec * 10**9 + msg.header.stamp.nanosec
        k = round(stamp / 1e6)
        if k in seen:
            return
        where = {n: i for i, n in enumerate(msg.name)}
        seen[k] = {"position": [msg.position[where[j]] for j in joints],
                   "velocity": [msg.velocity[where[j]] for j in joints],
                   "effort": [msg.effort[where[j]] for j in joints]}
        if k >= steps:
            return
        cmd = JointState()
        cmd.header.stamp = msg.header.stamp
        cmd.name = list(reversed(joints))
        cmd.effort = [effort(k, j) for j in reversed(range(len(joints)))]
        pub.publish(cmd)

    node.create_subscription(JointState, "/robot_joint_states", on_state, qos)
    clock_qos = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=10, reliability=ReliabilityPolicy.RELIABLE,
                           durability=DurabilityPolicy.TRANSIENT_LOCAL)
    node.create_subscription(Clock, "/clock", lambda m: clocks.append(m.clock.sec * 10**9 + m.clock.nanosec),
                             clock_qos)
    while steps not in seen:
        rclpy.spin_once(node, timeout_sec=0.1)
    for _ in range(5):
        rclpy.spin_once(node, timeout_sec=0.05)
    with open(out, "w") as f:
        json.dump({"states": {str(k): v for k, v in seen.items()}, "clock_ns": clocks}, f)
    print("PROBE done", flush=True)


if __name__ == "__main__":
    main()

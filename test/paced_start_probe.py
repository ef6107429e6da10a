"""What a paced robot does before its first command (run as its own process; rev_e 17).

    python test/paced_start_probe.py DOMAIN_ID WAIT_S

Subscribes /robot_joint_states and holds a publisher on /robot_joint_command (matched like the joint bus, silent)
until the first state comes and WAIT_S s of wall time more, then sends one zero command and listens 1 s more.
Prints ``BEFORE <distinct stamps [ns]>`` and ``AFTER <distinct stamps>`` and ends with ``PROBE END``.
"""
import json
import os
import sys
import time


def main() -> int:
    os.environ["ROS_DOMAIN_ID"] = sys.argv[1]
    os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
    wait_s = float(sys.argv[2])
    import rclpy
    from rclpy.qos import QoSProfile, ReliabilityPolicy
    from sensor_msgs.msg import JointState

    rclpy.init()
    node = rclpy.create_node("paced_start_probe")
    stamps = []
    node.create_subscription(JointState, "/robot_joint_states",
                             lambda m: stamps.append(m.header.stamp.sec * 10**9 + m.header.stamp.nanosec),
                             QoSProfile(depth=1000, reliability=ReliabilityPolicy.BEST_EFFORT))
    pub = node.create_publisher(JointState, "/robot_joint_command", QoSProfile(depth=10))
    end = time.monotonic() + 60.0  # discovery: until the first state comes
    while not stamps and time.monotonic() < end:
        rclpy.spin_once(node, timeout_sec=0.05)
    end = time.monotonic() + wait_s
    while time.monotonic() < end:
        rclpy.spin_once(node, timeout_sec=0.05)
    before = sorted(set(stamps))
    print(f"BEFORE {json.dumps(before[:20])}", flush=True)
    stamps.clear()
    msg = JointState()
    msg.name = ["s1", "s2", "s3", "e1", "e2", "w1", "w2"]  # the PA10's
    msg.effort = [0.0] * len(msg.name)
    pub.publish(msg)
    end = time.monotonic() + 1.0
    while time.monotonic() < end:
        rclpy.spin_once(node, timeout_sec=0.05)
    print(f"AFTER {len(set(stamps))}", flush=True)
    print("PROBE END", flush=True)
    sys.stdout.flush()
    os._exit(0)


if __name__ == "__main__":
    sys.exit(main())

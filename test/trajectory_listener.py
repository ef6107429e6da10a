"""A stand-in for a graph's reference node as the trajectory sender sees it (run as its own process): for each
namespace given, a ``<ns>/trajectory`` subscription of JointTrajectory, and /clock published every 50 ms.

    python test/trajectory_listener.py DOMAIN_ID NS [NS ...]

Prints ``LISTENING`` once its subscriptions exist, ``GOT <topic> <joint names>`` for each message, and ends on
SIGINT or SIGTERM with ``LISTENER END``.
"""
import sys

from ros_child import ros_node, serve


def main() -> int:
    rclpy, node = ros_node(sys.argv[1], "trajectory_listener")
    from rosgraph_msgs.msg import Clock
    from trajectory_msgs.msg import JointTrajectory

    from pa10_dnbs.ros.reference_node import TRAJECTORY_QOS

    for ns in sys.argv[2:]:
        topic = ns + "/trajectory"
        node.create_subscription(JointTrajectory, topic,
                                 lambda m, t=topic: print(f"GOT {t} {' '.join(m.joint_names)}", flush=True),
                                 TRAJECTORY_QOS)
    clock = node.create_publisher(Clock, "/clock", 10)
    node.create_timer(0.05, lambda: clock.publish(Clock()))
    serve("LISTENING", "LISTENER END", lambda: rclpy.spin_once(node, timeout_sec=0.05))
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""A stand-in for a graph's reference node as the trajectory sender sees it (run as its own process): for each
namespace given, a ``<ns>/trajectory`` subscription of JointTrajectory, and /clock published every 50 ms.

    python test/trajectory_listener.py DOMAIN_ID NS [NS ...]

Prints ``LISTENING`` once its subscriptions exist, ``GOT <topic> <joint names>`` for each message, and ends on
SIGINT or SIGTERM with ``LISTENER END``.
"""
import os
import signal
import sys


def main() -> int:
    os.environ["ROS_DOMAIN_ID"] = sys.argv[1]
    os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
    import rclpy
    from rosgraph_msgs.msg import Clock
    from trajectory_msgs.msg import JointTrajectory

    from pa10_dnbs.ros.reference_node import TRAJECTORY_QOS

    rclpy.init(signal_handler_options=rclpy.signals.SignalHandlerOptions.NO)
    node = rclpy.create_node("trajectory_listener")
    for ns in sys.argv[2:]:
        topic = ns + "/trajectory"
        node.create_subscription(JointTrajectory, topic,
                                 lambda m, t=topic: print(f"GOT {t} {' '.join(m.joint_names)}", flush=True),
                                 TRAJECTORY_QOS)
    clock = node.create_publisher(Clock, "/clock", 10)
    node.create_timer(0.05, lambda: clock.publish(Clock()))
    stop = []
    signal.signal(signal.SIGINT, lambda *_: stop.append(1))
    signal.signal(signal.SIGTERM, lambda *_: stop.append(1))
    print("LISTENING", flush=True)
    while not stop:
        rclpy.spin_once(node, timeout_sec=0.05)
    print("LISTENER END", flush=True)
    os._exit(0)


if __name__ == "__main__":
    sys.exit(main())

"""A second publisher on a topic, sending nothing (run as its own process), for the tests of a second commander.

    python test/rival_publisher.py DOMAIN_ID TOPIC

Creates a ``sensor_msgs/JointState`` publisher on TOPIC (reliable, depth 10), prints ``RIVAL READY`` and ends on
SIGINT or SIGTERM with ``RIVAL END``.
"""
import os
import signal
import sys
import time


def main() -> int:
    os.environ["ROS_DOMAIN_ID"] = sys.argv[1]
    os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
    import rclpy
    from sensor_msgs.msg import JointState

    rclpy.init(signal_handler_options=rclpy.signals.SignalHandlerOptions.NO)
    node = rclpy.create_node("rival")
    node.create_publisher(JointState, sys.argv[2], 10)
    stop = []
    signal.signal(signal.SIGINT, lambda *_: stop.append(1))
    signal.signal(signal.SIGTERM, lambda *_: stop.append(1))
    print("RIVAL READY", flush=True)
    while not stop:
        time.sleep(0.05)
    print("RIVAL END", flush=True)
    os._exit(0)


if __name__ == "__main__":
    sys.exit(main())

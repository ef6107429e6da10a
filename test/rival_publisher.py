"""A second publisher on a topic, sending nothing (run as its own process), for the tests of a second commander.

    python test/rival_publisher.py DOMAIN_ID TOPIC

Creates a ``sensor_msgs/JointState`` publisher on TOPIC (reliable, depth 10), prints ``RIVAL READY`` and ends on
SIGINT or SIGTERM with ``RIVAL END``.
"""
import sys
import time

from ros_child import ros_node, serve


def main() -> int:
    _, node = ros_node(sys.argv[1], "rival")
    from sensor_msgs.msg import JointState

    node.create_publisher(JointState, sys.argv[2], 10)
    serve("RIVAL READY", "RIVAL END", lambda: time.sleep(0.05))
    return 0


if __name__ == "__main__":
    sys.exit(main())

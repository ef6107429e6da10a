"""Print, as JSON, the topics each joint controller subscribes to and publishes (run as a separate process).

    python test/graph_probe.py DOMAIN_ID TIMEOUT_S
"""
import json
import os
import sys
import time


def main() -> int:
    os.environ["ROS_DOMAIN_ID"] = sys.argv[1]
    os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
    import rclpy

    from pa10_dnbs import JOINT_NAMES

    rclpy.init(signal_handler_options=rclpy.signals.SignalHandlerOptions.NO)
    node = rclpy.create_node("graph_probe")
    found = {}
    deadline = time.monotonic() + float(sys.argv[2])
    while time.monotonic() < deadline and len(found) < len(JOINT_NAMES):
        names = node.get_node_names_and_namespaces()
        for j in JOINT_NAMES:
            name = f"joint_controller_{j}"
            if j in found or (name, "/pa10") not in names:
                continue
            subs = node.get_subscriber_names_and_types_by_node(name, "/pa10")
            pubs = node.get_publisher_names_and_types_by_node(name, "/pa10")
            if subs and pubs:
                found[j] = {"subscribes": sorted(t for t, _ in subs), "publishes": sorted(t for t, _ in pubs)}
        time.sleep(0.2)
    print(json.dumps(found))
    node.destroy_node()
    rclpy.try_shutdown()
    return 0


if __name__ == "__main__":
    sys.exit(main())

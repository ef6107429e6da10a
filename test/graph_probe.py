"""Print, as JSON, the topics each joint controller subscribes to and publishes (run as a separate process).

    python test/graph_probe.py DOMAIN_ID TIMEOUT_S [JOINTS [SETTLE_S]]

A controller counts as found once its state and reference subscriptions and its /diagnostics publisher
are visible; SETTLE_S (default 1) later, the endpoints of every found controller are read again and
printed, so an endpoint the node has is not missed because discovery had not reached it yet.
JOINTS: comma-separated (default all seven).
"""
import json
import os
import sys
import time


def main() -> int:
    os.environ["ROS_DOMAIN_ID"] = sys.argv[1]
    os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
    import rclpy

    from pa10_dnbs.arm import load_arm

    JOINT_NAMES = load_arm("pa10").joint_names

    joints = sys.argv[3].split(",") if len(sys.argv) > 3 and sys.argv[3] else list(JOINT_NAMES)
    settle_s = float(sys.argv[4]) if len(sys.argv) > 4 else 1.0
    rclpy.init(signal_handler_options=rclpy.signals.SignalHandlerOptions.NO)
    node = rclpy.create_node("graph_probe")

    def endpoints(j):
        name = f"joint_controller_{j}"
        if (name, "/pa10") not in node.get_node_names_and_namespaces():
            return set(), set()
        subs = node.get_subscriber_names_and_types_by_node(name, "/pa10")
        pubs = node.get_publisher_names_and_types_by_node(name, "/pa10")
        return {t for t, _ in subs}, {t for t, _ in pubs}

    found = set()
    deadline = time.monotonic() + float(sys.argv[2])
    while time.monotonic() < deadline and len(found) < len(joints):
        for j in joints:
            subs, pubs = endpoints(j)
            if {f"/pa10/{j}/state", f"/pa10/{j}/reference"} <= subs and "/diagnostics" in pubs:
                found.add(j)
        time.sleep(0.2)
    time.sleep(settle_s)
    result = {}
    for j in sorted(found):
        subs, pubs = endpoints(j)
        result[j] = {"subscribes": sorted(subs), "publishes": sorted(pubs)}
    print(json.dumps(result))
    node.destroy_node()
    rclpy.try_shutdown()
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""Print, as JSON, which /clock messages a reader that matched late still received (run as a separate process).

    python test/late_reader_probe.py DOMAIN_ID N TIMEOUT_S

A writer with the plant's /clock QoS publishes N clocks on /probe/clock once a first reader has matched; only
then is a second reader, with the reference node's /clock QoS, created: the late match discovery can produce
on a loaded machine. Prints {"early": [...], "late": [...]}: the nanoseconds of what each reader received.
"""
import json
import os
import sys
import time


def main() -> int:
    os.environ["ROS_DOMAIN_ID"] = sys.argv[1]
    os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
    n, timeout = int(sys.argv[2]), float(sys.argv[3])
    import rclpy
    from rclpy.executors import SingleThreadedExecutor
    from rosgraph_msgs.msg import Clock

    from pa10_dnbs.ros.reference_node import CLOCK_DEPTH
    from pa10_dnbs.ros.endpoints import record_qos

    rclpy.init(signal_handler_options=rclpy.signals.SignalHandlerOptions.NO)
    writer_node, early_node, late_node = (rclpy.create_node(f"late_reader_probe_{k}") for k in ("w", "e", "l"))
    got = {"early": [], "late": []}
    pub = writer_node.create_publisher(Clock, "/probe/clock", record_qos())  # as the plant's /clock (ros/plant/endpoints.py)
    early_node.create_subscription(Clock, "/probe/clock", lambda m: got["early"].append(m.clock.nanosec),
                                   record_qos(CLOCK_DEPTH))
    ex = SingleThreadedExecutor()
    for node in (writer_node, early_node, late_node):
        ex.add_node(node)
    end = time.monotonic() + timeout
    while pub.get_subscription_count() < 1 and time.monotonic() < end:
        ex.spin_once(timeout_sec=0.05)
    for k in range(n):
        msg = Clock()
        msg.clock.nanosec = k * 10_000_000
        pub.publish(msg)
    while len(got["early"]) < n and time.monotonic() < end:
        ex.spin_once(timeout_sec=0.05)
    late_node.create_subscription(Clock, "/probe/clock", lambda m: got["late"].append(m.clock.nanosec),
                                  record_qos(CLOCK_DEPTH))  # as the reference node's
    while len(got["late"]) < n and time.monotonic() < end:
        ex.spin_once(timeout_sec=0.05)
    print(json.dumps(got))
    ex.shutdown()
    for node in (writer_node, early_node, late_node):
        node.destroy_node()
    rclpy.try_shutdown()
    return 0


if __name__ == "__main__":
    sys.exit(main())

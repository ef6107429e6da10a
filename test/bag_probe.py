"""Subscribe (raw) to topics and save every payload received, per topic, in order (run as a separate process).

    python test/bag_probe.py OUT_PICKLE EXPECTED_TOTAL TIMEOUT_S /topic:pkg/msg/Type ...

Prints READY once subscribed; exits when EXPECTED_TOTAL messages arrived or after TIMEOUT_S.
"""
import pickle
import sys
import time


def main() -> int:
    import rclpy
    from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy

    from pa10_dnbs.ros.msg_types import message_class

    out, expected, timeout = sys.argv[1], int(sys.argv[2]), float(sys.argv[3])
    rclpy.init(signal_handler_options=rclpy.signals.SignalHandlerOptions.NO)
    node = rclpy.create_node("bag_probe")
    got: dict[str, list[bytes]] = {}
    qos = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=10000, reliability=ReliabilityPolicy.RELIABLE,
                     durability=DurabilityPolicy.VOLATILE)
    for spec in sys.argv[4:]:
        topic, type_name = spec.split(":")
        got[topic] = []
        node.create_subscription(message_class(type_name), topic, got[topic].append, qos, raw=True)
    print("READY bag_probe", flush=True)
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline and sum(map(len, got.values())) < expected:
        rclpy.spin_once(node, timeout_sec=0.1)
    with open(out, "wb") as f:
        pickle.dump(got, f)
    print(f"DONE {sum(map(len, got.values()))}", flush=True)
    rclpy.try_shutdown()
    return 0


if __name__ == "__main__":
    sys.exit(main())

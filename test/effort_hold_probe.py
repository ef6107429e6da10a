"""Stand in for the plant and a late recorder of one joint controller (run as a separate process).

    python test/effort_hold_probe.py DOMAIN_ID JOINT HOLD_S

Subscribes to /pa10/JOINT/effort (the "plant"), publishes one plausible state at step 0 once the
controller's effort publisher is matched, and counts the efforts received over HOLD_S s; then adds a
second effort subscription (the "recorder") and waits up to 20 s for both to receive. Prints JSON:
{"plant_before": n, "plant_after": n, "recorder_after": n}.
"""
import json
import os
import sys
import time


def main() -> int:
    os.environ["ROS_DOMAIN_ID"] = sys.argv[1]
    os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
    joint, hold_s = sys.argv[2], float(sys.argv[3])
    import rclpy
    from sensor_msgs.msg import JointState

    from pa10_dnbs.ros.endpoints import effort_topic, loop_qos, state_topic

    rclpy.init(signal_handler_options=rclpy.signals.SignalHandlerOptions.NO)
    node = rclpy.create_node("effort_hold_probe", namespace="/pa10")  # the arm's namespace: relative names resolve
    qos = loop_qos("reliable")
    got = {"plant": 0, "recorder": 0}

    def counter(key):
        def on_effort(_msg):
            got[key] += 1
        return on_effort

    plant = node.create_subscription(JointState, effort_topic(joint), counter("plant"), qos)
    state_pub = node.create_publisher(JointState, state_topic(joint), qos)

    def spin_for(seconds, until=lambda: False):
        end = time.monotonic() + seconds
        while time.monotonic() < end and not until():
            rclpy.spin_once(node, timeout_sec=0.02)

    spin_for(60, lambda: state_pub.get_subscription_count() >= 1 and plant.get_publisher_count() >= 1)
    if plant.get_publisher_count() < 1:
        print(json.dumps({"error": "the controller offered no effort publisher"}))
        return 1
    msg = JointState()
    msg.name, msg.position, msg.velocity = [joint], [0.0], [0.0]
    state_pub.publish(msg)  # header stamp 0: step 0
    spin_for(hold_s)
    before = got["plant"]
    node.create_subscription(JointState, effort_topic(joint), counter("recorder"), qos)
    spin_for(20, lambda: got["plant"] > before and got["recorder"] > 0)
    print(json.dumps({"plant_before": before, "plant_after": got["plant"], "recorder_after": got["recorder"]}))
    node.destroy_node()
    rclpy.try_shutdown()
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""A node whose constructor fails after its rcl node exists (run as a separate process).

    python test/failed_start_probe.py DOMAIN_ID

Runs ``runtime.run_node`` on a node that raises ``ParameterError`` once built, as a node rejecting a
parameter does, and prints JSON: {"code": exit code, "events": what happened, in order}: "armed" when the
teardown's exit deadline was armed, "freed" when the half-built node was freed. The process then leaves
with ``exit_process``, as a node does.
"""
import json
import os
import sys
import weakref


def main() -> None:
    os.environ["ROS_DOMAIN_ID"] = sys.argv[1]
    os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
    from rclpy.node import Node

    from pa10_dnbs.ros import exit_deadline, runtime
    from pa10_dnbs.ros.params import ParameterError

    events = []
    arm = exit_deadline.arm

    def recording_arm(seconds, code):
        events.append("armed")
        return arm(seconds, code)

    exit_deadline.arm = recording_arm

    class FailingNode(Node):
        def __init__(self):
            super().__init__("failed_start_probe")
            weakref.finalize(self, events.append, "freed")
            raise ParameterError("parameter probe: rejected on purpose")

    code = runtime.run_node(FailingNode)
    print(json.dumps({"code": code, "events": events}), flush=True)
    runtime.exit_process(0)


if __name__ == "__main__":
    main()

"""A node whose constructor fails after its rcl node exists (run as a separate process).

    python test/failed_start_probe.py DOMAIN_ID

Runs ``runtime.run_node`` on a node that raises ``ParameterError`` once built, as a node rejecting a
parameter does, and prints JSON: {"code": exit code, "alive": whether the half-built node still exists after
``run_node`` returned}. The process then leaves with ``exit_process``, as a node does.
"""
import gc
import json
import os
import sys
import weakref


def main() -> None:
    os.environ["ROS_DOMAIN_ID"] = sys.argv[1]
    os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
    from rclpy.node import Node

    from pa10_dnbs.ros.params import ParameterError
    from pa10_dnbs.ros.runtime import exit_process, run_node

    built = []

    class FailingNode(Node):
        def __init__(self):
            super().__init__("failed_start_probe")
            built.append(weakref.ref(self))
            raise ParameterError("parameter probe: rejected on purpose")

    code = run_node(FailingNode)
    gc.collect()
    print(json.dumps({"code": code, "alive": bool(built) and built[0]() is not None}), flush=True)
    exit_process(0)


if __name__ == "__main__":
    main()

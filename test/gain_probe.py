"""Read parameters of a running node through its parameter services (rcl_interfaces get_parameters and
describe_parameters), as a ROS user's tool does; prints one JSON line. argv: node (fully qualified), names."""
import json
import os
import sys

import rclpy
from param_services import call
from rcl_interfaces.srv import DescribeParameters, GetParameters


def main() -> None:
    target, names = sys.argv[1], sys.argv[2:]
    rclpy.init()
    node = rclpy.create_node("gain_probe")
    values = call(node, GetParameters, f"{target}/get_parameters", GetParameters.Request(names=names)).values
    described = call(node, DescribeParameters, f"{target}/describe_parameters",
                      DescribeParameters.Request(names=names)).descriptors
    print(json.dumps({name: {"value": v.double_value, "type": v.type, "read_only": d.read_only,
                             "description": d.description,
                             "range": [[r.from_value, r.to_value] for r in d.floating_point_range]}
                      for name, v, d in zip(names, values, described)}), flush=True)
    os._exit(0)  # no rclpy teardown (pa10_dnbs/ros/runtime.py says why)


if __name__ == "__main__":
    main()

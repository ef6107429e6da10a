"""Read parameters of a running node through its parameter services (rcl_interfaces get_parameters and
describe_parameters), as a ROS user's tool does; prints one JSON line. argv: node (fully qualified), names."""
import json
import os
import sys

import rclpy
from rcl_interfaces.srv import DescribeParameters, GetParameters


def _call(node, kind, service: str, request):
    client = node.create_client(kind, service)
    if not client.wait_for_service(timeout_sec=30.0):
        raise SystemExit(f"no service {service}")
    future = client.call_async(request)
    rclpy.spin_until_future_complete(node, future, timeout_sec=30.0)
    if future.result() is None:
        raise SystemExit(f"no answer from {service}")
    return future.result()


def main() -> None:
    target, names = sys.argv[1], sys.argv[2:]
    rclpy.init()
    node = rclpy.create_node("gain_probe")
    values = _call(node, GetParameters, f"{target}/get_parameters", GetParameters.Request(names=names)).values
    described = _call(node, DescribeParameters, f"{target}/describe_parameters",
                      DescribeParameters.Request(names=names)).descriptors
    print(json.dumps({name: {"value": v.double_value, "type": v.type, "read_only": d.read_only,
                             "description": d.description,
                             "range": [[r.from_value, r.to_value] for r in d.floating_point_range]}
                      for name, v, d in zip(names, values, described)}), flush=True)
    os._exit(0)  # no rclpy teardown (pa10_dnbs/ros/runtime.py says why)


if __name__ == "__main__":
    main()

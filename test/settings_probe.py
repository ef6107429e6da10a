"""Read every parameter of running nodes through their parameter services, as ``ros2 param dump`` does, and try
to change one of each (set_parameters); prints one JSON line:
{node: {"values": {name: value}, "read_only": {name: bool}, "descriptions": {name: text}, "set": [ok, reason]}}.
argv: (node fully qualified, parameter to try to set)..."""
import json
import os
import sys

import rclpy
from param_services import call
from rcl_interfaces.srv import DescribeParameters, GetParameters, ListParameters, SetParameters
from rclpy.parameter import Parameter, parameter_value_to_python


def probe(node, target: str, to_set: str) -> dict:
    names = list(call(node, ListParameters, f"{target}/list_parameters", ListParameters.Request()).result.names)
    values = call(node, GetParameters, f"{target}/get_parameters", GetParameters.Request(names=names)).values
    described = call(node, DescribeParameters, f"{target}/describe_parameters",
                      DescribeParameters.Request(names=names)).descriptors
    current = dict(zip(names, (parameter_value_to_python(v) for v in values)))
    value = current[to_set]
    changed = [v + 1.0 for v in value] if isinstance(value, list) else value + 1.0
    answer = call(node, SetParameters, f"{target}/set_parameters",
                   SetParameters.Request(parameters=[Parameter(to_set, value=changed).to_parameter_msg()])).results[0]
    return {"values": {n: list(v) if isinstance(v, (list, tuple)) else v for n, v in current.items()},
            "read_only": {n: d.read_only for n, d in zip(names, described)},
            "descriptions": {n: d.description for n, d in zip(names, described)},
            "set": [answer.successful, answer.reason]}


def main() -> None:
    args = sys.argv[1:]
    rclpy.init()
    node = rclpy.create_node("settings_probe")
    print(json.dumps({target: probe(node, target, name) for target, name in zip(args[::2], args[1::2])}), flush=True)
    os._exit(0)  # no rclpy teardown (pa10_dnbs/ros/runtime.py says why)


if __name__ == "__main__":
    main()

"""Build a plant node, a reference node and joint a1's PID controller (the iiwa's first joint) in this process
from a params file and count how often each reads its arm (arm file and URDF: ``arm_file._build``); prints one
JSON line {node: [paths read]}.
argv: the params file, then an optional config_file for all three nodes."""
import functools
import json
import os
import sys


def main() -> None:
    import pa10_dnbs.arm.arm_file as arm_file

    reads: list[str] = []
    build = arm_file._build
    arm_file._build = lambda path, *a, **k: (reads.append(str(path)), build(path, *a, **k))[1]
    import rclpy
    from pa10_dnbs.ros.plant.node import PlantNode
    from pa10_dnbs.ros.joint_controller_node import JointControllerNode
    from pa10_dnbs.ros.reference_node import ReferenceNode

    extra = ["-p", f"config_file:={sys.argv[2]}"] if len(sys.argv) > 2 else []
    joint = ["-p", "joint:=a1", "-p", "controller:=pid"]  # the plant and reference declare neither
    rclpy.init(args=["probe", "--ros-args", "-r", "__ns:=/pa10", *extra, *joint, "--params-file", sys.argv[1]])
    controller = functools.partial(JointControllerNode, ["probe", "--ros-args", *joint])
    out = {}
    for name, kind in (("plant", PlantNode), ("reference", ReferenceNode), ("joint_controller_a1", controller)):
        arm_file._load.cache_clear()  # each node its own process in a graph: nothing read before it
        reads.clear()
        node = kind()
        out[name] = list(reads)
        if name == "plant":
            node._close_plant()
    print(json.dumps(out), flush=True)
    os._exit(0)  # no rclpy teardown (pa10_dnbs/ros/runtime.py says why)


if __name__ == "__main__":
    main()

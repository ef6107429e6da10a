"""Topic names of the graph (no ROS imports, so bag tools can use them without rclpy).

/pa10/<joint>/{state,effort,reference} per joint, /joint_states and /clock
for the whole arm, /robot_description (URDF), /diagnostics (every node's fault
counters) and, in bags, /tf and /tf_static.
"""
ARM_NS = "/pa10"
JOINT_STATES = "/joint_states"
CLOCK = "/clock"
ROBOT_DESCRIPTION = "/robot_description"
TF = "/tf"
TF_STATIC = "/tf_static"
DIAGNOSTICS = "/diagnostics"


def state_topic(joint: str) -> str:
    return f"{ARM_NS}/{joint}/state"


def effort_topic(joint: str) -> str:
    return f"{ARM_NS}/{joint}/effort"


def reference_topic(joint: str) -> str:
    return f"{ARM_NS}/{joint}/reference"

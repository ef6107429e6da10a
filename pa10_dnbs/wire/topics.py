"""Topic names of the graph, relative to the arm's namespace (no ROS imports: bag tools use them without rclpy).

Nodes create RELATIVE names (``s1/state``, ``joint_states``, ...) and run in
the arm's ROS namespace (``--ros-args -r __ns:=/pa10``, the default), so
rcl resolves them to ``/pa10/s1/state``, ``/pa10/joint_states``, ... Four
names are global whatever the namespace: /clock, /tf, /tf_static and
/diagnostics. ``ArmTopics`` resolves every name for one namespace (what
tools outside a node need: the launcher, the recorder's topic list, bag
analysis); ``find_arm`` finds the layout of a recorded bag, old bags with
/joint_states and /robot_description at the root included.
"""
from __future__ import annotations

import re
from dataclasses import dataclass

DEFAULT_NS = "/pa10"

# relative to the arm's namespace
JOINT_STATES = "joint_states"
ROBOT_DESCRIPTION = "robot_description"
TRACKING = "tracking"  # the live view's JSON channel (Foxglove only, not a ROS topic)
TRAJECTORY = "trajectory"  # trajectory_msgs/JointTrajectory of every joint, taken by the reference node
#: reference batches each <joint>/reference endpoint keeps (KEEP_LAST, transient-local: ros/endpoints.py); the
#: launcher sizes the batches so that the reference node's lookahead fits in fewer (supervisor/node_specs.py)
REFERENCE_DEPTH = 20
#: the most reference points one message holds (the reference node's batch_steps): 24 MB per joint's message
MAX_BATCH_STEPS = 1_000_000

# global
CLOCK = "/clock"
TF = "/tf"
TF_STATIC = "/tf_static"
DIAGNOSTICS = "/diagnostics"

_NS_RE = re.compile(r"/[A-Za-z0-9_]+(/[A-Za-z0-9_]+)*")
_TOKEN_RE = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")  # a node name, a topic name's token (rcl: rmw_validate_*)
_TOKEN_RULE = "letters, digits and '_' (ASCII), not starting with a digit, as ROS 2 node and topic names need"


def state_topic(joint: str) -> str:
    """Relative: the plant's state of ``joint`` [rad, rad/s]."""
    return f"{joint}/state"


def effort_topic(joint: str) -> str:
    """Relative: the controller's torque for ``joint`` [N m]."""
    return f"{joint}/effort"


def reference_topic(joint: str) -> str:
    """Relative: the reference batches of ``joint`` [rad, rad/s]."""
    return f"{joint}/reference"


def check_namespace(ns: str) -> str:
    """``ns`` if it is a valid arm namespace (starts with '/', [A-Za-z0-9_] segments, no '//', no trailing '/',
    no segment starting with a digit, no '__': rcl's remap rule ``__ns:=`` cannot carry one), else ValueError
    saying why."""
    if not isinstance(ns, str) or not _NS_RE.fullmatch(ns) or "__" in ns \
            or any(s[0].isdigit() for s in ns.split("/")[1:]):
        raise ValueError(f"expected a ROS namespace like /pa10 or /lab/arm2 ('/'-separated names of letters, digits "
                         f"and '_', not starting with a digit, without '__'; no '//' and no trailing '/'), got {ns!r}")
    return ns


def check_joint_name(joint: str) -> str:
    """``joint`` if the graph can name its node (``joint_controller_<joint>``) and topics (``<joint>/state``, ...)
    after it, else ValueError naming the joint and the rule (checked before any node starts)."""
    if not isinstance(joint, str) or not _TOKEN_RE.fullmatch(joint) or "__" in f"_{joint}":
        raise ValueError(f"joint {joint!r} cannot name a ROS node or topic: expected {_TOKEN_RULE}, without '__' "
                         "and not starting with '_' (its node joint_controller_<joint> goes through rcl's remap "
                         "rule __node:=, which cannot carry '__')")
    return joint


def check_topic_name(topic: str) -> str:
    """``topic`` if it is a valid ROS 2 topic name, absolute (/a/b) or relative (a/b): '/'-separated tokens of
    ASCII letters, digits and '_', none starting with a digit; no '//', no trailing '/'. Else ValueError."""
    body = topic[1:] if isinstance(topic, str) and topic.startswith("/") else topic
    if not isinstance(body, str) or not body or any(not _TOKEN_RE.fullmatch(t) for t in body.split("/")):
        raise ValueError(f"expected a ROS topic name like /robot_joint_states ('/'-separated tokens of "
                         f"{_TOKEN_RULE}), got {topic!r}")
    return topic


#: global topics every graph holds with a type of its own (the graph's /clock, /tf, /tf_static, /diagnostics; every
#: ROS 2 node's /rosout and /parameter_events): rcl refuses a second type on them ('incompatible type')
TAKEN_TOPICS = {CLOCK: "rosgraph_msgs/msg/Clock", TF: "tf2_msgs/msg/TFMessage", TF_STATIC: "tf2_msgs/msg/TFMessage",
                DIAGNOSTICS: "diagnostic_msgs/msg/DiagnosticArray", "/rosout": "rcl_interfaces/msg/Log",
                "/parameter_events": "rcl_interfaces/msg/ParameterEvent"}


def check_free_topic(topic: str, ns: str = DEFAULT_NS) -> str:
    """``topic`` (a valid name; a relative one resolved in ``ns``) unless it is one of TAKEN_TOPICS: ValueError
    naming the topic and the type it carries there (a robot's joint states or commands need a topic of their own)."""
    name = resolve(topic, ns)
    if name in TAKEN_TOPICS:
        raise ValueError(f"{topic!r} is {name}, which carries {TAKEN_TOPICS[name]} in every ROS 2 graph: the "
                         "robot's joint states and commands need topics of their own")
    return topic


def check_not_the_graphs(topic: str, ns: str = DEFAULT_NS) -> str:
    """``topic`` unless it is one the arm's own graph in ``ns`` carries (its joint states, description, trajectory
    input, or a joint's state, effort or reference): ValueError naming it (a robot's topics would meet the graph's
    own publishers: the joint bus reads its own states as a second robot's)."""
    name = resolve(topic, ns)
    arm = ArmTopics(ns)
    own = {arm.joint_states: "the graph's own joint states", arm.robot_description: "the graph's robot description",
           resolve(TRAJECTORY, ns): "the graph's trajectory input"}
    what = own.get(name)
    rest = name[len(ns) + 1:].split("/") if name.startswith(ns + "/") else []
    if what is None and len(rest) == 2 and rest[1] in ("state", "effort", "reference"):
        what = f"joint {rest[0]}'s {rest[1]} topic in the graph"
    if what is not None:
        where = "" if name == topic else f" ({name} in the namespace {ns})"
        raise ValueError(f"{topic!r} is {what}{where}: the robot's joint states and commands need topics of "
                         "their own")
    return topic


def resolve(name: str, ns: str = DEFAULT_NS) -> str:
    """The absolute name of ``name`` in namespace ``ns`` (absolute names stay as they are)."""
    return name if name.startswith("/") else f"{ns}/{name}"


@dataclass(frozen=True)
class ArmTopics:
    """Every topic name of one arm, resolved (absolute)."""

    ns: str = DEFAULT_NS
    joint_states: str = ""
    robot_description: str = ""

    def __post_init__(self):
        if not self.joint_states:
            object.__setattr__(self, "joint_states", resolve(JOINT_STATES, self.ns))
        if not self.robot_description:
            object.__setattr__(self, "robot_description", resolve(ROBOT_DESCRIPTION, self.ns))

    @property
    def tracking(self) -> str:
        return resolve(TRACKING, self.ns)

    def state(self, joint: str) -> str:
        return resolve(state_topic(joint), self.ns)

    def effort(self, joint: str) -> str:
        return resolve(effort_topic(joint), self.ns)

    def reference(self, joint: str) -> str:
        return resolve(reference_topic(joint), self.ns)

    def relative(self, topic: str) -> str:
        """``topic`` as a node in ``ns`` names it (the inverse of ``resolve``); global names unchanged."""
        if topic == self.joint_states:
            return JOINT_STATES
        if topic == self.robot_description:
            return ROBOT_DESCRIPTION
        prefix = self.ns + "/"
        return topic[len(prefix):] if topic.startswith(prefix) else topic


def default_namespace(arm_name: str) -> str:
    """``/<arm name>`` (each run of characters outside [A-Za-z0-9] as one _, as a namespace cannot hold '__'): the
    namespace of an arm's graph by default."""
    name = re.sub(r"[^A-Za-z0-9]+", "_", arm_name).strip("_") or "arm"
    return "/" + (name if name[0].isalpha() else "arm_" + name)


def arm_topics(ns: str = DEFAULT_NS) -> ArmTopics:
    return ArmTopics(check_namespace(ns))


def legacy_topics() -> ArmTopics:
    """Bags recorded before the namespace rule: per-joint topics under /pa10, /joint_states and
    /robot_description at the root."""
    return ArmTopics(DEFAULT_NS, joint_states="/" + JOINT_STATES, robot_description="/" + ROBOT_DESCRIPTION)


def find_arm(topics, joint: str | None = None) -> ArmTopics | None:
    """The arm layout of a set of topic names (a bag's): the namespace whose ``<ns>/joint_states`` and
    ``<ns>/<joint>/reference`` are both there (with ``joint`` None: any joint's reference), else the legacy
    layout if it fits, else None. Several arms: the default namespace first, then the first in sorted order."""
    names = set(topics)
    suffix = "/" + JOINT_STATES

    def has_reference(arm: ArmTopics) -> bool:
        if joint is not None:
            return arm.reference(joint) in names
        prefix, tail = arm.ns + "/", "/" + reference_topic("x").split("/")[-1]
        return any(t.startswith(prefix) and t.endswith(tail) and t.count("/") == prefix.count("/") + 1
                   for t in names)

    found = sorted(t[: -len(suffix)] for t in names if t.endswith(suffix) and len(t) > len(suffix))
    found.sort(key=lambda ns: ns != DEFAULT_NS)
    for ns in found:
        arm = ArmTopics(ns)
        if has_reference(arm):
            return arm
    legacy = legacy_topics()
    if legacy.joint_states in names and has_reference(legacy):
        return legacy
    return None


def renamed(topic: str, src: ArmTopics | None, ns: str | None) -> str:
    """``topic`` of arm ``src`` moved into namespace ``ns`` (replay --namespace); global names, topics of no
    arm, and any topic when ``ns`` is None stay as they are."""
    if ns is None or src is None:
        return topic
    rel = src.relative(topic)
    return topic if rel.startswith("/") else resolve(rel, ns)

"""The channels the live view serves: topic, encoding, schema, latched or not.

ROS types go out as ``ros2msg`` schemas (the same text rosbag2 writes into an
MCAP bag: the .msg followed by each dependency) with ``cdr`` payloads, so
Foxglove decodes them natively and payloads are forwarded as they came off the
wire. <ns>/tracking is JSON with a JSON schema. Channel names are the ROS names
resolved in the arm's namespace (``ArmTopics``): /pa10/joint_states, /pa10/robot_description, /tf, ...
"""
from __future__ import annotations

import json
from dataclasses import dataclass

from ..bag.bag_writer import typestore
from ..wire.topics import DIAGNOSTICS, TF, TF_STATIC, ArmTopics
from . import tracking


@dataclass(frozen=True)
class ChannelSpec:
    topic: str
    schema_name: str
    schema_encoding: str   # ros2msg or jsonschema
    schema: bytes
    message_encoding: str  # cdr or json
    latched: bool = False  # re-sent to every new subscriber (what transient-local gives on ROS)


def ros2msg_schema(msgtype: str) -> bytes:
    """The ros2msg definition of ``msgtype`` (e.g. sensor_msgs/msg/JointState) with its dependencies."""
    text, _ = typestore().generate_msgdef(msgtype, ros_version=2)
    return text.encode()


def _ros(topic: str, msgtype: str, latched: bool = False) -> ChannelSpec:
    return ChannelSpec(topic, msgtype, "ros2msg", ros2msg_schema(msgtype), "cdr", latched)


def live_channels(arm: ArmTopics = ArmTopics()) -> list[ChannelSpec]:
    """Every channel of the live view of ``arm``, in the order they are advertised."""
    return [
        _ros(arm.robot_description, "std_msgs/msg/String", latched=True),
        _ros(arm.joint_states, "sensor_msgs/msg/JointState"),
        _ros(TF, "tf2_msgs/msg/TFMessage"),
        _ros(TF_STATIC, "tf2_msgs/msg/TFMessage", latched=True),
        ChannelSpec(arm.tracking, tracking.SCHEMA_NAME, "jsonschema", json.dumps(tracking.SCHEMA).encode(), "json"),
        _ros(DIAGNOSTICS, "diagnostic_msgs/msg/DiagnosticArray"),
    ]

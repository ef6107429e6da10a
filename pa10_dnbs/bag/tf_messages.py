"""tf2_msgs/msg/TFMessage payloads (CDR) from the URDF forward kinematics.

tf2_msgs has no PyPI wheel, so /tf cannot be published from rclpy here; the
recorder writes it into the bag instead, serialized with rosbags' type store.
"""
from __future__ import annotations

from ..kinematics.urdf_chain import FrameTransform
from .bag_writer import typestore


def tf_message_cdr(transforms: list[FrameTransform], sec: int, nanosec: int) -> bytes:
    """CDR bytes of a TFMessage holding ``transforms``, all stamped (sec, nanosec)."""
    ts = typestore()
    Time = ts.types["builtin_interfaces/msg/Time"]
    Header = ts.types["std_msgs/msg/Header"]
    TransformStamped = ts.types["geometry_msgs/msg/TransformStamped"]
    Transform = ts.types["geometry_msgs/msg/Transform"]
    Vector3 = ts.types["geometry_msgs/msg/Vector3"]
    Quaternion = ts.types["geometry_msgs/msg/Quaternion"]
    TFMessage = ts.types["tf2_msgs/msg/TFMessage"]
    stamped = [TransformStamped(header=Header(stamp=Time(sec=sec, nanosec=nanosec), frame_id=t.parent),
                                child_frame_id=t.child,
                                transform=Transform(translation=Vector3(*t.translation_m),
                                                    rotation=Quaternion(*t.rotation_xyzw)))
               for t in transforms]
    return bytes(ts.serialize_cdr(TFMessage(transforms=stamped), "tf2_msgs/msg/TFMessage"))

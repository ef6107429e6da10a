"""The raw JointTrajectory reader agrees with rclpy's serializer."""
import struct

import pytest

rclpy_serialization = pytest.importorskip("rclpy.serialization")
from builtin_interfaces.msg import Duration  # noqa: E402
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint  # noqa: E402

from pa10_dnbs.wire.trajectory_cdr import decode_first_joint  # noqa: E402


def _msg(names, points, frame_id="", sec=3, nanosec=141_000_000):
    m = JointTrajectory(joint_names=names, points=points)
    m.header.frame_id = frame_id
    m.header.stamp.sec, m.header.stamp.nanosec = sec, nanosec
    return m


@pytest.mark.parametrize("frame_id,names", [("", ["s1"]), ("base_link", ["a_long_joint_name"]), ("x", ["e1", "w2"])])
def test_reads_what_rclpy_writes(frame_id, names):
    pts = [JointTrajectoryPoint(positions=[0.1 * i] + [9.0] * (len(names) - 1), velocities=[-0.5 * i] * len(names),
                                accelerations=[1.0] * (i % 2), time_from_start=Duration(sec=0, nanosec=1_000_000 * i))
           for i in range(7)]
    data = rclpy_serialization.serialize_message(_msg(names, pts, frame_id))
    sec, nanosec, pos, vel = decode_first_joint(data)
    assert (sec, nanosec) == (3, 141_000_000)
    assert pos == [0.1 * i for i in range(7)] and vel == [-0.5 * i for i in range(7)]


def test_empty_batch_and_malformed_bytes():
    assert decode_first_joint(rclpy_serialization.serialize_message(_msg(["s1"], []))) == (3, 141_000_000, [], [])
    no_velocity = rclpy_serialization.serialize_message(_msg(["s1"], [JointTrajectoryPoint(positions=[1.0])]))
    with pytest.raises(ValueError):
        decode_first_joint(no_velocity)
    good = rclpy_serialization.serialize_message(_msg(["s1"], [JointTrajectoryPoint(positions=[1.0],
                                                                                    velocities=[2.0])]))
    with pytest.raises((ValueError, IndexError, struct.error)):
        decode_first_joint(good[:-12])

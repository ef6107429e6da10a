"""The raw JointTrajectory reader agrees with rclpy's serializer."""
import pytest

rclpy_serialization = pytest.importorskip("rclpy.serialization")
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint  # noqa: E402

from pa10_dnbs.wire import joint_trajectory_cdr  # noqa: E402


def _msg(sec, nsec, frame, names, points):
    msg = JointTrajectory(joint_names=names)
    msg.header.stamp.sec, msg.header.stamp.nanosec = sec, nsec
    msg.header.frame_id = frame
    for pos, vel, acc, eff, (d_sec, d_nsec) in points:
        pt = JointTrajectoryPoint(positions=pos, velocities=vel, accelerations=acc, effort=eff)
        pt.time_from_start.sec, pt.time_from_start.nanosec = d_sec, d_nsec
        msg.points.append(pt)
    return msg


CASES = [
    # what the reference node sends: one joint, position and velocity per point, 1 ms apart
    (0, 100_000_000, "", ["s1"], [([0.1 * i], [0.5], [], [], (0, i * 1_000_000)) for i in range(100)]),
    (12, 999_999_999, "base_link", ["s1", "w2"], [([1.0, -2.0], [], [3.0, 4.0], [5.0], (1, 5)),
                                                 ([], [], [], [], (2, 0))]),
    (3, 7, "x", [], []),
]


@pytest.mark.parametrize("sec,nsec,frame,names,points", CASES)
def test_decode_reads_rclpy_bytes(sec, nsec, frame, names, points):
    data = rclpy_serialization.serialize_message(_msg(sec, nsec, frame, names, points))
    got_sec, got_nsec, got_names, got_points = joint_trajectory_cdr.decode(data)
    assert (got_sec, got_nsec, got_names) == (sec, nsec, names)
    assert got_points == [(tuple(p[0]), p[4][0] * 1_000_000_000 + p[4][1]) for p in points]


def test_rejects_garbage():
    with pytest.raises(ValueError):
        joint_trajectory_cdr.decode(b"\x01\x00")
    data = rclpy_serialization.serialize_message(_msg(*CASES[0]))
    # the point count sits after the stamp, frame_id "" and joint_names ["s1"]: body offset 28
    assert data[32:36] == (100).to_bytes(4, "little")
    with pytest.raises(ValueError, match="bad point count"):
        joint_trajectory_cdr.decode(data[:32] + b"\xff" * 4 + data[36:])
    with pytest.raises(ValueError, match="bad string length"):  # frame_id length past the end
        joint_trajectory_cdr.decode(data[:12] + b"\xff" * 4 + data[16:])

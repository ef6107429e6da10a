"""The raw JointTrajectory reader and writer (wire/trajectory_cdr.py) agree with rclpy's serializer: every point,
the first joint's batch a controller reads, and the batch the reference node writes."""
import struct

import numpy as np
import pytest

rclpy_serialization = pytest.importorskip("rclpy.serialization")
from builtin_interfaces.msg import Duration  # noqa: E402
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint  # noqa: E402

from pa10_dnbs.wire import trajectory_cdr  # noqa: E402
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

def _full_msg(sec, nsec, frame, names, points):
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
    data = rclpy_serialization.serialize_message(_full_msg(sec, nsec, frame, names, points))
    got_sec, got_nsec, got_names, got_points = trajectory_cdr.decode(data)
    assert (got_sec, got_nsec, got_names) == (sec, nsec, names)
    assert got_points == [(tuple(p[0]), tuple(p[1]), p[4][0] * 1_000_000_000 + p[4][1]) for p in points]


def test_rejects_garbage():
    with pytest.raises(ValueError):
        trajectory_cdr.decode(b"\x01\x00")
    data = rclpy_serialization.serialize_message(_full_msg(*CASES[0]))
    # the point count sits after the stamp, frame_id "" and joint_names ["s1"]: body offset 28
    assert data[32:36] == (100).to_bytes(4, "little")
    with pytest.raises(ValueError, match="bad point count"):
        trajectory_cdr.decode(data[:32] + b"\xff" * 4 + data[36:])
    with pytest.raises(ValueError, match="bad string length"):  # frame_id length past the end
        trajectory_cdr.decode(data[:12] + b"\xff" * 4 + data[16:])


@pytest.mark.parametrize("name", ["s1", "e12", "w", "abcd", "a_long_joint_name"])  # both alignments of the points
@pytest.mark.parametrize("n", [0, 1, 2, 20, 150])
def test_the_reference_nodes_encoder_is_read_back_by_rclpy_and_by_the_reader(name, n):
    rng = np.random.default_rng(n + len(name))
    pos, vel = rng.uniform(-3, 3, n).tolist(), rng.uniform(-3, 3, n).tolist()
    step_ns = 10_000_000  # 10 ms: the 150-point batch crosses a second of time_from_start
    data = trajectory_cdr.encode_one_joint(12, 345_000_000, name, pos, vel, step_ns)
    m = rclpy_serialization.deserialize_message(data, JointTrajectory)
    assert m.joint_names == [name] and m.header.frame_id == ""
    assert (m.header.stamp.sec, m.header.stamp.nanosec) == (12, 345_000_000)
    assert [list(p.positions) for p in m.points] == [[x] for x in pos]
    assert [list(p.velocities) for p in m.points] == [[x] for x in vel]
    assert all(len(p.accelerations) == 0 and len(p.effort) == 0 for p in m.points)
    assert [(p.time_from_start.sec, p.time_from_start.nanosec) for p in m.points] == \
        [divmod(i * step_ns, 10**9) for i in range(n)]
    assert decode_first_joint(data) == (12, 345_000_000, pos, vel)


def test_the_encoder_refuses_mismatched_points():
    with pytest.raises(ValueError, match="2 positions but 1 velocities"):
        trajectory_cdr.encode_one_joint(0, 0, "s1", [0.0, 1.0], [0.0], 1_000_000)

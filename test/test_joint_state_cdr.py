"""The raw JointState codec agrees with rclpy's serializer in both directions."""
import math
import struct

import pytest

rclpy_serialization = pytest.importorskip("rclpy.serialization")
from sensor_msgs.msg import JointState  # noqa: E402

from pa10_dnbs.wire import joint_state_cdr  # noqa: E402

CASES = [
    (3, 141_000_000, ["s1"], [0.25], [-1.5], []),
    (0, 0, ["s1", "s2", "s3", "e1", "e2", "w1", "w2"], [0.1 * i for i in range(7)], [-0.2] * 7, [1e3, -232.0, 0, 0, 14.5, math.pi, -1e-300]),
    (12, 999_999_999, ["w2"], [], [], [7.25]),
    (1, 2, ["a_long_joint_name"], [1.0], [], [2.0]),
]


@pytest.mark.parametrize("sec,nsec,names,pos,vel,eff", CASES)
def test_encode_is_read_back_by_rclpy(sec, nsec, names, pos, vel, eff):
    msg = rclpy_serialization.deserialize_message(joint_state_cdr.encode(sec, nsec, names, pos, vel, eff), JointState)
    assert (msg.header.stamp.sec, msg.header.stamp.nanosec) == (sec, nsec)
    assert list(msg.name) == names
    assert list(msg.position) == pos and list(msg.velocity) == vel and list(msg.effort) == eff


@pytest.mark.parametrize("sec,nsec,names,pos,vel,eff", CASES)
def test_decode_reads_rclpy_bytes(sec, nsec, names, pos, vel, eff):
    msg = JointState(name=names, position=pos, velocity=vel, effort=eff)
    msg.header.stamp.sec, msg.header.stamp.nanosec = sec, nsec
    msg.header.frame_id = "base_link"
    got = joint_state_cdr.decode(rclpy_serialization.serialize_message(msg))
    assert got == (sec, nsec, names, tuple(pos), tuple(vel), tuple(eff))


def test_rejects_garbage():
    with pytest.raises(ValueError):
        joint_state_cdr.decode(b"\x01\x00")


@pytest.mark.parametrize("name,fields", [("s1", ("position", "velocity")), ("w2", ("effort",)),
                                         ("a_long_joint_name", ("position", "velocity")), ("e1", ("effort",))])
def test_one_joint_layout_equals_the_general_codec(name, fields):
    lay = joint_state_cdr.OneJointLayout(name, fields)
    vals = (0.25, -1.5)[:len(fields)] if fields != ("effort",) else (7.25,)
    kw = {f: (v,) for f, v in zip(fields, vals)}
    general = joint_state_cdr.encode(12, 999_999_999, [name], kw.get("position", ()), kw.get("velocity", ()),
                                     kw.get("effort", ()))
    fast = lay.encode(12, 999_999_999, *vals)
    assert fast == general
    assert lay.decode(fast) == (12, 999_999_999, vals)
    nan = lay.decode(lay.encode(1, 2, *([math.nan] * len(vals))))
    assert all(math.isnan(v) for v in nan[2])


def test_one_joint_layout_falls_back_for_other_valid_messages_and_rejects_garbage():
    lay = joint_state_cdr.OneJointLayout("s1", ("effort",))
    other = joint_state_cdr.encode(3, 4, ["s1"], [1.0], [], [2.5], frame_id="base")  # valid, other shape
    assert lay.decode(other) == (3, 4, (2.5,))
    with pytest.raises((ValueError, IndexError, UnicodeDecodeError, struct.error)):
        lay.decode(b"\x00\x01\x00\x00garbage")

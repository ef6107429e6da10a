"""sensor_msgs/msg/JointState <-> CDR bytes, without rclpy's message conversion.

The 1 kHz loop publishes and receives JointState as raw CDR (little-endian
XCDR1, as rmw_fastrtps writes it); building a Python message object costs
more than the control law itself. test/test_joint_state_cdr.py checks both
directions against rclpy.serialization.

Layout: encapsulation 00 01 00 00, then header.stamp (int32 sec, uint32
nanosec), header.frame_id (string), name (sequence<string>), position,
velocity, effort (sequence<float64>), each field aligned to its size relative
to the start of the body.
"""
from __future__ import annotations

import struct

from .steps import STAMP as _STAMP

_ENCAPSULATION = b"\x00\x01\x00\x00"
_U32 = struct.Struct("<I")


def _pad(n: int, align: int) -> int:
    return (-n) % align


def encode(sec: int, nanosec: int, names, position, velocity, effort, frame_id: str = "") -> bytes:
    """CDR bytes of a JointState."""
    body = bytearray(_STAMP.pack(sec, nanosec))

    def string(s: str) -> None:
        raw = s.encode("utf-8") + b"\x00"
        body.extend(b"\x00" * _pad(len(body), 4))
        body.extend(_U32.pack(len(raw)))
        body.extend(raw)

    def doubles(vals) -> None:
        body.extend(b"\x00" * _pad(len(body), 4))
        body.extend(_U32.pack(len(vals)))
        if vals:
            body.extend(b"\x00" * _pad(len(body), 8))
            body.extend(struct.pack(f"<{len(vals)}d", *vals))

    string(frame_id)
    body.extend(b"\x00" * _pad(len(body), 4))
    body.extend(_U32.pack(len(names)))
    for n in names:
        string(n)
    doubles(position)
    doubles(velocity)
    doubles(effort)
    return _ENCAPSULATION + bytes(body)


def decode(data: bytes):
    """(sec, nanosec, names, position, velocity, effort) of a JointState's CDR bytes."""
    if len(data) < 12 or data[1] != 1:
        raise ValueError("not little-endian CDR")
    mv = memoryview(data)[4:]
    sec, nanosec = _STAMP.unpack_from(mv, 0)
    off = 8

    def string(off: int):
        off += _pad(off, 4)
        (n,) = _U32.unpack_from(mv, off)
        off += 4
        return bytes(mv[off:off + n - 1]).decode("utf-8"), off + n

    def doubles(off: int):
        off += _pad(off, 4)
        (n,) = _U32.unpack_from(mv, off)
        off += 4
        if n == 0:
            return (), off
        off += _pad(off, 8)
        return struct.unpack_from(f"<{n}d", mv, off), off + 8 * n

    _, off = string(off)
    off += _pad(off, 4)
    (count,) = _U32.unpack_from(mv, off)
    off += 4
    names = []
    for _ in range(count):
        name, off = string(off)
        names.append(name)
    position, off = doubles(off)
    velocity, off = doubles(off)
    effort, off = doubles(off)
    return sec, nanosec, names, position, velocity, effort

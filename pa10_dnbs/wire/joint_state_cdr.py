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


class OneJointLayout:
    """Fast encode/decode of the one-joint JointState the 1 kHz loop sends: a fixed name and a fixed set of
    one-value fields (states: position and velocity; efforts: effort only).

    The bytes are those of ``encode`` (a template is encoded once, then only the stamp and the values are
    written into a copy); ``decode`` reads a message of exactly this layout with two ``unpack_from`` calls
    and falls back to the general ``decode`` for anything else, so odd but valid messages still decode and
    malformed ones still raise.
    """

    _FIELDS = ("position", "velocity", "effort")

    def __init__(self, name: str, fields: tuple[str, ...]):
        if not fields or any(f not in self._FIELDS for f in fields):
            raise ValueError(f"fields must be some of {self._FIELDS}, got {fields}")
        self.name, self.fields = name, tuple(f for f in self._FIELDS if f in fields)
        sentinels = {f: 1.0 + 2.0 ** -(20 + i) for i, f in enumerate(self._FIELDS)}
        vals = {f: (sentinels[f],) if f in self.fields else () for f in self._FIELDS}
        self.template = encode(0, 0, [name], vals["position"], vals["velocity"], vals["effort"])
        self._offsets = [self.template.index(struct.pack("<d", sentinels[f])) for f in self.fields]
        self._values = struct.Struct("<" + "".join(f"{o - p}xd" for o, p in zip(
            self._offsets, [4 + 8] + [o + 8 for o in self._offsets[:-1]])))
        self._head = 12
        self._body_const = (self.template[self._head:self._offsets[0]],
                            *(self.template[a + 8:b] for a, b in zip(self._offsets, self._offsets[1:])),
                            self.template[self._offsets[-1] + 8:])

    def encode(self, sec: int, nanosec: int, *values: float) -> bytes:
        """Bytes of this joint's message stamped (sec, nanosec) with one value per field, in field order."""
        buf = bytearray(self.template)
        _STAMP.pack_into(buf, 4, sec, nanosec)
        for off, v in zip(self._offsets, values):
            struct.pack_into("<d", buf, off, v)
        return bytes(buf)

    def decode(self, data: bytes) -> tuple[int, int, tuple[float, ...]]:
        """(sec, nanosec, values in field order); ValueError / struct.error / IndexError on malformed bytes."""
        if len(data) == len(self.template) and data[:4] == self.template[:4] and self._same_shape(data):
            sec, nanosec = _STAMP.unpack_from(data, 4)
            return sec, nanosec, self._values.unpack_from(data, 12)
        sec, nanosec, _, position, velocity, effort = decode(data)
        got = {"position": position, "velocity": velocity, "effort": effort}
        return sec, nanosec, tuple(got[f][0] for f in self.fields)

    def _same_shape(self, data: bytes) -> bool:
        offs = self._offsets
        if data[self._head:offs[0]] != self._body_const[0]:
            return False
        for i in range(1, len(offs)):
            if data[offs[i - 1] + 8:offs[i]] != self._body_const[i]:
                return False
        return data[offs[-1] + 8:] == self._body_const[-1]

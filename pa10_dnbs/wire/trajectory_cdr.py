"""trajectory_msgs/msg/JointTrajectory CDR bytes <-> the reference points, without rclpy.

The reference node sends each joint's x_d in batches (one joint, 20-100
points); building rclpy's Python message (a JointTrajectoryPoint object per
point) and serializing it costs ~0.9 ms per 100 points here, so the
reference node writes the bytes itself (``encode_one_joint``, ~8x faster, and
its padding bytes are zeros where rclpy leaves whatever was in its buffer),
and controllers (``decode_first_joint``) and observers (``decode``: the live
view, progress lines) read them here. test/test_trajectory_cdr.py checks all
three against rclpy's serializer.

Layout (little-endian XCDR1, alignment relative to the body after the 4-byte
encapsulation): header.stamp (int32 sec, uint32 nanosec), header.frame_id
(string), joint_names (sequence<string>), points (sequence of positions,
velocities, accelerations, effort: sequence<float64> each, then
time_from_start: int32 sec, uint32 nanosec).
"""
from __future__ import annotations

import struct

from .steps import NS_PER_S, STAMP

_U32 = struct.Struct("<I")
ENCAPSULATION = b"\x00\x01\x00\x00"  # CDR, little-endian
# one point (one position, one velocity, no accelerations or efforts, time_from_start) starting at an offset
# = 0 mod 8 (count, pad, float64, count, pad, float64, count 0, count 0, sec, nanosec), or = 4 mod 8 (no pad)
_POINT_AT_0, _POINT_AT_4 = "I4xdI4xdIIiI", "IdI4xdIIiI"

Point = tuple[tuple[float, ...], tuple[float, ...], int]  # positions [rad], velocities [rad/s], time_from_start [ns]


def encode_one_joint(sec: int, nanosec: int, name: str, positions, velocities, step_ns: int) -> bytes:
    """A JointTrajectory of the one joint ``name`` stamped (sec, nanosec): point i holds positions[i] [rad],
    velocities[i] [rad/s] and time_from_start i * step_ns [ns]; empty frame_id, no accelerations or efforts."""
    if len(positions) != len(velocities):
        raise ValueError(f"{len(positions)} positions but {len(velocities)} velocities")
    raw = name.encode("utf-8") + b"\x00"
    # stamp; frame_id "" (length 1: its NUL) padded to 4; one joint name (length, bytes, NUL) padded to 4
    head = struct.pack("<iII4xII", sec, nanosec, 1, 1, len(raw)) + raw + b"\x00" * ((-len(raw)) % 4)
    n = len(positions)
    first = _POINT_AT_0 if (len(head) + 4) % 8 == 0 else _POINT_AT_4  # where the points start (after the count)
    fmt = "<I" + (first + _POINT_AT_0 * (n - 1) if n else "")
    values = [n]
    for i, (p, v) in enumerate(zip(positions, velocities)):
        values += (1, p, 1, v, 0, 0, *divmod(i * step_ns, NS_PER_S))
    return ENCAPSULATION + head + struct.pack(fmt, *values)


def decode(data: bytes) -> tuple[int, int, list[str], list[Point]]:
    """(sec, nanosec, joint_names, [(positions, velocities, time_from_start [ns]), ...]) of a JointTrajectory.

    Raises ValueError (or struct.error) on bytes that are not a little-endian JointTrajectory.
    (The point loop is written out flat: a batch of 100 points is read in about 0.1 ms.)
    """
    if len(data) < 12 or data[1] != 1:
        raise ValueError("not little-endian CDR")
    mv = memoryview(data)[4:]
    size = len(mv)
    u32 = _U32.unpack_from
    sec, nanosec = STAMP.unpack_from(mv, 0)

    def string(off: int) -> tuple[str, int]:
        off += (-off) % 4
        (n,) = u32(mv, off)
        off += 4
        if n == 0 or off + n > size:
            raise ValueError("bad string length")
        return bytes(mv[off:off + n - 1]).decode("utf-8"), off + n

    _, off = string(8)  # header.frame_id
    off += (-off) % 4
    (count,) = u32(mv, off)
    off += 4
    if count > size:
        raise ValueError("bad name count")
    names = []
    for _ in range(count):
        name, off = string(off)
        names.append(name)
    off += (-off) % 4
    (n_points,) = u32(mv, off)
    off += 4
    if n_points > size:  # each point takes at least 24 bytes: a count this large is garbage
        raise ValueError("bad point count")
    points = []
    for _ in range(n_points):
        positions = velocities = ()
        for field in range(4):  # positions, velocities, accelerations, effort: sequence<float64> each
            off += (-off) % 4
            (n,) = u32(mv, off)
            off += 4
            if n:
                off += (-off) % 8
                if field == 0:
                    positions = struct.unpack_from(f"<{n}d", mv, off)
                elif field == 1:
                    velocities = struct.unpack_from(f"<{n}d", mv, off)
                off += 8 * n
        off += (-off) % 4
        d_sec, d_nanosec = STAMP.unpack_from(mv, off)
        off += 8
        points.append((positions, velocities, d_sec * NS_PER_S + d_nanosec))
    return sec, nanosec, names, points


def decode_first_joint(data: bytes) -> tuple[int, int, list[float], list[float]]:
    """(stamp sec, nanosec, positions[0] of each point, velocities[0] of each point): a controller's batch.

    Raises ValueError or struct.error on malformed bytes, also when a point has no position or no velocity.
    """
    sec, nanosec, _, points = decode(data)
    if any(not p or not v for p, v, _ in points):
        raise ValueError("a reference point without position or velocity")
    return sec, nanosec, [p[0] for p, _, _ in points], [v[0] for _, v, _ in points]

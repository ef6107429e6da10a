"""trajectory_msgs/msg/JointTrajectory CDR bytes -> the first joint's positions and velocities, without rclpy.

A controller receives its reference as a batch of points for one joint;
building rclpy's Python message (a JointTrajectoryPoint object per point)
costs milliseconds per 100-point batch, in the middle of the 1 kHz loop.
Layout (little-endian XCDR1, offsets from the start of the body, each field
aligned to its size): header.stamp (int32 sec, uint32 nanosec),
header.frame_id (string), joint_names (sequence<string>), points
(sequence of: positions, velocities, accelerations, effort as
sequence<float64>, time_from_start as int32 sec + uint32 nanosec).
test/test_trajectory_cdr.py checks it against rclpy's serializer.
"""
from __future__ import annotations

import struct

_U32 = struct.Struct("<I")
_D = struct.Struct("<d")
_STAMP = struct.Struct("<iI")


def decode_first_joint(data: bytes) -> tuple[int, int, list[float], list[float]]:
    """(stamp sec, nanosec, positions[0] of each point, velocities[0] of each point).

    Raises ValueError, IndexError or struct.error on malformed bytes (also when a point has no position or
    no velocity).
    """
    if len(data) < 12 or data[1] != 1:
        raise ValueError("not little-endian CDR")
    mv = memoryview(data)[4:]
    sec, nanosec = _STAMP.unpack_from(mv, 0)
    off = 8
    u32 = _U32.unpack_from

    def skip_string(off: int) -> int:
        off += -off % 4
        (n,) = u32(mv, off)
        return off + 4 + n

    off = skip_string(off)                  # frame_id
    off += -off % 4
    (count,) = u32(mv, off)
    off += 4
    for _ in range(count):                  # joint_names
        off = skip_string(off)
    off += -off % 4
    (n_points,) = u32(mv, off)
    off += 4
    positions, velocities = [], []
    for _ in range(n_points):
        firsts = []
        for _field in range(4):             # positions, velocities, accelerations, effort
            off += -off % 4
            (n,) = u32(mv, off)
            off += 4
            if n:
                off += -off % 8
                firsts.append(_D.unpack_from(mv, off)[0])
                off += 8 * n
            else:
                firsts.append(None)
        off += -off % 4
        off += 8                            # time_from_start
        if firsts[0] is None or firsts[1] is None:
            raise ValueError("a reference point without position or velocity")
        positions.append(firsts[0])
        velocities.append(firsts[1])
    if off > len(mv):
        raise ValueError("truncated JointTrajectory")
    return sec, nanosec, positions, velocities

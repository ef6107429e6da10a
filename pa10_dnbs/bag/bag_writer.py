"""Write a rosbag2 bag directory (format version 9, MCAP storage, CDR payloads) with rosbags.

Payloads are written as they came off the wire (serialized CDR); a topic's
connection (type, ros2msg schema, offered QoS profiles) is added on its first
message. ``close()`` writes the MCAP summary and ``metadata.yaml``; until it
runs, the bag is incomplete.

Compression (default ``zstd``): zstd-compressed MCAP chunks of about 1 MiB,
what ``ros2 bag record -s mcap`` writes by default (storage-level compression:
metadata.yaml keeps compression_format and compression_mode empty, every MCAP
reader decompresses chunks itself). ``none`` writes plain chunks.
"""
from __future__ import annotations

import shutil
from pathlib import Path

from rosbags.interfaces import Qos
from rosbags.rosbag2 import CompressionFormat, CompressionMode, StoragePlugin, Writer
from rosbags.typesys import Stores, get_typestore

ROSBAG2_VERSION = 9
COMPRESSIONS = ("zstd", "none")
_TYPESTORE = None


class BagExistsError(FileExistsError):
    """The bag path exists and ``force`` was not given."""


def typestore():
    """The ROS 2 Jazzy type store (message definitions for the bag's schemas)."""
    global _TYPESTORE
    if _TYPESTORE is None:
        _TYPESTORE = get_typestore(Stores.ROS2_JAZZY)
    return _TYPESTORE


def check_bag_path(path: Path, force: bool) -> None:
    """Refuse an existing path unless ``force``; raises BagExistsError."""
    path = Path(path)
    if path.exists() and not force:
        raise BagExistsError(f"{path} exists; pass --force to replace it")
    if not path.parent.is_dir():
        raise FileNotFoundError(f"{path.parent}: no such directory for the bag")


class BagWriter:
    """One open bag. ``write(topic, t_ns, data)`` after ``add_topic``."""

    def __init__(self, path: Path, force: bool = False, custom_data: dict[str, str] | None = None,
                 compression: str = "zstd"):
        if compression not in COMPRESSIONS:
            raise ValueError(f"bag compression must be one of {', '.join(COMPRESSIONS)}, got {compression!r}")
        path = Path(path)
        check_bag_path(path, force)
        if path.exists():
            if path.is_dir() and not path.is_symlink():
                shutil.rmtree(path)
            else:
                path.unlink()
        self.path = path
        self._writer = Writer(path, version=ROSBAG2_VERSION, storage_plugin=StoragePlugin.MCAP)
        if compression == "zstd":
            self._writer.set_compression(CompressionMode.STORAGE, CompressionFormat.ZSTD)
        self.compression = compression
        for key, value in (custom_data or {}).items():
            self._writer.set_custom_data(key, str(value))
        self._writer.open()
        self._conns: dict[str, object] = {}
        self.counts: dict[str, int] = {}
        self.closed = False

    def add_topic(self, topic: str, msgtype: str, qos_profiles: list[Qos]) -> None:
        """Register ``topic`` of ``msgtype`` (e.g. sensor_msgs/msg/JointState) once."""
        if topic in self._conns:
            return
        store = typestore()
        if msgtype not in store.types:
            raise KeyError(f"{topic}: message type {msgtype} is not in the ROS 2 Jazzy type store")
        self._conns[topic] = self._writer.add_connection(topic, msgtype, typestore=store,
                                                         offered_qos_profiles=qos_profiles)
        self.counts[topic] = 0

    def has_topic(self, topic: str) -> bool:
        return topic in self._conns

    def write(self, topic: str, t_ns: int, data: bytes) -> None:
        """Append one serialized message received at ``t_ns`` [ns]."""
        self._writer.write(self._conns[topic], t_ns, data)
        self.counts[topic] += 1

    def close(self) -> None:
        """Write the MCAP summary and metadata.yaml (once)."""
        if not self.closed:
            self.closed = True
            self._writer.close()

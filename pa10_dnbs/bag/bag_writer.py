"""Write a rosbag2 bag directory (format version 9, MCAP storage, CDR payloads) as Jazzy's ``ros2 bag record``.

Payloads are written as they came off the wire (serialized CDR); a topic's
channel (type, ros2msg schema, offered QoS profiles, type hash) is added on
its first message. ``close()`` writes the MCAP summary and ``metadata.yaml``;
until it runs, the bag is incomplete.

What rosbag2_storage_mcap (Jazzy) writes, written the same way: MCAP profile
``ros2``; per channel the metadata ``offered_qos_profiles`` (YAML) and
``topic_type_hash`` (``RIHS01_<sha256 hex>``, the same value as
``type_description_hash`` in metadata.yaml); a Metadata record ``rosbag2``
whose ``serialized_metadata`` is metadata.yaml's body; ``ros_distro: jazzy``.
Every MCAP CRC is written (chunks, data section, summary; mcap_file.py), as
``ros2 bag record --storage-config-file`` writes with ``noChunkCRC: false``
and ``enableDataCRC: true``; analyse and replay check them (mcap_check.py).

Compression (default ``zstd``): zstd-compressed MCAP chunks of about 1 MiB,
what ``ros2 bag record -s mcap`` writes with ``compression: Zstd``
(storage-level compression: metadata.yaml keeps compression_format and
compression_mode empty, every MCAP reader decompresses chunks itself).
``none`` writes plain chunks.
"""
from __future__ import annotations

import os
import shutil
from pathlib import Path

import yaml
from rosbags.interfaces import Qos
from rosbags.rosbag2.metadata import dump_qos_v9
from rosbags.typesys import Stores, get_typestore

from .. import __version__
from ..output_mark import OUTPUT_MARK, OUTPUT_MARK_TEXT, is_previous_output
from ..refused import Refused
from .mcap_file import McapFileWriter

ROSBAG2_VERSION = 9
ROS_DISTRO = "jazzy"
COMPRESSIONS = ("zstd", "none")
ZSTD_LEVEL = 3  # zstd's default level, what rosbags and the MCAP writers use
_TYPESTORE = None


class BagExistsError(FileExistsError, Refused):
    """The bag path exists and ``force`` was not given."""


def typestore():
    """The ROS 2 Jazzy type store (message definitions and type hashes for the bag's schemas)."""
    global _TYPESTORE
    if _TYPESTORE is None:
        _TYPESTORE = get_typestore(Stores.ROS2_JAZZY)
    return _TYPESTORE


def check_bag_path(path: Path, force: bool) -> None:
    """Refuse an existing path unless ``force``, and even with ``force`` anything but an empty folder or a bag this
    writer made (it holds OUTPUT_MARK): a user's folder is never emptied for a bag. Raises BagExistsError."""
    path = Path(path)
    if os.path.lexists(path) and not force:
        raise BagExistsError(f"{path} exists; pass `force` to replace it")
    if os.path.lexists(path) and (path.is_symlink() or not path.is_dir()):
        raise BagExistsError(f"{path} exists and is not a folder: `force` replaces only a bag folder")
    if path.is_dir() and any(path.iterdir()) and not is_previous_output(path):
        raise BagExistsError(f"{path} holds files that are not a pa10-dnbs bag: `force` replaces only an empty "
                             "folder or a bag pa10-dnbs recorded; remove it yourself or choose another folder")
    if not path.parent.is_dir():
        raise FileNotFoundError(f"{path.parent}: no such directory for the bag")


def _yaml(data) -> str:
    return yaml.safe_dump(data, default_flow_style=False, sort_keys=False, width=1 << 16)


class BagWriter:
    """One open bag. ``write(topic, t_ns, data)`` after ``add_topic``."""

    def __init__(self, path: Path, force: bool = False, custom_data: dict[str, str] | None = None,
                 compression: str = "zstd"):
        if compression not in COMPRESSIONS:
            raise ValueError(f"bag compression must be one of {', '.join(COMPRESSIONS)}, got {compression!r}")
        path = Path(path)
        check_bag_path(path, force)
        if path.exists():
            shutil.rmtree(path)   # an empty folder or a bag of ours (check_bag_path)
        path.mkdir(mode=0o755)
        (path / OUTPUT_MARK).write_text(OUTPUT_MARK_TEXT)   # what a later --force may replace (check_bag_path)
        self.path = path
        self.mcap_path = path / f"{path.name}.mcap"
        self.compression = compression
        compress = None
        if compression == "zstd":
            import zstandard

            compress = zstandard.ZstdCompressor(level=ZSTD_LEVEL).compress
        self._file = McapFileWriter(self.mcap_path.open("xb"), profile="ros2", library=f"pa10_dnbs {__version__}",
                                    compression="zstd" if compress else "", compress=compress)
        self.custom_data = {k: str(v) for k, v in (custom_data or {}).items()}
        self._ids: dict[str, int] = {}          # topic -> channel id
        self._schema_ids: dict[str, int] = {}   # message type -> schema id
        self._topics: list[dict] = []           # metadata.yaml's topic_metadata, in channel order
        self.counts: dict[str, int] = {}
        self.closed = False

    def add_topic(self, topic: str, msgtype: str, qos_profiles: list[Qos]) -> None:
        """Register ``topic`` of ``msgtype`` (e.g. sensor_msgs/msg/JointState) once."""
        if topic in self._ids:
            return
        store = typestore()
        if msgtype not in store.types:
            raise KeyError(f"{topic}: message type {msgtype} is not in the ROS 2 Jazzy type store")
        type_hash = store.hash_rihs01(msgtype)
        if msgtype not in self._schema_ids:
            msgdef, _ = store.generate_msgdef(msgtype, ros_version=2)
            self._schema_ids[msgtype] = self._file.schema(msgtype, "ros2msg", msgdef.encode())
        qos = dump_qos_v9(list(qos_profiles))
        self._ids[topic] = self._file.channel(topic, "cdr", self._schema_ids[msgtype], {
            "offered_qos_profiles": _yaml(qos).strip(), "topic_type_hash": type_hash})
        self._topics.append({"name": topic, "type": msgtype, "serialization_format": "cdr",
                             "offered_qos_profiles": qos, "type_description_hash": type_hash})
        self.counts[topic] = 0

    def has_topic(self, topic: str) -> bool:
        return topic in self._ids

    def write(self, topic: str, t_ns: int, data: bytes) -> None:
        """Append one serialized message received at ``t_ns`` [ns]."""
        self._file.message(self._ids[topic], t_ns, data)
        self.counts[topic] += 1

    def _metadata(self) -> dict:
        """metadata.yaml's ``rosbag2_bagfile_information`` (rosbag2 version 9)."""
        f = self._file
        start = f.start_ns if f.start_ns is not None else (1 << 63) - 1
        duration = f.end_ns - f.start_ns if f.start_ns is not None else 0
        count = sum(self.counts.values())
        return {
            "version": ROSBAG2_VERSION,
            "storage_identifier": "mcap",
            "relative_file_paths": [self.mcap_path.name],
            "duration": {"nanoseconds": duration},
            "starting_time": {"nanoseconds_since_epoch": start},
            "message_count": count,
            "topics_with_message_count": [{"topic_metadata": t, "message_count": self.counts[t["name"]]}
                                          for t in self._topics],
            "compression_format": "",
            "compression_mode": "",
            "files": [{"path": self.mcap_path.name, "starting_time": {"nanoseconds_since_epoch": start},
                       "duration": {"nanoseconds": duration}, "message_count": count}],
            "custom_data": self.custom_data or None,
            "ros_distro": ROS_DISTRO,
        }

    def close(self) -> None:
        """Write the MCAP summary and metadata.yaml (once)."""
        if self.closed:
            return
        self.closed = True
        self._file.close_chunk()
        info = self._metadata()
        self._file.metadata("rosbag2", {"serialized_metadata": _yaml(info)})
        self._file.finish()
        tmp = self.path / "metadata.yaml.tmp"
        tmp.write_text(_yaml({"rosbag2_bagfile_information": info}), encoding="utf-8")
        os.replace(tmp, self.path / "metadata.yaml")

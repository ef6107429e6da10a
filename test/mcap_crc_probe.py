"""Test helper: a bag's MCAP CRCs and Jazzy fields, read with the ``mcap`` library (and zlib), not the project's reader."""
from __future__ import annotations

import re
import struct
import zlib
from pathlib import Path

import yaml
from mcap.reader import make_reader
from mcap.records import Chunk, DataEnd, Footer
from mcap.stream_reader import StreamReader, get_chunk_data_stream

RIHS01 = re.compile(r"RIHS01_[0-9a-f]{64}")


def mcap_file(bag: Path) -> Path:
    meta = yaml.safe_load((bag / "metadata.yaml").read_text())["rosbag2_bagfile_information"]
    (name,) = meta["relative_file_paths"]
    return bag / name


def assert_every_crc_written_and_valid(path: Path) -> int:
    """Every chunk's uncompressed_crc non-zero and equal to zlib.crc32 of its records, the data section and
    summary CRCs non-zero and right (the mcap StreamReader checks chunks and data section itself; the summary
    CRC is recomputed here from the bytes). Returns the number of chunks."""
    records = list(StreamReader(str(path), validate_crcs=True, emit_chunks=True).records)
    chunks = [r for r in records if isinstance(r, Chunk)]
    assert chunks
    for c in chunks:
        stream, n = get_chunk_data_stream(c, validate_crc=False)
        assert c.uncompressed_crc != 0 and c.uncompressed_crc == zlib.crc32(stream.read(n))
    (data_end,) = [r for r in records if isinstance(r, DataEnd)]
    (footer,) = [r for r in records if isinstance(r, Footer)]
    raw = path.read_bytes()
    assert data_end.data_section_crc != 0
    assert data_end.data_section_crc == zlib.crc32(raw[:footer.summary_start - 13])  # DataEnd: 13 bytes
    footer_at = len(raw) - 8 - 29
    assert footer.summary_crc != 0
    assert footer.summary_crc == zlib.crc32(raw[footer.summary_start:footer_at] + struct.pack(
        "<BQQQ", 0x02, 20, footer.summary_start, footer.summary_offset_start))
    with path.open("rb") as f:
        reader = make_reader(f, validate_crcs=True)
        n_msgs = sum(1 for _ in reader.iter_messages(log_time_order=False))
        assert n_msgs == reader.get_summary().statistics.message_count
    return len(chunks)


def assert_jazzy_fields(bag: Path) -> dict:
    """Channel metadata topic_type_hash = metadata.yaml's type_description_hash (RIHS01_<sha256 hex>) and
    offered_qos_profiles = metadata.yaml's, for every topic; ros_distro jazzy in metadata.yaml and in the MCAP
    rosbag2 metadata record (whose serialized_metadata is metadata.yaml's body). Returns {topic: hash}."""
    info = yaml.safe_load((bag / "metadata.yaml").read_text())["rosbag2_bagfile_information"]
    assert info["ros_distro"] == "jazzy"
    in_yaml = {t["topic_metadata"]["name"]: t["topic_metadata"] for t in info["topics_with_message_count"]}
    with mcap_file(bag).open("rb") as f:
        reader = make_reader(f)
        assert reader.get_header().profile == "ros2"
        channels = {c.topic: c for c in reader.get_summary().channels.values()}
        (record,) = [m for m in reader.iter_metadata() if m.name == "rosbag2"]
    assert set(channels) == set(in_yaml)
    hashes = {}
    for topic, ch in channels.items():
        assert set(ch.metadata) == {"offered_qos_profiles", "topic_type_hash"}, topic
        assert RIHS01.fullmatch(ch.metadata["topic_type_hash"]), ch.metadata
        assert ch.metadata["topic_type_hash"] == in_yaml[topic]["type_description_hash"], topic
        assert yaml.safe_load(ch.metadata["offered_qos_profiles"]) == in_yaml[topic]["offered_qos_profiles"], topic
        hashes[topic] = ch.metadata["topic_type_hash"]
    assert yaml.safe_load(record.metadata["serialized_metadata"]) == info
    return hashes


def rosidl_type_hash(msgtype: str) -> str | None:
    """The type hash rosidl generated for ``msgtype`` (share/<pkg>/msg/<Type>.json of the ROS wheels in
    the venv; what rclpy announces on the wire), or None if that package's share directory is not installed."""
    import json
    import sys

    pkg, _, name = msgtype.split("/")
    path = Path(sys.prefix) / "share" / pkg / "msg" / f"{name}.json"  # the ROS wheels install share/ in the venv
    if not path.is_file():
        return None
    for entry in json.loads(path.read_text())["type_hashes"]:
        if entry["type_name"] == msgtype:
            return entry["hash_string"]
    return None

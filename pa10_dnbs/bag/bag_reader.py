"""Open a rosbag2 MCAP bag for reading, turning every way it can be broken into one clear BagError.

Checks, in order: the path exists; it is a bag directory (``metadata.yaml``)
or an ``.mcap`` file inside one; metadata.yaml parses; each storage file ends
with the MCAP footer magic (a recording cut off before it closed does not);
every CRC in it matches (summary, each chunk, data section: mcap_check.py; a
damaged chunk is named with the topics it held); metadata.yaml agrees with the
MCAP summaries (total and per-topic message counts, topics and their types,
start and duration: metadata_check.py); rosbags opens it.
Reading messages later converts decoding failures into BagError as well.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Iterator

import yaml

from ..config_yaml import BoundedSafeLoader, yaml_error_line
from ..refused import Refused
from .metadata_check import check_metadata, read_summary

MCAP_MAGIC = b"\x89MCAP0\r\n"


class BagError(Refused):
    """The bag is missing, not a bag, truncated, corrupt, or lacks what is needed."""


@dataclass
class TopicInfo:
    msgtype: str
    count: int


class Bag:
    """A validated, open bag. Use as a context manager or call ``close()``."""

    def __init__(self, path: Path):
        from rosbags.rosbag2 import Reader

        self.path = _bag_dir(Path(path))
        meta = _load_metadata(self.path)
        info = meta["rosbag2_bagfile_information"]
        files = _storage_files(self.path, info)
        if info.get("storage_identifier") != "mcap":
            raise BagError(f"{self.path}: storage is {info.get('storage_identifier')!r}, expected mcap")
        for f in files:
            _check_mcap_file(f)
        self.crc_reports = [_check_crcs(f) for f in files]
        check_metadata(self.path, info, [read_summary(f, BagError) for f in files], BagError)
        self.custom_data: dict[str, str] = _custom_data(self.path, info)
        try:
            self._reader = Reader(self.path)
            self._reader.open()
        except Exception as exc:  # rosbags raises several types for damaged files
            raise BagError(f"{self.path}: cannot open bag: {exc}") from None
        self.topics = {c.topic: TopicInfo(c.msgtype, c.msgcount) for c in self._reader.connections}
        self.start_ns = self._reader.start_time
        self.end_ns = self._reader.end_time
        self.message_count = self._reader.message_count

    def __enter__(self) -> "Bag":
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def close(self) -> None:
        self._reader.close()

    def require_topics(self, topics, why: str) -> None:
        """BagError naming every topic of ``topics`` the bag lacks (or holds no message of)."""
        lacking = [t for t in topics if t not in self.topics or self.topics[t].count == 0]
        if lacking:
            raise BagError(f"{self.path}: {why} needs topics the bag does not have: {', '.join(lacking)}")

    def crc_note(self) -> str:
        """What the CRC check found, e.g. 'CRCs valid: 14 of 14 chunks, data section, summary'."""
        return "; ".join(r.describe() for r in self.crc_reports)

    def qos_profiles(self, topic: str):
        """The offered QoS profiles recorded for ``topic`` (rosbags Qos tuples)."""
        for c in self._reader.connections:
            if c.topic == topic:
                return list(c.ext.offered_qos_profiles)
        raise KeyError(topic)

    def messages(self, topics=None, start_ns: int | None = None) -> Iterator[tuple[str, str, int, bytes]]:
        """(topic, msgtype, log time [ns], CDR bytes) in log-time order."""
        conns = [c for c in self._reader.connections if topics is None or c.topic in topics]
        if not conns:
            return
        try:
            for conn, t_ns, data in self._reader.messages(connections=conns, start=start_ns):
                yield conn.topic, conn.msgtype, t_ns, data
        except BagError:
            raise
        except Exception as exc:
            raise BagError(f"{self.path}: corrupt data while reading messages: {type(exc).__name__}: {exc}") from None


def _bag_dir(path: Path) -> Path:
    if not path.exists():
        raise BagError(f"{path}: no such bag (" + ("a symbolic link to nothing, or a loop of links)" if path.is_symlink()
                                                   else "the path does not exist)"))
    if path.is_file():
        if path.suffix == ".mcap" and (path.parent / "metadata.yaml").is_file():
            return path.parent
        raise BagError(f"{path}: not a rosbag2 bag (expected a bag directory holding metadata.yaml)")
    if not (path / "metadata.yaml").is_file():
        mcaps = sorted(path.glob("*.mcap")) if path.is_dir() else []
        if mcaps:   # what a recording cut off before it was closed leaves (a second Ctrl-C, a kill)
            raise BagError(f"{path}: an unfinished bag: {mcaps[0].name} but no metadata.yaml (its recording was cut "
                           "off before it was closed: a second Ctrl-C, a kill); rosbag2's `ros2 bag reindex` "
                           "rebuilds metadata.yaml from the .mcap")
        raise BagError(f"{path}: not a rosbag2 bag directory (no metadata.yaml)")
    return path


def _load_metadata(bag: Path) -> dict:
    try:
        meta = yaml.load((bag / "metadata.yaml").read_text(encoding="utf-8"), Loader=BoundedSafeLoader)
    except UnicodeDecodeError as exc:
        raise BagError(f"{bag}/metadata.yaml: not valid YAML: not UTF-8 text (byte {exc.start})") from None
    except yaml.YAMLError as exc:
        raise BagError(yaml_error_line(bag / "metadata.yaml", exc)) from None
    if not isinstance(meta, dict) or not isinstance(meta.get("rosbag2_bagfile_information"), dict):
        raise BagError(f"{bag}/metadata.yaml: no rosbag2_bagfile_information mapping")
    return meta


def _storage_files(bag: Path, info: dict) -> list[Path]:
    """The storage files ``relative_file_paths`` lists (a list of file names); BagError naming the field."""
    names = info.get("relative_file_paths")
    field = f"{bag}/metadata.yaml: relative_file_paths"
    if names is None or names == []:
        raise BagError(f"{bag}: metadata.yaml lists no storage files")
    if not isinstance(names, list):
        raise BagError(f"{field}: expected a list of file names, got {type(names).__name__} {names!r}")
    bad = [n for n in names if not isinstance(n, str) or not n]
    if bad:
        raise BagError(f"{field}: expected file names, got {bad[0]!r}")
    return [bag / n for n in names]


def _custom_data(bag: Path, info: dict) -> dict[str, str]:
    """``custom_data``: a mapping of names to texts (absent: empty; a value YAML read as a number: its text; none: "")."""
    data = info.get("custom_data") or {}
    if not isinstance(data, dict) or any(isinstance(v, (dict, list)) for v in data.values()):
        raise BagError(f"{bag}/metadata.yaml: custom_data: expected a mapping of names to texts, got {data!r:.80}")
    return {str(k): v if isinstance(v, str) else "" if v is None else str(v) for k, v in data.items()}


def _check_mcap_file(f: Path) -> None:
    if not f.is_file():
        raise BagError(f"{f}: storage file listed in metadata.yaml is missing")
    size = f.stat().st_size
    with f.open("rb") as fh:
        head = fh.read(len(MCAP_MAGIC))
        fh.seek(max(0, size - len(MCAP_MAGIC)))
        tail = fh.read(len(MCAP_MAGIC))
    if head != MCAP_MAGIC:
        raise BagError(f"{f}: not an MCAP file (bad magic at the start)")
    if size < 2 * len(MCAP_MAGIC) or tail != MCAP_MAGIC:
        raise BagError(f"{f}: truncated MCAP file (no footer magic at the end): the recording was cut off "
                       "before the bag was closed")


def _check_crcs(f: Path):
    from .mcap_check import McapCrcError, check_mcap_crcs

    try:
        return check_mcap_crcs(f)
    except McapCrcError as exc:
        raise BagError(f"{f}: {exc}") from None

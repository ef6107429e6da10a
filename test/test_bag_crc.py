"""MCAP CRCs and Jazzy fields of the bags the writer makes, checked by the ``mcap`` library; damaged copies refused.

A flipped byte inside a chunk: ``analyse`` and ``replay`` exit 2 with one line naming the chunk (number, byte
offset) and the topics it held, and nothing is written. Bags without CRCs (recorded before they were written)
still read.
"""
import zlib

import pytest
import yaml
from cli_runner import run_cli
from mcap.reader import make_reader
from mcap.stream_reader import CRCValidationError
from mcap_crc_probe import assert_every_crc_written_and_valid, assert_jazzy_fields, mcap_file, rosidl_type_hash
from test_bag_files import QOS, _write_run_bag

from pa10_dnbs.bag.bag_reader import Bag
from pa10_dnbs.wire import joint_state_cdr


@pytest.fixture(scope="module")
def bags(tmp_path_factory):
    """The analysable kind of bag (joint_states and reference topics in /pa10), zstd and plain, two chunks each."""
    base = tmp_path_factory.mktemp("crc")
    return {c: _write_run_bag(base / c, n=3000, compression=c, ns="/pa10") for c in ("zstd", "none")}


def _chunks(bag):
    """(chunk indexes in file order, {channel id: topic}) from the mcap library."""
    with mcap_file(bag).open("rb") as f:
        summary = make_reader(f).get_summary()
    return (sorted(summary.chunk_indexes, key=lambda c: c.chunk_start_offset),
            {i: c.topic for i, c in summary.channels.items()})


def _copy_with(bag, tmp_path, flip_at, mask=0xFF):
    """A copy of ``bag`` under tmp_path with the bits ``mask`` of the byte at ``flip_at`` of its .mcap flipped."""
    copy = tmp_path / "damaged"
    copy.mkdir()
    (copy / "metadata.yaml").write_bytes((bag / "metadata.yaml").read_bytes())
    data = bytearray(mcap_file(bag).read_bytes())
    data[flip_at] ^= mask
    (copy / mcap_file(bag).name).write_bytes(bytes(data))
    return copy


def _assert_refused(r, *words):
    assert r.returncode == 2, (r.returncode, r.stderr)
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("pa10-dnbs: error: "), r.stderr
    for w in words:
        assert w in lines[0], (w, lines[0])
    return lines[0]


@pytest.mark.parametrize("compression", ["zstd", "none"])
def test_every_crc_is_written_and_valid(bags, compression):
    assert assert_every_crc_written_and_valid(mcap_file(bags[compression])) == 2
    with Bag(bags[compression]) as b:
        assert b.crc_note() == "CRCs valid: 2 of 2 chunks, data section, summary"


def test_channels_carry_the_type_hash_of_metadata_yaml_and_rosidl_and_ros_distro_is_jazzy(bags):
    hashes = assert_jazzy_fields(bags["zstd"])
    assert len(hashes) == 8
    meta = yaml.safe_load((bags["zstd"] / "metadata.yaml").read_text())["rosbag2_bagfile_information"]
    for t in meta["topics_with_message_count"]:
        expected = rosidl_type_hash(t["topic_metadata"]["type"])  # what ROS itself computes for the type
        assert expected is not None and hashes[t["topic_metadata"]["name"]] == expected


@pytest.mark.parametrize("compression", ["zstd", "none"])
@pytest.mark.parametrize("which", [0, 1])
def test_a_flipped_byte_in_a_chunk_is_refused_naming_the_chunk_and_its_topics(bags, tmp_path, compression, which):
    bag = bags[compression]
    chunks, topics = _chunks(bag)
    ci = chunks[which]
    held = sorted(topics[c] for c in ci.message_index_offsets)
    damaged = _copy_with(bag, tmp_path, ci.chunk_start_offset + ci.chunk_length // 2)  # inside its records
    if compression == "none":  # the third-party reader refuses it too
        with mcap_file(damaged).open("rb") as f, pytest.raises(CRCValidationError):
            list(make_reader(f, validate_crcs=True).iter_messages())
    line = _assert_refused(run_cli("analyse", damaged, "--out", tmp_path / "out"),
                           f"chunk {which + 1} of 2 (at byte {ci.chunk_start_offset}", "is corrupt",
                           "it held " + ", ".join(held) + ")")
    if compression == "none":
        assert "CRC" in line
    assert not (tmp_path / "out").exists()
    _assert_refused(run_cli("replay", damaged), f"chunk {which + 1} of 2")


def test_damage_outside_the_chunks_is_refused_by_the_data_section_or_summary_crc(bags, tmp_path):
    """A message index (after a chunk; no chunk CRC covers it) and a channel's topic in the summary (s3 -> r3:
    still valid UTF-8, so only the CRC tells)."""
    bag = bags["zstd"]
    chunks, _ = _chunks(bag)
    first_index = min(chunks[0].message_index_offsets.values())
    _assert_refused(run_cli("analyse", _copy_with(bag, tmp_path, first_index + 20), "--out", tmp_path / "out"),
                    "data section is corrupt", "CRC")
    raw = mcap_file(bag).read_bytes()
    summary_start = int.from_bytes(raw[-8 - 29 + 9:-8 - 29 + 17], "little")
    (tmp_path / "damaged").rename(tmp_path / "d1")
    at = raw.index(b"/pa10/s3/reference", summary_start) + len("/pa10/")
    _assert_refused(run_cli("analyse", _copy_with(bag, tmp_path, at, mask=0x01), "--out", tmp_path / "out"),
                    "MCAP summary", "is corrupt: CRC")
    assert not (tmp_path / "out").exists()


def test_a_bag_without_crcs_still_reads(tmp_path):
    """Written by rosbags (every CRC 0, as bags recorded before this change): read, and the note says so."""
    from rosbags.rosbag2 import StoragePlugin, Writer

    from pa10_dnbs.bag.bag_writer import typestore

    with Writer(tmp_path / "old", version=9, storage_plugin=StoragePlugin.MCAP) as w:
        conn = w.add_connection("/pa10/joint_states", "sensor_msgs/msg/JointState", typestore=typestore(),
                                offered_qos_profiles=[QOS])
        w.write(conn, 0, joint_state_cdr.encode(0, 0, ["s1"], [0.0], [0.0], [0.0]))
    raw = (tmp_path / "old" / "old.mcap").read_bytes()
    assert raw[-8 - 4:-8] == b"\x00" * 4  # summary_crc 0
    with Bag(tmp_path / "old") as b:
        assert b.message_count == 1
        assert b.crc_note().startswith("no CRCs in the file")


def test_the_crc_check_finds_what_zlib_finds(bags):
    """The writer's chunk CRC is zlib.crc32 of the uncompressed records (what every MCAP reader computes)."""
    from mcap.stream_reader import StreamReader, get_chunk_data_stream
    from mcap.records import Chunk

    for rec in StreamReader(str(mcap_file(bags["none"])), emit_chunks=True).records:
        if isinstance(rec, Chunk):
            stream, n = get_chunk_data_stream(rec)
            assert rec.data == stream.read(n) and rec.uncompressed_crc == zlib.crc32(rec.data)

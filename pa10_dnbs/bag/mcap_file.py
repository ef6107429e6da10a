"""Write one MCAP file (https://mcap.dev/spec): chunked, indexed, with every CRC the format has.

Layout, as the MCAP C++ writer behind ``ros2 bag record -s mcap`` lays it out:
magic, Header, then the data section (Chunks of about ``chunk_size`` bytes of
uncompressed records, each followed by one MessageIndex per channel in it;
Metadata records), DataEnd, the summary (Schemas, Channels, Statistics,
ChunkIndexes, MetadataIndexes, then SummaryOffsets), Footer, magic.

CRCs (CRC-32 as ``zlib.crc32``; 0 would mean "not written"):
- Chunk ``uncompressed_crc``: of the chunk's uncompressed records;
- DataEnd ``data_section_crc``: of every byte from the file's magic up to the DataEnd record;
- Footer ``summary_crc``: of the summary section and the Footer's opcode, length, summary_start and
  summary_offset_start fields.

The hot path is ``message()``: one ``struct.pack`` and two appends per message; chunk boundaries,
times and counts are worked out when a chunk closes (about every 1 MiB).
"""
from __future__ import annotations

import struct
import zlib
from typing import BinaryIO

MAGIC = b"\x89MCAP0\r\n"
OP_HEADER, OP_FOOTER, OP_SCHEMA, OP_CHANNEL, OP_MESSAGE, OP_CHUNK = 0x01, 0x02, 0x03, 0x04, 0x05, 0x06
OP_MESSAGE_INDEX, OP_CHUNK_INDEX, OP_STATISTICS, OP_METADATA, OP_METADATA_INDEX = 0x07, 0x08, 0x0B, 0x0C, 0x0D
OP_SUMMARY_OFFSET, OP_DATA_END = 0x0E, 0x0F

_MESSAGE_HEAD = struct.Struct("<BQHIQQ")  # opcode, record length, channel id, sequence, log time, publish time
_MESSAGE_FIELDS = 2 + 4 + 8 + 8
_U16, _U32, _U64 = struct.Struct("<H"), struct.Struct("<I"), struct.Struct("<Q")
_RECORD_HEAD = struct.Struct("<BQ")


def _string(s: str) -> bytes:
    raw = s.encode("utf-8")
    return _U32.pack(len(raw)) + raw


def _string_map(d: dict[str, str]) -> bytes:
    body = b"".join(_string(k) + _string(v) for k, v in d.items())
    return _U32.pack(len(body)) + body


def _record(op: int, body: bytes) -> bytes:
    return _RECORD_HEAD.pack(op, len(body)) + body


class McapFileWriter:
    """Append records to ``stream`` (opened for binary writing; closed by ``finish()``).

    ``compress``: bytes -> bytes for chunk records (None: uncompressed) named ``compression`` ("zstd", "").
    Times are nanoseconds; ids are assigned from 1 in the order of ``schema()`` / ``channel()``.
    """

    def __init__(self, stream: BinaryIO, profile: str, library: str, compression: str = "",
                 compress=None, chunk_size: int = 1 << 20):
        self._out = stream
        self._pos = 0
        self._crc = 0
        self._compression = compression
        self._compress = compress
        self._chunk_size = chunk_size
        self._schemas: list[bytes] = []     # record bodies, repeated in the summary
        self._channels: list[bytes] = []
        self._chunk = bytearray()
        self._index: dict[int, list[int]] = {}  # channel id -> [log time, offset in chunk, ...]
        self._chunk_indexes: list[bytes] = []
        self._metadata_indexes: list[bytes] = []
        self._channel_counts: dict[int, int] = {}
        self.message_count = 0
        self.start_ns: int | None = None
        self.end_ns: int | None = None
        self.chunk_count = 0
        self._emit(MAGIC)
        self._emit(_record(OP_HEADER, _string(profile) + _string(library)))

    def _emit(self, data: bytes) -> None:
        self._out.write(data)
        self._crc = zlib.crc32(data, self._crc)
        self._pos += len(data)

    # ------------------------------------------------------------- data section
    def schema(self, name: str, encoding: str, data: bytes) -> int:
        """Register a schema; its record goes into the current chunk. Returns its id."""
        sid = len(self._schemas) + 1
        body = _U16.pack(sid) + _string(name) + _string(encoding) + _U32.pack(len(data)) + data
        self._schemas.append(body)
        self._chunk += _record(OP_SCHEMA, body)
        return sid

    def channel(self, topic: str, message_encoding: str, schema_id: int, metadata: dict[str, str]) -> int:
        """Register a channel; its record goes into the current chunk. Returns its id."""
        cid = len(self._channels) + 1
        body = _U16.pack(cid) + _U16.pack(schema_id) + _string(topic) + _string(message_encoding) + \
            _string_map(metadata)
        self._channels.append(body)
        self._channel_counts[cid] = 0
        self._chunk += _record(OP_CHANNEL, body)
        return cid

    def message(self, channel_id: int, t_ns: int, data: bytes) -> None:
        """One message, log time = publish time = ``t_ns`` [ns], sequence 0."""
        chunk = self._chunk
        idx = self._index.get(channel_id)
        if idx is None:
            idx = self._index[channel_id] = []
        idx.append(t_ns)
        idx.append(len(chunk))
        chunk += _MESSAGE_HEAD.pack(OP_MESSAGE, _MESSAGE_FIELDS + len(data), channel_id, 0, t_ns, t_ns)
        chunk += data
        if len(chunk) >= self._chunk_size:
            self.close_chunk()

    def metadata(self, name: str, values: dict[str, str]) -> None:
        """A Metadata record (after the chunk in progress), indexed in the summary."""
        self.close_chunk()
        offset = self._pos
        rec = _record(OP_METADATA, _string(name) + _string_map(values))
        self._emit(rec)
        self._metadata_indexes.append(_U64.pack(offset) + _U64.pack(len(rec)) + _string(name))

    def close_chunk(self) -> None:
        """Write the chunk in progress (if it holds anything) and its message indexes."""
        raw = bytes(self._chunk)
        if not raw:
            return
        times = [t for idx in self._index.values() for t in idx[0::2]]
        start, end = (min(times), max(times)) if times else (0, 0)
        data = self._compress(raw) if self._compress is not None else raw
        chunk_start = self._pos
        self._emit(_record(OP_CHUNK, struct.pack("<QQQI", start, end, len(raw), zlib.crc32(raw))
                           + _string(self._compression) + _U64.pack(len(data)) + data))
        chunk_length = self._pos - chunk_start
        offsets = []
        for cid in sorted(self._index):
            idx = self._index[cid]
            offsets.append(_U16.pack(cid) + _U64.pack(self._pos))
            self._emit(_record(OP_MESSAGE_INDEX, _U16.pack(cid) + _U32.pack(8 * len(idx))
                               + struct.pack(f"<{len(idx)}Q", *idx)))
            self._channel_counts[cid] += len(idx) // 2
        index_length = self._pos - chunk_start - chunk_length
        offsets_body = b"".join(offsets)
        self._chunk_indexes.append(
            struct.pack("<QQQQ", start, end, chunk_start, chunk_length) + _U32.pack(len(offsets_body)) + offsets_body
            + _U64.pack(index_length) + _string(self._compression) + _U64.pack(len(data)) + _U64.pack(len(raw)))
        if times:
            n = len(times)
            self.message_count += n
            self.start_ns = start if self.start_ns is None else min(start, self.start_ns)
            self.end_ns = end if self.end_ns is None else max(end, self.end_ns)
        self.chunk_count += 1
        self._chunk = bytearray()
        self._index = {}

    # ------------------------------------------------------------- summary
    def finish(self) -> None:
        """Close the last chunk, write DataEnd, the summary and the Footer; close the stream."""
        self.close_chunk()
        self._emit(_record(OP_DATA_END, _U32.pack(self._crc)))
        summary_start = self._pos
        self._crc = 0  # from here on: the summary CRC
        groups: list[tuple[int, int, int]] = []

        def group(op: int, bodies: list[bytes]) -> None:
            if bodies:
                start = self._pos
                for body in bodies:
                    self._emit(_record(op, body))
                groups.append((op, start, self._pos - start))

        group(OP_SCHEMA, self._schemas)
        group(OP_CHANNEL, self._channels)
        counts = b"".join(_U16.pack(c) + _U64.pack(n) for c, n in sorted(self._channel_counts.items()))
        group(OP_STATISTICS, [struct.pack("<QHIIIIQQ", self.message_count, len(self._schemas), len(self._channels),
                                          0, len(self._metadata_indexes), self.chunk_count, self.start_ns or 0,
                                          self.end_ns or 0) + _U32.pack(len(counts)) + counts])
        group(OP_CHUNK_INDEX, self._chunk_indexes)
        group(OP_METADATA_INDEX, self._metadata_indexes)
        summary_offset_start = self._pos
        for op, start, length in groups:
            self._emit(_record(OP_SUMMARY_OFFSET, struct.pack("<BQQ", op, start, length)))
        footer = _RECORD_HEAD.pack(OP_FOOTER, 8 + 8 + 4) + _U64.pack(summary_start) + _U64.pack(summary_offset_start)
        self._emit(footer + _U32.pack(zlib.crc32(footer, self._crc)))
        self._emit(MAGIC)
        self._out.close()

    def abort(self) -> None:
        """Close the stream without a summary (the file is then truncated, as a crash leaves it)."""
        self._out.close()

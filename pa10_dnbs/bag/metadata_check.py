"""Cross-check a bag's ``metadata.yaml`` against the summaries of its MCAP files (cheap: no message is read).

rosbags, which Bag reads with, takes the topics, their types and message counts, the start and the duration from
metadata.yaml, not from the files: a topic whose type there is not its channel's plays no message, a topic left out
cannot be read at all. So each disagreement is one BagError naming metadata.yaml and the topic or field (the
first found, in this order):

- per topic (``topics_with_message_count``): its type against the schema name of its MCAP channel(s), its
  ``message_count`` against the statistics' ``channel_message_counts``; a topic the files hold messages of but
  metadata.yaml leaves out, or one it lists that the files have no channel of (rosbag2 and bag_writer.py make
  a topic's channel when they add the topic, before any message);
- the total ``message_count`` against the summaries' statistics;
- ``starting_time`` against the first message's log time, and ``duration`` (ns, >= 0) against the last one's:
  rosbag2 writes the starting time exactly and the duration as a running maximum, which falls short of the span
  when receive stamps come out of order, so the end it gives may lie up to DURATION_SLACK_NS before the last
  message, never after it.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

DURATION_SLACK_NS = 1_000_000_000  # how far before the last message metadata.yaml's end may lie [ns]


@dataclass
class McapSummary:
    """What one MCAP file's summary says: messages, log-time span [ns] (None: no message), topics."""
    message_count: int
    start_ns: int | None
    end_ns: int | None
    types: dict[str, set[str]] = field(default_factory=dict)   # topic -> schema names of its channels
    counts: dict[str, int] = field(default_factory=dict)       # topic -> messages


def read_summary(f: Path, error) -> McapSummary:
    """The summary of the MCAP file ``f``; ``error(text)`` makes the exception raised for a broken one."""
    from mcap.reader import make_reader

    try:
        with f.open("rb") as fh:
            summary = make_reader(fh).get_summary()
    except Exception as exc:
        raise error(f"{f}: corrupt MCAP summary: {type(exc).__name__}: {exc}") from None
    if summary is None or summary.statistics is None:
        raise error(f"{f}: MCAP file has no summary statistics (not closed properly)")
    stats = summary.statistics
    out = McapSummary(stats.message_count, stats.message_start_time if stats.message_count else None,
                      stats.message_end_time if stats.message_count else None)
    for cid, ch in summary.channels.items():
        schema = summary.schemas.get(ch.schema_id)
        out.types.setdefault(ch.topic, set()).add(schema.name if schema is not None else "(no schema)")
        out.counts[ch.topic] = out.counts.get(ch.topic, 0) + stats.channel_message_counts.get(cid, 0)
    return out


def check_metadata(bag: Path, info: dict, summaries: list[McapSummary], error) -> None:
    """Raise ``error(text)`` for the first way ``info`` (metadata.yaml's rosbag2_bagfile_information) disagrees
    with the files' ``summaries`` (a note says how many more there are)."""
    where = f"{bag}/metadata.yaml"
    expected = _whole(info.get("message_count", -1), f"{where}: message_count", error, minimum=-1)
    problems = _topic_problems(where, _listed_topics(where, info, error), summaries)  # first: they name the topic
    in_files = sum(s.message_count for s in summaries)
    if expected != in_files:
        problems.append(f"{bag}: metadata.yaml counts {expected} messages but the MCAP summary holds {in_files}")
    problems += _time_problems(where, info, summaries, error)
    if problems:
        more = f" (and {len(problems) - 1} more disagreements)" if len(problems) > 1 else ""
        raise error(f"{problems[0]}{more}; the bag is inconsistent")


def _whole(value, name: str, error, minimum: int = 0) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or value < minimum:
        raise error(f"{name}: expected a whole number >= {max(minimum, 0)}, got {value!r}")
    return value


def _listed_topics(where: str, info: dict, error) -> dict[str, tuple[str, int]]:
    """``topics_with_message_count`` as topic -> (type, message_count), each entry checked for its form."""
    entries = info.get("topics_with_message_count")
    if entries is None:
        entries = []
    if not isinstance(entries, list):
        raise error(f"{where}: topics_with_message_count: expected a list, got {type(entries).__name__}")
    listed: dict[str, tuple[str, int]] = {}
    for i, e in enumerate(entries):
        name = f"{where}: topics_with_message_count[{i}]"
        meta = e.get("topic_metadata") if isinstance(e, dict) else None
        if not isinstance(meta, dict):
            raise error(f"{name}: expected a mapping with topic_metadata and message_count, got {e!r:.80}")
        topic, msgtype = meta.get("name"), meta.get("type")
        if not isinstance(topic, str) or not topic:
            raise error(f"{name}.topic_metadata.name: expected a topic name, got {topic!r:.80}")
        if not isinstance(msgtype, str) or not msgtype:
            raise error(f"{name}.topic_metadata.type ({topic}): expected a message type, got {msgtype!r:.80}")
        count = _whole(e.get("message_count"), f"{name}.message_count ({topic})", error)
        if topic in listed:
            raise error(f"{name}: lists topic {topic} a second time")
        listed[topic] = (msgtype, count)
    return listed


def _topic_problems(where: str, listed: dict[str, tuple[str, int]], summaries: list[McapSummary]) -> list[str]:
    types: dict[str, set[str]] = {}
    counts: dict[str, int] = {}
    for s in summaries:
        for t, ts in s.types.items():
            types.setdefault(t, set()).update(ts)
        for t, n in s.counts.items():
            counts[t] = counts.get(t, 0) + n
    problems = []
    for topic in sorted(set(listed) | set(types)):
        in_file = counts.get(topic, 0)
        if topic not in listed:
            if in_file:
                problems.append(f"{where}: leaves out topic {topic}, of which the MCAP file holds {in_file} "
                                f"messages ({', '.join(sorted(types[topic]))})")
            continue
        msgtype, count = listed[topic]
        if topic not in types:
            problems.append(f"{where}: lists topic {topic} ({msgtype}, {count} messages), which the MCAP file "
                            "does not hold")
            continue
        if types[topic] != {msgtype}:
            problems.append(f"{where}: topic {topic} has type {msgtype} but the MCAP file holds it as "
                            f"{', '.join(sorted(types[topic]))}")
        elif count != in_file:
            problems.append(f"{where}: topic {topic} counts {count} messages but the MCAP summary holds {in_file}")
    return problems


def _time_problems(where: str, info: dict, summaries: list[McapSummary], error) -> list[str]:
    duration = info.get("duration")
    duration = duration.get("nanoseconds") if isinstance(duration, dict) else None
    duration = _whole(duration, f"{where}: duration.nanoseconds", error)
    starts = [s.start_ns for s in summaries if s.start_ns is not None]
    if not starts:  # no message: no time to check
        return []
    first, last = min(starts), max(s.end_ns for s in summaries if s.end_ns is not None)
    start = info.get("starting_time")
    start = start.get("nanoseconds_since_epoch") if isinstance(start, dict) else None
    start = _whole(start, f"{where}: starting_time.nanoseconds_since_epoch", error)
    if start != first:
        return [f"{where}: starting_time is {start} ns but the first message in the MCAP file is at {first} ns"]
    end = start + duration
    if end > last or end < last - DURATION_SLACK_NS:
        return [f"{where}: duration {duration} ns ends the bag at {end} ns but its last message in the MCAP file "
                f"is at {last} ns (duration {last - first} ns)"]
    return []

"""``pa10-dnbs replay BAG``: publish a recorded bag on the ROS graph (see ros/player_node.py)."""
from __future__ import annotations

import functools
import math
from pathlib import Path

from ..bag.bag_reader import Bag, BagError
from ..config import ConfigError


def run_replay(bag_path: Path, rate: float, topics: list[str] | None, start_offset_s: float, loop: bool,
               clock_hz: float, wait_for_subscribers_s: float, queue_depth: int) -> int:
    """Validate the bag and the options before joining ROS, then play. Returns the exit code."""
    if not (math.isfinite(rate) and rate > 0):
        raise ConfigError(f"--rate: must be a positive number, got {rate}")
    if not (math.isfinite(start_offset_s) and start_offset_s >= 0):
        raise ConfigError(f"--start-offset: must be >= 0 seconds, got {start_offset_s}")
    if not (math.isfinite(clock_hz) and clock_hz >= 0):
        raise ConfigError(f"--clock: must be a frequency >= 0 Hz, got {clock_hz}")
    if queue_depth < 1:
        raise ConfigError(f"--queue-depth: must be >= 1, got {queue_depth}")
    from ..ros.player_node import PlayerNode, PlayOptions
    from ..ros.runtime import run_node

    with Bag(bag_path) as bag:
        if topics:
            unknown = [t for t in topics if t not in bag.topics]
            if unknown:
                raise BagError(f"{bag.path}: no such topic in the bag: {', '.join(unknown)} "
                               f"(it has {', '.join(sorted(bag.topics))})")
        duration_s = (bag.end_ns - bag.start_ns) / 1e9
        if start_offset_s > duration_s:
            raise ConfigError(f"--start-offset: {start_offset_s} s is past the bag's end ({duration_s:.3f} s)")
        opt = PlayOptions(rate=rate, topics=list(topics or []), start_offset_s=start_offset_s, loop=loop,
                          clock_hz=clock_hz, wait_for_subscribers_s=wait_for_subscribers_s, queue_depth=queue_depth)
        return run_node(functools.partial(PlayerNode, bag, opt), args=[])

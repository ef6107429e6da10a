"""``pa10-dnbs replay BAG``: publish a recorded bag on the ROS graph (see ros/player_node.py), optionally live
in Foxglove (``--live``: the same view as ``launch --live``, at the bag's recorded timing)."""
from __future__ import annotations

import functools
import math
from pathlib import Path

from ..bag.analysis import bag_joint_names, run_info
from ..bag.bag_reader import Bag, BagError
from ..config import ConfigError, default_config_path
from ..live.options import check_live_options
from ..live.schemas import live_channels
from ..live.server import LiveServer, LiveServerError
from ..live.view import LiveView
from ..run_settings import build_settings
from ..wire.topics import ArmTopics, check_namespace, find_arm


def run_replay(bag_path: Path, rate: float, topics: list[str] | None, start_offset_s: float, loop: bool,
               clock_hz: float, wait_for_subscribers_s: float, queue_depth: int, live_port: int | None = None,
               live_host: str = "127.0.0.1", live_hz: float = 50.0, config_path: Path | None = None,
               namespace: str | None = None) -> int:
    """Validate the bag and the options before joining ROS (a bad one: the error, raised), then play and end the
    process with the player node's exit code (as every node, without an rclpy teardown: ros/runtime.py).

    ``namespace``: publish the arm's topics under this namespace instead of the recorded one (None: as recorded).
    ``live_port``: also serve the live view on ``live_host``:``live_port`` (0: a free port); its torque limits
    and step come from ``config_path``, else the config stored in the bag, else the shipped default.
    """
    if not (math.isfinite(rate) and rate > 0):
        raise ConfigError(f"--rate: must be a positive number, got {rate}")
    if not (math.isfinite(start_offset_s) and start_offset_s >= 0):
        raise ConfigError(f"--start-offset: must be >= 0 seconds, got {start_offset_s}")
    if not (math.isfinite(clock_hz) and clock_hz >= 0):
        raise ConfigError(f"--clock: must be a frequency >= 0 Hz, got {clock_hz}")
    if namespace is not None:
        try:
            check_namespace(namespace)
        except ValueError as exc:
            raise ConfigError(f"--namespace: {exc}") from None
    if queue_depth < 1:
        raise ConfigError(f"--queue-depth: must be >= 1, got {queue_depth}")
    if live_port is not None:
        check_live_options(live_host, live_port, live_hz)
    from ..ros.player_node import PlayerNode, PlayOptions
    from ..ros.runtime import exit_process, run_node  # the player leaves as a node does: no rclpy teardown

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
                          clock_hz=clock_hz, wait_for_subscribers_s=wait_for_subscribers_s, queue_depth=queue_depth,
                          namespace=namespace)
        if live_port is None:
            exit_process(run_node(functools.partial(PlayerNode, bag, opt), args=[]))
        cfg = _live_config(bag, config_path)
        arm = find_arm(bag.topics) or ArmTopics()
        joints = bag_joint_names(bag, arm)
        arm = ArmTopics(namespace) if namespace else arm
        try:
            server = LiveServer(live_channels(arm), host=live_host, port=live_port)
        except LiveServerError as exc:
            raise ConfigError(f"--live: {exc}") from None
        try:
            view = LiveView(server, cfg["plant"]["torque_limit_nm"], cfg["simulation"]["dt_s"], display_hz=live_hz,
                            joint_names=joints, arm=arm)
            print(f"LIVE {server.url} (Foxglove: Open connection, Foxglove WebSocket)", flush=True)
            code = run_node(functools.partial(PlayerNode, bag, opt, live=view), args=[])
        finally:
            server.stop()
        exit_process(code)


def _live_config(bag: Bag, config_path: Path | None) -> dict:
    """The config for the live view: ``config_path``, else the one stored in the bag, else the default."""
    if config_path is not None:
        return build_settings(config_path).to_config()
    stored = run_info(bag).get("config")
    try:
        float(stored["simulation"]["dt_s"]), list(stored["plant"]["torque_limit_nm"])
        return stored
    except (KeyError, TypeError, ValueError):
        return build_settings(default_config_path()).to_config()

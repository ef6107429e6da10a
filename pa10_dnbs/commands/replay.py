"""``pa10-dnbs replay BAG``: publish a recorded bag on the ROS graph (see ros/player_node.py), optionally live
in Foxglove (``--live``: the same view as ``launch --live``, at the bag's recorded timing)."""
from __future__ import annotations

import functools
import os
from typing import NoReturn

from ..bag.analysis import bag_joint_names, run_info
from ..bag.bag_reader import Bag, BagError
from ..bag.run_config import run_config
from ..config import ConfigError
from ..output_lock import lock_input, release_output
from ..ros.shm_cleanup import remove_stale, shm_files
from ..supervisor.domain_ids import shell_domain
from ..supervisor.rmw_check import check_rmw
from .options import ReplayOptions
from ..live.options import check_live_options
from ..live.schemas import live_channels
from ..live.server import LiveServer, LiveServerError
from ..live.view import LiveView
from ..wire.topics import ArmTopics, check_namespace, check_topic_name, find_arm


def run_replay(options: ReplayOptions) -> int:
    """Validate the bag and the options before joining ROS (a bad one: the error, raised), then play and end the
    process with the player node's exit code (as every node, without an rclpy teardown: ros/runtime.py).

    ``options.namespace``: publish the arm's topics under it instead of the recorded one (None: as recorded).
    ``options.live_port``: also serve the live view on ``live_host``:``live_port`` (0: a free port); its torque
    limits and step come from ``config_path``, else the config stored in the bag, else the shipped default.
    """
    o = options
    namespace = o.namespace
    if namespace is not None:
        try:
            check_namespace(namespace)
        except ValueError as exc:
            raise ConfigError(f"--namespace: {exc}") from None
    if o.live_port is not None:
        check_live_options(o.live_host, o.live_port, o.live_hz)
    shell_domain("the domain the bag is played on")   # one line here, not the DDS's error and a file in /dev/shm
    check_rmw()
    before = shm_files()
    try:
        _play(o, before)
    finally:   # refused after rclpy loaded (its LTTng file is made then): nothing of this process stays behind
        _remove_own_files(before)


def _remove_own_files(before: set[str]) -> None:
    """Remove the /dev/shm files (Fast DDS's, LTTng's) made since ``before`` whose owner is gone or is this
    process, about to end: no launcher sweeps after a replay, as one does after its nodes (ros/shm_cleanup.py)."""
    remove_stale(shm_files() - before, ignore_pids=frozenset({os.getpid()}))


def _play(o: ReplayOptions, before: set[str]) -> NoReturn:
    """Check the bag against ``o`` (a bad one: the error, raised), play it and end the process with the player
    node's exit code, first removing this process's /dev/shm files."""
    from ..ros.player_node import PlayerNode, PlayOptions
    from ..ros.runtime import exit_process, run_node  # the player leaves as a node does: no rclpy teardown

    namespace = o.namespace
    lock_input(o.bag_path, "bag")  # a bag another run still records (or replaces) is refused; readers share it
    with Bag(o.bag_path) as bag:
        if bag.message_count == 0:   # its start and end are unset: a --start-offset would be 'past -9.2e9 s'
            raise BagError(f"{bag.path}: the bag holds no messages: nothing to play")
        if o.topics:
            unknown = [t for t in o.topics if t not in bag.topics]
            if unknown:
                named = ", ".join(t or "(an empty name)" for t in unknown)
                raise BagError(f"{bag.path}: no such topic in the bag: {named} "
                               f"(it has {', '.join(sorted(bag.topics))})")
        unplayable = unplayable_topics(bag, o.topics or bag.topics)
        if len(unplayable) == len(set(o.topics or bag.topics)):
            why = "; ".join(f"{t} ({why})" for t, why in unplayable.items())
            text = f"nothing to play: {why}; the player publishes only the topics whose Python message package is installed"
            if o.topics:
                raise ConfigError(f"--topics: {text}")
            raise BagError(f"{bag.path}: {text}")
        _check_topic_names(bag, o.topics or bag.topics)
        check_start_offset(bag, o.start_offset_s, o.loop)
        opt = PlayOptions(rate=o.rate, topics=list(o.topics or []), start_offset_s=o.start_offset_s, loop=o.loop,
                          clock_hz=o.clock_hz, wait_for_subscribers_s=o.wait_for_subscribers_s, queue_depth=o.queue_depth,
                          namespace=namespace)
        if o.live_port is None:
            code = run_node(functools.partial(PlayerNode, bag, opt), args=[])
            release_output(o.bag_path)
            _remove_own_files(before)
            exit_process(code)
        arm = find_arm(bag.topics) or ArmTopics()
        joints = bag_joint_names(bag, arm)
        run_settings = run_config(bag, run_info(bag), o.config_path, joints)  # analyse's, checked for the bag's arm
        arm = ArmTopics(namespace) if namespace else arm
        try:
            server = LiveServer(live_channels(arm), host=o.live_host, port=o.live_port)
        except LiveServerError as exc:
            raise ConfigError(f"--live: {exc}") from None
        try:
            view = LiveView(server, run_settings.torque_limit_nm, run_settings.dt_s, display_hz=o.live_hz,
                            joint_names=joints, arm=arm)
            print(f"LIVE {server.url} (Foxglove: Open connection, Foxglove WebSocket)", flush=True)
            code = run_node(functools.partial(PlayerNode, bag, opt, live=view), args=[])
        finally:
            server.stop()
        release_output(o.bag_path)
        _remove_own_files(before)
        exit_process(code)


def check_start_offset(bag: Bag, offset_s: float, loop: bool) -> None:
    """ConfigError naming --start-offset when ``offset_s`` [s of the bag's timeline] is at or past its last message
    (nothing left to play but that instant, which ``--loop`` would replay without pause); naming --loop when
    the bag's messages are all at one instant (as the player counts: ``start_ns + round(offset * 1e9)``)."""
    span_ns = bag.end_ns - 1 - bag.start_ns   # rosbags' end time is just after the latest message
    span = f"{span_ns / 1e9:.9g} s"
    offset_ns = offset_s * 1e9
    if offset_ns >= span_ns + 0.5 or (span_ns > 0 and offset_ns >= span_ns - 0.5):
        where = "past" if offset_ns >= span_ns + 0.5 else "at"
        raise ConfigError(f"--start-offset: {offset_s:g} s is {where} the bag's end (its messages span {span}): "
                          f"nothing is left to play{' but its last instant' if where == 'at' else ''}; give "
                          f"less than {span}")
    if loop and span_ns == 0:
        raise ConfigError("--loop: the bag's messages are all at one instant (they span 0 s): a loop would "
                          "replay them without pause")


def unplayable_topics(bag: Bag, topics) -> dict[str, str]:
    """The topics of ``topics`` the player cannot publish, with why: their message type has no Python package
    here (tf2_msgs: ``/tf``, ``/tf_static``); PlayerNode skips them the same way (ros/msg_types.py)."""
    from ..ros.msg_types import message_class

    out = {}
    for t in dict.fromkeys(topics):
        try:
            message_class(bag.topics[t].msgtype)
        except LookupError as exc:
            out[t] = str(exc)
    return out


def _check_topic_names(bag: Bag, topics) -> None:
    """BagError naming the first of ``topics`` (the ones to play) whose name ROS 2 refuses (``/9bad-name``, from a
    bag another program wrote): rclpy would raise on its publisher."""
    for t in topics:
        try:
            check_topic_name(t)
        except ValueError as exc:
            raise BagError(f"{bag.path}: cannot play topic {t!r}: {exc}; --topics without it plays the others") from None

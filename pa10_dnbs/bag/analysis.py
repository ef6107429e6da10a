"""A run rebuilt from a bag alone: the arm's joint_states and reference topics -> RunData.

The arm is found in the bag's topics (``wire.topics.find_arm``): <ns>/joint_states with
<ns>/<joint>/reference under any namespace, or an old bag's /joint_states and /robot_description at
the root with /pa10/<joint>/reference.

The same WireRecord as the live wire monitor, so a bag of a run gives the
same time series, metrics and figures as the run itself. The run's config
travels in the bag (metadata custom_data ``pa10_dnbs.config``, JSON); a bag
without it is read with the config given (or the shipped default).
"""
from __future__ import annotations

import json
import struct

from rosbags.typesys import Stores, get_typestore

from ..wire.reference_buffer import ReferenceBuffer
from ..config_error import ConfigError
from ..run_size import check_run_size, run_bytes
from ..wire.wire_record import WireRecord
from ..wire import joint_state_cdr
from ..wire.steps import StepClock, to_ns
from ..kinematics.urdf_chain import UrdfChain
from ..wire.topics import ArmTopics, find_arm
from .bag_reader import Bag, BagError
from .custom_data import CUSTOM_CONFIG, CUSTOM_PREFIX

PROGRESS_EVERY = 500  # states between progress calls


def run_info(bag: Bag) -> dict:
    """What the launcher stored about the run: controller, mode, duration_s, ... (strings), config (dict or None)."""
    info = {k[len(CUSTOM_PREFIX):]: v for k, v in bag.custom_data.items() if k.startswith(CUSTOM_PREFIX)}
    raw = info.pop("config", None)
    try:
        info["config"] = json.loads(raw) if raw else None
    except (ValueError, RecursionError):  # JSONDecodeError, an integer past 4300 digits, nesting too deep
        raise BagError(f"{bag.path}: custom_data {CUSTOM_CONFIG} is not valid JSON") from None
    return info


def bag_arm(bag: Bag) -> ArmTopics:
    """The arm whose topics the bag holds (the default /pa10 layout when none fits, so errors name those)."""
    return find_arm(bag.topics) or ArmTopics()


def bag_joint_names(bag: Bag, arm: ArmTopics | None = None) -> tuple[str, ...]:
    """The arm's joints, chain order, as its first readable joint_states message names them (ROS's own record
    of which joints a robot has); BagError when the bag has none."""
    arm = arm or bag_arm(bag)
    bag.require_topics([arm.joint_states], "analysis")
    for _, _, _, data in bag.messages([arm.joint_states]):
        try:
            names = joint_state_cdr.decode(data)[2]
        except (ValueError, struct.error, UnicodeDecodeError):
            continue
        if names:
            return tuple(names)
    raise BagError(f"{bag.path}: no {arm.joint_states} message names the arm's joints")


def _check_steps(bag: Bag, n: int, dt_s: float, n_joints: int, n_states: int) -> None:
    """BagError naming the bag unless a record of steps 0..``n`` fits in memory (run_size.py): stamps from a
    wall clock (~1.7e9 s) instead of the sim clock imply trillions of steps for a few joint states."""
    if n < 0:
        raise BagError(f"{bag.path}: its {n_states} joint states are stamped before 0 s (step {n}); a run's "
                       "stamps start at 0 s (the sim clock)")
    try:
        check_run_size(n * dt_s, n, n_joints, graph=True)
    except ConfigError:
        need = run_bytes(n, n_joints, graph=True)
        raise BagError(f"{bag.path}: its stamps reach {n * dt_s:g} s, {n:,} steps of {dt_s:g} s for "
                       f"{n_states} joint states: about {need / 2**30:,.0f} GiB to hold, more than is available here "
                       "(stamped by a wall clock instead of the sim clock?)") from None


def wire_record_from_bag(bag: Bag, dt_s: float, n_steps: int | None, progress=None) -> WireRecord:
    """Fill a WireRecord from the bag; ``n_steps`` None means up to the last /joint_states stamp.

    ``progress(step, worst_abs_error)``, if given, is called as /joint_states is read (every
    PROGRESS_EVERY states, and at the end) with the step reached and the worst |x_d - x| [rad] so far.
    """
    arm = bag_arm(bag)
    joints = bag_joint_names(bag, arm)
    nj = len(joints)
    needed = [arm.joint_states] + [arm.reference(j) for j in joints]
    bag.require_topics(needed, "analysis")
    clock = StepClock(dt_s)
    store = get_typestore(Stores.ROS2_JAZZY)
    batches = []  # (joint, first step, offsets, positions), in the bag's order per joint
    ref_malformed = 0
    for j, name in enumerate(joints):
        topic = arm.reference(name)
        for _, msgtype, _, data in bag.messages([topic]):
            try:
                msg = store.deserialize_cdr(data, msgtype)
            except Exception:
                ref_malformed += 1
                continue
            if any(len(p.positions) == 0 for p in msg.points):  # x_d [rad] is each point's positions[0]
                raise BagError(f"{bag.path}: {topic}: a reference point holds no position (empty positions); "
                               "each point needs the joint's position [rad]")
            k0 = clock.step_of_sec_nanosec(msg.header.stamp.sec, msg.header.stamp.nanosec)
            offsets = [clock.step_of_ns(to_ns(p.time_from_start.sec, p.time_from_start.nanosec)) for p in msg.points]
            batches.append((j, k0, offsets, [float(p.positions[0]) for p in msg.points]))
    watch = None
    if progress is not None:  # x_d by step, to show the worst |e| while the states are read
        watch = ReferenceBuffer(nj, clock)
        for b in batches:
            watch.add(*b)
    states = []
    malformed = 0
    for _, _, _, data in bag.messages([arm.joint_states]):
        try:
            sec, nanosec, _, pos, vel, eff = joint_state_cdr.decode(data)
        except (ValueError, struct.error, UnicodeDecodeError):
            malformed += 1
            continue
        if len(pos) != nj or len(vel) != nj or len(eff) != nj:
            malformed += 1
            continue
        k = clock.step_of_sec_nanosec(sec, nanosec)
        states.append((k, pos, vel, eff))
        if watch is not None:
            watch.error(k, pos)
            if len(states) % PROGRESS_EVERY == 0:
                progress(k, watch.worst_abs_error)
    if not states:
        raise BagError(f"{bag.path}: no readable {arm.joint_states} message")
    n = n_steps if n_steps is not None else max(k for k, *_ in states)
    _check_steps(bag, n, dt_s, nj, len(states))
    if watch is not None:
        progress(n, watch.worst_abs_error)
    rec = WireRecord(n, dt_s, nj)
    rec.malformed = malformed + ref_malformed
    for k, pos, vel, eff in states:
        rec.add_joint_states(k, pos, vel, eff)
    for b in batches:
        rec.add_reference(*b)
    return rec


def robot_chain(bag: Bag, arm_file) -> UrdfChain | None:
    """The arm's kinematics for the 3D figure: the bag's robot_description, else the URDF of ``arm_file`` (the
    run's config's ``arm``; None: no figure)."""
    topic = bag_arm(bag).robot_description
    if topic in bag.topics:
        for _, msgtype, _, data in bag.messages([topic]):
            try:
                return UrdfChain(get_typestore(Stores.ROS2_JAZZY).deserialize_cdr(data, msgtype).data)
            except Exception:
                raise BagError(f"{bag.path}: {topic} does not hold a readable URDF") from None
    if arm_file is None:
        return None
    try:
        from ..arm import load_arm

        return load_arm(arm_file).chain
    except (KeyError, TypeError, ValueError):  # a config from elsewhere: no arm file here
        return None

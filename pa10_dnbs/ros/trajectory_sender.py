"""Send JointTrajectory files to a running graph's reference node, on <ns>/trajectory, one after another.

    python -m pa10_dnbs.ros.trajectory_sender FILE [FILE ...] [--namespace NS] [--after-clock S]
                                                [--gap S | --clock-gap S] [--stamp S] [--wait S]

Each file (YAML or JSON, docs/trajectories.md) goes out as a trajectory_msgs/JointTrajectory exactly as
written: the sender reads its fields but does not check them against an arm, so the reference node is the one
that accepts or refuses it (its log says which, in one line). Without ``--namespace`` it sends to the one graph
on the wire that takes trajectories (a ``<ns>/trajectory`` topic of JointTrajectory with a subscriber,
trajectory_target.py; several seen: exit 2 naming them, --namespace picks one). It waits until the reference node's
subscription has matched (``--wait`` s of wall time, else exit 1), and with ``--after-clock S`` until /clock
has reached S s of simulated time; then it sends the files in order, ``--gap`` s of wall time apart, or
``--clock-gap`` s of simulated time apart (/clock: independent of how fast the graph runs), reliable, so none
is lost and they arrive in order. ``--stamp S``: header.stamp (0, the default: the trajectory starts
at the first step the reference node has not yet published). Prints one ``sent FILE`` line per file. Exit 0
once every message is acknowledged, 1 on a timeout, 2 on a file it cannot read or a flag out of range (one
line, before ROS starts) or on several graphs and no --namespace, 130 on Ctrl-C. It refuses a file whose times --trajectory would refuse as out of range
(not finite, before 0, past ``MAX_TIME_FROM_START_S``: ``trajectory_file.read_sendable``), so no time wraps on
the wire (builtin_interfaces' sec is an int32), and a --stamp past what header.stamp carries.
"""
from __future__ import annotations

import argparse
import math
import os
import sys
import threading
import time
from pathlib import Path

import rclpy
from rclpy.duration import Duration
from rclpy.qos import HistoryPolicy, QoSProfile, ReliabilityPolicy
from rosgraph_msgs.msg import Clock
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint

from ..cli_values import plain_float
from ..core.joint_trajectory import JointTrajectory as Trajectory
from ..core.joint_trajectory import TrajectoryError
from ..interrupt import EXIT_INTERRUPTED
from ..trajectory_file import read_sendable
from ..wire.topics import CLOCK, TRAJECTORY, check_topic_name, resolve
from .reference_node import TRAJECTORY_QOS
from .shm_cleanup import remove_stale, shm_files
from .trajectory_target import SeveralGraphs, found_topic


INT32_MAX = 2**31 - 1   # builtin_interfaces Time/Duration sec is an int32: a larger one wraps on the wire
MAX_WAIT_S = 3600.0     # the longest --wait [s]
SAY_WAITING_S = 1.0     # a wait for the subscriber or /clock longer than this is said in one line (stderr)


def _stamp_ns(stamp_s: float) -> int:
    """--stamp [s] as whole nanoseconds, or ValueError: it must be finite, >= 0 and its sec fit an int32."""
    if not math.isfinite(stamp_s) or stamp_s < 0:
        raise ValueError(f"--stamp: expected simulated seconds, finite and >= 0, got {stamp_s:g}")
    ns = int(round(stamp_s * 1e9)) if stamp_s < 2.0**31 else 2**31 * 10**9
    if ns // 10**9 > INT32_MAX:
        raise ValueError(f"--stamp: {stamp_s:g} s is past what header.stamp carries ({INT32_MAX} s, int32 sec)")
    return ns


def check_args(args) -> None:
    """ValueError (one line naming the flag) for a flag out of range; nothing of ROS has started yet."""
    if args.namespace is not None:
        try:
            check_topic_name(args.namespace)
        except ValueError as exc:
            raise ValueError(f"--namespace: {exc}") from None
    if not (math.isfinite(args.wait) and 0 < args.wait <= MAX_WAIT_S):
        raise ValueError(f"--wait: expected seconds in (0, {MAX_WAIT_S:g}], got {args.wait:g}")
    for flag in ("after_clock", "gap", "clock_gap"):
        value = getattr(args, flag)
        if not (math.isfinite(value) and value >= 0):
            raise ValueError(f"--{flag.replace('_', '-')}: expected seconds, finite and >= 0, got {value:g}")
    _stamp_ns(args.stamp)


def message(traj: Trajectory, stamp_s: float) -> JointTrajectory:
    """The ROS message of ``traj`` with header.stamp ``stamp_s`` [s]."""
    msg = JointTrajectory()
    msg.header.stamp.sec, ns = divmod(_stamp_ns(stamp_s), 10**9)
    msg.header.stamp.nanosec = ns
    msg.joint_names = list(traj.joint_names)
    for i, t in enumerate(traj.time_from_start_s):
        pt = JointTrajectoryPoint()
        pt.positions = [float(x) for x in traj.positions_rad[i]]
        if traj.velocities_rad_s is not None:
            pt.velocities = [float(x) for x in traj.velocities_rad_s[i]]
        if traj.accelerations_rad_s2 is not None:
            pt.accelerations = [float(x) for x in traj.accelerations_rad_s2[i]]
        sec, nanosec = divmod(int(round(float(t) * 1e9)), 10**9)
        pt.time_from_start.sec, pt.time_from_start.nanosec = sec, nanosec
        msg.points.append(pt)
    return msg


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="trajectory_sender", description=__doc__.splitlines()[0])
    ap.add_argument("files", nargs="+", type=Path, metavar="FILE")
    ap.add_argument("--namespace", default=None, metavar="NS",
                    help="the arm's namespace, e.g. /panda (default: the one graph on the wire that takes "
                         "trajectories)")
    ap.add_argument("--after-clock", type=plain_float, default=0.0, metavar="S",
                    help="send once /clock has reached S seconds of simulated time (default 0: at once)")
    gaps = ap.add_mutually_exclusive_group()
    gaps.add_argument("--gap", type=plain_float, default=0.0, metavar="S",
                      help="wall time between two files [s] (default 0)")
    gaps.add_argument("--clock-gap", type=plain_float, default=0.0, metavar="S",
                      help="simulated time between two files [s], on /clock (default 0)")
    ap.add_argument("--stamp", type=plain_float, default=0.0, metavar="S", help="header.stamp [s] (default 0)")
    ap.add_argument("--wait", type=plain_float, default=60.0, metavar="S",
                    help="wall time to wait for the subscriber, /clock and each acknowledgement (default 60)")
    args = ap.parse_args(argv)
    try:
        check_args(args)
    except ValueError as exc:
        print(f"trajectory_sender: error: {exc}", file=sys.stderr)
        return 2
    try:
        msgs = [(f, message(read_sendable(f), args.stamp)) for f in args.files]
    except (TrajectoryError, OSError) as exc:
        print(f"trajectory_sender: error: {exc}", file=sys.stderr)
        return 2
    rclpy.init(args=[], signal_handler_options=rclpy.signals.SignalHandlerOptions.NO)
    node = rclpy.create_node("trajectory_sender")
    try:
        return _send(node, msgs, args)
    except KeyboardInterrupt:
        print(INTERRUPTED, file=sys.stderr, flush=True)
        return EXIT_INTERRUPTED
    finally:  # a short-lived client: its participant is destroyed, so Fast DDS removes its /dev/shm files; a
        # teardown that blocks (ros/runtime.py says how it can) is left after 5 s
        closing = threading.Thread(target=lambda: (node.destroy_node(), rclpy.try_shutdown()), daemon=True)
        closing.start()
        closing.join(5.0)
        # the graph's nodes leave their files for the launcher's sweep, which skips what a live process maps: a
        # sender that outlived the graph mapped its ports, so it sweeps too (its own files, if the teardown was
        # left, and any other dead process's, as the launcher does)
        remove_stale(shm_files(), ignore_pids=frozenset({os.getpid()}))


def _send(node, msgs, args) -> int:
    deadline = time.monotonic() + args.wait
    if args.namespace is None:
        try:
            topic = found_topic(node, deadline)
        except SeveralGraphs as exc:
            print(f"trajectory_sender: error: several graphs take trajectories ({exc}): give --namespace",
                  file=sys.stderr, flush=True)
            return 2
        if topic is None:
            print(f"trajectory_sender: no graph that takes trajectories (a <ns>/trajectory subscriber) after "
                  f"{args.wait:g} s", file=sys.stderr, flush=True)
            return 1
    else:
        topic = resolve(TRAJECTORY, args.namespace)
    pub = node.create_publisher(JointTrajectory, topic, TRAJECTORY_QOS)
    clock = [-1.0]
    node.create_subscription(Clock, CLOCK, lambda m: clock.__setitem__(0, m.clock.sec + m.clock.nanosec * 1e-9),
                             QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=10,
                                        reliability=ReliabilityPolicy.BEST_EFFORT))
    say_at = time.monotonic() + SAY_WAITING_S
    while pub.get_subscription_count() < 1 or clock[0] < args.after_clock:
        if say_at is not None and time.monotonic() > say_at:
            print(f"trajectory_sender: waiting up to {args.wait:g} s for "
                  + (f"a subscriber on {topic}" if pub.get_subscription_count() < 1
                     else f"/clock to reach {args.after_clock:g} s"), file=sys.stderr, flush=True)
            say_at = None
        if time.monotonic() > deadline:
            what = (f"no subscriber on {topic}" if pub.get_subscription_count() < 1
                    else f"/clock at {clock[0]:g} s, not yet {args.after_clock:g} s")
            print(f"trajectory_sender: {what} after {args.wait:g} s", file=sys.stderr, flush=True)
            return 1
        rclpy.spin_once(node, timeout_sec=0.05)
    sent_at = clock[0]
    for i, (f, msg) in enumerate(msgs):
        if i and args.clock_gap > 0:
            due = sent_at + args.clock_gap
            while clock[0] < due:
                if time.monotonic() > deadline + args.wait:
                    print(f"trajectory_sender: /clock at {clock[0]:g} s, not yet {due:g} s", file=sys.stderr, flush=True)
                    return 1
                rclpy.spin_once(node, timeout_sec=0.01)
        elif i:
            until = time.monotonic() + args.gap
            while time.monotonic() < until:
                rclpy.spin_once(node, timeout_sec=min(0.05, max(until - time.monotonic(), 0.0)))
        sent_at = clock[0]
        pub.publish(msg)
        print(f"sent {f}" + (f" at /clock {clock[0]:.3f} s" if clock[0] >= 0 else ""), flush=True)
    # the acknowledgements come with the writer's next heartbeat exchange (up to a few seconds): waited once
    # (waited in 0.2 s slices: a Ctrl-C is taken between two, not after the whole --wait)
    acked_by = time.monotonic() + args.wait
    while not (acked := pub.wait_for_all_acked(Duration(seconds=0.2))) and time.monotonic() < acked_by:
        pass
    if not acked:
        print(f"trajectory_sender: not acknowledged within {args.wait:g} s", file=sys.stderr, flush=True)
        return 1
    return 0


INTERRUPTED = "trajectory_sender: interrupted (the files above marked sent were sent)"


if __name__ == "__main__":
    sys.stdout.flush()
    try:
        code = main()
    except KeyboardInterrupt:   # Ctrl-C while ROS starts or while the participant is destroyed
        print(INTERRUPTED, file=sys.stderr, flush=True)
        code = EXIT_INTERRUPTED
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(code)  # no interpreter finalization: rclpy's threads may still be in a teardown left behind

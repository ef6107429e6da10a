"""recorder node: records topics into a rosbag2 MCAP bag, payloads as they come off the wire.

Like ``ros2 bag record``: each topic is subscribed (raw, no deserialising)
once a publisher is discovered, with reliable / transient-local QoS only if
every publisher offers it, and the publishers' offered QoS profiles go into
the bag. Log time is the latest /clock (``time_source: clock``, what
``--use-sim-time`` gives: in steps of 1 / clock_hz, 10 ms at the default
100 Hz; the stamps inside the messages keep every step) or the system clock. It also writes /tf (at
``tf_rate_hz`` of simulated time) and /tf_static from /joint_states and the
URDF's forward kinematics, since tf2_msgs has no Python wheel here.
Topic names are recorded resolved (absolute); a relative name in ``topics``
is resolved in the recorder's namespace, whose arm (``/pa10`` when the
recorder runs at the root) gives the joint_states and reference topics /tf
and PROGRESS are computed from.
On SIGINT/SIGTERM it takes what is still queued, then closes the bag
(summary + metadata.yaml). It prints ``PROGRESS k`` (the step of
/joint_states) now and then and, with ``end_stamp_ns`` >= 0, ``COMPLETE``
once every stamped topic has a message stamped at or after it: started by
the launcher, it is the run's observer. Messages are taken every
``poll_period_s`` (``polled.Inbox``), not one wake-up per message; each
subscription keeps ``qos_depth`` messages, so nothing is lost between drains.
"""
from __future__ import annotations

import json
import struct
import time
from pathlib import Path
from typing import NoReturn

from rclpy.node import Node

from ..bag.custom_data import CUSTOM_CONFIG, CUSTOM_PREFIX
from ..bag.bag_writer import COMPRESSIONS, BagExistsError, BagWriter
from ..config_error import said_as
from ..bag.tf_messages import tf_message_cdr
from ..wire import joint_state_cdr
from ..wire.reference_buffer import ReferenceBuffer
from ..wire.steps import StepClock, cdr_stamp_ns, to_ns
from ..wire.topics import DEFAULT_NS, ArmTopics, resolve
from .bag_qos import bag_qos, subscription_qos, to_bag_qos
from ..loop.cpu_meter import CpuMeter
from .msg_types import message_class
from ..loop.scheduling import apply_batch, apply_fifo
from .params import (MAX_QOS_DEPTH, RT_PRIORITY, SCHED_BATCH, SETTINGS_DEFAULTS, Param, ParameterError, check_choice,
                     declare, declare_settings)
from .settings_params import NODE_SECTIONS
from .polled import Inbox
from .ready import announce_when_ready
from .runtime import announce_ready, exit_process, run_node, spin_until
from .endpoints import CLOCK, TF, TF_STATIC
from .wall_timer import wall_timer

# types whose CDR body starts with a stamp (header.stamp, or the Clock's time)
# (/diagnostics is stamped too, but on a wall-clock timer: it says nothing about completeness)
STAMPED_TYPES = {"sensor_msgs/msg/JointState", "trajectory_msgs/msg/JointTrajectory", "rosgraph_msgs/msg/Clock",
                 "std_msgs/msg/Header"}
PROGRESS_PERIOD_NS = 500_000_000  # a PROGRESS line (step of /joint_states) per 0.5 s of stamps
DRAIN_IDLE_S = 0.3   # at stop: take queued messages until none came for this long
DRAIN_LIMIT_S = 5.0


def parse_topic_spec(spec: str, ns: str = DEFAULT_NS) -> tuple[str, str | None]:
    """'name' or 'name:pkg/msg/Type' -> (absolute name, type or None); a relative name is resolved in ``ns``."""
    name, _, type_name = spec.partition(":")
    if not name or name.endswith("/") or "//" in name:
        raise ParameterError(f"topic {name!r} is not a topic name")
    return resolve(name, ns), type_name or None


PARAMS = {
    "bag": Param("", "the bag directory to write (required)", writes=True),
    "force": Param(False, "replace an existing bag"),
    "topics": Param([""], "topics to record: names, optionally name:pkg/msg/Type; relative ones in the namespace",
                    topics=True),
    "all_topics": Param(False, "record every topic discovered"),
    "time_source": Param("clock", "log time: clock (latest /clock) or system (wall time)"),
    "config_file": SETTINGS_DEFAULTS,
    "sched_batch": SCHED_BATCH,
    "rt_priority": RT_PRIORITY,
    "custom_data": Param([""], "key=value entries for the bag's custom_data"),
    "tf_rate_hz": Param(100.0, "/tf written from joint_states at this rate [Hz of simulated time]; 0 = none", 0.0),
    "end_stamp_ns": Param(-1, "print COMPLETE once every stamped topic reached this stamp [ns]; -1 = never", -1),
    "qos_depth": Param(2000, "keep_last depth of each subscription [messages]", 1, MAX_QOS_DEPTH),
    "compression": Param("zstd", "MCAP chunk compression: zstd or none"),
    "poll_period_s": Param(0.01, "wall time between two drains of the subscriptions [s]", 0.0),
}


class RecorderNode(Node):
    def __init__(self):
        super().__init__("recorder")
        p = declare(self, PARAMS)
        if not p["bag"]:
            raise ParameterError("parameter bag is required (the bag directory to write)")
        if not p["poll_period_s"] > 0:
            raise ParameterError(f"parameter poll_period_s must be > 0 s, got {p['poll_period_s']}")
        if p["time_source"] not in ("clock", "system"):
            raise ParameterError(f"parameter time_source must be clock or system, got {p['time_source']!r}")
        ns = self.get_namespace()
        self.arm = ArmTopics(ns if ns != "/" else DEFAULT_NS)
        specs = [parse_topic_spec(s, self.arm.ns) for s in p["topics"] if s]
        if not specs and not p["all_topics"]:
            raise ParameterError("give parameter topics (a list of /names) or all_topics:=true")
        self.p = p
        settings = declare_settings(self, NODE_SECTIONS["recorder"], p["config_file"])  # the whole run, into the bag
        custom = {CUSTOM_CONFIG: json.dumps(settings.to_config())}
        for item in (s for s in p["custom_data"] if s):
            key, sep, value = item.partition("=")
            if not sep:
                raise ParameterError(f"custom_data entry {item!r} is not key=value")
            custom[CUSTOM_PREFIX + key] = value
        self.wanted = dict(specs)                    # topic -> type (None: from discovery)
        if p["time_source"] == "clock":
            self.wanted.setdefault(CLOCK, "rosgraph_msgs/msg/Clock")
        self.now_ns = 0
        self.clock_received = False
        self.end_ns = p["end_stamp_ns"]
        self.reached: dict[str, bool] = {}
        self.received = 0
        self._subs = {}
        self._announced = False
        model = settings.arm
        self.joint_names = model.joint_names
        self.chain = model.chain if p["tf_rate_hz"] > 0 else None
        self._tf_period_ns = int(round(1e9 / p["tf_rate_hz"])) if self.chain else 0
        self._next_tf_ns = 0
        self._next_progress_ns = 0
        self.dt_ns = int(round(settings.simulation.dt_s * 1e9))
        check_choice("compression", p["compression"], COMPRESSIONS)
        # x_d from the reference batches, for the worst |e| on PROGRESS lines (sampled at tf_rate_hz)
        self.refs = ReferenceBuffer(len(self.joint_names), StepClock(settings.simulation.dt_s))
        self._ref_joint = {self.arm.reference(j): i for i, j in enumerate(self.joint_names)}
        try:
            self.writer = BagWriter(Path(p["bag"]), force=p["force"], custom_data=custom, compression=p["compression"])
        except BagExistsError as exc:   # its `force` is this node's parameter
            raise BagExistsError(said_as(str(exc), {"force": "force:=true"})) from None
        self.cpu = CpuMeter()
        self.inbox = Inbox(self, p["poll_period_s"])
        self._discover()
        self._timer = wall_timer(self, 0.2, self._discover)
        if p["sched_batch"]:
            print(apply_batch()[1], flush=True)
        if p["rt_priority"]:  # after SCHED_BATCH: a granted priority replaces it
            print(apply_fifo(p["rt_priority"])[1], flush=True)
        announce_ready("recorder")
        announce_when_ready(self, self._ready_for_steps)

    def _ready_for_steps(self) -> str | None:
        """The start handshake (``ros/ready.py``): None once every wanted topic has a subscription matched with a
        publisher and, with ``time_source: clock``, a /clock has come in (the plant's at time 0); else what is
        missing."""
        unsubscribed = [t for t in self.wanted if not self._subs.get(t)]
        if unsubscribed:
            return f"no publisher discovered yet for {', '.join(unsubscribed)}"
        unmatched = [t for t, sub in self._subs.items() if sub is not None and sub.get_publisher_count() < 1]
        if unmatched:
            return f"its readers of {', '.join(unmatched)} have not matched a publisher"
        if self.p["time_source"] == "clock" and not self.clock_received:
            return "no /clock received yet"
        return None

    # ------------------------------------------------------------- discovery
    def _discover(self) -> None:
        types = dict(self.get_topic_names_and_types())
        names = set(self.wanted) | (set(types) if self.p["all_topics"] else set())
        for topic in sorted(names - set(self._subs)):
            if topic in (TF, TF_STATIC) and self.chain is not None:
                continue  # written by the recorder itself
            pubs = self.get_publishers_info_by_topic(topic)
            if not pubs:
                continue
            type_name = self.wanted.get(topic) or pubs[0].topic_type
            try:
                cls = message_class(type_name)
                profiles = [pi.qos_profile for pi in pubs]
                self.writer.add_topic(topic, type_name, [to_bag_qos(q, self.p["qos_depth"]) for q in profiles])
            except (LookupError, KeyError) as exc:
                self.get_logger().warning(f"not recording {topic}: {exc}")
                self._subs[topic] = None
                continue
            stamped = type_name in STAMPED_TYPES
            if stamped and self.end_ns >= 0:
                self.reached[topic] = False
            self._subs[topic] = self.inbox.subscribe(
                cls, topic, subscription_qos(profiles, self.p["qos_depth"]),
                lambda data, t=topic, s=stamped: self._on_message(t, s, data))
            self.get_logger().info(f"recording {topic} ({type_name})")

    # ------------------------------------------------------------- messages
    def _on_message(self, topic: str, stamped: bool, data: bytes) -> None:
        if topic == CLOCK and self.p["time_source"] == "clock" and len(data) >= 12:
            self.clock_received = True
            self.now_ns = max(self.now_ns, cdr_stamp_ns(data))
        t_ns = self.now_ns if self.p["time_source"] == "clock" else time.time_ns()
        self.writer.write(topic, t_ns, data)
        self.received += 1
        if topic == self.arm.joint_states:
            self._on_joint_states(data, t_ns)
        elif topic in self._ref_joint and self.chain is not None:
            self.refs.add_cdr(self._ref_joint[topic], data)
        if stamped and self.end_ns >= 0 and not self.reached.get(topic, True) and len(data) >= 12:
            if cdr_stamp_ns(data) >= self.end_ns:
                self.reached[topic] = True
                if not self._announced and all(self.reached.values()) and all(
                        self._subs.get(t) for t in self.wanted):
                    self._announced = True
                    print("COMPLETE", flush=True)

    def _on_joint_states(self, data: bytes, t_ns: int) -> None:
        """PROGRESS (every PROGRESS_PERIOD_NS of stamps) and /tf (at tf_rate_hz) from /joint_states."""
        if len(data) < 12:
            return
        stamp_ns = cdr_stamp_ns(data)
        self.cpu.mark(stamp_ns // self.dt_ns)
        if stamp_ns >= self._next_progress_ns:
            self._next_progress_ns = stamp_ns + PROGRESS_PERIOD_NS
            worst = self.refs.worst_abs_error  # NaN until /tf sampling has seen a state with its x_d
            print(f"PROGRESS {stamp_ns // self.dt_ns}" + (f" {worst:.6g}" if worst == worst else ""), flush=True)
        if self.chain is not None and stamp_ns >= self._next_tf_ns:
            self._write_tf(data, t_ns)

    def _write_tf(self, data: bytes, t_ns: int) -> None:
        try:
            sec, nanosec, names, pos, _, _ = joint_state_cdr.decode(data)
        except (ValueError, struct.error, UnicodeDecodeError):
            return
        stamp_ns = to_ns(sec, nanosec)
        if stamp_ns < self._next_tf_ns:
            return
        self._next_tf_ns = stamp_ns + self._tf_period_ns
        if not self.writer.has_topic(TF):
            self.writer.add_topic(TF_STATIC, "tf2_msgs/msg/TFMessage", [bag_qos(True, True, 1)])
            self.writer.write(TF_STATIC, t_ns, tf_message_cdr(self.chain.fixed_transforms(), sec, nanosec))
            self.writer.add_topic(TF, "tf2_msgs/msg/TFMessage", [bag_qos(True, False, 100)])
        positions = dict(zip(names or self.joint_names, pos))
        self.writer.write(TF, t_ns, tf_message_cdr(self.chain.moving_transforms(positions), sec, nanosec))
        step = stamp_ns // self.dt_ns
        self.refs.error(step, [positions.get(j, float("nan")) for j in self.joint_names])
        self.refs.forget_before(step)

    # ------------------------------------------------------------- run / stop
    def loop(self, executor, stop) -> None:
        spin_until(executor, stop, stop)
        # take what is still queued (and still arriving) before closing the bag
        self.destroy_timer(self._timer)
        self.destroy_timer(self.inbox.timer)
        t_end = time.monotonic() + DRAIN_LIMIT_S
        idle_since = time.monotonic()
        while time.monotonic() < t_end and time.monotonic() - idle_since < DRAIN_IDLE_S:
            if self.inbox.drain():
                idle_since = time.monotonic()
            time.sleep(self.p["poll_period_s"])

    def close(self) -> None:
        self.writer.close()
        missing = [t for t in self.wanted if not self._subs.get(t)]
        print(self.cpu.line("recorder"), flush=True)
        print(f"RECORDED {sum(self.writer.counts.values())} messages on {len(self.writer.counts)} topics into "
              f"{self.writer.path}" + (f"; never seen: {', '.join(missing)}" if missing else ""), flush=True)


def main(args=None) -> NoReturn:
    exit_process(run_node(RecorderNode, args, params=PARAMS))


if __name__ == "__main__":
    main()

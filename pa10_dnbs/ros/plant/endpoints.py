"""The plant's wire I/O: what it publishes each step and how it takes the efforts.

Names relative to the node's namespace (/pa10 by default, wire/topics.py).
Publishes robot_description (the URDF, transient-local), /clock (with the
states ``ClockSchedule`` picks: one per 1 / clock_hz of simulated time, and
the last; none with clock_hz 0),
joint_states (every joint: position, velocity, and as effort the torque applied
over the step that led to this state) and per joint <joint>/state
(that joint only, stamped k T), through each joint's fault-injecting state
link when ``faults.state`` configures one. The <joint>/effort
subscriptions are polled (``polled.py``): the plant blocks on one wait set
over them and takes every effort that is there at once, so it wakes once
per batch of efforts, not once per effort. Decoded efforts come out
saturated at the torque limit (counted) with their reception time; undecodable ones
are counted and dropped.
"""
from __future__ import annotations

import math
import struct
import time

import numpy as np
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import JointState
from std_msgs.msg import String

from ...faults.faulty_link import faulty_link
from ...loop.endpoint_match import Need
from ..acked import wait_acked
from ...wire import joint_state_cdr
from ...wire.clock_schedule import ClockSchedule
from ...settings import Settings
from ..polled import PolledSubscription, SubscriptionWaitSet
from ..endpoints import (CLOCK, JOINT_STATES, ROBOT_DESCRIPTION, StepClock, description_qos, effort_topic, loop_qos,
                   record_qos, state_topic)  # relative names


CLOCK_CDR = struct.Struct("<HHiI")  # rosgraph_msgs/Clock: encapsulation (little-endian CDR), sec, nanosec


class PlantEndpoints:
    def __init__(self, node, settings: Settings, clock: StepClock, reliability: str, state_depth: int, effort_depth: int,
                 clock_hz: float, last_step: int):
        """``reliability`` and the depths: QoS of the per-joint state and effort topics; ``clock_hz``: /clock
        rate [Hz of simulated time] (0: no /clock); ``last_step``: the run's last state (it carries a /clock)."""
        self.node = node
        self.clock = clock
        arm = settings.arm
        self.joint_names = names = arm.joint_names
        n = len(names)
        self.state_qos = loop_qos(reliability, depth=state_depth)
        self.effort_qos = loop_qos(reliability, depth=effort_depth)
        self._state_pubs = [node.create_publisher(JointState, state_topic(j), self.state_qos) for j in names]
        self._clock_pub = None
        if clock_hz > 0:
            self._clock_pub = node.create_publisher(Clock, CLOCK, record_qos())
            self._clock_schedule = ClockSchedule(clock_hz, clock.dt_ns / 1e9, last_step)
        self._js_pub = node.create_publisher(JointState, JOINT_STATES, record_qos())
        self._effort_subs = [PolledSubscription(node, JointState, effort_topic(j), self.effort_qos) for j in names]
        self._wait_set = SubscriptionWaitSet(node, self._effort_subs)
        # the URDF, latched, as robot_state_publisher offers it (Foxglove and the recorder read it)
        self._description_pub = node.create_publisher(String, ROBOT_DESCRIPTION, description_qos())
        self._description_pub.publish(String(data=arm.urdf_text()))
        self.state_links = [faulty_link(settings.faults, "state", i, self._state_pubs[i].publish, arm.upper_rad[i])
                            for i in range(n)]
        self.torque_limit = np.array(settings.plant.torque_limit_nm, dtype=float)
        self._limits = self.torque_limit.tolist()
        self._state_layouts = [joint_state_cdr.OneJointLayout(j, ("position", "velocity")) for j in names]
        self._effort_layouts = [joint_state_cdr.OneJointLayout(j, ("effort",)) for j in names]
        self.waits = 0                 # wait set waits (each a possible wake-up)
        self.wakeups_with_efforts = 0  # ... that returned with efforts queued
        self.malformed = np.zeros(n, dtype=np.int64)
        self.out_of_range = np.zeros(n, dtype=np.int64)

    # ------------------------------------------------------------- out
    def publish_state(self, k: int, q: np.ndarray, qd: np.ndarray, applied: np.ndarray, joints=None,
                      observed: bool = True) -> int:
        """State ``k`` on every per-joint topic (or only ``joints``, a resend); with all joints and ``observed``
        also joint_states and, when due, /clock (``observed=False``: the caller sends them later with
        ``publish_observed``). Returns the wall time [ns, system clock] just before the per-joint states went
        out."""
        ql, qdl = q.tolist(), qd.tolist()
        sec, nanosec = self.clock.sec_nanosec(k)
        t_ns = time.time_ns()
        for j in (range(len(self.joint_names)) if joints is None else joints):
            link = self.state_links[j]
            if link is None:
                self._state_pubs[j].publish(self._state_layouts[j].encode(sec, nanosec, ql[j], qdl[j]))
                continue
            fate = link.fate()
            pos = link.corrupt_value() if fate.corrupt else ql[j]
            link.send(self._state_layouts[j].encode(sec, nanosec, pos, qdl[j]), fate)
        if joints is None and observed:
            self.publish_observed(k, ql, qdl, applied.tolist())
        return t_ns

    def publish_start_clock(self) -> None:
        """/clock at time 0 before the first state (latched, so every reader gets it whenever it matches): the
        start handshake's proof that /clock reaches a node. State 0 then carries no second one."""
        if self._clock_pub is not None and self._clock_schedule.due(0):
            self._clock_pub.publish(CLOCK_CDR.pack(0x0100, 0, 0, 0))

    def publish_observed(self, k: int, q: list, qd: list, applied: list) -> None:
        """What observers read of state ``k`` (lists of n: [rad], [rad/s], the torque applied over step k - 1
        [N m]): joint_states and, when due, /clock."""
        sec, nanosec = self.clock.sec_nanosec(k)
        if self._clock_pub is not None and self._clock_schedule.due(k):
            self._clock_pub.publish(CLOCK_CDR.pack(0x0100, 0, sec, nanosec))  # raw CDR: no message conversion
        self._js_pub.publish(joint_state_cdr.encode(sec, nanosec, self.joint_names, q, qd, applied))

    # ------------------------------------------------------------- in
    @property
    def effort_subscriptions(self) -> list:
        """The polled effort subscriptions, one per joint in joint order (the joint bus's paced loop waits on them)."""
        return list(self._effort_subs)

    def effort_publishers(self) -> list[tuple[str, int]]:
        """Per joint: its effort topic (resolved) and how many publishers it has (one: its joint controller)."""
        return [(self.node.resolve_topic_name(sub.topic), sub.get_publisher_count()) for sub in self._effort_subs]

    def wait(self, timeout_s: float) -> list[int]:
        """Block until some effort is queued or ``timeout_s`` [s] passed; the joints with efforts queued."""
        ready = self._wait_set.wait(timeout_s)
        self.waits += 1
        self.wakeups_with_efforts += bool(ready)
        return ready

    def take_efforts(self, joints=None) -> list[tuple[int, int, float, int]]:
        """Every queued effort (of ``joints``, default all) as (joint, step, torque [N m], received [ns]),
        saturated at the torque limit."""
        out = []
        for joint in (range(len(self._effort_subs)) if joints is None else joints):
            sub, layout = self._effort_subs[joint], self._effort_layouts[joint]
            while (got := sub.take()) is not None:
                data, received_ns = got
                try:
                    sec, nanosec, (u,) = layout.decode(data)
                    u = float(u)
                except (ValueError, IndexError, struct.error, UnicodeDecodeError):
                    self.malformed[joint] += 1
                    continue
                lim = self._limits[joint]
                if math.isfinite(u) and abs(u) > lim:  # out of range: counted, saturated at the torque limit
                    self.out_of_range[joint] += 1
                    u = lim if u > 0 else -lim
                out.append((joint, self.clock.step_of_sec_nanosec(sec, nanosec), u, received_ns))
        return out

    # ------------------------------------------------------------- graph
    def needs(self, state_subscribers: int, clock_subscribers: int, joint_states_subscribers: int,
              recorders: int) -> list[Need]:
        """The endpoints the graph must have matched before the first state goes out (``MatchWait``); each
        names the nodes it waits for and the plant parameter that asked for them. The subscriber counts are
        the parameters' (``state_subscribers`` ...), without the ``recorders``, which come on top of each."""
        node = self.node
        out = [Need(pub.topic_name, "subscribers", state_subscribers + recorders, pub.get_subscription_count,
                    _who(f"joint_controller_{j}", state_subscribers, "state_subscribers", recorders))
               for j, pub in zip(self.joint_names, self._state_pubs)]
        out += [Need(node.resolve_topic_name(sub.topic), "publishers", 1, sub.get_publisher_count,
                     f"joint_controller_{j} (or a player of its efforts)")
                for j, sub in zip(self.joint_names, self._effort_subs)]
        # the plant's own subscription and one per recorder
        out += [Need(node.resolve_topic_name(effort_topic(j)), "subscribers", 1 + recorders,
                     lambda t=effort_topic(j): node.count_subscribers(t), _who("", 0, "", recorders))
                for j in self.joint_names if recorders]
        if self._clock_pub is not None:
            out.append(Need(CLOCK, "subscribers", clock_subscribers + recorders, self._clock_pub.get_subscription_count,
                            _who("the reference node", clock_subscribers, "clock_subscribers", recorders)))
        out.append(Need(self._js_pub.topic_name, "subscribers", joint_states_subscribers + recorders,
                        self._js_pub.get_subscription_count,
                        _who("an observer (the wire monitor)", joint_states_subscribers,
                             "min_joint_states_subscribers", recorders)))
        return out

    def flush(self, timeout_s: float = 2.0, stop=None) -> bool:
        """Wait (at most ``timeout_s`` in all, until ``stop`` is done) until every subscriber acknowledged what the
        reliable publishers sent, so the observer gets the last states before the plant's writers go away; True
        when all did."""
        return wait_acked([self._js_pub] + ([self._clock_pub] if self._clock_pub else []) + self._state_pubs,
                          timeout_s, stop)

    def close(self, stop=None) -> None:
        """Close the links and wait (2 s at most; not once ``stop`` is done: a stopped graph's subscribers are
        gone) for the last messages' acknowledgements."""
        for link in self.state_links:
            if link is not None:
                link.close()
        self.flush(stop=stop)
        self._wait_set.destroy()


def _who(reader: str, n: int, param: str, recorders: int) -> str:
    """Who a plant's subscriber count waits for: ``n`` x ``reader`` (set by ``param``) and the recorders."""
    parts = []
    if n:
        parts.append(f"{reader if n == 1 else f'{n} readers'} ({param}:={n})")
    if recorders:
        parts.append(f"{'the recorder' if recorders == 1 else f'{recorders} recorders'} (recorders:={recorders})")
    return " and ".join(parts)

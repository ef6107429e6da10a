"""plant_node: the PyBullet PA10 plant on the wire.

Publishes /robot_description (the URDF, transient-local), /clock,
/joint_states (all 7: position, velocity, and as effort the torque applied
over the step that led to this state) and per joint
/pa10/<joint>/state (that joint only, stamped k T). Subscribes to the seven
/pa10/<joint>/effort topics and applies them, saturated at Table 2.

mode lockstep: state k+1 is computed when all efforts answering state k have
arrived; a missing one is re-requested after ``resend_s`` and replaced (held
or zeroed, counted) after ``effort_timeout_s``. mode realtime: the plant
steps every T of wall time with the latest effort of each joint and counts
the ticks at which the effort answering the previous state was missing.
Defensive: a non-finite effort counts as missing (hold or zero, counted), an
out-of-range one is saturated at Table 2 and counted. Faults configured in
``faults.state`` are injected on each joint's state link (drop, delay,
corrupt). Fault counters go to /diagnostics every second; timing figures and
counters go to ``stats_file`` (JSON) at exit.
"""
from __future__ import annotations

import json
import math
import os
import struct
import sys
import time
from pathlib import Path

import numpy as np
from rclpy.node import Node
from rclpy.task import Future
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import JointState
from std_msgs.msg import String

from .. import JOINT_NAMES
from ..plant.from_config import open_client, plant_from_config
from ..wire import joint_state_cdr
from ..faults.faulty_link import links_from_config
from ..kinematics.urdf_chain import UrdfChain
from .diagnostics import DiagnosticsReporter, status
from ..loop.effort_gate import EffortGate
from .params import check_choice, declare, load_node_config
from .runtime import announce_ready, run_node, spin_until
from .wire import (CLOCK, JOINT_STATES, ROBOT_DESCRIPTION, StepClock, description_qos, effort_topic, loop_qos,
                   record_qos, state_topic)


class PlantNode(Node):
    def __init__(self):
        super().__init__("plant")
        p = declare(self, {
            "config_file": "", "mode": "lockstep", "duration_s": 0.0, "effort_timeout_s": 1.0,
            "resend_s": 0.25, "on_missing_effort": "hold", "reliability": "reliable", "stats_file": "",
            "min_joint_states_subscribers": 0, "start_timeout_s": 30.0, "settle_s": 0.3,
            "state_subscribers": 1, "clock_subscribers": 1, "recorders": 0, "effort_queue_depth": 1000,
        })
        check_choice("mode", p["mode"], ("lockstep", "realtime"))
        check_choice("on_missing_effort", p["on_missing_effort"], ("hold", "zero"))
        check_choice("reliability", p["reliability"], ("reliable", "best_effort"))
        self.p = p
        cfg = load_node_config(p["config_file"])
        self.dt = cfg["simulation"]["dt_s"]
        duration = p["duration_s"] if p["duration_s"] > 0 else cfg["simulation"]["duration_s"]
        self.n_steps = int(round(duration / self.dt))
        self.clock_ = StepClock(self.dt)
        self._client = open_client()
        self.plant = plant_from_config(cfg, self._client)
        self.gate = EffortGate(len(JOINT_NAMES), p["on_missing_effort"])
        self.gate.bin_steps = max(1, int(round(60.0 / self.dt)))  # realtime on-time fraction per simulated minute
        # realtime: latest value only (depth 1), a late reader skips stale states. lockstep: a deep
        # history, so a recorder that falls behind for a while still gets every message.
        realtime = p["mode"] == "realtime"
        qos = loop_qos(p["reliability"], depth=1 if realtime else record_qos().depth)
        effort_qos = loop_qos(p["reliability"], depth=1 if realtime else p["effort_queue_depth"])
        self._state_pubs = [self.create_publisher(JointState, state_topic(j), qos) for j in JOINT_NAMES]
        self._clock_pub = self.create_publisher(Clock, CLOCK, loop_qos("reliable", depth=record_qos().depth))
        self._js_pub = self.create_publisher(JointState, JOINT_STATES, record_qos())
        self._effort_subs = [
            self.create_subscription(JointState, effort_topic(j), lambda m, i=i: self._on_effort(i, m), effort_qos,
                                     raw=True)
            for i, j in enumerate(JOINT_NAMES)]
        # the URDF, latched, as robot_state_publisher offers it (Foxglove and the recorder read it)
        self._description_pub = self.create_publisher(String, ROBOT_DESCRIPTION, description_qos())
        self._description_pub.publish(String(data=Path(cfg["plant"]["urdf"]).read_text()))
        self._names = [[j] for j in JOINT_NAMES]
        chain = UrdfChain.from_file(cfg["plant"]["urdf"])
        self.torque_limit = np.array(cfg["plant"]["torque_limit_nm"])
        self.out_of_range = np.zeros(len(JOINT_NAMES), dtype=np.int64)
        self._state_links = [
            links_from_config(cfg, "state", i, self._state_pubs[i].publish, chain.joint(j).upper)
            for i, j in enumerate(JOINT_NAMES)]
        self._clock_msg = Clock()
        self.malformed = np.zeros(len(JOINT_NAMES), dtype=np.int64)
        self.t_pub = np.full(self.n_steps + 1, np.nan)          # wall time state k was published [s]
        self.latency = np.full((self.n_steps + 1, len(JOINT_NAMES)), np.nan)  # state k -> effort k [s]
        self.resends = np.zeros(len(JOINT_NAMES), dtype=np.int64)
        self.late_ticks = 0
        self.running = False  # set once state 0 is out; efforts arriving before are kept, not applied
        self.finished = False
        self._finished_future = Future()  # done when the last step is applied (lockstep spin ends on it)
        self.exit_code = 0  # a signal before the end is a clean stop; "completed" in the stats says if it ran out
        self.wall_start = self.wall_end = math.nan
        self.diagnostics = DiagnosticsReporter(self, self._diagnostics, lambda: self.clock_.stamp(self.gate.step))
        announce_ready("plant")

    # ---------------------------------------------------------------- wire
    def _publish_state(self, k: int, joints=None) -> None:
        q, qd = self.plant.state
        ql, qdl = q.tolist(), qd.tolist()
        sec, nanosec = self.clock_.sec_nanosec(k)
        for j in (range(len(JOINT_NAMES)) if joints is None else joints):
            link = self._state_links[j]
            if link is None:
                self._state_pubs[j].publish(
                    joint_state_cdr.encode(sec, nanosec, self._names[j], (ql[j],), (qdl[j],), ()))
                continue
            fate = link.fate()
            pos = link.corrupt_value() if fate.corrupt else ql[j]
            link.send(joint_state_cdr.encode(sec, nanosec, self._names[j], (pos,), (qdl[j],), ()), fate)
        if joints is not None:
            return
        self.t_pub[k] = time.perf_counter()
        self._clock_msg.clock.sec, self._clock_msg.clock.nanosec = sec, nanosec
        self._clock_pub.publish(self._clock_msg)
        self._js_pub.publish(joint_state_cdr.encode(sec, nanosec, JOINT_NAMES, ql, qdl, self.gate.applied.tolist()))

    def _on_effort(self, joint: int, data: bytes) -> None:
        try:
            sec, nanosec, _, _, _, effort = joint_state_cdr.decode(data)
            u = float(effort[0])
        except (ValueError, IndexError, struct.error, UnicodeDecodeError):
            self.malformed[joint] += 1
            return
        k = self.clock_.step_of_sec_nanosec(sec, nanosec)
        lim = self.torque_limit[joint]
        if math.isfinite(u) and abs(u) > lim:  # out of range: counted, saturated at Table 2
            self.out_of_range[joint] += 1
            u = lim if u > 0 else -lim
        if 0 <= k <= self.n_steps and math.isnan(self.latency[k, joint]):
            self.latency[k, joint] = time.perf_counter() - self.t_pub[k]
        if self.gate.offer(joint, k, u) and self.p["mode"] == "lockstep" and self.running:
            self._advance_while_ready()

    def _advance_while_ready(self) -> None:
        while self.gate.ready and not self.finished:  # efforts sent ahead may complete later steps too
            self._advance(timed_out=False)

    # ---------------------------------------------------------------- stepping
    def _advance(self, timed_out: bool) -> None:
        if self.p["mode"] == "lockstep":
            tau = self.gate.take_lockstep(timed_out)
        else:
            tau = self.gate.take_realtime()
        self.plant.step(tau)
        k = self.gate.step
        self._publish_state(k)
        if k >= self.n_steps:
            self.finished = True
            self.wall_end = time.perf_counter()
            if not self._finished_future.done():
                self._finished_future.set_result(None)

    def _wait_for_graph(self, executor, stop) -> bool:
        t0 = time.perf_counter()
        rec = self.p["recorders"]  # each recorder subscribes to every topic, efforts included
        need_state, need_clock = self.p["state_subscribers"] + rec, self.p["clock_subscribers"] + rec
        need_js = self.p["min_joint_states_subscribers"] + rec
        while not stop.done():
            lacking = [f"{state_topic(j)} (fewer than {need_state} subscribers)"
                       for j, pub in zip(JOINT_NAMES, self._state_pubs) if pub.get_subscription_count() < need_state]
            lacking += [f"{effort_topic(j)} (no publisher)" for j, sub in zip(JOINT_NAMES, self._effort_subs)
                        if sub.get_publisher_count() < 1]
            lacking += [f"{effort_topic(j)} (fewer than {rec} recorders)" for j in JOINT_NAMES
                        if self.count_subscribers(effort_topic(j)) < 1 + rec]
            if self._clock_pub.get_subscription_count() < need_clock:
                lacking.append(f"{CLOCK} (fewer than {need_clock} subscribers)")
            if self._js_pub.get_subscription_count() < need_js:
                lacking.append(f"{JOINT_STATES} (fewer than {need_js} subscribers)")
            if not lacking:
                settle_end = time.perf_counter() + self.p["settle_s"]
                while time.perf_counter() < settle_end and not stop.done():
                    executor.spin_once(timeout_sec=0.02)
                return not stop.done()
            if time.perf_counter() - t0 > self.p["start_timeout_s"]:
                raise RuntimeError("graph incomplete after start_timeout_s: " + "; ".join(lacking))
            executor.spin_once(timeout_sec=0.05)
        return False

    def loop(self, executor, stop) -> None:
        if not self._wait_for_graph(executor, stop):
            return
        print("RUNNING plant", flush=True)
        self.wall_start = time.perf_counter()
        self._publish_state(0)
        self.running = True
        if self.p["mode"] == "lockstep":
            self._advance_while_ready()
            self._loop_lockstep(executor, stop)
        else:
            self._loop_realtime(executor, stop)

    def _loop_lockstep(self, executor, stop) -> None:
        # Callbacks drive the steps (an effort completing step k publishes k+1);
        # a 10 ms wall-clock timer handles resends and timeouts.
        self._last_resend = (-1, 0.0)
        timer = self.create_timer(0.01, self._check_lockstep_timeouts)
        spin_until(executor, self._finished_future, stop)
        self.destroy_timer(timer)

    def _check_lockstep_timeouts(self) -> None:
        if self.finished:
            return
        k = self.gate.step
        now = time.perf_counter()
        waited = now - self.t_pub[k]
        if waited > self.p["effort_timeout_s"]:
            missing = self.gate.missing
            self.get_logger().warning(
                f"step {k}: no effort from {', '.join(JOINT_NAMES[j] for j in missing)} after "
                f"{self.p['effort_timeout_s']:g} s; applying {self.p['on_missing_effort']}")
            self._advance(timed_out=True)
        elif waited > self.p["resend_s"]:
            step, t = self._last_resend
            if step != k or now - t > self.p["resend_s"]:
                missing = self.gate.missing
                self.resends[missing] += 1
                self._publish_state(k, joints=missing)
                self._last_resend = (k, now)

    def _loop_realtime(self, executor, stop) -> None:
        # Ticks follow the wall clock; a plant that falls behind keeps stepping
        # (physics is never skipped) and counts the ticks it was late for.
        t_next = self.t_pub[0] + self.dt
        n_subs = len(JOINT_NAMES)
        while not self.finished and not stop.done():
            now = time.perf_counter()
            if now >= t_next:
                if now - t_next > self.dt:
                    self.late_ticks += 1
                self._advance(timed_out=False)
                t_next += self.dt
                for _ in range(n_subs):  # serve what arrived, even when there is no slack
                    executor.spin_once(timeout_sec=0.0)
            else:
                executor.spin_once(timeout_sec=t_next - now)

    # ---------------------------------------------------------------- report
    FAULT_KEYS = ("effort_timeouts", "nonfinite_efforts", "out_of_range_efforts", "malformed_efforts")

    def _joint_counters(self, i: int) -> dict:
        c = {"effort_timeouts": int(self.gate.timeouts[i]), "nonfinite_efforts": int(self.gate.nonfinite[i]),
             "out_of_range_efforts": int(self.out_of_range[i]), "malformed_efforts": int(self.malformed[i]),
             "missed_ticks": int(self.gate.misses[i]), "resent_states": int(self.resends[i])}
        link = self._state_links[i]
        if link is not None:
            c.update({f"injected_state_{k}": v for k, v in link.counters().items()})
        return c

    def _diagnostics(self) -> list:
        return [status(f"pa10/plant/{name}", "plant", self._joint_counters(i), self.FAULT_KEYS)
                for i, name in enumerate(JOINT_NAMES)]

    def stats(self) -> dict:
        k = self.gate.step
        wall = (self.wall_end if self.finished else time.perf_counter()) - self.wall_start
        lat = self.latency[:k]
        joints = []
        for i, name in enumerate(JOINT_NAMES):
            li = lat[:, i][np.isfinite(lat[:, i])]
            joints.append({
                "name": name,
                "effort_timeouts": int(self.gate.timeouts[i]),
                "missed_ticks": int(self.gate.misses[i]),
                "nonfinite_efforts": int(self.gate.nonfinite[i]),
                "stale_efforts": int(self.gate.stale[i]),
                "ahead_efforts_dropped": int(self.gate.dropped_ahead[i]),
                "resent_states": int(self.resends[i]),
                "malformed_efforts": int(self.malformed[i]),
                "out_of_range_efforts": int(self.out_of_range[i]),
                "timeout_ranges": _ranges(self.gate.timeout_steps[i]),
                "injected_state_faults": (self._state_links[i].counters() if self._state_links[i] is not None
                                          else None),
                "latency_median_us": float(np.median(li) * 1e6) if li.size else None,
                "latency_p99_us": float(np.percentile(li, 99) * 1e6) if li.size else None,
                "latency_max_us": float(li.max() * 1e6) if li.size else None,
            })
        on_time = None
        if self.p["mode"] == "realtime" and self.gate.ticks > 0:
            # a tick is on time when every joint's effort for the previous state had arrived
            on_time = self.gate.ticks_all_on_time / self.gate.ticks
        return {
            "mode": self.p["mode"], "steps": int(k), "completed": self.finished,
            "sim_time_s": k * self.dt, "wall_time_s": wall if math.isfinite(wall) else None,
            "real_time_factor": (k * self.dt / wall) if wall and math.isfinite(wall) and wall > 0 else None,
            "on_missing_effort": self.p["on_missing_effort"], "effort_timeout_s": self.p["effort_timeout_s"],
            "late_ticks": int(self.late_ticks), "on_time_fraction": on_time,
            "on_time_fraction_per_bin": [o / t for o, t in zip(self.gate.on_time_per_bin, self.gate.ticks_per_bin)],
            "bin_s": self.gate.bin_steps * self.dt,
            "limit_hits": self.plant.limit_hits.tolist(), "joints": joints,
        }

    def close(self) -> None:
        for link in self._state_links:
            if link is not None:
                link.close()
        path = self.p["stats_file"]
        if path:
            tmp = f"{path}.tmp"
            with open(tmp, "w") as f:
                json.dump(self.stats(), f, indent=2)
            os.replace(tmp, path)
        self._client.disconnect()


def _ranges(steps: list[int]) -> list[list[int]]:
    """Sorted steps as [first, last] runs of consecutive steps: [1, 2, 3, 7] -> [[1, 3], [7, 7]]."""
    out: list[list[int]] = []
    for k in steps:
        if out and k == out[-1][1] + 1:
            out[-1][1] = k
        else:
            out.append([k, k])
    return out


def main(args=None) -> int:
    return run_node(PlantNode, args)


if __name__ == "__main__":
    sys.exit(main())

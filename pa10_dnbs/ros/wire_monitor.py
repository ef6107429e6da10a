"""wire_monitor node: collects what travels on the wire, for metrics and reports.

Subscribes to /joint_states and every joint's reference topic and, at exit,
writes what it received to ``out_file`` (npz): state k from /joint_states
stamped k, the torque applied over step k from the effort field of
/joint_states stamped k+1, x_d(k) from the reference batches. Prints
``PROGRESS k`` now and then and ``COMPLETE`` once every step has arrived.
The launcher runs it as its own process, so the launcher never joins DDS.
It takes its messages every ``poll_period_s`` (``polled.Inbox``), not one
wake-up per message; /joint_states is reliable with a 2000-deep history, so
nothing is lost between two drains.
"""
from __future__ import annotations

import struct
from pathlib import Path
from typing import NoReturn

from rclpy.node import Node
from sensor_msgs.msg import JointState
from trajectory_msgs.msg import JointTrajectory

from ..wire.wire_record import WireRecord
from ..wire import joint_state_cdr, trajectory_cdr
from ..loop.scheduling import apply_batch, apply_fifo
from .params import (RT_PRIORITY, SCHED_BATCH, SETTINGS_DEFAULTS, Param, ParameterError, declare, declare_settings,
                     duration_steps)
from ..loop.cpu_meter import CpuMeter
from .polled import Inbox
from .ready import announce_when_ready
from .runtime import announce_ready, exit_process, run_node, spin_until
from .settings_params import NODE_SECTIONS
from .endpoints import JOINT_STATES, StepClock, record_qos, reference_qos, reference_topic


PARAMS = {
    "config_file": SETTINGS_DEFAULTS,
    "sched_batch": SCHED_BATCH,
    "rt_priority": RT_PRIORITY,
    "duration_s": Param(0.0, "the run's simulated time [s]; 0 = simulation.duration_s of the config", 0.0),
    "out_file": Param("", "the record written at exit [.npz] (required)", writes=True),
    "poll_period_s": Param(0.01, "wall time between two drains of the subscriptions [s]", 0.0),
}


class WireMonitorNode(Node):
    def __init__(self):
        super().__init__("wire_monitor")
        p = declare(self, PARAMS)
        if not p["out_file"]:
            raise ParameterError("parameter out_file is required")
        if not p["poll_period_s"] > 0:
            raise ParameterError(f"parameter poll_period_s must be > 0 s, got {p['poll_period_s']}")
        settings = declare_settings(self, NODE_SECTIONS["wire_monitor"], p["config_file"])
        dt_s = settings.simulation.dt_s
        duration = p["duration_s"] if p["duration_s"] > 0 else settings.simulation.duration_s
        self.joint_names = names = settings.arm.joint_names
        self.record = WireRecord(duration_steps(duration, dt_s), dt_s, len(names))
        self.out_file = p["out_file"]
        self.clock = StepClock(dt_s)
        self._announced = False
        self.cpu = CpuMeter()
        self.inbox = Inbox(self, p["poll_period_s"])
        self._js_sub = self.inbox.subscribe(JointState, JOINT_STATES, record_qos(), self._on_joint_states)
        self._refs_seen: set[int] = set()  # joints with a reference batch in
        for j, name in enumerate(names):
            self.inbox.subscribe(JointTrajectory, reference_topic(name), reference_qos(),
                                 lambda data, j=j: self._on_reference(j, data))
        self._last_step = -1
        if p["sched_batch"]:
            print(apply_batch()[1], flush=True)
        if p["rt_priority"]:  # after SCHED_BATCH: a granted priority replaces it
            print(apply_fifo(p["rt_priority"])[1], flush=True)
        announce_ready("wire_monitor")
        announce_when_ready(self, self._ready_for_steps)

    def _ready_for_steps(self) -> str | None:
        """The start handshake (``ros/ready.py``): None once the joint_states reader has matched the plant's
        writer and a reference batch of every joint has come in; else what is missing."""
        if self._js_sub.get_publisher_count() < 1:
            return f"its {JOINT_STATES} reader has not matched the plant"
        lacking = [n for j, n in enumerate(self.joint_names) if j not in self._refs_seen]
        return f"no reference batch yet for {', '.join(lacking)}" if lacking else None

    def _on_joint_states(self, data: bytes) -> None:
        try:
            sec, nanosec, _, pos, vel, eff = joint_state_cdr.decode(data)
        except (ValueError, struct.error, UnicodeDecodeError):
            self.record.malformed += 1
            return
        k = self.clock.step_of_sec_nanosec(sec, nanosec)
        if k > self._last_step:
            self._last_step = k
            self.cpu.mark(k)
        if self.record.add_joint_states(k, pos, vel, eff):
            if k % 500 == 0:  # the step, and the worst |e| so far [rad] for the launcher's progress bar
                print(f"PROGRESS {k} {self.record.worst_abs_error(k):.6g}", flush=True)
            self._check_complete()

    def _on_reference(self, joint: int, data: bytes) -> None:
        """A reference batch, read from its CDR bytes (wire/trajectory_cdr.py: no rclpy message per point)."""
        try:
            sec, nanosec, _, points = trajectory_cdr.decode(data)
            positions = [pos[0] for pos, _, _ in points]
        except (ValueError, IndexError, struct.error, UnicodeDecodeError):
            self.record.malformed += 1
            return
        self._refs_seen.add(joint)
        self.record.add_reference(joint, self.clock.step_of_sec_nanosec(sec, nanosec),
                                  [self.clock.step_of_ns(t_ns) for _, _, t_ns in points], positions)
        self._check_complete()

    def _check_complete(self) -> None:
        if not self._announced and self.record.complete:
            self._announced = True
            print("COMPLETE", flush=True)

    def loop(self, executor, stop) -> None:
        spin_until(executor, stop, stop)
        self.inbox.drain()  # what came after the last timer

    def close(self) -> None:
        self.record.save(Path(self.out_file))
        print(self.cpu.line("wire_monitor"), flush=True)


def main(args=None) -> NoReturn:
    exit_process(run_node(WireMonitorNode, args, params=PARAMS))


if __name__ == "__main__":
    main()

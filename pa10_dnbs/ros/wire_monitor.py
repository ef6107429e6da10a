"""wire_monitor node: collects what travels on the wire, for metrics and reports.

Subscribes to /joint_states and the seven reference topics and, at exit,
writes what it received to ``out_file`` (npz): state k from /joint_states
stamped k, the torque applied over step k from the effort field of
/joint_states stamped k+1, x_d(k) from the reference batches. Prints
``PROGRESS k`` now and then and ``COMPLETE`` once every step has arrived.
The launcher runs it as its own process, so the launcher never joins DDS.
"""
from __future__ import annotations

import struct
import sys
from pathlib import Path

from rclpy.node import Node
from sensor_msgs.msg import JointState
from trajectory_msgs.msg import JointTrajectory

from .. import JOINT_NAMES
from ..wire.wire_record import WireRecord
from ..wire import joint_state_cdr
from .params import ParameterError, declare, load_node_config
from .runtime import announce_ready, run_node
from .wire import JOINT_STATES, StepClock, record_qos, reference_qos, reference_topic


class WireMonitorNode(Node):
    def __init__(self):
        super().__init__("wire_monitor")
        p = declare(self, {"config_file": "", "duration_s": 0.0, "out_file": ""})
        if not p["out_file"]:
            raise ParameterError("parameter out_file is required")
        cfg = load_node_config(p["config_file"])
        dt_s = cfg["simulation"]["dt_s"]
        duration = p["duration_s"] if p["duration_s"] > 0 else cfg["simulation"]["duration_s"]
        self.record = WireRecord(int(round(duration / dt_s)), dt_s, len(JOINT_NAMES))
        self.out_file = p["out_file"]
        self.clock = StepClock(dt_s)
        self._announced = False
        self.create_subscription(JointState, JOINT_STATES, self._on_joint_states, record_qos(), raw=True)
        for j, name in enumerate(JOINT_NAMES):
            self.create_subscription(JointTrajectory, reference_topic(name), lambda m, j=j: self._on_reference(j, m),
                                     reference_qos())
        announce_ready("wire_monitor")

    def _on_joint_states(self, data: bytes) -> None:
        try:
            sec, nanosec, _, pos, vel, eff = joint_state_cdr.decode(data)
        except (ValueError, struct.error, UnicodeDecodeError):
            self.record.malformed += 1
            return
        k = self.clock.step_of_sec_nanosec(sec, nanosec)
        if self.record.add_joint_states(k, pos, vel, eff):
            if k % 500 == 0:  # the step, and the worst |e| so far [rad] for the launcher's progress bar
                print(f"PROGRESS {k} {self.record.worst_abs_error(k):.6g}", flush=True)
            self._check_complete()

    def _on_reference(self, joint: int, msg: JointTrajectory) -> None:
        self.record.add_reference(joint, self.clock.step_of(msg.header.stamp),
                                  [self.clock.steps_of(pt.time_from_start) for pt in msg.points],
                                  [pt.positions[0] for pt in msg.points])
        self._check_complete()

    def _check_complete(self) -> None:
        if not self._announced and self.record.complete:
            self._announced = True
            print("COMPLETE", flush=True)

    def close(self) -> None:
        self.record.save(Path(self.out_file))


def main(args=None) -> int:
    return run_node(WireMonitorNode, args)


if __name__ == "__main__":
    sys.exit(main())

"""wire_monitor node: collects what travels on the wire, for metrics and reports.

Subscribes to /joint_states and the seven reference topics and, at exit,
writes what it received to ``out_file`` (npz): state k from /joint_states
stamped k, the torque applied over step k from the effort field of
/joint_states stamped k+1, x_d(k) from the reference batches. Prints
``PROGRESS k`` now and then and ``COMPLETE`` once every step has arrived.
The launcher runs it as its own process, so the launcher never joins DDS.
"""
from __future__ import annotations

import os
import struct
import sys
from pathlib import Path

import numpy as np
from rclpy.node import Node
from sensor_msgs.msg import JointState
from trajectory_msgs.msg import JointTrajectory

from .. import JOINT_NAMES
from ..sim.run_data import RunData
from . import joint_state_cdr
from .params import declare, load_node_config
from .runtime import announce_ready, run_node
from .wire import JOINT_STATES, StepClock, record_qos, reference_qos, reference_topic


class WireMonitorNode(Node):
    def __init__(self):
        super().__init__("wire_monitor")
        p = declare(self, {"config_file": "", "duration_s": 0.0, "out_file": ""})
        if not p["out_file"]:
            raise ValueError("parameter out_file is required")
        cfg = load_node_config(p["config_file"])
        self.dt_s = cfg["simulation"]["dt_s"]
        duration = p["duration_s"] if p["duration_s"] > 0 else cfg["simulation"]["duration_s"]
        self.n = int(round(duration / self.dt_s))
        self.out_file = p["out_file"]
        self.clock = StepClock(self.dt_s)
        nj = len(JOINT_NAMES)
        self.pos, self.vel, self.eff, self.ref = (np.full((self.n + 1, nj), np.nan) for _ in range(4))
        self.got_state = np.zeros(self.n + 1, dtype=bool)   # NaN in the data is data, not a gap
        self.got_ref = np.zeros((self.n + 1, nj), dtype=bool)
        self.received = 0
        self.malformed = 0
        self._ref_missing = self.n
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
            self.malformed += 1
            return
        k = self.clock.step_of_sec_nanosec(sec, nanosec)
        if 0 <= k <= self.n and not self.got_state[k]:
            self.got_state[k] = True
            self.received += 1
            self.pos[k], self.vel[k], self.eff[k] = pos, vel, eff
            if k % 500 == 0:
                print(f"PROGRESS {k}", flush=True)
            self._check_complete()

    def _on_reference(self, joint: int, msg: JointTrajectory) -> None:
        k0 = self.clock.step_of(msg.header.stamp)
        for pt in msg.points:
            k = k0 + self.clock.steps_of(pt.time_from_start)
            if 0 <= k < self.n:
                self.ref[k, joint] = pt.positions[0]
                self.got_ref[k, joint] = True
        self._ref_missing = int((~self.got_ref[: self.n]).any(axis=1).sum())
        self._check_complete()

    def _check_complete(self) -> None:
        if not self._announced and self.received == self.n + 1 and self._ref_missing == 0:
            self._announced = True
            print("COMPLETE", flush=True)

    def close(self) -> None:
        tmp = f"{self.out_file}.tmp.npz"
        np.savez(tmp, dt_s=self.dt_s, position_rad=self.pos, velocity_rad_s=self.vel, effort_nm=self.eff,
                 reference_rad=self.ref, got_state=self.got_state, got_ref=self.got_ref, malformed=self.malformed)
        os.replace(tmp, self.out_file)


def load_wire_run(path: Path, controller: str, torque_limit_nm, wall_time_s: float) -> tuple[RunData, str | None]:
    """RunData from the monitor's file, and a description of what is missing (None when complete)."""
    with np.load(path) as z:
        pos, vel, eff, ref = z["position_rad"], z["velocity_rad_s"], z["effort_nm"], z["reference_rad"]
        got_state, got_ref = z["got_state"], z["got_ref"]
        dt = float(z["dt_s"])
    n = pos.shape[0] - 1
    states = int((~got_state).sum())
    refs = int((~got_ref[:n]).any(axis=1).sum())
    missing = None if states == 0 and refs == 0 else (
        f"{states} of {n + 1} joint states and {refs} of {n} reference steps missing")
    run = RunData(controller=controller, dt_s=dt, joint_names=JOINT_NAMES, torque_limit_nm=np.asarray(torque_limit_nm),
                  position_rad=pos[:n].copy(), velocity_rad_s=vel[:n].copy(), reference_rad=ref[:n].copy(),
                  torque_nm=eff[1:n + 1].copy(), wall_time_s=wall_time_s)
    return run, missing


def main(args=None) -> int:
    return run_node(WireMonitorNode, args)


if __name__ == "__main__":
    sys.exit(main())

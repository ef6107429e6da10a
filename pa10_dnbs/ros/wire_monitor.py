"""Collects what travels on the wire: /joint_states and the reference batches.

Runs inside the launcher process, spun by a background thread. From the
messages alone it rebuilds the run's time series (RunData): state k from
/joint_states stamped k, the torque applied over step k from the effort field
of /joint_states stamped k+1, x_d(k) from the reference batches.
"""
from __future__ import annotations

import threading

import numpy as np
import rclpy
from rclpy.context import Context
from rclpy.experimental import EventsExecutor
from rclpy.node import Node
from rclpy.task import Future
from sensor_msgs.msg import JointState
from trajectory_msgs.msg import JointTrajectory

from .. import JOINT_NAMES
from ..sim.run_data import RunData
from . import joint_state_cdr
from .wire import JOINT_STATES, StepClock, record_qos, reference_qos, reference_topic


class WireMonitor:
    """Subscribes on its own context and thread; ``stop()`` joins it."""

    def __init__(self, dt_s: float, n_steps: int, torque_limit_nm):
        self.clock = StepClock(dt_s)
        self.dt_s = dt_s
        self.n = n_steps
        self.limit = np.asarray(torque_limit_nm, float)
        nj = len(JOINT_NAMES)
        self.pos = np.full((n_steps + 1, nj), np.nan)
        self.vel = np.full((n_steps + 1, nj), np.nan)
        self.eff = np.full((n_steps + 1, nj), np.nan)
        self.ref = np.full((n_steps + 1, nj), np.nan)
        self.received = 0
        self.latest_step = -1
        self._context = Context()
        rclpy.init(context=self._context, signal_handler_options=rclpy.signals.SignalHandlerOptions.NO)
        self.node = Node("wire_monitor", namespace="/pa10", context=self._context)
        self.node.create_subscription(JointState, JOINT_STATES, self._on_joint_states, record_qos(), raw=True)
        for j, name in enumerate(JOINT_NAMES):
            self.node.create_subscription(JointTrajectory, reference_topic(name),
                                          lambda m, j=j: self._on_reference(j, m), reference_qos())
        self._executor = EventsExecutor(context=self._context)
        self._executor.add_node(self.node)
        self._stop = Future()
        self._thread = threading.Thread(target=self._spin, name="wire_monitor", daemon=True)
        self._thread.start()

    def _spin(self) -> None:
        while not self._stop.done():
            self._executor.spin_until_future_complete(self._stop, timeout_sec=0.2)

    def _on_joint_states(self, data: bytes) -> None:
        sec, nanosec, _, pos, vel, eff = joint_state_cdr.decode(data)
        k = self.clock.step_of_sec_nanosec(sec, nanosec)
        if 0 <= k <= self.n:
            if np.isnan(self.pos[k, 0]):
                self.received += 1
            self.pos[k], self.vel[k], self.eff[k] = pos, vel, eff
            self.latest_step = max(self.latest_step, k)

    def _on_reference(self, joint: int, msg: JointTrajectory) -> None:
        k0 = self.clock.step_of(msg.header.stamp)
        for pt in msg.points:
            k = k0 + self.clock.steps_of(pt.time_from_start)
            if 0 <= k <= self.n:
                self.ref[k, joint] = pt.positions[0]

    def complete(self) -> bool:
        """Every state 0..n and every reference 0..n-1 has arrived."""
        return self.received == self.n + 1 and not np.isnan(self.ref[: self.n]).any()

    def missing_summary(self) -> str:
        states = int(np.isnan(self.pos[:, 0]).sum())
        refs = int(np.isnan(self.ref[: self.n]).any(axis=1).sum())
        return f"{states} of {self.n + 1} joint states and {refs} of {self.n} reference steps missing"

    def run_data(self, controller: str, wall_time_s: float) -> RunData:
        n = self.n
        return RunData(controller=controller, dt_s=self.dt_s, joint_names=JOINT_NAMES,
                       torque_limit_nm=self.limit, position_rad=self.pos[:n].copy(),
                       velocity_rad_s=self.vel[:n].copy(), reference_rad=self.ref[:n].copy(),
                       torque_nm=self.eff[1: n + 1].copy(), wall_time_s=wall_time_s)

    def stop(self) -> None:
        """Stop spinning and release the node and its context (idempotent)."""
        if self._stop.done():
            return
        self._stop.set_result(None)
        self._thread.join(timeout=5)
        self._executor.remove_node(self.node)
        self._executor.shutdown()
        self.node.destroy_node()
        rclpy.try_shutdown(context=self._context)
        self._context.destroy()  # frees the DDS participant and its shared-memory segment now

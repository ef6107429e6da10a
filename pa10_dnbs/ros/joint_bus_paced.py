"""The joint bus's paced loop (``mode:=realtime``): the robot runs at its own rate, the bus follows it.

Each new robot state goes out at once on the per-joint topics (and joint_states, /clock when the bus keeps the
graph's time) as the graph's next step. Its command goes out as soon as every controller has answered it; a
state that comes before that is the deadline: the efforts still missing are held or zeroed (``on_missing_effort``)
and counted as misses of that tick (the effort gate's realtime accounting, so ``on_time_fraction`` says how often
every answer beat the robot's next state), and that command still goes out, late, before the new state is
forwarded. One wait set over the effort subscriptions (one per joint) and the robot's state subscription: the bus wakes
for whichever comes. No new state within ``robot_timeout_s``: a stale robot (``RobotFault``).
"""
from __future__ import annotations

import time

from .polled import SubscriptionWaitSet

SLICE_S = 0.05         # longest single wait: the stop request and the stale timeout are checked this often
HOUSEKEEPING_S = 0.05  # wall seconds between turns of the executor (timers, services)


def run_paced(node, executor, stop) -> None:
    """Run ``node`` (a JointBusNode) behind a paced robot until its last step or ``stop``."""
    robot, gate, endpoints = node.robot, node.gate, node.endpoints
    n = robot.n_joints
    waits = SubscriptionWaitSet(node, list(endpoints.effort_subscriptions) + [robot.subscription])
    clock = time.monotonic
    node.publish_state(0)
    sent = False  # the command answering the current state went out
    last_state = clock()
    next_housekeeping = last_state + HOUSEKEEPING_S
    try:
        while not node.finished and not stop.done():
            ready = waits.wait(SLICE_S)
            efforts = [j for j in ready if j < n]
            if efforts or not ready:
                node.take_efforts(efforts or None)
            if not sent and gate.ready:
                robot.send(gate.take_deadline())
                sent = True
            if robot.take_state():  # the robot's next state: the deadline of the current one
                if not sent:
                    robot.send(gate.take_deadline())
                node.step_to_robot_state()
                node.publish_state(gate.step)
                sent = False
                last_state = clock()
            elif clock() - last_state > robot.timeout_s:
                robot.stale(clock() - last_state)
            now = clock()
            if now >= next_housekeeping:
                executor.spin_once(timeout_sec=0.0)
                next_housekeeping = now + HOUSEKEEPING_S
    finally:
        waits.destroy()

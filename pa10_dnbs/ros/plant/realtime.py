"""The plant's realtime loop: deadline-synchronous ticks paced by the wall clock.

The first ``handshake_steps`` steps are a handshake: each waits (at most
``effort_timeout_s``) until every joint has answered, so the first, slow
messages on new DDS connections and the controllers' first steps do not
count as misses; the tick schedule starts after them.
Tick k (``loop/tick_schedule.py``): state k goes out at its start; the plant
blocks on the effort wait set until every joint has answered state k or the
deadline (``deadline_fraction`` of the tick) has passed, taking what is
there at each wake-up; at the deadline the missing efforts are held or
zeroed and counted as misses (``EffortGate.take_deadline``), and the physics
steps with exactly those torques. What only observers read of state k
(joint_states, and /clock every 10th state at 100 Hz, with up to nine
subscribers) goes out at the deadline, before the physics step: not in the
window in which the joint controllers need the CPU. Then the plant sleeps until the next
tick's start; a start later than ``late_tolerance`` of the tick is counted
and the schedule shifts (no catch-up). Misses and late starts are warned
about at most once per ``warn_period_s`` (``loop/miss_warnings.py``).
"""
from __future__ import annotations

import math
import time

from ...loop.miss_warnings import MissWarnings
from ...loop.tick_schedule import TickSchedule

SLICE_S = 0.2          # longest single wait: the stop request is checked at least this often
HOUSEKEEPING_S = 0.05  # wall seconds between turns of the executor (timers, services)


def run_realtime(node, executor, stop) -> None:
    """Run ``node`` (a PlantNode) in realtime until its last step or ``stop``."""
    p = node.p
    sched = node.schedule = TickSchedule(node.dt / p["real_time_factor"], p["deadline_fraction"], p["late_tolerance"])
    warnings = MissWarnings(node.plant.joint_names, p["warn_period_s"])
    clock = time.monotonic
    log = node.get_logger()
    next_housekeeping = clock() + HOUSEKEEPING_S
    # Handshake: the first ``handshake_steps`` steps wait until every joint has answered (the first messages
    # on new DDS connections and the controllers' first steps, which load numpy's linear algebra, take
    # milliseconds), each at most effort_timeout_s (a robot: start_timeout_s, resending, ``_await_handshake``);
    # the tick schedule starts after them. A joint still silent then misses that step like any other.
    for k in range(min(p["handshake_steps"], node.n_steps)):
        node.publish_state(k, observed=False)
        _await_handshake(node, k, stop, clock)
        if stop.done():
            return
        warnings.missed(k, node.gate.missing)
        node.step(node.gate.take_deadline())
        node.publish_observed()
    sched.begin(clock())
    node.publish_state(node.gate.step, observed=False)
    if node.finished:
        node.publish_observed()
        return
    try:
        _ticks(node, executor, stop, sched, warnings, clock, next_housekeeping)
    finally:
        text = warnings.poll(float("inf"))  # what happened since the last warning
        if text:
            log.warning(text)


def _await_handshake(node, k: int, stop, clock) -> None:
    """Wait for every joint's answer to handshake state ``k``. A robot on the standard interface sends the state
    again every ``resend_s`` while its command is missing, and waits at most ``start_timeout_s`` (its
    ``effort_timeout_s`` is infinite): a state that went out before the joint bus's best-effort reader had
    matched the robot's writer is lost, and without a resend the robot and the bus would wait for each other.
    The per-joint plant waits ``effort_timeout_s`` and sends nothing again: a lost answer there is a miss of
    its joint, as on any tick."""
    p = node.p
    robot = p["interface"] == "standard"
    t_end = clock() + (p["start_timeout_s"] if robot else p["effort_timeout_s"])
    next_resend = clock() + p["resend_s"] if robot else math.inf
    ready = None
    while not node.take_efforts(ready) and not stop.done() and clock() < t_end:
        if clock() >= next_resend:
            node.resend_state(k)
            next_resend = clock() + p["resend_s"]
        ready = node.endpoints.wait(max(0.0, min(SLICE_S, t_end - clock(), next_resend - clock())))


def _ticks(node, executor, stop, sched, warnings, clock, next_housekeeping) -> None:
    gate, endpoints, log = node.gate, node.endpoints, node.get_logger()
    while not stop.done():
        # collect the answers to the state of this tick until all are in or the deadline passes
        ready = None  # first look at every joint (stale answers may be queued)
        while not node.take_efforts(ready):
            left = sched.deadline - clock()
            if left <= 0 or stop.done():
                node.take_efforts()  # a last look at the deadline
                break
            ready = endpoints.wait(min(left, SLICE_S))
        if stop.done():
            return
        k = gate.step
        warnings.missed(k, gate.missing)
        torques = gate.take_deadline()
        node.publish_observed()  # state k's joint_states and /clock, now that the window is over
        node.step(torques)
        # idle until the next tick (the last state goes out on schedule too): housekeeping, then sleep
        now = clock()
        if now >= next_housekeeping and not node.finished:
            text = warnings.poll(now)
            if text:
                log.warning(text)
            executor.spin_once(timeout_sec=0.0)
            next_housekeeping = now + HOUSEKEEPING_S
        left = sched.next_start - clock()
        if left > 0:
            time.sleep(left)
        if sched.begin(clock()):
            warnings.late_start(k + 1)
        node.publish_state(k + 1, observed=False)
        if node.finished:
            node.publish_observed()
            return

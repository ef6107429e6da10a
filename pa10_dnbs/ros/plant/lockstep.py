"""The plant's lockstep loop: step as soon as every joint has answered, resend and time out otherwise.

One wait set over the effort subscriptions (one per joint): the plant sleeps until
some effort is queued (or a resend / timeout is due), takes every effort
that is there, steps as many times as complete steps allow (a player
re-driving the plant from a bag sends efforts ahead) and publishes each new
state. When to resend and when to give up: ``loop/lockstep_policy.py``.
Between batches, at most every ``HOUSEKEEPING_S``, the executor serves the
node's timers (diagnostics) and services.
"""
from __future__ import annotations

import time

from ...loop.lockstep_policy import LockstepPolicy

SLICE_S = 0.2          # longest single wait: the stop request is checked at least this often
HOUSEKEEPING_S = 0.05  # wall seconds between turns of the executor (timers, services)


def run_lockstep(node, executor, stop) -> None:
    """Run ``node`` (a PlantNode) in lockstep until its last step or ``stop``."""
    policy = LockstepPolicy(node.p["resend_s"], node.p["effort_timeout_s"])
    clock = time.monotonic
    gate = node.gate

    def publish(k: int) -> None:
        node.publish_state(k)
        policy.published(k, clock())

    publish(0)
    next_housekeeping = clock() + HOUSEKEEPING_S
    while not node.finished and not stop.done():
        if not gate.ready:
            ready = node.endpoints.wait(min(SLICE_S, policy.next_check_s(clock()),
                                            max(0.0, next_housekeeping - clock())))
            if ready:
                node.take_efforts(ready)
        while gate.ready and not node.finished:  # efforts sent ahead may complete later steps too
            node.step(gate.take_lockstep())
            publish(gate.step)
            if gate.ready:  # stepping on efforts sent ahead: keep taking, so the queues never overflow
                ready = node.endpoints.wait(0.0)
                if ready:
                    node.take_efforts(ready)
        if node.finished:
            break
        now = clock()
        action = policy.action(now)
        if action == "timeout":
            missing = gate.missing
            node.get_logger().warning(
                f"step {gate.step}: no effort from {', '.join(node.plant.joint_names[j] for j in missing)} after "
                f"{node.p['effort_timeout_s']:g} s; applying {node.p['on_missing_effort']}")
            node.step(gate.take_lockstep(timed_out=True))
            publish(gate.step)
        elif action == "resend":
            node.resend_state(gate.step)
        if now >= next_housekeeping:
            executor.spin_once(timeout_sec=0.0)
            next_housekeeping = now + HOUSEKEEPING_S

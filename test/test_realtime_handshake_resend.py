"""A robot's realtime handshake sends a state again while its command is missing (``plant/realtime.py``).

A state that goes out before the joint bus's best-effort reader has matched the robot's writer is lost; once
lost, robot and bus waited for each other. Here the first copy of each state is lost on purpose: a robot's
handshake must still complete, within about one ``resend_s``; the per-joint plant sends nothing again (a lost
answer is a miss of its joint there, as test_graph_faults counts)."""
from __future__ import annotations

import math
import time
from concurrent.futures import Future

import pytest

pytest.importorskip("rclpy")  # the plant package imports rclpy

from pa10_dnbs.ros.plant.node import PlantNode  # noqa: E402
from pa10_dnbs.ros.plant.realtime import _await_handshake  # noqa: E402


class _Gate:
    def __init__(self, n: int):
        self.n = n
        self.answered: set[int] = set()

    @property
    def missing(self) -> list[int]:
        return [j for j in range(self.n) if j not in self.answered]


class _Endpoints:
    def wait(self, timeout_s: float) -> list[int]:
        time.sleep(min(timeout_s, 0.01))
        return []


class _LossyLink:
    """A plant whose readers lose the first copy of each state and answer every later one at once."""

    def __init__(self, n: int, interface: str, effort_timeout_s: float):
        self.p = {"interface": interface, "effort_timeout_s": effort_timeout_s, "start_timeout_s": 5.0,
                  "resend_s": 0.05}
        self.gate = _Gate(n)
        self.endpoints = _Endpoints()
        self.resends = [0] * n
        self.resent_steps: list[list[int]] = [[] for _ in range(n)]
        self.sent: list[tuple[int, tuple[int, ...] | None]] = []

    def publish_state(self, k: int, joints=None, observed: bool = True) -> None:
        copies = sum(1 for step, _ in self.sent if step == k)
        self.sent.append((k, None if joints is None else tuple(joints)))
        if copies >= 1:  # the first copy was lost; this one arrives and is answered
            self.gate.answered.update(range(self.gate.n) if joints is None else joints)

    def take_efforts(self, joints=None) -> bool:
        return not self.gate.missing

    resend_state = PlantNode.resend_state  # the plant's own: counts, then publish_state to the missing joints


def test_a_robot_sends_a_lost_handshake_state_again_and_is_answered():
    node = _LossyLink(3, "standard", math.inf)  # a robot's effort_timeout_s (plant/node.py)
    t0 = time.monotonic()
    node.publish_state(0, observed=False)  # as run_realtime does before waiting
    _await_handshake(node, 0, Future(), time.monotonic)
    waited = time.monotonic() - t0
    assert node.gate.missing == [], node.sent
    assert node.sent[1] == (0, (0, 1, 2)), node.sent  # the state again, to the joints still missing
    assert node.resends == [1, 1, 1] and node.resent_steps == [[0], [0], [0]]
    assert waited < 0.5, waited  # one resend_s (0.05 s), not the start timeout


def test_a_robot_that_never_answers_ends_the_wait_at_start_timeout():
    node = _LossyLink(2, "standard", math.inf)
    node.p["start_timeout_s"] = 0.3
    node.publish_state = lambda k, joints=None, observed=True: None  # nothing ever arrives
    t0 = time.monotonic()
    _await_handshake(node, 0, Future(), time.monotonic)
    assert 0.25 < time.monotonic() - t0 < 2.0
    assert node.gate.missing == [0, 1]


def test_the_per_joint_plant_sends_nothing_again_and_waits_its_effort_timeout():
    node = _LossyLink(3, "", 0.3)  # the per-joint topics
    t0 = time.monotonic()
    node.publish_state(0, observed=False)
    _await_handshake(node, 0, Future(), time.monotonic)
    assert 0.25 < time.monotonic() - t0 < 2.0
    assert node.sent == [(0, None)] and node.resends == [0, 0, 0]
    assert node.gate.missing == [0, 1, 2]  # each a miss of its joint

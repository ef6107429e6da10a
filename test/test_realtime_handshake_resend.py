"""The plant's realtime handshake sends a state again while an answer is missing (``plant/realtime.py``).

A state that goes out before its reader has matched the writer is lost on a best-effort reader (the joint
bus's, realtime controllers'); once lost, the plant and the reader wait for each other. Here the first copy of
each state is lost on purpose: the handshake must still complete, within about one ``resend_s``."""
from __future__ import annotations

import math
import time
from concurrent.futures import Future

import pytest

pytest.importorskip("rclpy")  # the plant package imports rclpy

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

    def __init__(self, n: int, effort_timeout_s: float):
        self.p = {"effort_timeout_s": effort_timeout_s, "start_timeout_s": 5.0, "resend_s": 0.05}
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


@pytest.mark.parametrize("effort_timeout_s", [1.0, math.inf])  # the per-joint plant's default; a robot's
def test_a_lost_handshake_state_is_sent_again_and_answered(effort_timeout_s):
    node = _LossyLink(3, effort_timeout_s)
    stop = Future()
    t0 = time.monotonic()
    node.publish_state(0, observed=False)  # as run_realtime does before waiting
    _await_handshake(node, 0, stop, time.monotonic)
    waited = time.monotonic() - t0
    assert node.gate.missing == [], node.sent
    assert node.sent[1] == (0, (0, 1, 2)), node.sent  # the state again, to the joints still missing
    assert node.resends == [1, 1, 1] and node.resent_steps == [[0], [0], [0]]
    assert waited < 0.5, waited  # one resend_s (0.05 s), not the effort or start timeout


def test_a_robot_that_never_answers_ends_the_wait_at_start_timeout():
    """An infinite effort timeout (a robot waits for its command) is bounded by start_timeout_s here."""
    node = _LossyLink(2, math.inf)
    node.p["start_timeout_s"] = 0.3
    node.publish_state = lambda k, joints=None, observed=True: None  # nothing ever arrives
    t0 = time.monotonic()
    _await_handshake(node, 0, Future(), time.monotonic)
    assert 0.25 < time.monotonic() - t0 < 2.0
    assert node.gate.missing == [0, 1]

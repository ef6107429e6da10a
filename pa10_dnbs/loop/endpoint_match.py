"""Waiting until endpoints have matched: the one helper the plant (its whole graph), a controller (its
effort subscribers) and the player (a subscriber per topic) use. No ROS: counts come from callables.
"""
from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Callable


@dataclass(frozen=True)
class Need:
    """``want`` endpoints of kind ``kind`` ('subscribers', 'publishers') on ``topic``; ``count()`` says how many
    have matched so far; ``who`` names the endpoints expected (nodes, and the parameter that set ``want``)."""

    topic: str
    kind: str
    want: int
    count: Callable[[], int]
    who: str = ""

    def missing(self) -> str | None:
        """'<topic> (n of want <kind>[: who])' while fewer than ``want`` have matched, else None."""
        have = self.count()
        if have >= self.want:
            return None
        return f"{self.topic} ({have} of {self.want} {self.kind}{': ' + self.who if self.who else ''})"


class MatchWait:
    """Polled until every need is met (``poll`` -> 'met') or ``timeout_s`` [s] of ``now()`` passed ('timeout')."""

    def __init__(self, needs: list[Need], timeout_s: float, now: Callable[[], float] = time.monotonic):
        self.needs = list(needs)
        self._now = now
        self.started = now()
        self.deadline = self.started + timeout_s
        self.lacking: list[str] = []

    def poll(self) -> str:
        """'met', 'waiting' or 'timeout'; ``lacking`` holds what is still missing."""
        self.lacking = [m for n in self.needs if (m := n.missing()) is not None]
        if not self.lacking:
            return "met"
        return "timeout" if self._now() >= self.deadline else "waiting"

    @property
    def waited_s(self) -> float:
        return self._now() - self.started

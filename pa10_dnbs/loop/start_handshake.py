"""The start handshake without ROS: what a node says on the ``ready`` topic, and the plant's board of answers.

Every node the plant waits for publishes its status on ``ready`` (latched:
reliable, transient-local, the last message per node): ``<name> waiting:
<what>`` while it is not ready for the first steps, then ``<name> ready``.
Each node decides from what it has itself matched and received (its readers'
side of every match, and the data the first steps need); the plant adds its
writers' side (``endpoint_match``) and publishes step 0 once every expected
node said ready, or gives up after one timeout naming those that did not.
"""
from __future__ import annotations

import time
from typing import Callable

READY = "ready"
WAITING = "waiting: "


def status_text(name: str, waiting_for: str | None) -> str:
    """The message a node publishes: '<name> ready', or '<name> waiting: <what>'."""
    return f"{name} ready" if waiting_for is None else f"{name} {WAITING}{waiting_for}"


def parse_status(text: str) -> tuple[str, str | None] | None:
    """(name, None) for a ready node, (name, what it waits for) otherwise; None for anything else."""
    name, sep, rest = text.partition(" ")
    if not name or not sep:
        return None
    if rest == READY:
        return name, None
    if rest.startswith(WAITING):
        return name, rest[len(WAITING):] or "?"
    return None


class ReadyBoard:
    """The plant's view of the handshake: which of the ``expected`` nodes said ready, and what the others wait
    for (the latest status of each)."""

    def __init__(self, expected: list[str]):
        self.expected = [n for n in expected if n]
        self.status: dict[str, str | None] = {}  # name -> None (ready) or what it waits for
        self.first_ready: dict[str, float] = {}

    def offer(self, text: str, now: float | None = None) -> None:
        """A message from the ``ready`` topic (unknown names and malformed texts are ignored)."""
        parsed = parse_status(text)
        if parsed is None or parsed[0] not in self.expected:
            return
        name, waiting = parsed
        if waiting is None or self.status.get(name, "") is not None:  # a node once ready stays ready
            self.status[name] = waiting
        if waiting is None:
            self.first_ready.setdefault(name, time.monotonic() if now is None else now)

    @property
    def complete(self) -> bool:
        return all(n in self.status and self.status[n] is None for n in self.expected)

    @property
    def lacking(self) -> list[str]:
        """'<name> (never reported)' or '<name> (waiting: <what>)' for every node not ready yet."""
        out = []
        for n in self.expected:
            if n not in self.status:
                out.append(f"{n} (no status on the ready topic)")
            elif self.status[n] is not None:
                out.append(f"{n} ({WAITING}{self.status[n]})")
        return out


class ReadyAnnouncer:
    """A node's side: ``poll()`` asks ``check()`` (None when ready, else what it still waits for) and hands the
    status to ``publish(text)`` whenever it changes, at most every ``min_period_s`` while waiting; once ready it
    publishes that and stops asking."""

    def __init__(self, name: str, check: Callable[[], str | None], publish: Callable[[str], None],
                 min_period_s: float = 0.5, now: Callable[[], float] = time.monotonic):
        self.name, self._check, self._publish, self._min_period_s, self._now = name, check, publish, min_period_s, now
        self.ready = False
        self.started = now()
        self.ready_after_s: float | None = None
        self._last_text: str | None = None
        self._last_sent = -float("inf")

    def poll(self) -> bool:
        """Check once; True once ready (then the caller can stop polling)."""
        if self.ready:
            return True
        waiting = self._check()
        text = status_text(self.name, waiting)
        now = self._now()
        if waiting is None:
            self.ready = True
            self.ready_after_s = now - self.started
            self._publish(text)
            return True
        if text != self._last_text and now - self._last_sent >= self._min_period_s:
            self._last_text, self._last_sent = text, now
            self._publish(text)
        return False

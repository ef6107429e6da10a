"""One direction of one joint's link with its injected faults: drop, delay, corrupt.

The sender asks ``fate()`` first (to know whether to put a corrupted value
in the message it builds), then hands the payload to ``send(payload, fate)``.
"""
from __future__ import annotations

from typing import Callable

from .delay_line import DelayLine
from .link_faults import Fate, FaultInjector, LinkFaults


class FaultyLink:
    def __init__(self, faults: LinkFaults, seed, publish: Callable[[bytes], None], limit: float):
        """``limit``: the value's range (joint limit [rad] or torque limit [N m]) for out_of_range corruption."""
        self.injector = FaultInjector(faults, seed)
        self._publish = publish
        self.limit = limit
        self._line = DelayLine(publish) if faults.delay_s > 0 or faults.jitter_s > 0 else None

    def fate(self) -> Fate:
        return self.injector.next_fate()

    def corrupt_value(self) -> float:
        return self.injector.corrupt_value(self.limit)

    def send(self, payload: bytes, fate: Fate) -> None:
        if fate.drop:
            return
        if fate.delay_s > 0.0 and self._line is not None:
            self._line.send(payload, fate.delay_s)
        else:
            self._publish(payload)

    def counters(self) -> dict[str, int]:
        c = self.injector.counters()
        c["lost_in_flight_at_exit"] = self._line.lost_at_close if self._line is not None else 0
        return c

    def close(self) -> None:
        if self._line is not None:
            self._line.close()


def faulty_link(faults, direction: str, joint: int, publish, limit: float) -> FaultyLink | None:
    """The link of joint ``joint`` for ``direction`` 'state' or 'effort', or None when it has no faults
    (``faults``: a run's fault settings, ``settings.faults``)."""
    link = LinkFaults.of(getattr(faults, direction), joint)
    if not link.active:
        return None
    seed = (faults.seed, joint, 0 if direction == "state" else 1)
    return FaultyLink(link, seed, publish, limit)

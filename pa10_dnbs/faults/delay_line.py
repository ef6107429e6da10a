"""Deliver payloads after a delay, from a background thread (a late wire).

``send(payload, delay_s)`` returns at once; ``deliver(payload)`` runs on the
line's thread when the delay has passed (rclpy's publish is thread-safe).
Payloads with different delays may overtake each other, as on a real link.
``close()`` stops the thread; what is still in flight is counted as lost.
"""
from __future__ import annotations

import heapq
import itertools
import threading
import time
from typing import Callable


class DelayLine:
    def __init__(self, deliver: Callable[[object], None]):
        self._deliver = deliver
        self._heap: list[tuple[float, int, object]] = []
        self._order = itertools.count()
        self._cv = threading.Condition()
        self._closed = False
        self.delivered = 0
        self.lost_at_close = 0
        self._thread = threading.Thread(target=self._run, name="delay-line", daemon=True)
        self._thread.start()

    def send(self, payload, delay_s: float) -> None:
        with self._cv:
            heapq.heappush(self._heap, (time.monotonic() + delay_s, next(self._order), payload))
            self._cv.notify()

    def _run(self) -> None:
        while True:
            with self._cv:
                while not self._closed and (not self._heap or self._heap[0][0] > time.monotonic()):
                    self._cv.wait(None if not self._heap else max(0.0, self._heap[0][0] - time.monotonic()))
                if self._closed:
                    return
                _, _, payload = heapq.heappop(self._heap)
            self._deliver(payload)
            self.delivered += 1

    def close(self) -> None:
        with self._cv:
            self._closed = True
            self.lost_at_close = len(self._heap)
            self._heap.clear()
            self._cv.notify()
        self._thread.join(timeout=1.0)

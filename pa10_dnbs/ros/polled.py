"""Subscriptions the executor does not serve: the node takes their messages itself, in batches.

rclpy's executors wake the process once per message (the EventsExecutor
posts an event per DDS sample; the wait-set executors rebuild a wait set
and take one message per ready subscription per wait). At 1 kHz per topic
that wake-up is most of a message's cost. A ``PolledSubscription`` is an
rcl subscription made through ``rclpy.impl.implementation_singleton``
(``_rclpy.Subscription``, what ``Node.create_subscription`` makes inside)
but not registered on the node, so no executor knows it; its messages wait
in the DDS reader's history (the QoS depth) until the node takes them:

- ``Inbox``: drain every subscription on one node timer (observers, the
  reference node: one wake-up per period, however many messages came);
- ``SubscriptionWaitSet``: one rcl wait set over fixed subscriptions, for a
  loop that blocks until any of them has data, then takes all that is there
  (the plant waiting for its efforts, one per joint).

Topic names are expanded and remapped by rcl, as for ordinary subscriptions.
``destroy()`` releases them (``runtime.run_node`` does it for ``node.polled``).
"""
from __future__ import annotations

from typing import Callable

from rclpy.impl.implementation_singleton import rclpy_implementation as _rclpy
from rclpy.qos import QoSProfile
from rclpy.type_support import check_is_valid_msg_type

from .wall_timer import wall_timer


class PolledSubscription:
    """A subscription outside the executor; ``take()`` returns (message or CDR bytes, received [ns]) or None."""

    def __init__(self, node, msg_type, topic: str, qos: QoSProfile, raw: bool = True):
        check_is_valid_msg_type(msg_type)  # loads the type support
        with node.handle:
            self.handle = _rclpy.Subscription(node.handle, msg_type, topic, qos.get_c_qos_profile())
        self.msg_type, self.topic, self.raw, self.qos = msg_type, topic, raw, qos
        registry = getattr(node, "polled", None)
        if registry is None:
            registry = node.polled = []
        registry.append(self)

    def take(self):
        """The oldest queued message as (data, received_timestamp [ns, system clock]), or None."""
        got = self.handle.take_message(self.msg_type, self.raw)  # single-threaded use: no in-use guard needed
        return None if got is None else (got[0], got[1]["received_timestamp"])

    def get_publisher_count(self) -> int:
        with self.handle:
            return self.handle.get_publisher_count()

    def destroy(self) -> None:
        self.handle.destroy_when_not_in_use()


class Inbox:
    """Polled subscriptions drained together every ``period_s`` of wall time by one node timer."""

    def __init__(self, node, period_s: float):
        if not period_s > 0:
            raise ValueError(f"period_s must be > 0, got {period_s}")
        self._node = node
        self._routes: list[tuple[PolledSubscription, Callable]] = []
        self.received = 0
        self.timer = wall_timer(node, period_s, self.drain)

    def subscribe(self, msg_type, topic: str, qos: QoSProfile, callback: Callable, raw: bool = True
                  ) -> PolledSubscription:
        """``callback(data)`` is called for each message at the next drain, in arrival order per topic."""
        sub = PolledSubscription(self._node, msg_type, topic, qos, raw)
        self._routes.append((sub, callback))
        return sub

    def drain(self) -> int:
        """Take and handle every queued message now; returns how many."""
        n = 0
        for sub, callback in self._routes:
            while (got := sub.take()) is not None:
                callback(got[0])
                n += 1
        self.received += n
        return n


class SubscriptionWaitSet:
    """One persistent rcl wait set over fixed polled subscriptions."""

    def __init__(self, node, subs: list[PolledSubscription]):
        self.subs = list(subs)
        self._index = {s.handle.pointer: i for i, s in enumerate(self.subs)}
        self._context = node.context
        with self._context.handle:
            self._ws = _rclpy.WaitSet(len(self.subs), 0, 0, 0, 0, 0, self._context.handle)

    def wait(self, timeout_s: float) -> list[int]:
        """Block until some subscription has a message or ``timeout_s`` [s] passed (0: just look); the indices
        (into ``subs``) of those that have one."""
        ws = self._ws
        ws.clear_entities()
        for s in self.subs:
            ws.add_subscription(s.handle)
        ws.wait(max(0, int(timeout_s * 1e9)))
        ready = ws.get_ready_entities("subscription")
        return [self._index[p] for p in ready] if ready else []

    def destroy(self) -> None:
        self._ws.destroy_when_not_in_use()

"""The Foxglove WebSocket server of the live view (PyPI ``foxglove-sdk``), no ROS.

Advertises the live view's channels, sends each logged message to the
clients subscribed to its channel, and broadcasts the simulated time (the
``time`` capability, so Foxglove's clock follows the run, as foxglove_bridge
does with use_sim_time). The SDK serves clients from its own threads, with a
bounded queue per client whose oldest messages are dropped when a client does
not keep up: ``log`` never blocks, so a client that connects, disconnects or
stalls does not slow the process that logs. Latched channels (the URDF and
/tf_static) are sent again whenever a client subscribes to them.

Subprotocol: the SDK speaks the Foxglove WebSocket protocol v1 under the name
``foxglove.sdk.v1`` (the protocol of ``foxglove.websocket.v1``, renamed); a
client must offer that name in its handshake (Foxglove's app does).
"""
from __future__ import annotations

import threading

from .options import host_port
from .schemas import ChannelSpec

SUBPROTOCOL = "foxglove.sdk.v1"
LEGACY_SUBPROTOCOL = "foxglove.websocket.v1"  # offer both when connecting: older servers know only this one


class LiveServerError(RuntimeError):
    """The server could not start (port taken, bad host)."""


class LiveServer:
    def __init__(self, channels: list[ChannelSpec], host: str = "127.0.0.1", port: int = 8765,
                 name: str = "pa10_dnbs", backlog: int = 256):
        """``port`` 0 takes a free port (see ``self.port``); ``backlog``: messages queued per client at most."""
        import foxglove
        from foxglove.websocket import Capability

        self._ctx = foxglove.Context()
        self._channels = {}
        self._latched: dict[str, tuple[bytes, int] | None] = {}
        for c in channels:
            schema = foxglove.Schema(name=c.schema_name, encoding=c.schema_encoding, data=c.schema)
            self._channels[c.topic] = foxglove.Channel(c.topic, schema=schema, message_encoding=c.message_encoding,
                                                       context=self._ctx)
            if c.latched:
                self._latched[c.topic] = None
        self._lock = threading.Lock()
        self._resend: set[str] = set()
        self.subscriptions = 0  # subscribe requests seen (all clients, all channels)
        try:
            self._server = foxglove.start_server(name=name, host=host, port=port, capabilities=[Capability.Time],
                                                 server_listener=_Listener(self), context=self._ctx,
                                                 message_backlog_size=backlog)
        except Exception as exc:  # the SDK raises its own error types for bind failures
            raise LiveServerError(f"cannot serve the live view on {host_port(host, port)}: {exc}") from None
        self.host = host
        self.port = self._server.port

    @property
    def url(self) -> str:
        return f"ws://{host_port(self.host, self.port)}"

    def _on_subscribe(self, topic: str) -> None:  # called on the SDK's thread
        with self._lock:
            self.subscriptions += 1
            if topic in self._latched:
                self._resend.add(topic)

    def wanted(self, topic: str) -> bool:
        """True while a client is subscribed to ``topic`` (work for it can be skipped otherwise)."""
        return self._channels[topic].has_sinks()

    def log(self, topic: str, payload: bytes, log_time_ns: int) -> None:
        """Send ``payload`` (CDR or JSON bytes) on ``topic``, stamped ``log_time_ns``; never blocks."""
        if topic in self._latched:
            self._latched[topic] = (payload, log_time_ns)
        self._channels[topic].log(payload, log_time=log_time_ns)

    def resend_latched(self) -> None:
        """Send the latched messages again to channels that got a new subscriber since the last call."""
        with self._lock:
            topics, self._resend = self._resend, set()
        for topic in topics:
            held = self._latched.get(topic)
            if held is not None:
                self._channels[topic].log(held[0], log_time=held[1])

    def broadcast_time(self, time_ns: int) -> None:
        self._server.broadcast_time(int(time_ns))

    def clear_session(self) -> None:
        """Tell clients to drop what they have (a replay that starts over)."""
        self._server.clear_session()

    def stop(self) -> None:
        self._server.stop()
        for ch in self._channels.values():
            ch.close()


class _Listener:
    """foxglove ServerListener: only subscriptions matter here."""

    def __init__(self, server: LiveServer):
        self._server = server

    def on_subscribe(self, client, channel) -> None:
        self._server._on_subscribe(channel.topic)

    def on_unsubscribe(self, client, channel) -> None:
        pass

"""A minimal Foxglove WebSocket protocol (v1) client for the tests, on the ``websockets`` package.

Connects offering ``foxglove.websocket.v1`` and its current name ``foxglove.sdk.v1`` (the pinned
foxglove-sdk server accepts only the latter), collects the advertised channels, subscribes to topics,
and keeps every message received: text ops as JSON, binary message data (op 0x01: subscription id,
log time, payload) and server time (op 0x02).
"""
from __future__ import annotations

import json
import struct
import time

from websockets.exceptions import ConnectionClosed
from websockets.sync.client import connect

SUBPROTOCOLS = ["foxglove.websocket.v1", "foxglove.sdk.v1"]
_MESSAGE_DATA = struct.Struct("<BIQ")   # op, subscription id, log time [ns]
_TIME = struct.Struct("<BQ")             # op, time [ns]


class FoxgloveClient:
    def __init__(self, url: str, open_timeout: float = 20.0):
        self.ws = connect(url, subprotocols=SUBPROTOCOLS, proxy=None, open_timeout=open_timeout,
                          max_size=None, close_timeout=1.0, legacy=True)
        self.server_info: dict | None = None
        self.channels: dict[str, dict] = {}          # topic -> advertised channel
        self.messages: dict[str, list[tuple[int, bytes]]] = {}  # topic -> [(log time [ns], payload)]
        self.times: list[int] = []                    # server time broadcasts [ns]
        self._subs: dict[int, str] = {}              # subscription id -> topic
        self._next_sub = 1
        self.closed = False                           # the server closed the connection

    @property
    def subprotocol(self) -> str | None:
        return self.ws.subprotocol

    def _handle(self, frame) -> None:
        if isinstance(frame, str):
            msg = json.loads(frame)
            if msg.get("op") == "serverInfo":
                self.server_info = msg
            elif msg.get("op") == "advertise":
                for ch in msg["channels"]:
                    self.channels[ch["topic"]] = ch
            return
        if frame[0] == 0x01:
            _, sub, log_time = _MESSAGE_DATA.unpack_from(frame, 0)
            topic = self._subs.get(sub)
            if topic is not None:
                self.messages.setdefault(topic, []).append((log_time, bytes(frame[_MESSAGE_DATA.size:])))
        elif frame[0] == 0x02:
            self.times.append(_TIME.unpack_from(frame, 0)[1])

    def pump(self, seconds: float, until=None) -> bool:
        """Receive for up to ``seconds``; stop early once ``until()`` is true or the server closes the connection.
        Returns ``until()`` (or True)."""
        deadline = time.monotonic() + seconds
        while time.monotonic() < deadline and not self.closed:
            if until is not None and until():
                return True
            try:
                frame = self.ws.recv(timeout=min(0.2, max(0.0, deadline - time.monotonic())))
            except TimeoutError:
                continue
            except ConnectionClosed:
                self.closed = True
                break
            self._handle(frame)
        return until() if until is not None else True

    def wait_for_channels(self, topics, seconds: float = 30.0) -> bool:
        return self.pump(seconds, lambda: all(t in self.channels for t in topics))

    def subscribe(self, *topics: str) -> None:
        subs = []
        for t in topics:
            sid = self._next_sub
            self._next_sub += 1
            self._subs[sid] = t
            subs.append({"id": sid, "channelId": self.channels[t]["id"]})
        self.ws.send(json.dumps({"op": "subscribe", "subscriptions": subs}))

    def count(self, topic: str) -> int:
        return len(self.messages.get(topic, []))

    def close(self) -> None:
        self.ws.close()

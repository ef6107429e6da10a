#!/usr/bin/env python3
"""Probe a live view (``launch --live`` / ``replay --live``) like a Foxglove client would, from a terminal.

Connects (retrying until ``--wait`` seconds have passed), prints the advertised channels, subscribes to
all of them and counts what arrives until the server goes away or ``--seconds`` have passed; then prints
the count per channel and the last /pa10/tracking frame's worst |e|.

    python scripts/live_probe.py [ws://127.0.0.1:8765] [--seconds 600] [--wait 120]
"""
from __future__ import annotations

import argparse
import json
import struct
import sys
import time
from pathlib import Path
from urllib.parse import urlsplit

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
sys.path.insert(0, str(Path(__file__).resolve().parent))

import script_main  # noqa: E402  (first: a Ctrl-C while the modules load is one line)
from websockets.exceptions import ConnectionClosed
from websockets.sync.client import connect

from pa10_dnbs.cli_values import OneLineParser, number_in, seconds  # noqa: E402
from pa10_dnbs.interrupt import EXIT_INTERRUPTED  # noqa: E402
from pa10_dnbs.live.server import LEGACY_SUBPROTOCOL, SUBPROTOCOL  # noqa: E402

SUBPROTOCOLS = [LEGACY_SUBPROTOCOL, SUBPROTOCOL]
#: --wait's bound [s]: an hour of retries is a hang, not a wait (as replay --wait-for-subscribers)
WAIT_MAX_S = 3600.0


def ws_url(text: str) -> str:
    """The url argument's argparse type: ws://host[:port][/path] or wss://..."""
    try:
        parts = urlsplit(text)
        parts.port  # noqa: B018  (raises ValueError on a port that is not a number in 0..65535)
    except ValueError as exc:
        raise argparse.ArgumentTypeError(f"not a WebSocket URL ({exc}), got {text!r}") from None
    if parts.scheme not in ("ws", "wss") or not parts.hostname:
        raise argparse.ArgumentTypeError(f"expected a WebSocket URL like ws://127.0.0.1:8765, got {text!r}")
    return text


def _connect(url: str, wait_s: float):
    deadline = time.monotonic() + wait_s
    while True:
        try:
            return connect(url, subprotocols=SUBPROTOCOLS, proxy=None, max_size=None, close_timeout=1.0,
                           legacy=True)
        except OSError:
            if time.monotonic() > deadline:
                raise
            time.sleep(0.5)


def main() -> int:
    ap = OneLineParser(description=__doc__.splitlines()[0])
    ap.add_argument("url", nargs="?", type=ws_url, default="ws://127.0.0.1:8765")
    ap.add_argument("--seconds", type=seconds, default=600.0, help="stop after this long (default 600)")
    ap.add_argument("--wait", type=number_in(0.0, WAIT_MAX_S), default=120.0,
                    help=f"keep trying to connect this long, in (0, {WAIT_MAX_S:g}] s (default 120)")
    args = ap.parse_args()
    try:
        ws = _connect(args.url, args.wait)
    except OSError as exc:
        print(f"live_probe: cannot connect to {args.url}: {exc}", file=sys.stderr)
        return 1
    print(f"connected to {args.url}, subprotocol {ws.subprotocol}")
    channels, subs, counts, last = {}, {}, {}, {}
    interrupted = False
    deadline = time.monotonic() + args.seconds
    try:
        while time.monotonic() < deadline:
            try:
                frame = ws.recv(timeout=0.5)
            except TimeoutError:
                continue
            if isinstance(frame, str):
                msg = json.loads(frame)
                if msg.get("op") == "advertise":
                    new = []
                    for ch in msg["channels"]:
                        channels[ch["id"]] = ch
                        print(f"  channel {ch['topic']}: {ch['schemaName']} ({ch['schemaEncoding']}, {ch['encoding']})")
                        subs[len(subs) + 1] = ch["topic"]
                        new.append({"id": len(subs), "channelId": ch["id"]})
                    ws.send(json.dumps({"op": "subscribe", "subscriptions": new}))
            elif frame[0] == 1:
                topic = subs.get(struct.unpack_from("<I", frame, 1)[0])
                counts[topic] = counts.get(topic, 0) + 1
                last[topic] = bytes(frame[13:])
    except ConnectionClosed:
        print("the server closed the connection")
    except KeyboardInterrupt:   # the counts so far are the probe's answer
        print("live_probe: interrupted; the counts below are those so far", file=sys.stderr, flush=True)
        interrupted = True
    finally:
        ws.close()
    for topic in sorted(counts):
        print(f"  {topic}: {counts[topic]} messages")
    if "/pa10/tracking" in last:
        f = json.loads(last["/pa10/tracking"])
        print(f"last frame: step {f['step']}, worst |e| so far {f['worst_abs_error_rad']} rad")
    return EXIT_INTERRUPTED if interrupted else 0 if counts else 1


if __name__ == "__main__":
    sys.exit(script_main.run(main, "live_probe", interrupted="nothing counted"))

"""Checks of the live view's options before anything starts (no ROS): a clear ConfigError naming the flag."""
from __future__ import annotations

import math
import socket

from ..config import ConfigError


def check_live_options(host: str, port: int, display_hz: float = 50.0) -> None:
    """--live PORT in 0..65535 (0: a free one), --live-host an address of this machine, and the port free there."""
    if not 0 <= port <= 65535:
        raise ConfigError(f"--live: port must be in 0..65535 (0: any free port), got {port}")
    if not (math.isfinite(display_hz) and 0 < display_hz <= 1000):
        raise ConfigError(f"--live-hz: must be in (0, 1000] frames per second, got {display_hz}")
    try:
        infos = socket.getaddrinfo(host, port, type=socket.SOCK_STREAM)
    except socket.gaierror as exc:
        raise ConfigError(f"--live-host: cannot resolve {host!r}: {exc.strerror}") from None
    family, _, _, _, addr = infos[0]
    with socket.socket(family, socket.SOCK_STREAM) as s:
        s.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        try:
            s.bind(addr)
        except OSError as exc:
            what = "in use" if exc.errno == 98 else exc.strerror
            raise ConfigError(f"--live: cannot serve on {host}:{port} ({what})") from None

"""Checks of the live view's options before anything starts (no ROS): a clear ConfigError naming the setting
(live_port, live_host, live_hz; the command line names its flag)."""
from __future__ import annotations

import math
import socket

from ..config import ConfigError


def check_live_options(host: str, port: int, display_hz: float = 50.0) -> None:
    """``port`` in 0..65535 (0: a free one), ``host`` an address of this machine, and the port free there."""
    if not 0 <= port <= 65535:
        raise ConfigError(f"live_port: port must be in 0..65535 (0: any free port), got {port}", setting="live_port")
    if not (math.isfinite(display_hz) and 0 < display_hz <= 1000):
        raise ConfigError(f"live_hz: must be in (0, 1000] frames per second, got {display_hz}", setting="live_hz")
    try:
        infos = socket.getaddrinfo(host, port, type=socket.SOCK_STREAM)
    except socket.gaierror as exc:
        raise ConfigError(f"live_host: cannot resolve {host!r}: {exc.strerror}", setting="live_host") from None
    family, _, _, _, addr = infos[0]
    with socket.socket(family, socket.SOCK_STREAM) as s:
        s.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        try:
            s.bind(addr)
        except OSError as exc:
            what = "in use" if exc.errno == 98 else exc.strerror
            raise ConfigError(f"live_port: cannot serve on {host}:{port} ({what})", setting="live_port") from None

"""Checks of the live view's options before anything starts (no ROS): a clear ConfigError naming the setting
(live_port, live_host, live_hz; the command line names its flag)."""
from __future__ import annotations

import errno
import math
import socket

from ..config import ConfigError


def host_port(host: str, port: int) -> str:
    """``host:port`` as a URL writes it: an IPv6 address in brackets (``[::1]:8765``)."""
    return f"[{host}]:{port}" if ":" in host else f"{host}:{port}"


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
        except OSError as exc:   # the port taken or not ours to take: live_port; else the address: live_host
            if exc.errno in (errno.EADDRINUSE, errno.EACCES):
                what = "in use" if exc.errno == errno.EADDRINUSE else exc.strerror
                raise ConfigError(f"live_port: cannot serve on {host_port(host, port)} ({what})",
                                  setting="live_port") from None
            raise ConfigError(f"live_host: cannot serve on {host} ({exc.strerror}): not an address this machine "
                              "listens on" + (" (a link-local one needs its interface, e.g. fe80::1%eth0)"
                                              if host.lower().startswith("fe80:") and "%" not in host else ""),
                              setting="live_host") from None

"""The shell's RMW_IMPLEMENTATION, checked before any ROS process starts.

rcl refuses an implementation other than the one its wheels hold ("Expected RMW implementation identifier of
'rmw_cyclonedds_cpp' but instead found 'rmw_fastrtps_cpp', exiting with 102"): every node would start and exit
102. The installed ones are the ``ros-rmw-*-cpp`` distributions of this environment (the ROS 2 wheels ship
Fast DDS's alone).
"""
from __future__ import annotations

import importlib.metadata
import os
import re

from ..config_error import ConfigError

_RMW_DIST = re.compile(r"ros[-_]rmw[-_](?!.*shared)(.+)[-_]cpp$")   # ros-rmw-fastrtps-cpp, not its -shared-cpp


def installed_rmws() -> tuple[str, ...]:
    """The RMW implementations installed here, as RMW_IMPLEMENTATION names them (rmw_fastrtps_cpp, ...)."""
    names = set()
    for dist in importlib.metadata.distributions():
        m = _RMW_DIST.match((dist.metadata["Name"] or "").lower())
        if m and m.group(1) not in ("implementation", "dds-common", "dds_common"):
            names.add("rmw_" + m.group(1).replace("-", "_") + "_cpp")
    return tuple(sorted(names))


def check_rmw() -> None:
    """ConfigError (one line) when RMW_IMPLEMENTATION names an implementation this environment does not hold."""
    asked = os.environ.get("RMW_IMPLEMENTATION", "").strip()
    have = installed_rmws()
    if asked and have and asked not in have:
        raise ConfigError(f"RMW_IMPLEMENTATION: {asked!r} is not installed here (this environment's ROS 2 holds "
                          f"{', '.join(have)}): unset it or set one of those")

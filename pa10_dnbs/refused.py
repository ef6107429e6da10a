"""The error a command refuses its input with, in one line and exit 2 (``pa10-dnbs``'s contract, cli.main):
an output that exists or is in use, a bag that is missing or exists, a kernel that cannot be built.
Its own module, light, so that the CLI catches every such error without importing the modules that raise it.
(ConfigError, config_error.py, is the other: a bad setting, its message naming the key.)"""
from __future__ import annotations

from collections.abc import Mapping

from .config_error import said_as


class Refused(Exception):
    """Base of the errors a command ends on with their message as one line and exit code 2. The message names
    settings as a library does (`force`, config_error.SETTING_MARK)."""

    def named(self, names: Mapping[str, str]) -> str:
        """The message, each setting marked in it said as ``names`` says it (``{"force": "--force"}``)."""
        return said_as(str(self), names)

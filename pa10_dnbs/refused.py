"""The error a command refuses its input with, in one line and exit 2 (``pa10-dnbs``'s contract, cli.main):
an output that exists or is in use, a bag that is missing or exists, a kernel that cannot be built.
Its own module, light, so that the CLI catches every such error without importing the modules that raise it.
(ConfigError, config_error.py, is the other: a bad setting, its message naming the key.) A message names
settings as a library does (`force`): the CLI says them as flags (config_error.said_as)."""
from __future__ import annotations


class Refused(Exception):
    """Base of the errors a command ends on with their message as one line and exit code 2."""

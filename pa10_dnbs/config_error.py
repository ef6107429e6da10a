"""The one error type of bad input (config files, arm files, options): its message names the key, file or
setting."""
from __future__ import annotations


class ConfigError(ValueError):
    """A configuration value is missing, unknown, or invalid; the message names the key.

    ``setting``: the option the message opens with (``duration_s``, ``trajectory``, ``jobs``) where a library
    checks a command's option; whoever knows how the user gave it names it so (:meth:`named`: the command line
    by its flag, a node by its parameter)."""

    def __init__(self, message: str, setting: str | None = None):
        super().__init__(message)
        self.setting = setting

    def named(self, name: str | None) -> str:
        """The message, the setting it opens with called ``name`` (e.g. ``--duration``) when there is one."""
        text = str(self)
        if name and self.setting and text.startswith(self.setting):
            return name + text[len(self.setting):]
        return text

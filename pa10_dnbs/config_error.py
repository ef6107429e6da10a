"""The one error type of bad input (config files, arm files, options): its message names the key, file or
setting. A library message names a setting, never a flag: the setting's name in backquotes (`force`), which
whoever knows how the user gave it says their way (:func:`said_as`: the command line as ``--force``)."""
from __future__ import annotations

import re
import unicodedata
from collections.abc import Mapping

#: a setting named inside a message: its name in single backquotes (`config_path`), not in a reST ``literal``
SETTING_MARK = re.compile(r"(?<!`)`([a-z][a-z0-9_]*)`(?!`)")


def said_as(text: str, names: Mapping[str, str]) -> str:
    """``text`` with each setting marked in it (`force`) that ``names`` knows said as ``names`` says it
    (``{"force": "--force"}``); a setting ``names`` does not know keeps its mark."""
    return SETTING_MARK.sub(lambda m: names.get(m.group(1), m.group(0)), text)


class ConfigError(ValueError):
    """A configuration value is missing, unknown, or invalid; the message names the key.

    ``setting``: the option the message opens with (``duration_s``, ``trajectory``, ``jobs``) where a library
    checks a command's option; whoever knows how the user gave it names it so (:meth:`named`: the command line
    by its flag, a node by its parameter)."""

    def __init__(self, message: str, setting: str | None = None):
        super().__init__(message)
        self.setting = setting

    def named(self, names: Mapping[str, str]) -> str:
        """The message, each setting in it said as ``names`` says it (``{"duration_s": "--duration"}``): the one it
        opens with (``setting``) and those marked inside it (:func:`said_as`)."""
        text = str(self)
        name = names.get(self.setting) if self.setting else None
        if name and text.startswith(self.setting):
            text = name + text[len(self.setting):]
        return said_as(text, names)


SHORT_CHARS = 80   # a value shown in a message is cut to this many characters (the message stays one line)


def short(value) -> str:
    """``value``'s repr for a message, cut to SHORT_CHARS characters (a list of a million items stays readable)."""
    try:
        text = repr(value)
    except ValueError:   # an int past Python's 4300 digits inside it
        return "a value too long to show"
    return text if len(text) <= SHORT_CHARS else text[:SHORT_CHARS - 3] + "..."


def key_text(key) -> str:
    """A mapping's key as a message names it: a name as it is; a key that is not one (YAML reads ``1:`` as a
    number, ``~:`` as null, ``2024-01-01:`` as a date) as YAML writes it, said so: ``1 (a number, not a name)``."""
    if isinstance(key, str):
        return key
    if key is None:
        return "null (not a name)"
    if isinstance(key, bool):
        return f"{str(key).lower()} (a boolean, not a name)"
    if isinstance(key, (int, float)):
        return f"{short(key)} (a number, not a name)"
    kind = "a date" if hasattr(key, "isoformat") else f"a {type(key).__name__}"
    shown = key.isoformat() if hasattr(key, "isoformat") else short(key)
    return f"{shown} ({kind}, not a name)"


def first_unknown(keys, allowed) -> str | None:
    """The first of ``keys`` not in ``allowed`` (names in order, then keys that are not names), as :func:`key_text`
    names it; None when every key is allowed. Names and numbers are never compared (sorted() would raise)."""
    unknown = [k for k in keys if not (isinstance(k, str) and k in allowed)]
    if not unknown:
        return None
    names = sorted(k for k in unknown if isinstance(k, str))
    return key_text(names[0] if names else unknown[0])


def too_large(value: int) -> str:
    """What is wrong with a whole number past the largest float (~1.8e308), by its size: ``str()`` of one past
    Python's 4300 digits would raise."""
    bits = abs(value).bit_length()
    digits = len(str(abs(value))) if bits <= 14_000 else f"about {int(bits * 0.30103)}"
    return f"a whole number of {digits} digits is too large (at most ~1.8e308)"


def control_char(text: str) -> str | None:
    """The first control character of ``text`` (a newline, a tab, ...: it would split a line that prints it), or
    None."""
    return next((c for c in text if unicodedata.category(c) == "Cc"), None)

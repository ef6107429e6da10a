"""The command line's value checks, in one place: argparse ``type=`` validators and a parser whose errors are one line.

A validator turns the flag's text into a value or raises ``argparse.ArgumentTypeError``; argparse then prints
``prog: error: argument --flag: <why>`` and exits 2 before any work. The library checks the same settings again
(by their config key) for callers that do not come through the CLI.
"""
from __future__ import annotations

import argparse
import math
import re
import sys
from pathlib import Path

from .config_error import control_char

#: replay --clock's bound [Hz of wall time]: a /clock at most every millisecond (the plant's step on every preset),
#: a rate the player's publisher keeps; a faster one only delays the bag's messages
MAX_REPLAY_CLOCK_HZ = 1000.0
#: launch --rtf's range: a tick of dt / R [s of wall time] between 1000x faster and 1000x slower than real time
#: (far below, the plant's wall-clock schedule overflows the platform's time_t; docs/timing.md)
RTF_MIN, RTF_MAX = 1e-3, 100.0
#: launch --effort-timeout's bound [s of wall time]: an hour's wait for one effort is a hang, not a timeout
EFFORT_TIMEOUT_MAX_S = 3600.0
#: replay --rate's range: the bag played between 1000x slower (a millisecond of the bag per second, as launch
#: --rtf's lower end) and 1000x faster; 1e-300 was accepted and a message's wall-clock time overflowed to inf
REPLAY_RATE_MIN, REPLAY_RATE_MAX = 1e-3, 1000.0
#: replay --wait-for-subscribers' bound [s of wall time] (0: no wait): as --effort-timeout, an hour is a hang
WAIT_FOR_SUBSCRIBERS_MAX_S = 3600.0


def utf8_text(text: str) -> str:
    """A flag's text that names a file or an arm: valid UTF-8 (a name of bytes in another encoding would end the
    command with a traceback where its report names it, after the run)."""
    try:
        text.encode("utf-8")
    except UnicodeEncodeError:
        shown = text.encode("utf-8", "surrogateescape").decode("utf-8", "backslashreplace")
        raise argparse.ArgumentTypeError(f"'{shown}': the name is not valid UTF-8 (bytes of another encoding): "
                                         "rename it") from None
    return text


def path_arg(text: str) -> Path:
    """A path flag's value (:func:`utf8_text`): not empty (an unset shell variable: Path('') is the current
    folder), no control character (a newline would split every line that names the path)."""
    if not text:
        raise argparse.ArgumentTypeError("empty: a path is needed (an unset shell variable?)")
    if control := control_char(text):
        raise argparse.ArgumentTypeError(f"{text!r} holds a control character ({control!r}): rename it")
    return Path(utf8_text(text))


class OneLineParser(argparse.ArgumentParser):
    """An ArgumentParser whose errors are ONE line (``prog: error: ...; see prog --help``), exit 2."""

    def error(self, message: str):
        self.exit(2, f"{self.prog}: error: {message} (see {self.prog} --help)\n")


#: a number as the flags take it: ASCII digits, a dot, an exponent (float() also reads ``1_0`` as 10, ``١`` as 1 and
#: surrounding spaces); inf and nan spellings too, refused as not finite
_PLAIN_NUMBER = re.compile(r"[-+]?(?:(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][-+]?[0-9]+)?|inf|infinity|nan)", re.IGNORECASE)
_PLAIN_WHOLE = re.compile(r"[-+]?[0-9]+")


def _number(text: str) -> float:
    if not _PLAIN_NUMBER.fullmatch(text):
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}")
    v = float(text)
    if not math.isfinite(v):
        raise argparse.ArgumentTypeError(f"must be a finite number, got {text!r}")
    return v


def _integer(text: str) -> int:
    if not _PLAIN_WHOLE.fullmatch(text):
        raise argparse.ArgumentTypeError(f"expected a whole number, got {text!r}")
    try:
        return int(text)
    except ValueError:   # past Python's 4300 digits
        raise argparse.ArgumentTypeError(f"expected a whole number, got {len(text)} digits") from None


def plain_float(text: str) -> float:
    """A number spelled plainly (no ``1_0``, no digits of other scripts); its range, and whether it may be inf or
    nan, is checked where it is used."""
    if not _PLAIN_NUMBER.fullmatch(text):
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}")
    return float(text)


def plain_int(text: str) -> int:
    """A whole number spelled plainly; its range is checked where it is used."""
    return _integer(text)


def seconds(text: str) -> float:
    """A duration in seconds: finite and > 0 (the size of the run is checked against memory later)."""
    v = _number(text)
    if v <= 0:
        raise argparse.ArgumentTypeError(f"must be a positive number of seconds, got {text!r}")
    return v


def nonnegative(text: str) -> float:
    """A finite number >= 0 (an offset, a wait, a delay)."""
    v = _number(text)
    if v < 0:
        raise argparse.ArgumentTypeError(f"must be >= 0, got {text!r}")
    return v


def positive(text: str) -> float:
    """A finite number > 0 (a rate, a frequency)."""
    v = _number(text)
    if v <= 0:
        raise argparse.ArgumentTypeError(f"must be > 0, got {text!r}")
    return v


def number_in(low: float, high: float, low_open: bool = True):
    """A validator of a finite number in (low, high] (``low_open``) or [low, high]."""
    def check(text: str) -> float:
        v = _number(text)
        if v > high or v < low or (low_open and v == low):
            raise argparse.ArgumentTypeError(f"must be in {'(' if low_open else '['}{low:g}, {high:g}], got {text!r}")
        return v
    check.__name__ = "number"
    return check


def whole_in(low: int, high: int | None = None):
    """A validator of a whole number in [low, high] (``high`` None: no upper bound)."""
    def check(text: str) -> int:
        v = _integer(text)
        if v < low or (high is not None and v > high):
            raise argparse.ArgumentTypeError(
                f"must be >= {low}, got {text!r}" if high is None else f"must be in {low}..{high}, got {text!r}")
        return v
    check.__name__ = "whole number"
    return check


def say(prog: str, line: str) -> None:
    """A one-line warning on stderr, as ``prog: warning: line``."""
    print(f"{prog}: warning: {line}", file=sys.stderr, flush=True)

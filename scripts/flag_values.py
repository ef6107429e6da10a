"""The developer scripts' comma-separated flag values, checked as argparse ``type=`` validators.

Built on pa10_dnbs/cli_values.py (one number's checks): a bad item makes argparse print one line naming the
flag and exit 2, before any work.

    ap.add_argument("--kernels", type=names_in(KERNELS), default="numpy,auto")
    ap.add_argument("--cutoffs", type=list_of(positive), default="200,50")
"""
from __future__ import annotations

import argparse
import os
from collections.abc import Callable, Sequence
from pathlib import Path


def names_in(choices: Sequence[str]):
    """A validator of a comma-separated list of at least one of ``choices`` -> list[str] (empty items dropped)."""
    def check(text: str) -> list[str]:
        names = [n.strip() for n in text.split(",") if n.strip()]
        if not names:
            raise argparse.ArgumentTypeError(f"expected one or more of {', '.join(choices)}, got {text!r}")
        for n in names:
            if n not in choices:
                raise argparse.ArgumentTypeError(f"{n!r} is not one of {', '.join(choices)}")
        return names
    check.__name__ = "list"
    return check


def list_of(item: Callable[[str], object], allow_empty: bool = False):
    """A validator of a comma-separated list whose items each pass ``item`` (a cli_values validator) -> list.

    ``allow_empty``: '' (or only commas) is the empty list; otherwise it is refused."""
    def check(text: str) -> list:
        parts = [p.strip() for p in text.split(",") if p.strip()]
        if not parts and not allow_empty:
            raise argparse.ArgumentTypeError(f"expected one or more comma-separated values, got {text!r}")
        return [item(p) for p in parts]  # each item's error names its text
    check.__name__ = "list"
    return check


def arm_settings(ap: argparse.ArgumentParser, arm: str):
    """The default config's settings on ``arm`` (a preset's name, an arm file or a URDF), the rules' table not
    printed; a missing or bad arm is ``ap``'s one-line error naming --arm (exit 2)."""
    from pa10_dnbs.config import ConfigError, default_config_path
    from pa10_dnbs.run_settings import build_settings

    try:
        return build_settings(default_config_path(), arm, report=False)
    except ConfigError as exc:  # ArmError included
        ap.error(f"argument --arm: {exc}")


def folder(text: str) -> Path:
    """A folder to keep output in: an existing directory, or a path to make one at (not an existing file)."""
    path = Path(text)
    if path.exists() and not path.is_dir():
        raise argparse.ArgumentTypeError(f"{text!r} is a file, not a directory")
    return path


def file_to_write(text: str) -> Path:
    """A file to write, its missing folders made when it is written. Refused (before any work): a directory, an
    existing file that is not a regular one (a device, a pipe: the atomic write would replace it), a path through a
    file, a place this process cannot write."""
    path = Path(text)
    if not text or text.endswith("/") or path.is_dir():
        raise argparse.ArgumentTypeError(f"{text!r} is a directory, not a file to write")
    if path.exists() and not path.is_file():
        raise argparse.ArgumentTypeError(f"{text!r} is not a regular file (a device, pipe or socket): not replaced")
    present = next((p for p in path.parents if os.path.lexists(p)), Path("/"))  # the folder the missing ones go in
    if not present.is_dir():
        raise argparse.ArgumentTypeError(f"{text!r}: {str(present)!r} is a file, not a folder")
    if not os.access(present, os.W_OK | os.X_OK) or (path.exists() and not os.access(path, os.W_OK)):
        raise argparse.ArgumentTypeError(f"{text!r}: not writable")
    return path

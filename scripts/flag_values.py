"""The developer scripts' comma-separated flag values, checked as argparse ``type=`` validators.

Built on pa10_dnbs/cli_values.py (one number's checks): a bad item makes argparse print one line naming the
flag and exit 2, before any work.

    ap.add_argument("--kernels", type=names_in(KERNELS), default="numpy,auto")
    ap.add_argument("--cutoffs", type=list_of(positive), default="200,50")
"""
from __future__ import annotations

import argparse
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


def folder(text: str) -> Path:
    """A folder to keep output in: an existing directory, or a path to make one at (not an existing file)."""
    path = Path(text)
    if path.exists() and not path.is_dir():
        raise argparse.ArgumentTypeError(f"{text!r} is a file, not a directory")
    return path

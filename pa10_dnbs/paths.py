"""Locate the package's data files (config/, urdf/) in a source tree or an install."""
from __future__ import annotations

import sys
from pathlib import Path

_SOURCE_ROOT = Path(__file__).resolve().parent.parent


def share_path(*parts: str) -> Path:
    """Path of a data file: the source tree first, then ``<prefix>/share/pa10_dnbs``."""
    candidate = _SOURCE_ROOT.joinpath(*parts)
    if candidate.exists():
        return candidate
    return Path(sys.prefix, "share", "pa10_dnbs", *parts)

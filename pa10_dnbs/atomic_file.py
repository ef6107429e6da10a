"""Files written atomically: to a temporary sibling first, then renamed over the target, so a process killed
mid-write leaves the previous file (or none), never half a file. The one writer for stats JSON files,
controller checkpoints and the wire monitor's record.
"""
from __future__ import annotations

import os
from contextlib import contextmanager
from pathlib import Path

from .json_text import json_text


@contextmanager
def atomic_path(path, suffix: str = ".tmp"):
    """Yields the temporary path to write; on success it replaces ``path``, on error it is removed.
    ``suffix`` ends the temporary name (np.savez needs '.npz')."""
    path = Path(path)
    tmp = path.with_name(path.name + suffix)
    try:
        yield tmp
        os.replace(tmp, path)
    finally:
        if tmp.exists():
            tmp.unlink()


def write_json(path, obj, indent: int = 2) -> None:
    """``obj`` as strict JSON (non-finite floats: null) into ``path``, atomically."""
    with atomic_path(path) as tmp:
        tmp.write_text(json_text(obj, indent))

"""Files written atomically: to a temporary sibling first, then renamed over the target, so a process killed
mid-write leaves the previous file (or none), never half a file. The one writer for stats JSON files,
controller checkpoints and the wire monitor's record. Also the mode a folder made by ``tempfile.mkdtemp`` (for
an output renamed into place) takes instead of mkdtemp's 0700: :func:`mkdir_mode`.
"""
from __future__ import annotations

import os
import stat
from contextlib import contextmanager
from pathlib import Path

from .json_text import json_text


def umask() -> int:
    """The process's file-mode creation mask (Linux: /proc/self/status, read without changing it; else set and
    restored at once)."""
    try:
        for line in Path("/proc/self/status").read_text().splitlines():
            if line.startswith("Umask:"):
                return int(line.split()[1], 8)
    except (OSError, ValueError, IndexError):
        pass
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def mkdir_mode(path) -> None:
    """Give a folder made private by ``tempfile.mkdtemp`` (0700) the mode ``mkdir`` gives: 0777 less the umask,
    so an output renamed into place is readable as any other folder the user makes; the setgid bit a folder
    inherits from a shared group's parent is kept."""
    os.chmod(path, (os.stat(path).st_mode & stat.S_ISGID) | (0o777 & ~umask()))


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

"""What a path the user gives names: a regular file, a folder, or why neither (missing, refused by the OS, a pipe or
a device). One check for every input file's path (config files, arm files, URDFs), so each says the same in one line.
"""
from __future__ import annotations

import errno
import os
import stat
from pathlib import Path

SHOWN_PATH_CHARS = 200     # a longer path is shown shortened in a message (its head and tail, and its length)
NOT_REGULAR = "not a regular file (a pipe or a device): give the path of a file"


class PathProblem(ValueError):
    """A path names no readable file or folder; ``str()`` says why, naming the path; ``missing``: nothing is there
    (``path``: the absolute path looked for); ``special``: a pipe or a device is there (NOT_REGULAR)."""

    def __init__(self, text: str, path: Path | None = None, missing: bool = False, special: bool = False):
        super().__init__(text)
        self.path, self.missing, self.special = path, missing, special


def shown(path) -> str:
    """``path`` for a message: as it is, or its head and tail and its length when longer than SHOWN_PATH_CHARS."""
    text = str(path)
    if len(text) <= SHOWN_PATH_CHARS:
        return text
    return f"{text[:120]}...{text[-60:]} ({len(text)} characters)"


def absolute(path: Path) -> Path:
    """``path`` resolved (its links followed) where it can be, else made absolute as it is."""
    try:
        return path.resolve()
    except (RuntimeError, OSError):   # a loop of symbolic links (RuntimeError before Python 3.13)
        return Path(os.path.abspath(path))


def file_or_folder(path) -> tuple[Path, bool]:
    """(``path`` resolved, whether it is a folder), when it is a regular file or a folder; else PathProblem: file
    not found, the OS's reason (a name too long, a loop of symbolic links, no permission, a NUL byte), or not a
    regular file (a pipe such as bash's ``<(...)``, a device: nothing to read twice or hand to the simulator)."""
    path = Path(path)
    try:
        mode = os.stat(path).st_mode   # the kernel follows the links, /dev/fd/N too
    except (FileNotFoundError, NotADirectoryError):
        where = absolute(path)
        raise PathProblem(f"file not found: {shown(where)}", where, missing=True) from None
    except ValueError:
        raise PathProblem(f"{shown(path)!r}: a path cannot hold a NUL byte") from None
    except OSError as exc:   # ENAMETOOLONG, ELOOP, EACCES
        why = "a loop of symbolic links" if exc.errno == errno.ELOOP else (exc.strerror or str(exc))
        raise PathProblem(f"{shown(absolute(path))}: {why}") from None
    if not (stat.S_ISREG(mode) or stat.S_ISDIR(mode)):
        raise PathProblem(f"{shown(path)}: {NOT_REGULAR}", special=True)
    return absolute(path), stat.S_ISDIR(mode)

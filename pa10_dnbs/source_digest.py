"""What names this pa10_dnbs's code exactly: a digest of its source files, for the cluster's workers to match.

``__version__`` stays 0.1.0 while the code changes, so a worker running an edited copy passed the version check
and its runs gave other numbers (study/cluster.py compares this digest too).
"""
from __future__ import annotations

import functools
import hashlib
import importlib
from pathlib import Path

SOURCE_SUFFIXES = (".py", ".c")   # the package's code: its modules and the compiled kernel's source


@functools.cache
def source_digest() -> str:
    """SHA-256 (hex) of every SOURCE_SUFFIXES file of the package, by path relative to it and content, in path
    order (about 10 ms, once per process)."""
    # the package as imported, not this file's folder: an edited copy without this module (a worker's) can import
    # it from another install, whose own files are not what that worker runs
    root = Path(importlib.import_module(__package__).__file__).resolve().parent
    h = hashlib.sha256()
    for path in sorted(p for p in root.rglob("*") if p.suffix in SOURCE_SUFFIXES and "__pycache__" not in p.parts
                       and p.is_file()):   # not an editor's dangling lock link (.#x.py)
        h.update(path.relative_to(root).as_posix().encode() + b"\0")
        h.update(path.read_bytes() + b"\0")
    return h.hexdigest()

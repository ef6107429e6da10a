"""Build (once) and locate the shared library of ``dnbs_kernel.c``.

The library goes to ``$PA10_DNBS_CACHE`` (default ``$XDG_CACHE_HOME/pa10_dnbs``, else
``~/.cache/pa10_dnbs``), named by a hash of the source and the compiler command, so an edited source
or other flags build anew (earlier builds stay, ~40 kB each: another checkout may still use one). It is
compiled to a temporary file and renamed into place: processes that start together (the joint
controllers) never load a half-written library.

    python -m pa10_dnbs.accel.build     # builds if needed, prints the library's path
"""
from __future__ import annotations

import contextlib
import hashlib
import os
import shutil
import subprocess
import sys
from pathlib import Path

from ..refused import Refused

SOURCE = Path(__file__).with_name("dnbs_kernel.c")
# -ffp-contract=off: no fused multiply-add (it would change result bits); no -ffast-math for the same reason
FLAGS = ("-O3", "-ffp-contract=off", "-fno-fast-math", "-fPIC", "-shared")


class KernelBuildError(RuntimeError, Refused):
    """The compiled kernel cannot be built or loaded here; the message says why and what to do.

    ``reason``: why, in a few words on one line (``dnbs.kernel: auto`` says it when it falls back to numpy).
    """

    def __init__(self, message: str, reason: str):
        super().__init__(message)
        self.reason = reason


def cache_dir() -> Path:
    """Where built libraries are kept."""
    if os.environ.get("PA10_DNBS_CACHE"):
        return Path(os.environ["PA10_DNBS_CACHE"])
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "pa10_dnbs"


def _compiler() -> str:
    cc = os.environ.get("CC", "cc")
    path = shutil.which(cc)
    if path is None:
        raise KernelBuildError(f"dnbs.kernel: c needs a C compiler, and {cc!r} is not on PATH (set CC, install gcc, "
                               f"or use dnbs.kernel: numpy)", reason=f"no C compiler: {cc!r} is not on PATH")
    return path


def library_target(cc: str | None = None) -> Path:
    """Where the library built by compiler ``cc`` (a path; default: $CC found on PATH) is cached, built or not."""
    cc = _compiler() if cc is None else cc
    key = hashlib.sha256(SOURCE.read_bytes() + "\0".join((cc, *FLAGS)).encode()).hexdigest()[:16]
    return cache_dir() / f"libdnbs_kernel-{key}.so"


def library_path(rebuild: bool = False) -> Path:
    """The path of the built library (building it first if it is not there; ``rebuild``: built anew and renamed
    over the cached one, for a cached file that does not load, e.g. truncated)."""
    cc = _compiler()
    target = library_target(cc)
    if target.is_file() and not rebuild:
        return target
    tmp = target.with_name(f".{target.name}.{os.getpid()}.tmp")
    try:
        target.parent.mkdir(parents=True, exist_ok=True)
        done = subprocess.run([cc, *FLAGS, "-o", str(tmp), str(SOURCE), "-lm"], capture_output=True, text=True,
                              timeout=120)
        if done.returncode != 0:
            first = next((line for line in done.stderr.splitlines() if "error" in line), f"exit {done.returncode}")
            raise KernelBuildError(f"dnbs.kernel: c: compiling {SOURCE.name} failed:\n{done.stderr.strip()}",
                                   reason=f"compiling {SOURCE.name} failed: {first.strip()}")
        os.replace(tmp, target)
    except (OSError, subprocess.TimeoutExpired) as exc:  # an unwritable cache, a compiler that hangs
        raise KernelBuildError(f"dnbs.kernel: c: cannot build {target}: {exc} (set PA10_DNBS_CACHE to a writable "
                               f"directory, or use dnbs.kernel: numpy)", reason=f"cannot build {target}: {exc}") from None
    finally:
        with contextlib.suppress(OSError):
            tmp.unlink(missing_ok=True)
    return target


if __name__ == "__main__":
    try:
        print(library_path())
    except KernelBuildError as exc:
        print(f"error: {exc}", file=sys.stderr)
        sys.exit(2)

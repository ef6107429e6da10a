"""``dnbs.kernel``: which DNBS step a run uses, ``auto`` resolved to ``c`` or ``numpy`` once per process.

``auto`` (the default) is the compiled step (``dnbs_kernel.c``) where it builds and loads here, else the
numpy reference, said in one line; both give the same result bits (test/test_compiled_dnbs.py), so the
choice changes only the speed. ``c`` fails (KernelBuildError, exit 2) where it cannot build; ``numpy``
never builds anything. Commands resolve ``auto`` once, before any controller exists: the launcher
writes the resolved kernel into the run's params file (ros_params.yaml), so every joint controller runs
what it chose and none of them builds.
"""
from __future__ import annotations

import functools
from dataclasses import dataclass
from typing import Callable

from ..settings import Settings, replace_in
from .build import KernelBuildError, library_path

KERNELS = ("auto", "numpy", "c")


@dataclass(frozen=True)
class KernelChoice:
    """What ``auto`` resolved to here: ``kernel`` 'c' or 'numpy', and ``line``, one line saying which and why."""

    kernel: str
    line: str


@functools.cache
def auto_kernel() -> KernelChoice:
    """``auto`` in this process: the compiled step if it builds (or is built) and loads, else numpy."""
    from .compiled_dnbs import _library  # builds on first use, then loads with ctypes

    try:
        _library()
    except KernelBuildError as exc:
        return KernelChoice("numpy", f"dnbs.kernel: auto -> numpy, the reference step ({exc.reason}; the compiled "
                                     f"step would give the same bits, faster)")
    return KernelChoice("c", f"dnbs.kernel: auto -> c, the compiled step ({library_path()}; the same bits as numpy)")


def resolve_kernel(settings: Settings, say: Callable[[str], None] | None = None) -> Settings:
    """``settings`` with ``dnbs.kernel`` as a run uses it: ``auto`` replaced by ``c`` or ``numpy`` (a copy; the
    one line passed to ``say``); ``c`` built here first (KernelBuildError if it cannot be); ``numpy`` as is."""
    kernel = settings.dnbs.kernel
    if kernel == "c":
        library_path()
    if kernel != "auto":
        return settings
    choice = auto_kernel()
    if say is not None:
        say(choice.line)
    return replace_in(settings, "dnbs.kernel", choice.kernel)

"""The numeric platform of this process: which BLAS kernels and which numpy SIMD loops its arithmetic runs on.

A run's last bits hold on one platform, not across machines. The plant's forward dynamics go through LAPACK and
BLAS (``np.linalg.solve``, ``inv``, ``@`` in plant/pybullet_plant.py), and OpenBLAS picks its kernels by CPU
when it loads: on one AMD EPYC its ``SkylakeX`` (AVX-512) kernels give the PA10 main job a worst RMS of
3.159710322586883e-05 rad, its ``Haswell`` kernels 3.159710322586797e-05 (``OPENBLAS_CORETYPE``, set before
numpy loads, picks them; ``Zen`` selects the same kernels and reports ``Haswell``). numpy's SIMD loops
(``NPY_DISABLE_CPU_FEATURES`` switches them off) move the closed loop's bits too. The DNBS step avoids BLAS
(core/ekf.py: fixed-order sums, no matmul): the banks' fingerprints (scripts/result_fingerprint.py) were the
same here with the Haswell kernels and with numpy's AVX-512 loops off, the closed loop's were not; its
``np.tanh`` still runs numpy's SIMD loops, so a CPU without AVX2 may give the banks other bits. Records
(scripts/bench_record.py) say the platform they were made on.
"""
from __future__ import annotations

import ctypes
import functools
from pathlib import Path

import numpy as np

#: The CPU flags (/proc/cpuinfo) an OpenBLAS core's kernels need, for the cores of x86-64 machines today.
CORE_FLAGS = {
    "Haswell": ("avx2", "fma"), "Zen": ("avx2", "fma"),
    "SkylakeX": ("avx512f", "avx512cd", "avx512bw", "avx512dq", "avx512vl"),
    "Cooperlake": ("avx512f", "avx512cd", "avx512bw", "avx512dq", "avx512vl", "avx512_bf16"),
    "SapphireRapids": ("avx512f", "avx512cd", "avx512bw", "avx512dq", "avx512vl", "avx512_bf16", "amx_tile"),
}
_CORENAME_SYMBOLS = ("scipy_openblas_get_corename64_", "scipy_openblas_get_corename", "openblas_get_corename64_",
                     "openblas_get_corename")
_CONFIG_SYMBOLS = ("scipy_openblas_get_config64_", "scipy_openblas_get_config", "openblas_get_config64_",
                   "openblas_get_config")


@functools.cache
def _openblas():
    """numpy's bundled OpenBLAS (a ctypes library: the one numpy loaded, not a second copy); None where numpy
    bundles none this can open (a pip wheel's numpy.libs holds it; conda and distro builds do not)."""
    for path in sorted((Path(np.__file__).resolve().parent.parent / "numpy.libs").glob("lib*openblas*.so*")):
        try:
            return ctypes.CDLL(str(path))
        except OSError:
            continue
    return None


def _openblas_text(symbols: tuple[str, ...]) -> str | None:
    """What the first of ``symbols`` that numpy's OpenBLAS exports returns (a C string); None without one."""
    lib = _openblas()
    for symbol in symbols if lib is not None else ():
        function = getattr(lib, symbol, None)
        if function is not None:
            function.restype = ctypes.c_char_p
            return function().decode().strip()
    return None


def blas_core() -> str | None:
    """The OpenBLAS core whose kernels numpy's BLAS runs here (``SkylakeX``, ``Haswell``, ...); None where
    numpy's BLAS is not an OpenBLAS this can ask."""
    return _openblas_text(_CORENAME_SYMBOLS)


def numpy_simd() -> list[str]:
    """The SIMD extensions numpy found on this CPU and dispatches its loops to (``X86_V3``, ``X86_V4``, ...)."""
    try:   # numpy's own np.show_runtime() reads the same two names
        from numpy._core._multiarray_umath import __cpu_dispatch__, __cpu_features__
    except ImportError:
        return []
    return [name for name in __cpu_dispatch__ if __cpu_features__.get(name)]


def numeric_platform() -> dict:
    """``{"blas_core": ..., "numpy_simd": [...], "numpy": version, "blas": OpenBLAS's build line}``: what a
    record's bits hold on."""
    return {"blas_core": blas_core(), "numpy_simd": numpy_simd(), "numpy": np.__version__,
            "blas": _openblas_text(_CONFIG_SYMBOLS)}


def platform_line(platform: dict) -> str:
    """``platform`` (:func:`numeric_platform`) in one line."""
    blas = " ".join((platform.get("blas") or "no OpenBLAS found").split()[:2])
    return (f"{blas}, {platform['blas_core'] or 'unknown'} kernels; numpy {platform['numpy']}, SIMD "
            f"{' '.join(platform['numpy_simd']) or 'baseline only'}")


def can_run_core(core: str, cpuinfo: str | None = None) -> bool:
    """Whether this CPU has the flags OpenBLAS's ``core`` kernels need (``cpuinfo``: /proc/cpuinfo's text, read
    when None); False for a core not in :data:`CORE_FLAGS` (older ones, Sandybridge say: not asked, not tried)."""
    if core not in CORE_FLAGS:
        return False
    if cpuinfo is None:
        try:
            cpuinfo = Path("/proc/cpuinfo").read_text()
        except OSError:
            return False
    flags = next((line.split(":", 1)[1].split() for line in cpuinfo.splitlines() if line.startswith("flags")), [])
    return all(flag in flags for flag in CORE_FLAGS[core])


def platform_env(recorded: dict, here: dict, cpuinfo: str | None = None) -> dict | None:
    """The environment variables that run numpy on this machine (``here``: its :func:`numeric_platform`) on the
    ``recorded`` platform: ``OPENBLAS_CORETYPE`` for its OpenBLAS core, ``NPY_DISABLE_CPU_FEATURES`` for numpy's
    SIMD loops past the recorded ones (numpy refuses it beside ``NPY_ENABLE_CPU_FEATURES``); None where this CPU
    cannot (it lacks a recorded core's or loop's instructions)."""
    env = {}
    if recorded["blas_core"] != here["blas_core"]:
        if not can_run_core(recorded["blas_core"], cpuinfo):
            return None
        env["OPENBLAS_CORETYPE"] = recorded["blas_core"]
    if not set(recorded["numpy_simd"]) <= set(here["numpy_simd"]):
        return None
    extra = [name for name in here["numpy_simd"] if name not in recorded["numpy_simd"]]
    if extra:
        env["NPY_DISABLE_CPU_FEATURES"] = " ".join(extra)
    return env

"""``CompiledDNBSControllers``: ``DNBSControllers`` whose answer and training run in ``dnbs_kernel.c``.

Everything but the step's arithmetic is the numpy reference's own code (construction, seeds, the EKF
guard's full check and reset, checkpoints): the kernel works in place on the bank's arrays (weights,
covariances, regressors), so ``state_dict`` and ``load_state_dict`` see what it computed. np.tanh
stays numpy's (applied between the kernel's three answer calls), so the results are bit for bit those
of ``DNBSControllers`` (test/test_compiled_dnbs.py).
"""
from __future__ import annotations

import ctypes
import sys
import weakref

import numpy as np

from ..core.dnbs_controller import DNBSControllers, DNBSParams
from ..core.reference import ReferenceSample
from .build import KernelBuildError, library_path

_P = ctypes.c_void_p
_LIB = None


class _Config(ctypes.Structure):
    """``dnbs_config`` of dnbs_kernel.c: the same fields in the same order."""

    _fields_ = ([(f, ctypes.c_long) for f in ("n", "W", "La", "Lt", "Da", "Dt", "oa", "ot")]
                + [(f, _P) for f in ("fa", "ft", "w", "P", "H", "hph", "alpha", "u_unsat", "ia", "it", "A", "U", "ka",
                                     "ku", "lim", "E", "d", "eta", "r", "q", "bounds")]
                + [(f, ctypes.c_double) for f in ("kv", "p_max", "ramp_steps", "sigma")]
                + [(f, ctypes.c_long) for f in ("eta_is_ones", "anti_windup", "dead_zone", "printed")])


def _first_line(exc: Exception, path) -> str:
    """The first line of ``exc``'s message without the library's path (dlerror starts with it)."""
    line = (str(exc).strip().splitlines() or [type(exc).__name__])[0]
    return line.removeprefix(f"{path}: ")


def _library() -> ctypes.CDLL:
    """The kernel's library, built on first use, loaded once per process."""
    global _LIB
    if _LIB is None:
        path = library_path()
        try:
            lib = ctypes.CDLL(str(path))
        except OSError as exc:  # a cached file that does not load (truncated, damaged): built anew once
            print(f"dnbs.kernel: the cached {path} did not load ({_first_line(exc, path)}); rebuilding it",
                  file=sys.stderr, flush=True)
            path = library_path(rebuild=True)
            try:
                lib = ctypes.CDLL(str(path))
            except OSError as again:
                why = f"cannot load {path.name} even after rebuilding it: {_first_line(again, path)}"
                raise KernelBuildError(f"dnbs.kernel: c: {why} (use dnbs.kernel: numpy)", reason=why) from None
        lib.dnbs_new.restype, lib.dnbs_new.argtypes = _P, [ctypes.POINTER(_Config)]
        lib.dnbs_free.restype, lib.dnbs_free.argtypes = None, [_P]
        for name in ("dnbs_tanh_in", "dnbs_tanh_alpha"):
            getattr(lib, name).restype, getattr(lib, name).argtypes = ctypes.POINTER(ctypes.c_double), [_P]
        lib.dnbs_answer_inputs.restype, lib.dnbs_answer_inputs.argtypes = None, [_P, _P, ctypes.c_int]
        lib.dnbs_answer_alpha.restype, lib.dnbs_answer_alpha.argtypes = None, [_P, _P]
        lib.dnbs_answer_torque.restype, lib.dnbs_answer_torque.argtypes = None, [_P, _P, _P]
        lib.dnbs_learn.restype, lib.dnbs_learn.argtypes = ctypes.c_int, [_P, ctypes.c_long]
        _LIB = lib
    return _LIB


class CompiledDNBSControllers(DNBSControllers):
    """The DNBS controllers of ``joints`` (see DNBSControllers), stepped by the compiled kernel."""

    def __init__(self, params: DNBSParams, seed: int, joints):
        super().__init__(params, seed, joints)
        lib = _library()
        n, width = self.n_joints, self.ekf.w.shape[1]
        # the arrays the kernel writes stay where they are (alpha and torque_unsaturated are such buffers,
        # see below); the reference's EKF replaces last_hph every step, here it is one buffer
        self.ekf.last_hph = np.zeros(2 * n)
        self._keep = []  # every array whose address the kernel holds, alive as long as this bank

        def addr(a, dtype=float, size=None):
            a = np.ascontiguousarray(a if size is None else np.broadcast_to(a, (size,)), dtype=dtype)
            self._keep.append(a)
            return a.ctypes.data

        ekf, a_honn, t_honn = self.ekf, self.alpha_honn, self.torque_honn
        for arr in (ekf.w, ekf.P, self._H, ekf.last_hph, self._alpha_out, self._u_unsat_out):
            assert arr.flags.c_contiguous and arr.dtype == np.float64
        cfg = _Config(
            n=n, W=width, La=a_honn.n_terms, Lt=t_honn.n_terms, Da=a_honn._factors.shape[1],
            Dt=t_honn._factors.shape[1], oa=self.alpha_ekf.cols.start, ot=self.torque_ekf.cols.start,
            fa=addr(a_honn._factors, np.int64), ft=addr(t_honn._factors, np.int64),
            w=addr(ekf.w), P=addr(ekf.P), H=addr(self._H), hph=addr(ekf.last_hph), alpha=addr(self._alpha_out),
            u_unsat=addr(self._u_unsat_out), ia=addr(a_honn._inv_scale), it=addr(t_honn._inv_scale),
            A=addr(self._A, size=n), U=addr(self._U, size=n), ka=addr(self._k_a), ku=addr(self._k_u),
            lim=addr(self._lim, size=n), E=addr(self._E), d=addr(self._d), eta=addr(ekf.eta), r=addr(ekf.r),
            q=addr(ekf.q), kv=float(self._k_v), p_max=ekf.p_max, ramp_steps=float(self._ramp_steps),
            sigma=float(self._sigma), bounds=None if self._bounds is None else addr(self._bounds),
            eta_is_ones=int(ekf._ones is not None),
            anti_windup=int(self._anti_windup), dead_zone=int(self._dead_zone), printed=int(self._printed))
        kernel = lib.dnbs_new(ctypes.byref(cfg))
        if not kernel:
            raise MemoryError("dnbs_new: out of memory")
        self._kernel = kernel
        weakref.finalize(self, lib.dnbs_free, kernel)
        self._tanh_in = np.ctypeslib.as_array(lib.dnbs_tanh_in(kernel), shape=(n, 4))
        self._tanh_alpha = np.ctypeslib.as_array(lib.dnbs_tanh_alpha(kernel), shape=(n,))
        self._in = np.zeros((6, n))  # rows x1, x2, x_d, x_d_dot, x_d(k+2), active
        self._in_addr = self._in.ctypes.data
        self._u = np.zeros(n)
        self._u_addr = self._u.ctypes.data
        self._calls = (lib.dnbs_answer_inputs, lib.dnbs_answer_alpha, lib.dnbs_answer_torque, lib.dnbs_learn)

    # The last virtual control alpha (n,) [rad/s] and unclipped torque (n,) [N m]: the buffers the kernel
    # writes, overwritten by the next answer (the reference replaces its arrays instead); copy to keep them.
    @property
    def alpha(self) -> np.ndarray:
        return self._alpha_out

    @alpha.setter
    def alpha(self, value) -> None:
        self._set_buffer("_alpha_out", value)

    @property
    def torque_unsaturated(self) -> np.ndarray:
        return self._u_unsat_out

    @torque_unsaturated.setter
    def torque_unsaturated(self, value) -> None:
        self._set_buffer("_u_unsat_out", value)

    def _set_buffer(self, name: str, value) -> None:
        """Write into the buffer ``name`` in place once it exists (the kernel holds its address)."""
        if name in self.__dict__:
            self.__dict__[name][...] = value
        else:
            self.__dict__[name] = np.array(value, dtype=float)

    def answer(self, x1: np.ndarray, x2: np.ndarray, ref: ReferenceSample, active: np.ndarray | None = None) -> np.ndarray:
        """As ``DNBSControllers.answer``: torques (n,) [N m], the training left pending for ``learn``."""
        if self._pending is not None:
            self.learn()
        inputs, alpha, torque, _ = self._calls
        b, k, b_addr = self._in, self._kernel, self._in_addr
        b[0] = x1
        b[1] = x2
        b[2] = ref.position_rad
        b[3] = ref.velocity_rad_s
        b[4] = ref.position_ahead_rad
        if active is not None:
            b[5] = active
        inputs(k, b_addr, active is not None)
        np.tanh(self._tanh_in, out=self._tanh_in)
        alpha(k, b_addr)
        np.tanh(self._tanh_alpha, out=self._tanh_alpha)
        torque(k, b_addr, self._u_addr)
        self._pending = True
        return self._u.copy()

    def learn(self) -> None:
        """As ``DNBSControllers.learn``: train on the last answer (a no-op when nothing is pending)."""
        if self._pending is None:
            return
        self._pending = None
        cheap_check_failed = self._calls[3](self._kernel, self.steps)
        self.steps += 1
        every = self.params.ekf_full_check_every
        full = every > 0 and self.steps % every == 0
        if full or cheap_check_failed:
            self._reset_unhealthy(full)

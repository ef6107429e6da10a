"""Extended Kalman filter training of scalar-output, weight-linear networks, one per row.

Eq. 7-9 / 13-16 of the paper with m = 1, for n independent networks (one
per joint) of L weights each; row i only ever reads row i:
    M = 1 / (R + H^T P H)
    K = P H M
    w <- w + eta K e
    P <- P - K H^T P + Q
P stays exactly symmetric: the correction is computed as v v^T with v = P H sqrt(M).
Every sum over weights is an elementwise product reduced along the last axis
(numpy's fixed-order pairwise sum), never einsum or matmul, whose summation
order depends on the operands' shape and memory alignment: so a row's bits do
not depend on how many rows the bank has.
A row whose ``active`` flag is 0 skips the step entirely (no correction, no Q):
conditional integration, for anti-windup. With ``p_max`` finite, Q is added
to a diagonal entry of P only while it is below p_max: without it, P grows by
q every step in every direction the regressors do not excite (covariance
windup), and a later excitation there meets a huge gain.

Guard: ``unhealthy()`` names the rows whose w or P are no longer finite (and,
when ``full``, whose P is not symmetric positive definite); ``reset(rows)``
returns them to their initial weights and P = p0 I.
"""
from __future__ import annotations

import math

import numpy as np


def _per_row(name: str, value, n: int, allow_zero: bool) -> np.ndarray:
    arr = np.broadcast_to(np.asarray(value, dtype=float), (n,)).copy()
    if not np.all(np.isfinite(arr)) or np.any(arr < 0) or (not allow_zero and np.any(arr == 0)):
        raise ValueError(f"EKF parameter {name} must be finite and positive{' or 0' if allow_zero else ''}, "
                         f"got {value}")
    return arr


def _not_positive_definite(P: np.ndarray, skip: np.ndarray) -> np.ndarray:
    """Bool (n,): which of the matrices P (n, L, L) are not finite, symmetric and positive definite; rows
    where ``skip`` is True are not looked at one by one (they are already condemned)."""
    bad = np.zeros(P.shape[0], dtype=bool)
    try:
        if np.isfinite(P).all() and np.array_equal(P, P.transpose(0, 2, 1)):
            np.linalg.cholesky(P)  # all rows at once; one that fails sends us row by row
            return bad
    except np.linalg.LinAlgError:
        pass
    for i in np.flatnonzero(~skip):
        Pi = P[i]
        if not (np.isfinite(Pi).all() and np.array_equal(Pi, Pi.T)):
            bad[i] = True
            continue
        try:
            np.linalg.cholesky(Pi)
        except np.linalg.LinAlgError:
            bad[i] = True
    return bad


class EKFBank:
    """Weights w (n, L) and covariances P (n, L, L) of n networks, trained one EKF step per call.

    p0: initial diagonal of P; q: diagonal of Q added every step; r: R; eta:
    learning rate in (0, 1] (eq. 7). Each is a number or one value per row, for
    the network's dimensionless output and training error.
    """

    def __init__(self, weights, p0, q, r, eta, p_max=np.inf):
        self.w0 = np.array(weights, dtype=float, ndmin=2)  # the safe state reset() returns to
        n, L = self.w0.shape
        self.p0 = _per_row("p0", p0, n, allow_zero=False)
        self.q = _per_row("q", q, n, allow_zero=True)
        self.r = _per_row("r", r, n, allow_zero=False)
        self.eta = _per_row("eta", eta, n, allow_zero=False)
        if np.any(self.eta > 1.0):
            raise ValueError(f"EKF parameter eta must be in (0, 1] (eq. 7), got {eta}")
        self.p_max = float(p_max)
        if not self.p_max > 0:
            raise ValueError(f"EKF parameter p_max must be positive, got {p_max}")
        self.w = self.w0.copy()
        self.P = self.p0[:, None, None] * np.eye(L)  # C-contiguous, always written in place
        self._diag = self.P.reshape(n, L * L)[:, :: L + 1]  # a view of the n diagonals, (n, L)
        self._q_col = self.q[:, None]
        self._ones = self.eta if np.all(self.eta == 1.0) else None  # eta = 1 everywhere: skip multiplying by it
        self._nLL = np.empty((n, L, L))  # scratch
        self._nL = np.empty((n, L))
        self._PH = np.empty((n, L))
        self.last_hph = np.zeros(n)

    def update(self, H: np.ndarray, error: np.ndarray, eta: np.ndarray, active: np.ndarray | None = None) -> np.ndarray:
        """One step per row with regressor H (n, L), training error (n,), learning rate eta (n,) and
        ``active`` (n,) 1.0 to train, 0.0 to skip (None: every row trains); returns the gain g = H^T K (n,).

        g in [0, 1) is the fraction of eta*e that the output at the same input moves by.
        """
        PH = np.add.reduce(np.multiply(self.P, H[:, None, :], out=self._nLL), axis=2, out=self._PH)
        hph = np.add.reduce(np.multiply(H, PH, out=self._nL), axis=1)
        m = 1.0 / (self.r + hph)
        sqrt_m = np.sqrt(m)
        v = PH * (sqrt_m if active is None else sqrt_m * active)[:, None]
        step = sqrt_m * error if eta is self._ones else eta * sqrt_m * error  # eta = 1: the same bits
        self.w += v * step[:, None]                       # eta K e, K = P H M
        self.P -= np.multiply(v[:, :, None], v[:, None, :], out=self._nLL)  # K H^T P = v v^T: exactly symmetric
        q = self._q_col if active is None else (self.q * active)[:, None]
        d = self._diag
        if self.p_max == np.inf:
            d += q
        else:
            np.add(d, q, out=d, where=d < self.p_max)
        self.last_hph = hph
        return hph * m

    def unhealthy(self, full: bool = True, blocks=None) -> np.ndarray:
        """Bool (n,): rows that must be reset. Cheap check (every step): w finite and the last H^T P H finite
        and >= 0 (NaN or Inf anywhere in P that H reaches shows there). ``full``: also P finite, symmetric and
        positive definite (a Cholesky factorisation, ~L^3/3 flops per row), on the blocks ``blocks``: pairs
        (rows, cols) of slices, P[rows, cols, cols] each (None: every row's whole P). A padded bank checks
        each network's own block, as a bank of that network alone would: padding can tip a nearly singular
        P's factorisation either way."""
        hph = self.last_hph
        if math.isfinite(self.w.sum()) and math.isfinite(hph.sum()) and hph.min() >= 0.0:
            bad = np.zeros(hph.size, dtype=bool)  # every entry finite (so are the totals) and hph >= 0
        else:
            bad = ~(np.isfinite(hph) & (hph >= 0.0) & np.isfinite(self.w).all(axis=1))
        if full:
            for rows, cols in blocks if blocks is not None else ((slice(None), slice(None)),):
                bad[rows] |= _not_positive_definite(self.P[rows, cols, cols], bad[rows])
        return bad

    def reset(self, rows) -> None:
        """Rows ``rows`` (indices or a bool mask) back to their initial weights and P = p0 I, in place."""
        rows = np.flatnonzero(np.asarray(rows)) if np.asarray(rows).dtype == bool else np.asarray(rows)
        L = self.w.shape[1]
        for i in rows:
            self.w[i] = self.w0[i]
            self.P[i] = np.eye(L) * self.p0[i]
            self.last_hph[i] = 0.0


class EKFRows:
    """One network's part of a bank that holds several: rows ``rows`` and weight columns ``cols`` (slices).

    ``w`` (n, L), ``P`` (n, L, L) and ``w0`` are views into the bank (writes go to it). The bank's other
    columns of these rows are padding (see padded_layout).
    """

    def __init__(self, bank: EKFBank, rows: slice, cols: slice):
        self.bank, self.rows, self.cols = bank, rows, cols

    @property
    def w(self) -> np.ndarray:
        return self.bank.w[self.rows, self.cols]

    @property
    def P(self) -> np.ndarray:
        return self.bank.P[self.rows, self.cols, self.cols]

    @property
    def w0(self) -> np.ndarray:
        return self.bank.w0[self.rows, self.cols]

    def unhealthy(self, full: bool = True) -> np.ndarray:
        """Bool (n,) over these rows: ``EKFBank.unhealthy`` on this block (its cheap check still reads
        the whole bank)."""
        return self.bank.unhealthy(full, blocks=((self.rows, self.cols),))[self.rows]

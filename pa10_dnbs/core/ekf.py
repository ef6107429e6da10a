"""Extended Kalman filter training of a scalar-output, weight-linear network.

Eq. 7-9 / 13-16 of the paper with m = 1:
    M = 1 / (R + H^T P H)
    K = P H M
    w <- w + eta K e
    P <- P - K H^T P + Q
P stays exactly symmetric: the correction is computed as v v^T with v = P H sqrt(M).

Guard: ``healthy()`` says whether w is finite and P finite, symmetric and
positive definite (a Cholesky factorisation, when ``full``); ``reset()``
returns to the initial weights and P = p0 I.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class EKFParams:
    """EKF settings for one network.

    p0: initial diagonal of P [output-units^2 per unit-regressor^2];
    q: diagonal of Q added every step; r: R (scalar, error-units^2);
    eta: learning rate (dimensionless step scale).
    """

    p0: float
    q: float
    r: float
    eta: float

    def __post_init__(self):
        for name in ("p0", "q", "r", "eta"):
            v = getattr(self, name)
            if not np.isfinite(v) or v < 0 or (name in ("p0", "r", "eta") and v == 0):
                raise ValueError(f"EKF parameter {name} must be finite and positive (q may be 0), got {v}")


class EKFTrainer:
    """Holds w (L,) and P (L, L) and applies one EKF step per call."""

    def __init__(self, weights: np.ndarray, params: EKFParams):
        self.params = params
        self.w0 = np.array(weights, dtype=float)  # the safe state reset() returns to
        self.w = self.w0.copy()
        n = self.w.size
        self.P = np.eye(n) * params.p0
        self._P_diag = self.P.reshape(-1)[:: n + 1]  # a view: adds Q in place
        self._outer = np.empty((n, n))
        self._v = np.empty(n)           # P H sqrt(M)
        self._v_col = self._v[:, None]  # the same buffer as a column (a view, made once)
        self._eta, self._q, self._r = params.eta, params.q, params.r
        self._last_hph = 0.0

    def update(self, H: np.ndarray, error: float) -> float:
        """One step with regressor H (L,) and training error e; returns the gain g = H^T K.

        g in [0, 1) is the fraction of eta*e that the output at the same input moves by.
        """
        PH = self.P @ H
        hph = float(H @ PH)
        m = 1.0 / (self._r + hph)
        sqrt_m = math.sqrt(m)
        v = np.multiply(PH, sqrt_m, out=self._v)
        self.w += (self._eta * sqrt_m * error) * v          # eta K e, K = P H M
        self.P -= np.multiply(self._v_col, v, out=self._outer)  # K H^T P = v v^T: exactly symmetric
        self._P_diag += self._q
        self._last_hph = hph
        return hph * m

    def healthy(self, full: bool = True) -> bool:
        """Cheap (every step): w finite and the last H^T P H finite and >= 0 (NaN or Inf anywhere in P
        that H reaches shows there). ``full``: also every entry of P finite, P symmetric and positive
        definite (a Cholesky factorisation, ~L^3/3 flops)."""
        if not (math.isfinite(self._last_hph) and self._last_hph >= 0.0 and math.isfinite(float(self.w @ self.w))):
            return False
        if not full:
            return True
        if not (np.isfinite(self.P).all() and np.array_equal(self.P, self.P.T)):
            return False
        try:
            np.linalg.cholesky(self.P)
        except np.linalg.LinAlgError:
            return False
        return True

    def reset(self) -> None:
        """Back to the initial weights and P = p0 I (in place: the views on P stay valid)."""
        self.w[:] = self.w0
        self.P[:] = np.eye(self.w.size) * self.params.p0
        self._last_hph = 0.0

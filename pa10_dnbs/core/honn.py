"""High-order neural network of eq. 3-4 with a scalar output, for n joints at once.

phi(w, z) = w^T S(z),  S_i(z) = prod_j tanh(z_j / scale_j)^(d_ij),
for a configurable set of exponent rows d_i (a row of zeros is the bias).
The output is linear in w, so the EKF's H = d phi / d w = S(z).
Inputs come as rows, one per joint: z has shape (n, p), S(z) has shape (n, L),
and row i of S depends on row i of z only.
"""
from __future__ import annotations

from itertools import product

import numpy as np


def monomial_exponents(n_inputs: int, max_degree: int) -> np.ndarray:
    """All exponent rows with total degree <= max_degree, bias first.

    Returns an int array of shape (L, n_inputs), ordered by degree, then
    lexicographically (descending), so the order is stable across runs.
    """
    if n_inputs < 1 or max_degree < 0:
        raise ValueError("n_inputs must be >= 1 and max_degree >= 0")
    rows = [r for r in product(range(max_degree + 1), repeat=n_inputs) if sum(r) <= max_degree]
    rows.sort(key=lambda r: (sum(r), tuple(-x for x in r)))
    return np.array(rows, dtype=int)


class HONN:
    """The regressor S(z) of a scalar-output HONN.

    Parameters
    ----------
    exponents : array_like of int, shape (L, p)
        d_ij: power of tanh(z_j) in term i.
    input_scale : array_like, shape (p,)
        Each input is divided by its scale before tanh (units of that input).
    """

    def __init__(self, exponents, input_scale):
        self.exponents = np.asarray(exponents, dtype=int)
        self.input_scale = np.asarray(input_scale, dtype=float)
        if self.exponents.ndim != 2 or self.exponents.shape[1] != self.input_scale.size:
            raise ValueError("exponents must have shape (L, p) with p = len(input_scale)")
        if np.any(self.exponents < 0):
            raise ValueError("exponents must be non-negative")
        if np.any(~np.isfinite(self.input_scale)) or np.any(self.input_scale <= 0):
            raise ValueError("input_scale must be finite and positive")
        # Term i is the product of D factors ext[:, f_i1] ... ext[:, f_iD], where
        # ext = [1, s_1, ..., s_p] and D is the largest total degree; a term of
        # lower degree is padded with index 0 (the constant 1). The factors are
        # gathered in one take and multiplied left to right, (f_i1 f_i2) f_i3 ...,
        # one binary multiply per factor (cheaper than a multiply.reduce over D, same bits).
        degree = int(self.exponents.sum(axis=1).max(initial=0))
        factors = np.zeros((self.exponents.shape[0], max(degree, 1)), dtype=np.intp)
        for i, row in enumerate(self.exponents):
            idx = [j + 1 for j, d in enumerate(row) for _ in range(d)]
            factors[i, :len(idx)] = idx
        self._factors = factors
        self._inv_scale = 1.0 / self.input_scale
        self._alloc(0)

    def _alloc(self, n: int) -> None:
        self._ext = np.ones((n, self.input_scale.size + 1))
        self._ext_s = self._ext[:, 1:]
        self._zs = np.empty((n, self.input_scale.size))
        self._gathered = np.empty((n,) + self._factors.shape)
        views = [self._gathered[:, :, d] for d in range(self._factors.shape[1])]  # each (n, L)
        self._first, self._second, self._more = views[0], (views[1] if len(views) > 1 else None), views[2:]
        self._S = np.empty((n, self.exponents.shape[0]))

    @property
    def n_inputs(self) -> int:
        """p, the number of inputs."""
        return self.input_scale.size

    @property
    def n_terms(self) -> int:
        """L, the number of weights."""
        return self.exponents.shape[0]

    def regressor(self, z: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
        """S(z), shape (n, L), for inputs z of shape (n, p) (one row per joint).

        Written into ``out`` (n, L) when given (any strides, e.g. a block of a wider array), else into this
        network's own buffer, overwritten by the next call: copy it to keep it.
        """
        if z.shape != self._zs.shape:  # one test on the hot path: a new n re-allocates, a wrong shape raises
            if z.ndim != 2 or z.shape[1] != self.input_scale.size:
                raise ValueError(f"expected inputs of shape (n, {self.input_scale.size}), got {z.shape}")
            self._alloc(z.shape[0])
        np.tanh(np.multiply(z, self._inv_scale, out=self._zs), out=self._ext_s)
        self._ext.take(self._factors, axis=1, out=self._gathered, mode="clip")  # indices valid: no buffering
        S = self._S if out is None else out
        if self._second is None:
            S[...] = self._first
            return S
        np.multiply(self._first, self._second, out=S)
        for factor in self._more:
            np.multiply(S, factor, out=S)
        return S

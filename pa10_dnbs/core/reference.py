"""Desired joint trajectories of the paper, eq. 27 with Table 1.

x_d(k) = x_c + c (1 - exp(-d (kT)^3)) sin(w kT), with kT in seconds; the centre x_c is 0 in the paper
(Table 1) and lies inside the joint's limits on other arms (docs/arms.md). The printed
exponent ``e^{d k T^3}`` is read as ``exp(-d (kT)^3)`` (see
docs/design.md): with T = 1 ms the literal reading never moves or diverges.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class ReferenceSample:
    """What the joint controllers need from the reference at step k, one entry per joint (arrays (n,)).

    position_rad: x_d(k); velocity_rad_s: dx_d/dt at kT (analytic);
    position_ahead_rad: x_d(k+2), the preview used by the virtual control;
    acceleration_rad_s2: d2x_d/dt2 at kT (analytic), or None where nobody sent it
    (the joint controllers never need it; the centralized computed-torque baseline does).
    """

    position_rad: np.ndarray
    velocity_rad_s: np.ndarray
    position_ahead_rad: np.ndarray
    acceleration_rad_s2: np.ndarray | None = None


class Reference:
    """Eq. 27 for N joints.

    Parameters
    ----------
    amplitude_rad, envelope_rate_per_s3, frequency_rad_s : array_like, shape (N,)
        c_i [rad], d_i [1/s^3], w_i [rad/s] of each joint (Table 1's on the PA10).
    dt_s : float
        Sampling time T [s].
    preview_steps : int
        How far ahead ``position_ahead_rad`` looks (the paper's k+2).
    centre_rad : array_like, shape (N,), optional
        x_c [rad], the position the joint oscillates about (None or all zero: the paper's eq. 27 as printed).
    """

    def __init__(self, amplitude_rad, envelope_rate_per_s3, frequency_rad_s,
                 dt_s: float, preview_steps: int = 2, centre_rad=None):
        self.c = np.asarray(amplitude_rad, dtype=float)
        self.d = np.asarray(envelope_rate_per_s3, dtype=float)
        self.w = np.asarray(frequency_rad_s, dtype=float)
        centre = np.zeros_like(self.c) if centre_rad is None else np.asarray(centre_rad, dtype=float)
        if not (self.c.shape == self.d.shape == self.w.shape == centre.shape) or self.c.ndim != 1:
            raise ValueError("reference parameters must be 1-D arrays of equal length")
        self.centre = centre
        self._offset = bool(np.any(centre != 0.0))  # without one, the paper's expression exactly (same bits)
        self.dt_s = float(dt_s)
        self.preview_steps = int(preview_steps)

    @property
    def n_joints(self) -> int:
        return self.c.size

    def position(self, k) -> np.ndarray:
        """x_d at step(s) k [rad]: shape (N,) for scalar k, (len(k), N) for an array."""
        t = np.asarray(k, dtype=float)[..., None] * self.dt_s
        x = self.c * (1.0 - np.exp(-self.d * t**3)) * np.sin(self.w * t)
        return x + self.centre if self._offset else x

    def velocity(self, k) -> np.ndarray:
        """Analytic dx_d/dt at step(s) k [rad/s], same shapes as :meth:`position`."""
        t = np.asarray(k, dtype=float)[..., None] * self.dt_s
        env = 1.0 - np.exp(-self.d * t**3)
        denv = 3.0 * self.d * t**2 * np.exp(-self.d * t**3)
        return self.c * (denv * np.sin(self.w * t) + env * self.w * np.cos(self.w * t))

    def acceleration(self, k) -> np.ndarray:
        """Analytic d2x_d/dt2 at step(s) k [rad/s^2], same shapes as :meth:`position`."""
        t = np.asarray(k, dtype=float)[..., None] * self.dt_s
        ex = np.exp(-self.d * t**3)
        env = 1.0 - ex
        denv = 3.0 * self.d * t**2 * ex
        ddenv = (6.0 * self.d * t - 9.0 * self.d**2 * t**4) * ex
        wt = self.w * t
        return self.c * (ddenv * np.sin(wt) + 2.0 * denv * self.w * np.cos(wt) - env * self.w**2 * np.sin(wt))

    def sample(self, k: int, joints=None) -> ReferenceSample:
        """The reference at step k for ``joints`` (indices; all when None), with the k + preview_steps preview."""
        sel = slice(None) if joints is None else np.asarray(joints)
        return ReferenceSample(self.position(k)[sel], self.velocity(k)[sel],
                               self.position(k + self.preview_steps)[sel], self.acceleration(k)[sel])

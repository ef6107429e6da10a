"""The reference with joint trajectories spliced in: eq. 27 (or any base) until a trajectory starts, then it.

``TrajectoryReference`` answers what ``Reference`` answers (position, velocity, acceleration at step(s) k,
``sample`` with the k + preview_steps look-ahead), so the in-process loop and the reference node sample it
alike. ``start(traj, start_step, origin_s)`` splices a trajectory in from ``start_step`` on (steps before it
keep what they had; a later start replaces what an earlier trajectory planned from there on):

- its time origin is ``origin_s`` [s] (a message's header stamp), or the start step's time;
- the first knot is the current desired state (position, velocity, acceleration) at the start step; a point
  within half a step of the start replaces its position (a jump if it differs; the velocity and acceleration
  it gives, else the current ones), points before the start are dropped, the later points follow;
- one quintic per segment and joint (``QuinticSpline``; velocities and accelerations the points do not give
  come from ``knot_derivatives``); after the last point its position is held;
- it is refused (``TrajectoryError``, one line, nothing changes) when ``check_trajectory`` refuses it, when a
  time_from_start lies past ``MAX_TIME_FROM_START_S``, when no point is left after the start, or when the
  interpolation passes a joint limit at a step between the points (each quintic's extrema found analytically,
  so the check costs the same for a trajectory of a second or of days).
Numpy only.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .joint_trajectory import JointTrajectory, QuinticSpline, TrajectoryError, check_trajectory, knot_derivatives
from .reference import ReferenceSample

MAX_TIME_FROM_START_S = 1.0e6  # [s] (11.6 days): the longest trajectory followed; a later point is refused


@dataclass(frozen=True)
class Started:
    """What ``start`` did: first step it decides, the step its last knot falls on (held after), knots used."""

    start_step: int
    end_step: int
    knots: int
    dropped: int  # points before the start step, left out


def received_start(first_free_step: int, stamp_s: float, dt_s: float) -> tuple[int, float | None]:
    """(start step, time origin [s] or None) of a trajectory received while running: the first step not yet
    published (``first_free_step``), its t = 0 there (None); with a non-zero header stamp ``stamp_s`` [s], t = 0
    at the stamp and the start at the stamp's step, or at ``first_free_step`` if that is later."""
    if stamp_s == 0.0:
        return int(first_free_step), None
    return max(int(first_free_step), int(np.ceil(stamp_s / dt_s - 1e-9))), float(stamp_s)


def check_span(traj: JointTrajectory) -> None:
    """TrajectoryError (one line) when a point of ``traj`` lies past ``MAX_TIME_FROM_START_S``."""
    t = np.asarray(traj.time_from_start_s, dtype=float)
    if t.size and not t[-1] <= MAX_TIME_FROM_START_S:
        i = int(np.argmax(~(t <= MAX_TIME_FROM_START_S)))
        raise TrajectoryError(f"points[{i}].time_from_start = {t[i]:g} s is past the longest trajectory followed "
                              f"({MAX_TIME_FROM_START_S:g} s)")


def extremum_times(spline: QuinticSpline) -> np.ndarray:
    """The times [s] inside each segment where a joint's quintic may turn (real parts of the roots of its
    derivative, with the segment scaled to [0, 1]), flattened segment by segment, joint by joint; a superset of
    its interior extrema.

    The roots are ``np.roots``' (the eigenvalues of the companion matrix of the derivative, its leading and
    trailing zero coefficients stripped, a root 0 per trailing zero), computed for every segment and joint at
    once: the companion matrices of one shape go to one batched ``np.linalg.eigvals`` call (the same LAPACK
    routine on the same matrices, so the same bits as one ``np.roots`` call per quintic, at 1e5 points ~100x
    faster)."""
    h = np.diff(spline.t)
    if h.size == 0:
        return np.empty(0)
    scaled = spline.c * (h[:, None] ** np.arange(6)).T[:, :, None]  # (6, m-1, n): coefficients in u = tau / h
    d = np.arange(1, 6)[:, None, None] * scaled[1:]                  # (5, m-1, n): derivative's, u^0 .. u^4
    poly = np.moveaxis(d[::-1], 0, -1)                                # (m-1, n, 5): np.roots' order, u^4 first
    nonzero = poly != 0.0
    curved = nonzero[..., :4].any(axis=-1)                            # not a line: may turn inside
    lead = np.argmax(nonzero, axis=-1)                                # leading zeros (stripped)
    trail = np.argmax(nonzero[..., ::-1], axis=-1)                    # trailing zeros: roots at u = 0
    u = np.full(poly.shape[:2] + (4,), np.nan)                        # each quintic's 4 - lead roots, NaN after
    for lz in range(4):
        for tz in range(5 - lz):                                      # N = 5 - lz - tz >= 1 coefficients
            at = np.flatnonzero((curved & (lead == lz) & (trail == tz)).ravel())
            if at.size == 0:
                continue
            size = 4 - lz - tz                                        # companion matrix size (np.roots: N - 1)
            coeffs = poly.reshape(-1, 5)[at, lz:5 - tz]
            if size > 0:
                companion = np.zeros((at.size, size, size))
                companion[:, np.arange(1, size), np.arange(size - 1)] = 1.0
                companion[:, 0, :] = -coeffs[:, 1:] / coeffs[:, :1]
                u.reshape(-1, 4)[at, :size] = np.linalg.eigvals(companion).real
            u.reshape(-1, 4)[at, size:size + tz] = 0.0
    inside = (u >= 0.0) & (u <= 1.0)
    times = spline.t[:-1, None, None] + u * h[:, None, None]
    return times[inside]


class TrajectoryReference:
    """``base`` (a Reference: eq. 27) with trajectories of the arm's joints spliced in.

    joint_names (n,), lower_rad, upper_rad (n,): the arm's joints and position limits [rad], against which
    every trajectory is checked (by name) and its interpolation sampled at every step.
    """

    def __init__(self, base, joint_names, lower_rad, upper_rad):
        self.base = base
        self.dt_s = base.dt_s
        self.preview_steps = base.preview_steps
        self.joint_names = tuple(joint_names)
        self.lower_rad = np.asarray(lower_rad, dtype=float)
        self.upper_rad = np.asarray(upper_rad, dtype=float)
        if not (len(self.joint_names) == self.lower_rad.size == self.upper_rad.size == base.n_joints):
            raise ValueError("joint_names, lower_rad, upper_rad must have one entry per joint of the base reference")
        self._starts: list[int] = []
        self._splines: list[QuinticSpline] = []

    @property
    def n_joints(self) -> int:
        return self.base.n_joints

    def start(self, traj: JointTrajectory, start_step: int, origin_s: float | None = None) -> Started:
        """Follow ``traj`` from step ``start_step`` on, its time_from_start counted from ``origin_s`` [s] (None:
        the start step's time). Raises TrajectoryError (and changes nothing) on a trajectory that cannot be
        followed."""
        traj = check_trajectory(traj, self.joint_names, self.lower_rad, self.upper_rad)
        check_span(traj)
        dt, start_step = self.dt_s, int(start_step)
        t_start = start_step * dt
        times = (t_start if origin_s is None else float(origin_s)) + traj.time_from_start_s
        at_start = np.flatnonzero(np.abs(times - t_start) <= 0.5 * dt)
        later = np.flatnonzero(times > t_start + 0.5 * dt)
        if at_start.size == 0 and later.size == 0:
            raise TrajectoryError(f"every point lies before step {start_step} (t = {t_start:.3f} s), where the "
                                  "reference can still change: nothing left to follow")
        first = at_start[-1] if at_start.size else None
        p0 = self.position(start_step) if first is None else traj.positions_rad[first]
        given_v, given_a = traj.velocities_rad_s, traj.accelerations_rad_s2
        v0 = given_v[first] if first is not None and given_v is not None else self.velocity(start_step)
        a0 = given_a[first] if first is not None and given_a is not None else self.acceleration(start_step)
        t = np.concatenate([[t_start], times[later]])
        p = np.vstack([p0, traj.positions_rad[later]])
        pick = lambda a: None if a is None else np.vstack([np.zeros(self.n_joints), a[later]])  # noqa: E731
        with np.errstate(over="ignore", invalid="ignore"):   # an overflow is refused just below, in one line
            v, a = knot_derivatives(t, p, pick(given_v), pick(given_a), v0=v0, a0=a0)
            spline = QuinticSpline(t, p, v, a)
        finite = np.isfinite(spline.c).all(axis=(0, 2)) & np.isfinite(v[1:] + a[1:]).all(axis=1)   # per segment
        if not finite.all():
            seg = int(np.argmin(finite))
            raise TrajectoryError(f"points[{int(later[seg])}]: the quintic from t = {t[seg]:g} s to this point at "
                                  f"{t[seg + 1]:g} s overflows a float (its velocities, accelerations or positions "
                                  "are beyond any arm's)")
        end_step = int(np.ceil(spline.end_s / dt - 1e-9))
        end_step += int(end_step * dt < spline.end_s)  # the first step held, as evaluate() decides it
        self._check_limits(spline, start_step, end_step)
        keep = [i for i, s in enumerate(self._starts) if s < start_step]
        self._starts = [self._starts[i] for i in keep] + [start_step]
        self._splines = [self._splines[i] for i in keep] + [spline]
        return Started(start_step, end_step, t.size, len(times) - later.size - int(first is not None))

    def _check_limits(self, spline: QuinticSpline, first: int, last: int) -> None:
        """TrajectoryError naming the first step in [first, last] where the interpolation leaves
        [lower_rad, upper_rad].

        Within a segment each joint's quintic is monotone between its turning points, so over the steps the
        extremes lie at the steps next to a knot or a turning point (``extremum_times``), or at first / last:
        only those are sampled (two steps either side, for rounding), which decides as sampling every step.
        Between two such steps a joint is monotone, so its first step beyond is found by bisection."""
        dt = self.dt_s
        marks = np.concatenate([spline.t, extremum_times(spline)])
        near = np.clip((np.floor(marks / dt)[:, None] + np.arange(-2, 3)).ravel(), first, last).astype(np.int64)
        if last - first < 8 * near.size:   # the steps marked in a mask of the span: np.unique's set, sorted, faster
            marked = np.zeros(last - first + 1, dtype=bool)
            marked[near - first] = True
            marked[[0, -1]] = True
            k = np.flatnonzero(marked).astype(np.int64) + first
        else:
            k = np.union1d(np.unique(near), [first, last])
        x = spline.evaluate(k * dt)
        beyond = (x < self.lower_rad) | (x > self.upper_rad)
        if not np.any(beyond):
            return
        found = []  # (first step beyond, joint)
        for j in np.flatnonzero(beyond.any(axis=0)):
            i = int(np.argmax(beyond[:, j]))
            lo_k, hi_k = (int(k[i - 1]), int(k[i])) if i > 0 else (int(k[i]) - 1, int(k[i]))
            while hi_k - lo_k > 1:  # lo_k within the limits, hi_k beyond; monotone between them
                mid = (lo_k + hi_k) // 2
                xm = spline.evaluate(np.array([mid * dt]))[0, j]
                if xm < self.lower_rad[j] or xm > self.upper_rad[j]:
                    hi_k = mid
                else:
                    lo_k = mid
            found.append((hi_k, int(j)))
        step, j = min(found)
        value = spline.evaluate(np.array([step * dt]))[0, j]
        lo, hi = self.lower_rad[j], self.upper_rad[j]
        raise TrajectoryError(f"the interpolation of joint {self.joint_names[j]!r} reaches {value:.6g} rad "
                              f"at t = {step * dt:.3f} s, beyond its limits [{lo:.6g}, {hi:.6g}] rad "
                              "(points further inside, or velocities that keep it inside)")

    def _evaluate(self, k, derivative: int) -> np.ndarray:
        base = (self.base.position, self.base.velocity, self.base.acceleration)[derivative]
        if not self._starts:
            return base(k)  # eq. 27 alone: exactly its own values
        scalar = np.ndim(k) == 0
        ks = np.atleast_1d(np.asarray(k))
        piece = np.searchsorted(self._starts, ks, side="right") - 1
        out = np.empty((ks.size, self.n_joints))
        before = piece < 0
        if np.any(before):
            out[before] = base(ks[before])
        for i in np.unique(piece[~before]):
            mask = piece == i
            out[mask] = self._splines[i].evaluate(ks[mask] * self.dt_s, derivative)
        return out[0] if scalar else out

    def position(self, k) -> np.ndarray:
        """x_d at step(s) k [rad]: shape (n,) for scalar k, (len(k), n) for an array."""
        return self._evaluate(k, 0)

    def velocity(self, k) -> np.ndarray:
        """dx_d/dt at step(s) k [rad/s], same shapes as :meth:`position`."""
        return self._evaluate(k, 1)

    def acceleration(self, k) -> np.ndarray:
        """d2x_d/dt2 at step(s) k [rad/s^2], same shapes as :meth:`position`."""
        return self._evaluate(k, 2)

    def sample(self, k: int, joints=None) -> ReferenceSample:
        """The reference at step k for ``joints`` (indices; all when None), with the k + preview_steps preview."""
        sel = slice(None) if joints is None else np.asarray(joints)
        return ReferenceSample(self.position(k)[sel], self.velocity(k)[sel],
                               self.position(k + self.preview_steps)[sel], self.acceleration(k)[sel])

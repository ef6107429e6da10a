"""A joint trajectory (trajectory_msgs/JointTrajectory's fields), its checks, and its quintic interpolation.

``JointTrajectory``: joint names and m points, each with positions [rad], optional velocities [rad/s] and
accelerations [rad/s^2], and its time_from_start [s]. ``check_trajectory`` validates one against an arm
(names matched by name, not by order; limits; timing) and returns it in the arm's joint order, or raises
``TrajectoryError`` with one line naming what is wrong. ``QuinticSpline`` interpolates knots (time, p, v, a)
with one quintic per segment and joint (position, velocity and acceleration continuous at every knot) and
holds the last knot's position after it. ``knot_derivatives`` is the rule for the velocities and
accelerations a trajectory does not give (docs/trajectories.md). Numpy only.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np


class TrajectoryError(ValueError):
    """A trajectory that cannot be followed; the message is one line naming what is wrong."""


@dataclass(frozen=True)
class JointTrajectory:
    """joint_names (n,); time_from_start_s (m,); positions_rad (m, n); velocities_rad_s and
    accelerations_rad_s2 (m, n) or None where the points give none."""

    joint_names: tuple[str, ...]
    time_from_start_s: np.ndarray
    positions_rad: np.ndarray
    velocities_rad_s: np.ndarray | None = None
    accelerations_rad_s2: np.ndarray | None = None

    @property
    def duration_s(self) -> float:
        return float(self.time_from_start_s[-1])


_FLOAT_OVERFLOW = 2**1024 - 2**970   # the least whole number that float() refuses (it would round to 2**1024)


def _too_large(value, where: str) -> TrajectoryError:
    """The one line for a whole number past the largest float (~1.8e308): its size, not its digits."""
    bits = abs(value).bit_length()   # str() of an int past 4300 digits raises (Python's int_max_str_digits)
    digits = len(str(abs(value))) if bits <= 14_000 else f"about {int(bits * 0.30103)}"
    return TrajectoryError(f"{where}: a whole number of {digits} digits is too large for a float (at most ~1.8e308)")


def _seconds(value, where: str) -> float:
    """time_from_start as seconds (a number) or {sec, nanosec} (builtin_interfaces/Duration; at least one)."""
    if isinstance(value, dict):
        unknown = set(value) - {"sec", "nanosec"}
        if unknown:
            raise TrajectoryError(f"{where}: unknown key {_first(unknown)} (expected sec, nanosec)")
        if not value:
            raise TrajectoryError(f"{where}: {{}} gives no time (expected sec and nanosec)")
        sec, nanosec = value.get("sec", 0), value.get("nanosec", 0)
        if not all(isinstance(v, int) and not isinstance(v, bool) for v in (sec, nanosec)) or not 0 <= nanosec < 10**9:
            raise TrajectoryError(f"{where}: sec and nanosec must be integers, nanosec in [0, 1e9)")
        try:
            return sec + nanosec * 1e-9
        except OverflowError:
            raise _too_large(sec, f"{where}.sec") from None
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise TrajectoryError(f"{where}: expected seconds (a number) or {{sec, nanosec}}, got {_short(value)}")
    try:
        return float(value)
    except OverflowError:
        raise _too_large(value, where) from None


_NOT_FINITE = ("nan", "inf", "infinity")   # what JSON writers print for non-finite floats, read as text


def _numbers(value, where: str) -> list[float]:
    if not isinstance(value, (list, tuple)) or any(isinstance(v, bool) or not isinstance(v, (int, float))
                                                  for v in value):
        text = next((v for v in value if isinstance(v, str) and v.strip().lstrip("+-").lower() in _NOT_FINITE), None) \
            if isinstance(value, (list, tuple)) else None
        why = f" ({text!r} is text, not a number: the values must be finite)" if text is not None else ""
        raise TrajectoryError(f"{where}: expected a list of numbers, got {_short(value)}{why}")
    try:
        return [float(v) for v in value]
    except OverflowError:
        i, v = next((i, v) for i, v in enumerate(value) if isinstance(v, int) and abs(v) >= _FLOAT_OVERFLOW)
        raise _too_large(v, f"{where}[{i}]") from None


def _short(value) -> str:
    """``value``'s repr, cut to 80 characters (a message stays one readable line)."""
    try:
        text = repr(value)
    except ValueError:   # an int past Python's 4300 digits in it
        return "a value too long to show"
    return text if len(text) <= 80 else text[:77] + "..."


def _first(keys) -> str:
    """The first of the unknown ``keys`` for a message (:func:`_short`): names in order, then keys that are not names
    (YAML's ``1:``, ``~:``), never compared with a name (sorted() would raise)."""
    names = sorted(k for k in keys if isinstance(k, str))
    return _short(names[0] if names else next(iter(keys)))


POINT_KEYS = ("positions", "velocities", "accelerations", "effort", "time_from_start")


def trajectory_from_mapping(data) -> JointTrajectory:
    """A JointTrajectory from a mapping as in a YAML or JSON file: ``joint_names`` (list of str) and ``points``
    (list of mappings: positions [rad], optional velocities [rad/s], accelerations [rad/s^2], time_from_start
    [s] or {sec, nanosec}; an empty or absent optional list = not given; effort must be empty); a ``header`` is
    ignored (a file starts at t = 0). Shapes and types only: ``check_trajectory`` does the rest."""
    if not isinstance(data, dict):
        raise TrajectoryError("a trajectory is a mapping with joint_names and points")
    unknown = set(data) - {"joint_names", "points", "header"}
    if unknown:
        raise TrajectoryError(f"unknown key {_first(unknown)} (expected joint_names, points)")
    if "header" in data and not isinstance(data["header"], dict):
        raise TrajectoryError(f"header: expected a mapping (stamp, frame_id) or none, got {_short(data['header'])}")
    names = data.get("joint_names")
    if not isinstance(names, list) or not names or not all(isinstance(n, str) for n in names):
        raise TrajectoryError("joint_names: expected a non-empty list of joint names")
    points = data.get("points")
    if not isinstance(points, list) or not points:
        raise TrajectoryError("points: expected a non-empty list of points")
    times, fields = [], {"positions": [], "velocities": [], "accelerations": []}
    for i, pt in enumerate(points):
        where = f"points[{i}]"
        if not isinstance(pt, dict):
            raise TrajectoryError(f"{where}: expected a mapping with positions and time_from_start")
        unknown = set(pt) - set(POINT_KEYS)
        if unknown:
            raise TrajectoryError(f"{where}: unknown key {_first(unknown)} (expected {', '.join(POINT_KEYS)})")
        if "time_from_start" not in pt:
            raise TrajectoryError(f"{where}.time_from_start: missing")
        times.append(_seconds(pt["time_from_start"], f"{where}.time_from_start"))
        if _numbers(pt.get("effort") or [], f"{where}.effort"):
            raise TrajectoryError(f"{where}.effort: efforts are not followed (give positions)")
        for key, values in fields.items():
            values.append(_numbers(pt.get(key) or [], f"{where}.{key}"))
    return trajectory_from_lists(names, times, fields["positions"], fields["velocities"], fields["accelerations"])


def trajectory_from_lists(joint_names, times_s, positions, velocities, accelerations) -> JointTrajectory:
    """A JointTrajectory from per-point lists (a ROS message's fields): an empty velocity or acceleration list
    = not given; they must be given for every point or none, each with one value per joint."""
    n, m = len(joint_names), len(times_s)
    arrays = {}
    for key, rows in (("positions", positions), ("velocities", velocities), ("accelerations", accelerations)):
        given = [len(r) > 0 for r in rows]
        if key != "positions" and not any(given):
            arrays[key] = None
            continue
        for i, r in enumerate(rows):
            if len(r) != n:
                what = "given for every point or none" if key != "positions" and not given[i] else f"{n} values"
                raise TrajectoryError(f"points[{i}].{key}: {len(r)} values for {n} joint names ({what})")
        arrays[key] = np.array(rows, dtype=float).reshape(m, n)
    if arrays["accelerations"] is not None and arrays["velocities"] is None:
        raise TrajectoryError("points: accelerations given without velocities")
    return JointTrajectory(tuple(joint_names), np.array(times_s, dtype=float), arrays["positions"],
                           arrays["velocities"], arrays["accelerations"])


def check_trajectory(traj: JointTrajectory, arm_joint_names, lower_rad, upper_rad) -> JointTrajectory:
    """``traj`` validated against the arm and reordered into ``arm_joint_names`` (matched by name), or
    TrajectoryError: unknown, duplicate or missing joint names; non-finite values; a first point before
    t = 0; times not strictly increasing; a position beyond [lower_rad, upper_rad]; a last point that does
    not come to rest (velocities or accelerations not zero: the last point is held)."""
    arm = list(arm_joint_names)
    names = list(traj.joint_names)
    for name in names:
        if name not in arm:
            raise TrajectoryError(f"unknown joint {name!r} (the arm's joints: {', '.join(arm)})")
        if names.count(name) > 1:
            raise TrajectoryError(f"joint {name!r} named twice")
    missing = [a for a in arm if a not in names]
    if missing:
        raise TrajectoryError(f"joint {missing[0]!r} missing (every joint of the arm needs its positions: "
                              f"{', '.join(arm)})")
    order = [names.index(a) for a in arm]
    t = traj.time_from_start_s
    if t.size == 0:
        raise TrajectoryError("no points")
    arrays = {"positions": traj.positions_rad, "velocities": traj.velocities_rad_s,
              "accelerations": traj.accelerations_rad_s2}
    if not np.all(np.isfinite(t)):
        raise TrajectoryError(f"points[{int(np.argmin(np.isfinite(t)))}].time_from_start is not finite")
    for key, a in arrays.items():
        if a is not None and not np.all(np.isfinite(a)):
            i, j = np.argwhere(~np.isfinite(a))[0]
            raise TrajectoryError(f"points[{i}].{key} of joint {names[j]!r} is not finite ({a[i, j]})")
    if t[0] < 0:
        raise TrajectoryError(f"points[0].time_from_start = {t[0]:g} s is before the start (must be >= 0)")
    steps = np.diff(t)
    if np.any(steps <= 0):
        i = int(np.argmax(steps <= 0)) + 1
        raise TrajectoryError(f"points[{i}].time_from_start = {t[i]:g} s is not after points[{i - 1}]'s "
                              f"{t[i - 1]:g} s (times must increase strictly)")
    p = traj.positions_rad[:, order]
    lo, hi = np.asarray(lower_rad, dtype=float), np.asarray(upper_rad, dtype=float)
    beyond = (p < lo) | (p > hi)
    if np.any(beyond):
        i, j = np.argwhere(beyond)[0]
        raise TrajectoryError(f"points[{i}].positions of joint {arm[j]!r} = {p[i, j]:.6g} rad is beyond its limits "
                              f"[{lo[j]:.6g}, {hi[j]:.6g}] rad")
    for key in ("velocities", "accelerations"):
        a = arrays[key]
        if a is not None and np.any(a[-1] != 0.0):
            j = int(np.argmax(a[-1] != 0.0))
            raise TrajectoryError(f"points[{len(t) - 1}].{key} of joint {names[j]!r} = {a[-1, j]:g}: the last point "
                                  "is held, so it must come to rest (zero velocities and accelerations)")
    pick = lambda a: None if a is None else a[:, order]  # noqa: E731
    return JointTrajectory(tuple(arm), t.copy(), p, pick(traj.velocities_rad_s), pick(traj.accelerations_rad_s2))


def knot_derivatives(t, p, v=None, a=None, v0=None, a0=None):
    """Velocities and accelerations (m, n) at knots t (m,) with positions p (m, n) where none are given.

    The first knot takes v0, a0 (the state the trajectory starts from; zero when None); the last knot is at rest
    (zero velocity and acceleration). Interior knots, when not given: the velocity is the mean of the two
    adjacent segments' slopes when both have the same sign, else zero (no overshoot at a turning point), and
    the acceleration is the central difference of the velocities, (v[i+1] - v[i-1]) / (t[i+1] - t[i-1]).
    """
    m, n = p.shape
    if v is None:
        v = np.zeros((m, n))
        if m > 2:
            s = np.diff(p, axis=0) / np.diff(t)[:, None]
            same = s[:-1] * s[1:] > 0
            v[1:-1] = np.where(same, 0.5 * (s[:-1] + s[1:]), 0.0)
    else:
        v = np.array(v, dtype=float)
    if a is None:
        a = np.zeros((m, n))
        if m > 2:
            a[1:-1] = (v[2:] - v[:-2]) / (t[2:] - t[:-2])[:, None]
    else:
        a = np.array(a, dtype=float)
    v[0] = 0.0 if v0 is None else v0
    a[0] = 0.0 if a0 is None else a0
    v[-1] = 0.0
    a[-1] = 0.0
    return v, a


class QuinticSpline:
    """Knots at times t (m,) [s] with positions p, velocities v, accelerations a (m, n); one quintic per segment
    and joint meets both knots' p, v and a. Before t[0] it gives the first knot's position (callers sample from
    t[0] on); from t[-1] on it holds the last knot's position with zero velocity and acceleration."""

    def __init__(self, t, p, v, a):
        self.t = np.asarray(t, dtype=float)
        p, v, a = (np.asarray(x, dtype=float) for x in (p, v, a))
        if self.t.ndim != 1 or self.t.size < 1 or p.shape != (self.t.size, p.shape[1]) or v.shape != p.shape \
                or a.shape != p.shape:
            raise ValueError("knots: t (m,), p, v, a (m, n)")
        if np.any(np.diff(self.t) <= 0):
            raise ValueError("knot times must increase strictly")
        self.last = p[-1].copy()
        h = np.diff(self.t)[:, None]  # (m-1, 1)
        dp = p[1:] - p[:-1]
        v0, v1, a0, a1 = v[:-1], v[1:], a[:-1], a[1:]
        # c0 + c1 tau + ... + c5 tau^5 on [0, h] with p, v, a given at both ends
        self.c = np.stack([p[:-1], v0, 0.5 * a0,
                           (20 * dp - (8 * v1 + 12 * v0) * h - (3 * a0 - a1) * h**2) / (2 * h**3),
                           (-30 * dp + (14 * v1 + 16 * v0) * h + (3 * a0 - 2 * a1) * h**2) / (2 * h**4),
                           (12 * dp - 6 * (v1 + v0) * h + (a1 - a0) * h**2) / (2 * h**5)])  # (6, m-1, n)

    @property
    def n_joints(self) -> int:
        return self.last.size

    @property
    def end_s(self) -> float:
        return float(self.t[-1])

    def evaluate(self, t_s, derivative: int = 0) -> np.ndarray:
        """Position (0), velocity (1) or acceleration (2) at times t_s (k,) [s]: shape (k, n)."""
        t_s = np.asarray(t_s, dtype=float)
        seg = np.clip(np.searchsorted(self.t, t_s, side="right") - 1, 0, max(self.t.size - 2, 0))
        out = np.zeros((t_s.size, self.n_joints))
        held = t_s >= self.t[-1]
        if derivative == 0:
            out[held] = self.last
        live = ~held
        if self.t.size < 2 or not np.any(live):
            if derivative == 0:
                out[live] = self.last if self.t.size < 2 else self.c[0, 0]
            return out
        s = seg[live]
        tau = np.maximum(t_s[live] - self.t[s], 0.0)[:, None]
        c = self.c[:, s]  # (6, k, n)
        if derivative == 0:
            out[live] = c[0] + tau * (c[1] + tau * (c[2] + tau * (c[3] + tau * (c[4] + tau * c[5]))))
        elif derivative == 1:
            out[live] = c[1] + tau * (2 * c[2] + tau * (3 * c[3] + tau * (4 * c[4] + tau * 5 * c[5])))
        elif derivative == 2:
            out[live] = 2 * c[2] + tau * (6 * c[3] + tau * (12 * c[4] + tau * 20 * c[5]))
        else:
            raise ValueError("derivative: 0, 1 or 2")
        return out

"""Trajectories (core/joint_trajectory.py, core/trajectory_reference.py, trajectory_file.py): the quintic's
continuity at the knots, the hold, the splice into eq. 27, and every refusal in one line."""
import json

import numpy as np
import pytest

from pa10_dnbs.config import ConfigError
from pa10_dnbs.controller_factory import build_reference, switchable_reference
from pa10_dnbs.core.joint_trajectory import (JointTrajectory, QuinticSpline, TrajectoryError, check_trajectory,
                                             knot_derivatives, trajectory_from_mapping)
from pa10_dnbs.core.trajectory_reference import received_start
from pa10_dnbs.trajectory_file import load_trajectory_file

NAMES = ("s1", "s2", "s3", "e1", "e2", "w1", "w2")
EXAMPLE = "config/trajectory_example.yaml"


def _traj(times, positions, names=NAMES, velocities=None, accelerations=None):
    return JointTrajectory(tuple(names), np.array(times, float), np.array(positions, float),
                           None if velocities is None else np.array(velocities, float),
                           None if accelerations is None else np.array(accelerations, float))


def _jumps(spline, t, derivative):
    """|left - right| limits at the interior knots t, one step of 1e-7 s either side (first-order terms removed
    by the symmetric difference of two one-sided steps)."""
    e = 1e-7
    left = 2 * spline.evaluate(t - e, derivative) - spline.evaluate(t - 2 * e, derivative)
    right = 2 * spline.evaluate(t + e, derivative) - spline.evaluate(t + 2 * e, derivative)
    return np.abs(left - right).max()


@pytest.mark.parametrize("given", ["none", "velocities", "both"])
def test_quintic_is_continuous_in_position_velocity_acceleration_at_the_knots(given):
    rng = np.random.default_rng(1)
    t = np.array([0.0, 0.5, 1.3, 2.0, 2.2, 3.0])
    p = rng.uniform(-1, 1, (6, 3))
    v = rng.uniform(-2, 2, (6, 3)) if given != "none" else None
    a = rng.uniform(-5, 5, (6, 3)) if given == "both" else None
    v, a = knot_derivatives(t, p, v, a, v0=np.full(3, 0.3), a0=np.full(3, -0.2))
    s = QuinticSpline(t, p, v, a)
    # the knots' own values, exactly where they are given
    np.testing.assert_allclose(s.evaluate(t[:-1]), p[:-1], atol=1e-15)
    np.testing.assert_allclose(s.evaluate(t[:-1], 1), v[:-1], atol=1e-12)
    np.testing.assert_allclose(s.evaluate(t[:-1], 2), a[:-1], atol=1e-10)
    np.testing.assert_allclose(s.evaluate(t[-1] - 1e-12), p[-1:], atol=1e-9)  # the last segment ends on it
    for d, tol in ((0, 1e-12), (1, 1e-9), (2, 1e-6)):
        assert _jumps(s, t[1:-1], d) < tol, (d, _jumps(s, t[1:-1], d))
    # velocity and acceleration are the derivatives of position and velocity
    tt = np.linspace(0.01, 2.99, 500)
    h = 1e-6
    np.testing.assert_allclose((s.evaluate(tt + h) - s.evaluate(tt - h)) / (2 * h), s.evaluate(tt, 1), atol=1e-6)
    np.testing.assert_allclose((s.evaluate(tt + h, 1) - s.evaluate(tt - h, 1)) / (2 * h), s.evaluate(tt, 2),
                               atol=1e-5)


def test_the_rule_for_missing_velocities_holds_still_at_turning_points():
    t = np.array([0.0, 1.0, 2.0, 3.0])
    p = np.array([[0.0], [1.0], [3.0], [2.0]])
    v, a = knot_derivatives(t, p)
    assert v.ravel().tolist() == [0.0, 1.5, 0.0, 0.0]  # mean of slopes 1 and 2; 2 then -1 turns: zero
    assert a.ravel().tolist() == [0.0, 0.0, -0.75, 0.0]  # central differences, zero at both ends


def test_last_point_is_held_with_zero_velocity_and_acceleration():
    s = QuinticSpline([0.0, 1.0], [[0.0, 1.0], [0.5, -0.5]], np.zeros((2, 2)), np.zeros((2, 2)))
    after = np.array([1.0, 1.5, 100.0])
    assert np.array_equal(s.evaluate(after), np.tile([0.5, -0.5], (3, 1)))
    assert np.array_equal(s.evaluate(after, 1), np.zeros((3, 2)))
    assert np.array_equal(s.evaluate(after, 2), np.zeros((3, 2)))


def test_a_file_trajectory_starts_from_eq27_at_step_0_and_passes_every_point(cfg):
    traj = load_trajectory_file(EXAMPLE, cfg.arm)
    ref = build_reference(cfg, traj)
    eq27 = build_reference(cfg)
    assert np.array_equal(ref.position(0), eq27.position(0)) and np.array_equal(ref.velocity(0), eq27.velocity(0))
    steps = np.round(traj.time_from_start_s / ref.dt_s).astype(int)
    np.testing.assert_allclose(ref.position(steps), traj.positions_rad, atol=1e-12)
    # held after the last point; the batches a node publishes equal the whole run's arrays (same bits)
    assert np.array_equal(ref.position(np.arange(4000, 4100)), np.tile(traj.positions_rad[-1], (100, 1)))
    k = np.arange(0, 5000)
    assert np.array_equal(ref.position(k)[1234:1334], ref.position(np.arange(1234, 1334)))
    assert np.array_equal(ref.position(k + 2)[1234], ref.sample(1234).position_ahead_rad)


def test_a_trajectory_sent_while_running_splices_in_continuously(cfg):
    arm = cfg.arm
    ref = switchable_reference(cfg, build_reference(cfg))
    eq27 = build_reference(cfg)
    t = [0.8, 1.6, 2.4, 3.2, 4.0]
    p = np.tile(np.linspace(0.1, 0.5, 5)[:, None], (1, 7))
    started = ref.start(_traj(t, p, names=NAMES[::-1]), 1500)  # names in another order: matched by name
    assert (started.start_step, started.end_step, started.knots, started.dropped) == (1500, 5500, 6, 0)
    k = np.arange(1000, 6000)
    assert np.array_equal(ref.position(k[:500]), eq27.position(k[:500]))  # before the start: unchanged
    for d, f in enumerate((ref.position, ref.velocity, ref.acceleration)):
        g = (eq27.position, eq27.velocity, eq27.acceleration)[d]
        np.testing.assert_allclose(f(1500), g(1500), atol=1e-15)  # starts from the current desired state
    np.testing.assert_allclose(ref.position(1500 + 800 * np.arange(1, 6)), p[:, ::-1], atol=1e-12)
    assert np.all(ref.position(k) >= arm.lower_rad) and np.all(ref.position(k) <= arm.upper_rad)
    # a second one at a later step replaces the first from there on, from the first's state there
    before = ref.position(3000)
    ref.start(_traj([1.0], [np.zeros(7)]), 3000)
    np.testing.assert_allclose(ref.position(3000), before, atol=1e-15)
    assert np.array_equal(ref.position(4000), np.zeros(7))
    # a header stamp: its points in the past are dropped, the rest follow from the start step
    s = ref.start(_traj([0.5, 1.0, 5.0], np.zeros((3, 7))), 4500, origin_s=3.0)
    assert (s.knots, s.dropped) == (2, 2)
    s = ref.start(_traj([0.5, 1.0, 5.0], np.zeros((3, 7))), 4500, origin_s=4.0)  # the first at the start
    assert (s.knots, s.dropped) == (3, 0)


def test_the_step_named_as_the_end_is_the_first_step_held(cfg):
    """k T and the start time plus time_from_start round differently: the end step is the one evaluate() holds
    from (1640 + 4000 steps: k T = 5.64 < 1.64 + 4.0 in floating point, so the hold starts at 5641)."""
    last = np.linspace(0.1, 0.3, 7)
    for start in (1500, 1600, 1640):
        ref = switchable_reference(cfg, build_reference(cfg))
        s = ref.start(_traj([2.0, 4.0], np.vstack([last / 2, last])), start)
        assert s.end_step in (start + 4000, start + 4001)
        assert not np.array_equal(ref.position(s.end_step - 1), last), start
        assert np.array_equal(ref.position(np.arange(s.end_step, s.end_step + 50)), np.tile(last, (50, 1))), start


def test_a_received_trajectory_starts_at_the_first_free_step_or_its_stamp():
    assert received_start(1234, 0.0, 1e-3) == (1234, None)  # no stamp: t = 0 where the reference can change
    assert received_start(1234, 2.0, 1e-3) == (2000, 2.0)  # a later stamp: there
    assert received_start(1234, 2.0005, 1e-3) == (2001, 2.0005)  # between two steps: the next one
    assert received_start(1234, 1.0, 1e-3) == (1234, 1.0)  # an earlier stamp: its time origin, started here


BAD = [
    (dict(names=("s1", "s2", "s3", "e1", "e2", "w1", "x9")), "unknown joint 'x9'"),
    (dict(names=("s1", "s2", "s3", "e1", "e2", "w1", "w1")), "joint 'w1' named twice"),
    (dict(names=NAMES[:6], positions=np.zeros((2, 6))), "joint 'w2' missing"),
    (dict(times=[1.0, 1.0]), "points[1].time_from_start = 1 s is not after points[0]'s 1 s"),
    (dict(times=[2.0, 1.0]), "is not after"),
    (dict(times=[-0.5, 1.0]), "points[0].time_from_start = -0.5 s is before the start"),
    (dict(times=[1.0, np.nan]), "points[1].time_from_start is not finite"),
    (dict(positions=[[0.0] * 7, [0.0, 0.0, 0.0, np.inf, 0.0, 0.0, 0.0]]), "points[1].positions of joint 'e1' is not finite"),
    (dict(positions=[[0.0] * 7, [0.0, 1.7, 0.0, 0.0, 0.0, 0.0, 0.0]]), "joint 's2' = 1.7 rad is beyond its limits"),
    (dict(velocities=[[0.0] * 7, [0.1] + [0.0] * 6]), "the last point is held, so it must come to rest"),
]


@pytest.mark.parametrize("change,message", BAD)
def test_a_wrong_trajectory_is_refused_in_one_line_and_nothing_changes(cfg, change, message):
    arm = cfg.arm
    ref = switchable_reference(cfg, build_reference(cfg))
    before = ref.position(np.arange(2000, 7000))
    kw = {"times": [1.0, 2.0], "positions": np.full((2, len(change.get("names", NAMES))), 0.1), **change}
    traj = _traj(kw["times"], kw["positions"], kw.get("names", NAMES), kw.get("velocities"))
    with pytest.raises(TrajectoryError, match=None) as err:
        ref.start(traj, 2000)
    assert message in str(err.value) and "\n" not in str(err.value), str(err.value)
    assert np.array_equal(ref.position(np.arange(2000, 7000)), before)
    with pytest.raises(TrajectoryError):
        check_trajectory(traj, arm.joint_names, arm.lower_rad, arm.upper_rad)


def test_an_interpolation_beyond_a_limit_is_refused(cfg):
    """Points inside the limits whose quintic leaves them: s2's limit is 1.64 rad; a fast swing to 1.6 rad and
    back, with given velocities that overshoot."""
    ref = switchable_reference(cfg, build_reference(cfg))
    p = np.zeros((3, 7))
    p[1, 1] = 1.6
    v = np.zeros((3, 7))
    v[1, 1] = 3.0
    with pytest.raises(TrajectoryError, match="the interpolation of joint 's2' reaches 1.6"):
        ref.start(_traj([0.5, 1.0, 1.5], p, velocities=v), 0)


def test_every_point_in_the_past_is_refused(cfg):
    ref = switchable_reference(cfg, build_reference(cfg))
    with pytest.raises(TrajectoryError, match="every point lies before step 3000"):
        ref.start(_traj([0.5, 1.0], np.zeros((2, 7))), 3000, origin_s=1.0)


def test_files_yaml_and_json_and_their_mistakes(cfg, tmp_path):
    arm = cfg.arm
    doc = {"joint_names": list(NAMES), "points": [
        {"time_from_start": {"sec": 1, "nanosec": 500000000}, "positions": [0.1] * 7},
        {"time_from_start": 2.0, "positions": [0.2] * 7, "velocities": []}]}
    f = tmp_path / "t.json"
    f.write_text(json.dumps(doc))
    traj = load_trajectory_file(f, arm)
    assert traj.time_from_start_s.tolist() == [1.5, 2.0] and traj.velocities_rad_s is None
    example = load_trajectory_file(EXAMPLE, arm)
    assert len(example.time_from_start_s) == 5 and example.duration_s == 4.0
    for bad, message in [("points: [", "not YAML or JSON at line"),
                         ("joint_names: [s1]\npoints: [{positions: [0]}]", "points[0].time_from_start: missing"),
                         ("joint_names: [s1]\npoints: [{time_from_start: 1, positions: [0], speed: [1]}]",
                          "unknown key 'speed'"),
                         ("[1, 2]", "a trajectory is a mapping"),
                         ("joint_names: [s1, s2]\npoints: [{time_from_start: 1, positions: [0]}]",
                          "points[0].positions: 1 values for 2 joint names")]:
        f.write_text(bad)
        with pytest.raises(ConfigError) as err:
            load_trajectory_file(f, arm)
        assert str(err.value).startswith(f"trajectory {f}: ") and message in str(err.value), str(err.value)
        assert err.value.named({"trajectory": "--trajectory"}).startswith(f"--trajectory {f}: ")  # the command line's form
        assert "\n" not in str(err.value)
    with pytest.raises(ConfigError, match="No such file"):
        load_trajectory_file(tmp_path / "none.yaml", arm)


def test_mapping_velocities_for_some_points_only_is_refused():
    doc = {"joint_names": ["a"], "points": [{"time_from_start": 1, "positions": [0], "velocities": [1]},
                                             {"time_from_start": 2, "positions": [0]}]}
    with pytest.raises(TrajectoryError, match=r"points\[1\].velocities: 0 values for 1 joint names \(given for "
                                              r"every point or none\)"):
        trajectory_from_mapping(doc)


@pytest.mark.parametrize("change, said", [
    (lambda d: d.update({1: "a", "foo": "b"}), "unknown key 'foo' (expected joint_names, points)"),
    (lambda d: d.update({1: "a"}), "unknown key 1 (expected joint_names, points)"),
    (lambda d: d["points"][0].update({1: "a", "foo": "b"}), "points[0]: unknown key 'foo' (expected positions"),
    (lambda d: d["points"][0].update(time_from_start={1: 2, "foo": 3}),
     "points[0].time_from_start: unknown key 'foo' (expected sec, nanosec)"),
    (lambda d: d["points"][0].update(time_from_start={None: 2}),
     "points[0].time_from_start: unknown key None (expected sec, nanosec)"),
])
def test_a_key_that_is_not_a_name_is_one_line(change, said):
    """Keys of mixed types (YAML reads ``1:`` as a number) were a TypeError traceback from sorting them."""
    doc = {"joint_names": ["a"], "points": [{"time_from_start": 1, "positions": [0]}]}
    change(doc)
    with pytest.raises(TrajectoryError) as err:
        trajectory_from_mapping(doc)
    assert str(err.value).startswith(said), str(err.value)

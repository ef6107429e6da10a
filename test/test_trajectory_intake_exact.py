"""The trajectory intake made faster without changing a value: extremum_times' batched companion-matrix
eigenvalues are np.roots' per quintic bit for bit, the limit check still finds the first step beyond as
sampling every step would, and a plain JSON file read by ``json`` gives config_yaml.load_strict's document."""
import json

import numpy as np
import pytest

from long_trajectory import long_trajectory
from pa10_dnbs.config_yaml import load_strict
from pa10_dnbs.controller_factory import build_reference
from pa10_dnbs.core.joint_trajectory import QuinticSpline, TrajectoryError, trajectory_from_mapping
from pa10_dnbs.core.trajectory_reference import extremum_times
from pa10_dnbs.trajectory_file import load_trajectory_file, plain_json

EXAMPLE = "config/trajectory_example.yaml"


def _roots_one_by_one(spline):
    """extremum_times as it was written first (np.roots per segment and joint): the oracle."""
    out = []
    h = np.diff(spline.t)
    for i, hi in enumerate(h):
        scaled = spline.c[:, i, :] * (hi ** np.arange(6))[:, None]
        for j in range(scaled.shape[1]):
            d = np.arange(1, 6) * scaled[1:, j]
            if not np.any(d[1:]):
                continue
            u = np.roots(d[::-1]).real
            u = u[(u >= 0.0) & (u <= 1.0)]
            out.append(spline.t[i] + u * hi)
    return np.concatenate(out) if out else np.empty(0)


def _same_bits(a, b):
    return a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes()


def _spline_of(cfg, mapping):
    return build_reference(cfg, trajectory_from_mapping(mapping))._splines[0]


def test_the_example_and_a_random_trajectory_turn_at_the_same_bits(cfg):
    arm = cfg.arm
    splines = [build_reference(cfg, load_trajectory_file(EXAMPLE, arm))._splines[0]]
    for m, velocities in ((10000, False), (500, True)):
        splines.append(_spline_of(cfg, long_trajectory(arm.joint_names, arm.lower_rad, arm.upper_rad, m, seed=m,
                                                        velocities=velocities)))
    for spline in splines:
        fast = extremum_times(spline)
        assert fast.size > 0 and _same_bits(fast, _roots_one_by_one(spline))


def test_degenerate_quintics_turn_at_the_same_bits():
    """Segments whose derivative has leading zeros (c5 = 0: a quartic, a cubic), trailing zeros (at rest at the
    start: roots at u = 0), a single term, a line (no root), and a single knot."""
    t = np.array([0.0, 1.0, 2.0, 3.0, 4.5, 6.0])
    n = 6
    p = np.zeros((t.size, n))
    v = np.zeros_like(p)
    a = np.zeros_like(p)
    p[:, 0] = [0, 1, 1, 2, 0, 0]                        # rest to rest: only u^2.. terms, trailing zeros
    p[:, 1] = t                                         # a line through every knot: v = 1, no turn
    v[:-1, 1] = 1.0
    p[:, 2] = t ** 3 / 10                               # a cubic met exactly: c4 = c5 = 0
    v[:, 2], a[:, 2] = 3 * t ** 2 / 10, 6 * t / 10
    p[:, 3] = t ** 4 / 100                              # a quartic: c5 = 0
    v[:, 3], a[:, 3] = 4 * t ** 3 / 100, 12 * t ** 2 / 100
    p[:, 4] = t ** 2                                    # a parabola: the derivative is one line, one root or none
    v[:, 4], a[:, 4] = 2 * t, 2.0
    p[:, 5] = [0, 0.5, -0.5, 0.25, 0.25, 0.0]           # mixed
    for spline in (QuinticSpline(t, p, v, a), QuinticSpline(t[:1], p[:1], v[:1], a[:1]),
                   QuinticSpline(t[:2], p[:2], v[:2], a[:2])):
        assert _same_bits(extremum_times(spline), _roots_one_by_one(spline))


@pytest.mark.parametrize("point, joint, dip", [(20, 1, 0.3), (3, 0, 0.05), (45, 6, 1.0), (1, 3, 0.2)])
def test_the_first_step_beyond_a_limit_is_the_one_every_step_finds(cfg, point, joint, dip):
    arm = cfg.arm
    doc = long_trajectory(arm.joint_names, arm.lower_rad, arm.upper_rad, 50, seed=point)
    hi = float(arm.upper_rad[joint])
    doc["points"][point]["positions"][joint] = hi                # at the limit, arriving fast: the quintic overshoots
    doc["points"][point - 1]["positions"][joint] = hi - dip
    doc["points"][point + 1]["positions"][joint] = hi - 1e-3
    traj = trajectory_from_mapping(doc)
    with pytest.raises(TrajectoryError) as err:
        build_reference(cfg, traj)
    # every step of the interpolation, from the reference the check was about to accept
    t = traj.time_from_start_s
    from pa10_dnbs.core.trajectory_reference import TrajectoryReference
    ref = TrajectoryReference(build_reference(cfg), arm.joint_names, arm.lower_rad - 10, arm.upper_rad + 10)
    ref.start(traj, 0)
    k = np.arange(0, int(np.ceil(t[-1] / cfg.simulation.dt_s)) + 2)
    x = ref.position(k)
    beyond = (x < arm.lower_rad) | (x > arm.upper_rad)
    first = int(np.argmax(beyond.any(axis=1)))
    j = int(np.argmax(beyond[first]))
    assert f"joint {arm.joint_names[j]!r} reaches {x[first, j]:.6g} rad at t = {first * 0.001:.3f} s" in str(err.value)


def _typed(x):
    """x with every leaf as (type, repr): -0.0 and 0.0, 1 and 1.0 told apart."""
    if isinstance(x, dict):
        return {k: _typed(v) for k, v in x.items()}
    if isinstance(x, list):
        return [_typed(v) for v in x]
    return type(x).__name__, repr(x)


def test_plain_json_reads_what_the_strict_yaml_reader_reads(cfg):
    arm = cfg.arm
    example = json.dumps(load_strict(open(EXAMPLE, encoding="utf-8").read()), indent=2)
    random = json.dumps(long_trajectory(arm.joint_names, arm.lower_rad, arm.upper_rad, 300, seed=3, velocities=True))
    numbers = ('{"a": [1e5, -0.0, -0, 0, 1E+5, 1.5e3, -1.5E-3, 1e999, -1e999, 5e-324, 1e-400, 0.1, 17, '
               '123456789012345678901234567890, true, false, null], "b": {"<<": "x # y", "c": []}, "d": {}}')
    for text in (example, random, numbers, ' \r\n{"a": 1}\r\n', "[]", '"x"', "1"):
        got = plain_json(text)
        assert got is not None and _typed(got) == _typed(load_strict(text)), text[:60]


@pytest.mark.parametrize("text", ['{"a": 1, "a": 2}', '{"a": {"b": 1, "b": 1}}', '{"a": NaN}', '{"a": -Infinity}',
                                  "[" * 5000 + "]" * 5000, '{"a": ' + "1" * 5000 + "}", '{"a": "\\u00e9"}',
                                  '{"a": "x\ty"}', '{"a": "\x7f"}', '{"a": 1} x', "", "a: 1", '\ufeff{"a": 1}'])
def test_what_plain_json_leaves_to_the_strict_yaml_reader(text):
    """A key given twice, NaN, nesting past the recursion limit, a 5000-digit integer, an escape, a tab in a string
    (a tab between tokens is JSON's whitespace: test_trajectory_misuse.py), DEL,
    not JSON: the strict YAML reader reads it (or says what is wrong in its one line), as before."""
    assert plain_json(text) is None


def test_a_long_yaml_file_is_announced_and_plain_json_is_not(cfg, tmp_path, monkeypatch):
    import yaml

    import pa10_dnbs.trajectory_file as trajectory_file
    arm = cfg.arm
    doc = long_trajectory(arm.joint_names, arm.lower_rad, arm.upper_rad, 40, seed=2)
    monkeypatch.setattr(trajectory_file, "SAY_YAML_BYTES", 1000)
    said = []
    for suffix, text in (("yaml", yaml.safe_dump(doc)), ("json", json.dumps(doc))):
        path = tmp_path / f"t.{suffix}"
        path.write_text(text)
        traj = load_trajectory_file(path, arm, say=said.append)
        assert traj.positions_rad.shape == (40, 7)
    assert len(said) == 1 and said[0].startswith(f"trajectory {tmp_path / 't.yaml'}: 0 MB of YAML")

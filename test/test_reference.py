"""Reference of eq. 27 / Table 1: values, envelope, analytic velocity, k+2 preview."""
import math

import numpy as np

from pa10_dnbs.controller_factory import build_reference


def test_values_match_eq27(cfg):
    ref = build_reference(cfg)
    c, d, w = (np.array(cfg["reference"][k]) for k in ("amplitude_rad", "envelope_rate_per_s3", "frequency_rad_s"))
    for k in (0, 1, 1234, 7000, 19999):
        t = k * 1e-3
        np.testing.assert_allclose(ref.position(k), c * (1 - np.exp(-d * t**3)) * np.sin(w * t), rtol=1e-14, atol=0)
    assert np.all(ref.position(0) == 0.0)


def test_table1_constants(cfg):
    ref = build_reference(cfg)
    np.testing.assert_allclose(ref.c, [math.pi / 2, math.pi / 3] * 3 + [math.pi / 2])
    np.testing.assert_allclose(ref.w, [0.285, 0.435, 0.555, 0.645, 0.345, 0.615, 0.465])


def test_envelope_reaches_95_percent_at_documented_times(cfg):
    # 1 - exp(-d t^3) = 0.95  ->  t = (ln 20 / d)^(1/3): 14.4 s for d = 0.001, 6.7 s for d = 0.01
    for d, t95 in ((1e-3, 14.4), (1e-2, 6.7)):
        assert abs((math.log(20) / d) ** (1 / 3) - t95) < 0.05


def test_velocity_is_derivative_of_position(cfg):
    ref = build_reference(cfg)
    k = np.arange(100, 19000, 977)
    fd = (ref.position(k + 1) - ref.position(k - 1)) / (2 * ref.dt_s)
    np.testing.assert_allclose(ref.velocity(k), fd, atol=1e-6)


def test_sample_carries_k_plus_2_preview(cfg):
    ref = build_reference(cfg)
    s = ref.sample(3, 5000)
    assert s.position_rad == ref.position(5000)[3]
    assert s.position_ahead_rad == ref.position(5002)[3]
    assert s.velocity_rad_s == ref.velocity(5000)[3]
    assert [x.position_ahead_rad for x in ref.samples(5000)] == list(ref.position(5002))

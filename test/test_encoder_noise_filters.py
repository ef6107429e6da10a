"""scripts/encoder_noise_filters.py's parts: the Kalman gain is the Riccati recursion's fixed point, and the
filter with gain 1 and no low-pass hands the controllers what was measured (to rounding)."""
import numpy as np
from script_module import load_script

S = load_script("encoder_noise_filters")


def test_gain_is_the_fixed_point_of_the_scalar_riccati_recursion():
    dt, sq, sv = 1e-3, 1e-4, 1e-3
    p = 1.0
    for _ in range(100000):   # prior variance: predict after the update
        p = p - p * p / (p + sq * sq) + (dt * sv) ** 2
    assert abs(S.kalman_gain(dt, sq, sv) - p / (p + sq * sq)) < 1e-9
    assert 0.0099 < S.kalman_gain(dt, sq, sv) < 0.0101


class _Echo:
    controllers = None

    def step(self, x1, x2, reference):
        return x1, x2


def test_gain_one_without_low_pass_passes_the_measurement_through():
    f = S.FilteredLoop(_Echo(), 1e-3, 1.0, None)
    rng = np.random.default_rng(0)
    for _ in range(5):
        x1, x2 = rng.normal(size=3), rng.normal(size=3)
        q, v = f.step(x1, x2, None)
        assert np.allclose(q, x1, rtol=0, atol=1e-14) and np.allclose(v, x2, rtol=0, atol=1e-14)


def test_the_filter_smooths_position_noise():
    f = S.FilteredLoop(_Echo(), 1e-3, S.kalman_gain(1e-3, 1e-4, 1e-3), None)
    rng = np.random.default_rng(1)
    q = [f.step(rng.normal(0.0, 1e-4, 1), rng.normal(0.0, 1e-3, 1), None)[0][0] for _ in range(5000)]
    assert np.std(q[1000:]) < 0.3e-4   # about 1e-5 (the filter's steady state), against 1e-4 measured

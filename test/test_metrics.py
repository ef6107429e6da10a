"""Per-joint metrics over a window."""
import numpy as np
import pytest

from pa10_dnbs.core.metrics import joint_metrics, window_slice


def test_window_and_values():
    dt = 0.5
    err = np.zeros((10, 2))
    err[4:8, 0] = [1.0, -1.0, 1.0, -1.0]  # t = 2.0 .. 3.5 s
    err[2, 1] = 5.0  # t = 1.0 s, outside the window
    tau = np.array([[10.0, 1.0]] * 10)
    tau[3, 0] = -20.0
    m = joint_metrics(err, tau, [20.0, 2.0], dt, (2.0, 4.0))
    assert window_slice(10, dt, (2.0, 4.0)) == slice(4, 8)
    assert m[0]["rms_error_rad"] == pytest.approx(1.0)
    assert m[0]["max_abs_error_rad"] == 1.0
    assert m[1]["rms_error_rad"] == 0.0
    assert m[0]["max_abs_torque_nm"] == 20.0
    assert m[0]["saturated_fraction"] == pytest.approx(0.1)
    assert m[1]["saturated_fraction"] == 0.0


def test_empty_window_is_an_error():
    with pytest.raises(ValueError, match="no sample"):
        window_slice(10, 1e-3, (5.0, 6.0))


def test_run_metrics_by_hand():
    from pa10_dnbs.core.metrics import run_metrics

    dt = 0.1
    err = np.zeros((10, 3))
    err[:4, 0] = [0.3, -0.2, 0.05, 0.011]   # outside the 0.01 band up to t = 0.3 s: settled from 0.4 s
    err[:, 1] = 0.001                        # never outside: 0.0
    err[-1, 2] = 0.5                         # outside at the last sample: not settled
    tau = np.zeros((10, 3))
    tau[:, 0] = [10, -10, 10, 0, 0, 0, 0, 0, 0, 10]   # |d tau| sums to 20 + 20 + 10 + 10 = 60 N m
    tau[2:, 2] = 5.0                                   # at the 5 N m limit from t = 0.2 s
    m = run_metrics(err, tau, [10.0, 1.0, 5.0], dt, settle_band_rad=0.01, startup_s=0.2)
    assert [x["settling_time_s"] for x in m] == [pytest.approx(0.4), 0.0, None]
    assert m[0]["max_abs_error_run_rad"] == 0.3 and m[2]["max_abs_error_run_rad"] == 0.5
    assert m[0]["torque_variation"] == pytest.approx(6.0) and m[2]["torque_variation"] == pytest.approx(1.0)
    # steps k >= 2 (t >= 0.2 s): joint 0 at +-10 at k = 2 and 9 (2 of 8); joint 2 at the limit on all 8
    assert m[0]["saturated_fraction_after_s"] == pytest.approx(2 / 8)
    assert m[2]["saturated_fraction_after_s"] == 1.0 and m[1]["saturated_fraction_after_s"] == 0.0

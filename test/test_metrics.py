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

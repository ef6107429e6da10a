"""In-process closed loop on the PyBullet plant: bounded, converging, within Table 2."""
import numpy as np
import pytest

from pa10_dnbs.sim.closed_loop import simulate


@pytest.fixture(scope="module")
def dnbs_6s(_default_cfg):
    return simulate(_default_cfg, "dnbs", 6.0)


def test_dnbs_short_run_is_bounded_and_error_shrinks(dnbs_6s):
    run = dnbs_6s
    err = np.abs(run.error_rad)
    assert np.all(np.isfinite(run.position_rad)) and np.all(np.isfinite(run.torque_nm))
    assert err.max() < 0.5  # bounded through the learning transient
    early = err[:1000].max(axis=0)   # t in [0, 1) s: starts 0.1 rad off
    late = err[5000:].max(axis=0)    # t in [5, 6) s
    assert np.all(late < early / 5), (early, late)
    assert np.all(late < 0.02)


def test_torques_within_table2(dnbs_6s):
    assert np.all(np.abs(dnbs_6s.torque_nm) <= dnbs_6s.torque_limit_nm + 1e-12)


def test_deterministic(_default_cfg, dnbs_6s):
    again = simulate(_default_cfg, "dnbs", 1.0)
    np.testing.assert_array_equal(again.position_rad, dnbs_6s.position_rad[:1000])
    np.testing.assert_array_equal(again.torque_nm, dnbs_6s.torque_nm[:1000])


def test_pid_baseline_tracks(_default_cfg):
    run = simulate(_default_cfg, "pid", 3.0)
    assert np.abs(run.error_rad[2000:]).max() < 0.01

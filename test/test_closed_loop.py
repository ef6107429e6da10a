"""In-process closed loop on the PyBullet plant: the DNBS must-targets of the default config, determinism,
the PID and computed-torque baselines, warm starts and the in-process disturbances."""
import numpy as np
import pytest

from pa10_dnbs.core.metrics import run_metrics
from pa10_dnbs.report.metrics_file import metrics_dict, metrics_settings
from pa10_dnbs.sim.closed_loop import Disturbances, simulate


@pytest.fixture(scope="module")
def dnbs_20s(_default_cfg):
    return simulate(_default_cfg, "dnbs", 20.0)


def test_default_dnbs_meets_the_must_targets_on_every_joint(dnbs_20s, _default_cfg):
    """Cold start, random seeded weights: the targets of the controller's specification (docs/controller.md)."""
    m = metrics_dict(dnbs_20s, metrics_settings(_default_cfg, 20.0))
    err = np.abs(dnbs_20s.error_rad)
    assert err[1000:].max() < 1e-2, "every |e| below 1e-2 rad from t = 1.0 s on"
    assert m["worst_max_abs_error_run_rad"] <= 0.12
    assert m["worst_torque_variation"] <= 10.0
    assert m["worst_saturated_fraction_after_s"] == 0.0, "no step at the torque limit after 0.2 s"
    assert m["worst_rms_error_rad"] <= 6e-4, "RMS over [10, 20) s"
    assert m["all_finite"] and m["torques_within_limits"]


def test_deterministic(_default_cfg, dnbs_20s):
    again = simulate(_default_cfg, "dnbs", 1.0)
    np.testing.assert_array_equal(again.position_rad, dnbs_20s.position_rad[:1000])
    np.testing.assert_array_equal(again.torque_nm, dnbs_20s.torque_nm[:1000])


@pytest.mark.parametrize("kind", ["pid", "ctc"])
def test_baselines_track(_default_cfg, kind):
    run = simulate(_default_cfg, kind, 3.0)
    assert np.abs(run.error_rad[2000:]).max() < 0.01
    assert np.all(np.abs(run.torque_nm) <= run.torque_limit_nm + 1e-12)


def test_warm_start_from_a_trained_controller_starts_without_a_transient(_default_cfg, dnbs_20s):
    """Weights and P of the end of a 20 s run: the next run's first second has no learning transient."""
    bank = dnbs_20s.extra["controllers"]
    states = [bank.state_dict(row) for row in range(7)]
    warm = simulate(_default_cfg, "dnbs", 1.0, init_states=states)
    cold = dnbs_20s
    tv = lambda r: run_metrics(r.error_rad, r.torque_nm, r.torque_limit_nm, r.dt_s, 0.01, 0.2)  # noqa: E731
    assert not np.array_equal(warm.torque_nm, cold.torque_nm[:1000])
    # the same initial offset, but the learned feed-forward and gravity terms are already there
    assert np.abs(warm.error_rad[500:1000]).max() < np.abs(cold.error_rad[500:1000]).max()
    assert max(j["torque_variation"] for j in tv(warm)) < 10.0


def test_disturbances_sensor_noise_and_torque_delay(_default_cfg):
    base = simulate(_default_cfg, "pid", 0.3)
    delayed = simulate(_default_cfg, "pid", 0.3, disturbances=Disturbances(torque_delay_steps=1))
    assert np.array_equal(delayed.torque_nm[0], np.zeros(7))         # nothing has arrived at step 0
    assert np.array_equal(delayed.torque_nm[1], base.torque_nm[0])   # the answer to state 0, one step late
    noisy = simulate(_default_cfg, "pid", 0.3, disturbances=Disturbances(1e-4, 1e-3, 0, seed=3))
    again = simulate(_default_cfg, "pid", 0.3, disturbances=Disturbances(1e-4, 1e-3, 0, seed=3))
    assert np.array_equal(noisy.torque_nm, again.torque_nm) and not np.array_equal(noisy.torque_nm, base.torque_nm)

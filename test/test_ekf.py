"""EKF training step (eq. 7-9, 13-16) against a hand-computed case, and P's invariants."""
import numpy as np
import pytest

from pa10_dnbs.core.ekf import EKFParams, EKFTrainer


def test_step_matches_hand_computed_case():
    # L = 2, P = diag(2, 1), H = [1, 2], R = 1, eta = 0.5, Q = 0.1 I, e = 0.4, w = [1, -1].
    # PH = [2, 2]; H^T P H = 1*2 + 2*2 = 6; M = 1/(1+6) = 1/7; K = [2/7, 2/7]
    # w+ = w + 0.5 * K * 0.4 = [1 + 0.4/7, -1 + 0.4/7]
    # P+ = P - K H^T P + Q = [[2 - 4/7 + .1, -4/7], [-4/7, 1 - 4/7 + .1]]
    ekf = EKFTrainer(np.array([1.0, -1.0]), EKFParams(p0=1.0, q=0.1, r=1.0, eta=0.5))
    ekf.P[:] = np.diag([2.0, 1.0])
    g = ekf.update(np.array([1.0, 2.0]), 0.4)
    np.testing.assert_allclose(ekf.w, [1 + 0.4 / 7, -1 + 0.4 / 7], rtol=0, atol=1e-15)
    np.testing.assert_allclose(ekf.P, [[2 - 4 / 7 + 0.1, -4 / 7], [-4 / 7, 1 - 4 / 7 + 0.1]], atol=1e-15)
    assert g == pytest.approx(6 / 7)


def test_matches_textbook_matrix_form():
    rng = np.random.default_rng(3)
    p = EKFParams(p0=5.0, q=1e-3, r=0.7, eta=0.8)
    ekf = EKFTrainer(rng.normal(size=6), p)
    for _ in range(50):
        H, e = rng.normal(size=6), rng.normal()
        P, w = ekf.P.copy(), ekf.w.copy()
        M = np.linalg.inv(p.r + H[None, :] @ P @ H[:, None])
        K = P @ H[:, None] @ M
        w_ref = w + p.eta * (K * e).ravel()
        P_ref = P - K @ H[None, :] @ P + p.q * np.eye(6)
        ekf.update(H, e)
        np.testing.assert_allclose(ekf.w, w_ref, rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(ekf.P, P_ref, rtol=1e-12, atol=1e-12)


def test_P_stays_exactly_symmetric_and_positive_definite():
    rng = np.random.default_rng(11)
    ekf = EKFTrainer(np.zeros(10), EKFParams(p0=10.0, q=1e-2, r=1.0, eta=1.0))
    for _ in range(20000):
        ekf.update(np.tanh(rng.normal(size=10)), rng.normal())
    assert np.array_equal(ekf.P, ekf.P.T)
    assert np.all(np.linalg.eigvalsh(ekf.P) > 0)
    assert np.all(np.isfinite(ekf.w))


@pytest.mark.parametrize("field,value", [("p0", 0.0), ("r", -1.0), ("eta", float("nan")), ("q", -1e-3)])
def test_bad_params_are_rejected(field, value):
    kw = dict(p0=1.0, q=0.0, r=1.0, eta=1.0)
    kw[field] = value
    with pytest.raises(ValueError, match=rf"EKF parameter {field} must"):
        EKFParams(**kw)

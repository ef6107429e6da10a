"""EKF training step (eq. 7-9, 13-16) against a hand-computed case, P's invariants, rows, the covariance bound."""
import numpy as np
import pytest

from pa10_dnbs.core.ekf import EKFBank

ONE = np.ones(1)


def test_step_matches_hand_computed_case():
    # L = 2, P = diag(2, 1), H = [1, 2], R = 1, eta = 0.5, Q = 0.1 I, e = 0.4, w = [1, -1].
    # PH = [2, 2]; H^T P H = 1*2 + 2*2 = 6; M = 1/(1+6) = 1/7; K = [2/7, 2/7]
    # w+ = w + 0.5 * K * 0.4 = [1 + 0.4/7, -1 + 0.4/7]
    # P+ = P - K H^T P + Q = [[2 - 4/7 + .1, -4/7], [-4/7, 1 - 4/7 + .1]]
    ekf = EKFBank([[1.0, -1.0]], p0=1.0, q=0.1, r=1.0, eta=0.5)
    ekf.P[0] = np.diag([2.0, 1.0])
    g = ekf.update(np.array([[1.0, 2.0]]), np.array([0.4]), ekf.eta, ONE)
    np.testing.assert_allclose(ekf.w[0], [1 + 0.4 / 7, -1 + 0.4 / 7], rtol=0, atol=1e-15)
    np.testing.assert_allclose(ekf.P[0], [[2 - 4 / 7 + 0.1, -4 / 7], [-4 / 7, 1 - 4 / 7 + 0.1]], atol=1e-15)
    assert g[0] == pytest.approx(6 / 7)


def test_matches_textbook_matrix_form_row_by_row():
    rng = np.random.default_rng(3)
    p0, q, r, eta = np.array([5.0, 1.0, 2.0]), 1e-3, np.array([0.7, 1.0, 3.0]), np.array([0.8, 1.0, 0.3])
    ekf = EKFBank(rng.normal(size=(3, 6)), p0, q, r, eta)
    for _ in range(50):
        H, e = rng.normal(size=(3, 6)), rng.normal(size=3)
        P, w = ekf.P.copy(), ekf.w.copy()
        ekf.update(H, e, eta, np.ones(3))
        for i in range(3):
            M = np.linalg.inv(r[i] + H[i][None, :] @ P[i] @ H[i][:, None])
            K = P[i] @ H[i][:, None] @ M
            np.testing.assert_allclose(ekf.w[i], w[i] + eta[i] * (K * e[i]).ravel(), rtol=1e-12, atol=1e-12)
            np.testing.assert_allclose(ekf.P[i], P[i] - K @ H[i][None, :] @ P[i] + q * np.eye(6), rtol=1e-12,
                                       atol=1e-12)


def test_P_stays_exactly_symmetric_and_positive_definite():
    rng = np.random.default_rng(11)
    ekf = EKFBank(np.zeros((2, 10)), p0=10.0, q=1e-2, r=1.0, eta=1.0)
    for _ in range(20000):
        ekf.update(np.tanh(rng.normal(size=(2, 10))), rng.normal(size=2), ekf.eta, np.ones(2))
    assert np.array_equal(ekf.P, ekf.P.transpose(0, 2, 1))
    assert np.all(np.linalg.eigvalsh(ekf.P) > 0)
    assert not ekf.unhealthy(full=True).any()


def test_an_inactive_row_is_left_alone_and_the_others_are_not_disturbed():
    rng = np.random.default_rng(2)
    ekf = EKFBank(rng.normal(size=(3, 4)), p0=1.0, q=0.01, r=1.0, eta=1.0)
    ref = EKFBank(ekf.w0.copy(), p0=1.0, q=0.01, r=1.0, eta=1.0)
    H, e = rng.normal(size=(3, 4)), rng.normal(size=3)
    w1, P1 = ekf.w[1].copy(), ekf.P[1].copy()
    ekf.update(H, e, ekf.eta, np.array([1.0, 0.0, 1.0]))
    ref.update(H, e, ref.eta, np.ones(3))
    assert np.array_equal(ekf.w[1], w1) and np.array_equal(ekf.P[1], P1)
    for i in (0, 2):
        assert np.array_equal(ekf.w[i], ref.w[i]) and np.array_equal(ekf.P[i], ref.P[i])


def test_covariance_bound_stops_q_from_winding_up_p():
    """Unexcited directions (H = 0 there) grow by q per step without the bound, never past p_max with it."""
    H = np.array([[1.0, 0.0, 0.0]])
    free = EKFBank(np.zeros((1, 3)), p0=1.0, q=0.01, r=1.0, eta=1.0)
    bound = EKFBank(np.zeros((1, 3)), p0=1.0, q=0.01, r=1.0, eta=1.0, p_max=2.0)
    for _ in range(1000):
        free.update(H, np.array([0.1]), free.eta, ONE)
        bound.update(H, np.array([0.1]), bound.eta, ONE)
    assert free.P[0, 1, 1] == pytest.approx(1.0 + 1000 * 0.01)
    assert 1.99 <= bound.P[0, 1, 1] <= 2.0 + 0.01 and np.diag(bound.P[0]).max() <= 2.01


def test_guard_finds_the_broken_row_and_reset_restores_it():
    ekf = EKFBank(np.full((2, 3), 0.01), p0=1.0, q=0.01, r=1.0, eta=1.0)
    H = np.full((2, 3), 0.5)
    ekf.update(H, np.array([0.3, 0.3]), ekf.eta, np.ones(2))
    assert not ekf.unhealthy(full=True).any()
    ekf.P[1, 0, 2] = ekf.P[1, 2, 0] = np.nan
    ekf.update(H, np.array([0.3, 0.3]), ekf.eta, np.ones(2))
    assert ekf.unhealthy(full=False).tolist() == [False, True]  # NaN reaches H^T P H and w at once
    ekf.reset(np.array([False, True]))
    assert not ekf.unhealthy(full=True).any() and np.array_equal(ekf.w[1], ekf.w0[1])
    ekf.P[0, 0, 0] = -5.0  # symmetric, finite, not positive definite: only the full check sees it
    assert ekf.unhealthy(full=True).tolist() == [True, False] and not ekf.unhealthy(full=False).any()


@pytest.mark.parametrize("field,value,match", [("p0", 0.0, "p0"), ("r", -1.0, "r"), ("eta", float("nan"), "eta"),
                                               ("q", -1e-3, "q"), ("eta", 1.5, r"eta must be in \(0, 1\]")])
def test_bad_params_are_rejected(field, value, match):
    kw = dict(p0=1.0, q=0.0, r=1.0, eta=1.0)
    kw[field] = value
    with pytest.raises(ValueError, match=f"EKF parameter {match}"):
        EKFBank(np.zeros((1, 2)), **kw)

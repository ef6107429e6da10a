"""HONN of eq. 3-4: the regressor, H = dphi/dw by finite differences, and rows that never mix."""
import numpy as np
import pytest

from pa10_dnbs.core.honn import HONN, monomial_exponents


def test_monomials_up_to_degree_two_of_three_inputs():
    e = monomial_exponents(3, 2)
    assert e.shape == (10, 3)
    assert e[0].tolist() == [0, 0, 0]  # bias first
    assert {tuple(r) for r in e} == {r for r in np.ndindex(3, 3, 3) if sum(r) <= 2}


def test_regressor_is_product_of_tanh_powers():
    net = HONN([[0, 0], [1, 0], [0, 1], [2, 1], [0, 3]], input_scale=[2.0, 0.5])
    z = np.array([[0.7, -0.3]])
    s = np.tanh(z[0] / [2.0, 0.5])
    np.testing.assert_allclose(net.regressor(z)[0], [1, s[0], s[1], s[0] ** 2 * s[1], s[1] ** 3], rtol=1e-15)


def _phi_eq3(w, z, exponents, scale):
    """phi(w, z) of eq. 3 written out term by term, independently of HONN.regressor."""
    total = 0.0
    for wi, d in zip(w, exponents):
        term = 1.0
        for zj, sj, dj in zip(z, scale, d):
            term *= np.tanh(zj / sj) ** dj
        total += wi * term
    return total


@pytest.mark.parametrize("degree", [1, 2, 3])
def test_H_equals_finite_difference_of_output(degree):
    # H (the regressor the EKF uses) against d phi / d w by central differences of eq. 3 itself.
    rng = np.random.default_rng(degree)
    scale = [3.0, 2.0, 0.5]
    net = HONN(monomial_exponents(3, degree), input_scale=scale)
    w = rng.normal(size=net.n_terms)
    z = rng.normal(size=3)
    h = 1e-6
    fd = np.array([(_phi_eq3(w + h * e, z, net.exponents, scale) - _phi_eq3(w - h * e, z, net.exponents, scale))
                   / (2 * h) for e in np.eye(net.n_terms)])
    S = net.regressor(z[None, :])[0]
    np.testing.assert_allclose(S, fd, rtol=1e-7, atol=1e-9)
    assert float(w @ S) == pytest.approx(_phi_eq3(w, z, net.exponents, scale), rel=1e-12)


def test_each_row_is_its_own_joint_bit_for_bit():
    """A bank of seven rows gives each row exactly what a bank of one gives it (decentralization)."""
    rng = np.random.default_rng(5)
    net = HONN(monomial_exponents(3, 2), input_scale=[3.0, 3.0, 3.0])
    z = rng.normal(size=(7, 3))
    together = net.regressor(z).copy()
    alone = HONN(monomial_exponents(3, 2), input_scale=[3.0, 3.0, 3.0])
    for i in range(7):
        assert np.array_equal(alone.regressor(z[i:i + 1])[0], together[i])


def test_bad_input_shape_is_rejected():
    with pytest.raises(ValueError, match=r"shape \(n, 2\)"):
        HONN(monomial_exponents(2, 2), [3.0, 3.0]).regressor(np.zeros(2))

"""The padded row layout that lets both networks train in one EKF bank: numpy's summation order, and the bits."""
from math import comb

import numpy as np
import pytest

from pa10_dnbs.core.padded_layout import shared_width, summation_tree


def _evaluate(tree, values):
    """The float the symbolic sum ``tree`` gives for ``values`` (None = 0.0), in its order."""
    if tree is None:
        return 0.0
    if isinstance(tree, int):
        return values[tree]
    return _evaluate(tree[0], values) + _evaluate(tree[1], values)


@pytest.mark.parametrize("n", [1, 2, 6, 7, 8, 9, 10, 12, 15, 16, 17, 35, 128, 129, 300])
def test_the_summation_model_is_numpys_own_order(n):
    rng = np.random.default_rng(n)
    tree = summation_tree(tuple(range(n)))
    for _ in range(200):
        # magnitudes over 16 decades: a different order of the same numbers almost surely changes the bits
        x = rng.normal(size=n) * 10.0 ** rng.uniform(-8, 8, size=n)
        assert _evaluate(tree, x.tolist()) == np.add.reduce(x)
        assert _evaluate(tree, x.tolist()) == np.add.reduce(x[None, None, :], axis=2)[0, 0]


DEGREES = range(5)  # config.py allows max_degree 0..4 for both networks


@pytest.mark.parametrize("alpha_degree", DEGREES)
@pytest.mark.parametrize("torque_degree", DEGREES)
def test_every_allowed_pair_of_networks_shares_a_row_with_its_own_bits(alpha_degree, torque_degree):
    lengths = (comb(2 + alpha_degree, 2), comb(3 + torque_degree, 3))  # 2 and 3 inputs
    layout = shared_width(lengths)
    assert layout is not None
    width, offsets = layout
    rng = np.random.default_rng(sum(lengths))
    for length, offset in zip(lengths, offsets):
        assert 0 <= offset and offset + length <= width
        own = rng.normal(size=(50, length)) * 10.0 ** rng.uniform(-8, 8, size=(50, length))
        padded = np.zeros((50, width))
        padded[:, offset:offset + length] = own
        assert np.add.reduce(padded, axis=1).tobytes() == np.add.reduce(own, axis=1).tobytes()


@pytest.mark.parametrize("n", [1, 5, 7, 8, 12, 20])
def test_a_sum_of_negative_zeros_is_positive_zero_padded_or_not(n):
    """Padding adds +0.0, which turns -0.0 into +0.0: harmless only because numpy's reduce starts from +0.0."""
    assert np.add.reduce(np.full(n, -0.0)).tobytes() == np.float64(0.0).tobytes()
    assert np.add.reduce(np.full((2, n), -0.0), axis=1).tobytes() == np.zeros(2).tobytes()


def test_a_careless_offset_changes_the_bits():
    """The reason for the search: six numbers at the start of a 12-wide row are added in another order."""
    assert shared_width((6, 10)) == (12, (6, 0))
    rng = np.random.default_rng(0)
    own = rng.normal(size=(200, 6)) * 10.0 ** rng.uniform(-8, 8, size=(200, 6))
    padded = np.zeros((200, 12))
    padded[:, :6] = own
    assert np.add.reduce(padded, axis=1).tobytes() != np.add.reduce(own, axis=1).tobytes()


@pytest.mark.parametrize("alpha_degree, torque_degree", [(0, 0), (1, 4), (2, 2), (3, 1), (4, 4)])
def test_one_padded_bank_trains_two_networks_as_two_banks_do_bit_for_bit(alpha_degree, torque_degree):
    """The DNBS layout: alpha and torque networks of 3 joints in one padded bank (default degrees: 6 and 10
    weights in a 12-wide row)."""
    from pa10_dnbs.core.ekf import EKFBank

    rng = np.random.default_rng(7)
    n, (la, lt) = 3, (comb(2 + alpha_degree, 2), comb(3 + torque_degree, 3))
    width, (oa, ot) = shared_width((la, lt))
    wa, wt = rng.normal(size=(n, la)), rng.normal(size=(n, lt))
    alone_a = EKFBank(wa, p0=1.0, q=0.01, r=1.0, eta=1.0, p_max=10.0)
    alone_t = EKFBank(wt, p0=2.0, q=0.02, r=0.5, eta=1.0, p_max=10.0)
    w0 = np.zeros((2 * n, width))
    w0[:n, oa:oa + la], w0[n:, ot:ot + lt] = wa, wt
    both = EKFBank(w0, p0=[1.0] * n + [2.0] * n, q=[0.01] * n + [0.02] * n, r=[1.0] * n + [0.5] * n,
                   eta=1.0, p_max=10.0)
    H = np.zeros((2 * n, width))
    for k in range(300):
        Ha, Ht = np.tanh(rng.normal(size=(n, la))), np.tanh(rng.normal(size=(n, lt)))
        ea, et = rng.normal(size=n), rng.normal(size=n)
        eta = np.full(n, min(1.0, k / 100))
        act = (rng.random(n) > 0.1).astype(float)
        alone_a.update(Ha, ea, eta, act)
        alone_t.update(Ht, et, eta, act)
        H[:n, oa:oa + la], H[n:, ot:ot + lt] = Ha, Ht
        both.update(H, np.concatenate([ea, et]), np.concatenate([eta, eta]), np.concatenate([act, act]))
    assert both.w[:n, oa:oa + la].tobytes() == alone_a.w.tobytes()
    assert both.w[n:, ot:ot + lt].tobytes() == alone_t.w.tobytes()
    assert both.P[:n, oa:oa + la, oa:oa + la].tobytes() == alone_a.P.tobytes()
    assert both.P[n:, ot:ot + lt, ot:ot + lt].tobytes() == alone_t.P.tobytes()
    pad_a = np.ones(width, bool)
    pad_a[oa:oa + la] = False
    pad_t = np.ones(width, bool)
    pad_t[ot:ot + lt] = False
    assert not both.w[:n, pad_a].any() and not both.w[n:, pad_t].any()  # the padding stays exact zeros

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
        assert np.array_equal(np.add.reduce(padded, axis=1), np.add.reduce(own, axis=1))


def test_a_careless_offset_changes_the_bits():
    """The reason for the search: six numbers at the start of a 12-wide row are added in another order."""
    assert shared_width((6, 10)) == (12, (6, 0))
    rng = np.random.default_rng(0)
    own = rng.normal(size=(200, 6)) * 10.0 ** rng.uniform(-8, 8, size=(200, 6))
    padded = np.zeros((200, 12))
    padded[:, :6] = own
    assert not np.array_equal(np.add.reduce(padded, axis=1), np.add.reduce(own, axis=1))

"""Where networks of different sizes sit in one zero-padded array so that every sum over weights keeps its bits.

The DNBS step trains both of a joint's networks (L_alpha and L_torque
weights) in one EKF bank of width W >= both, each network in a block of
its row, the rest exact zeros. Every sum over weights (w^T H, P H, H^T P H)
is a numpy ``add.reduce`` along the row, and numpy adds a contiguous row
pairwise (``pairwise_sum`` in numpy/_core/src/umath/loops_utils.h.src):
fewer than 8 numbers one after the other from 0.0, up to 128 in 8
interleaved partial sums added as a tree, more in halves. So a row's bits
depend on where its numbers sit. ``shared_width`` finds the narrowest W, and
each network's offset, at which the padded sum adds the network's own
numbers in exactly the order its unpadded sum does, so the padded bank
gives the same bits as one bank per network. Adding a padding +0.0 leaves
every x as it is but -0.0, which it turns into +0.0; a partial sum can only
be -0.0 if the whole sum is a zero, and numpy's reduce starts from +0.0, so
the whole sum is +0.0 either way (test_padded_layout pins this).
(test/test_padded_layout.py checks the orders against numpy itself.)
"""
from __future__ import annotations

from functools import lru_cache

_ZERO = None  # a padding slot: exact +0.0


def _add(a, b):
    """The symbolic sum a + b, with 0.0 + x = x."""
    if a is _ZERO:
        return b
    if b is _ZERO:
        return a
    return (a, b)


def summation_tree(items: tuple) -> object:
    """The order in which numpy's ``add.reduce`` adds the contiguous row ``items`` (nested pairs; _ZERO = 0.0)."""
    n = len(items)
    if n < 8:
        res = _ZERO
        for x in items:
            res = _add(res, x)
        return res
    if n <= 128:
        r = list(items[:8])
        i = 8
        while i < n - n % 8:
            for j in range(8):
                r[j] = _add(r[j], items[i + j])
            i += 8
        res = _add(_add(_add(r[0], r[1]), _add(r[2], r[3])), _add(_add(r[4], r[5]), _add(r[6], r[7])))
        for x in items[i:]:
            res = _add(res, x)
        return res
    half = n // 2
    half -= half % 8
    return _add(summation_tree(items[:half]), summation_tree(items[half:]))


def _keeps_order(length: int, width: int, offset: int) -> bool:
    own = tuple(range(length))
    padded = (_ZERO,) * offset + own + (_ZERO,) * (width - offset - length)
    return summation_tree(padded) == summation_tree(own)


@lru_cache(maxsize=None)
def shared_width(lengths: tuple[int, ...], max_width: int = 256) -> tuple[int, tuple[int, ...]] | None:
    """(W, offsets): the narrowest width at which every length has an offset that keeps its summation order
    (the lowest such offset each); None when there is none up to ``max_width``."""
    for width in range(max(lengths), max_width + 1):
        offsets = []
        for length in lengths:
            found = next((o for o in range(width - length + 1) if _keeps_order(length, width, o)), None)
            if found is None:
                break
            offsets.append(found)
        else:
            return width, tuple(offsets)
    return None

"""`stabctl._jit.borrow.borrowed`: the same views without a reference count."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit

from stabctl._jit.borrow import borrowed


class _Pair(NamedTuple):
    a: np.ndarray
    n: int
    inner: tuple


@njit
def _scale_through_borrowed(pair, factor):
    b = borrowed(pair)
    for j in range(b.a.size):
        b.a[j] *= factor
    x, y = b.inner
    x[0, 1] = b.n
    return b.a.sum() + y


def test_borrowed_views_share_the_data_and_keep_other_values():
    a = np.arange(4.0)
    m = np.zeros((2, 3))
    pair = _Pair(a, 7, (m, 2.5))
    total = _scale_through_borrowed(pair, 3.0)
    assert np.array_equal(a, [0.0, 3.0, 6.0, 9.0])  # written through the borrowed view
    assert m[0, 1] == 7.0  # nested tuple members borrowed too
    assert total == 18.0 + 2.5  # scalars pass unchanged


@njit
def _column_sum(x):
    xb = borrowed(x)
    return xb.reshape(2, 3)[:, 1].sum()


def test_views_of_a_borrowed_array_read_the_same_elements():
    x = np.arange(6.0)
    assert _column_sum(x) == x.reshape(2, 3)[:, 1].sum()

"""Rows picked by index (lbl_illum.engine.gather): the same values as numpy's indexing."""

import numpy as np
import pytest

from lbl_illum.engine.gather import rows


@pytest.mark.parametrize("shape", [(50, 3), (50, 3, 3), (50,)])
def test_rows_equal_fancy_indexing(shape):
    rng = np.random.default_rng(3)
    a = rng.random(shape)
    for index in (rng.integers(0, 50, 80), np.array([-1, 0, -50, 7]), np.zeros(0, np.int64),
                  np.arange(50, dtype=np.int32)[::-3]):
        out = rows(a, index)
        assert out.dtype == a.dtype and out.shape == a[index].shape
        assert np.array_equal(out, a[index])


def test_rows_take_a_boolean_mask_as_a_mask():
    a = np.arange(30.0).reshape(10, 3)
    mask = np.arange(10) % 3 == 1
    assert np.array_equal(rows(a, mask), a[mask])
    assert rows(a, np.zeros(10, bool)).shape == (0, 3)
    with pytest.raises(IndexError):
        rows(a, np.ones(9, bool))
    with pytest.raises(IndexError):
        rows(a, np.array([10]))

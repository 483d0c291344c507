import numpy as np
import pytest
from numba import prange

from lbl_illum.engine import compiled
from lbl_illum.engine.compiled import PARALLEL_MIN, PIECES_PER_THREAD, RowKernel


def _scaled_rows(x, shift, out, seen):
    for i in prange(x.shape[0]):
        for j in range(x.shape[1]):
            out[i, j] = 2.0 * x[i, j] + shift[j]
        seen[i] = x.shape[0]                      # the rows this call was given


@pytest.mark.parametrize("threads", [1, 2, 3])
def test_a_row_kernel_gives_the_same_rows_whole_or_cut_over_threads(monkeypatch, threads):
    """Rows are cut only from ``work`` = PARALLEL_MIN and with more than one thread, into
    PIECES_PER_THREAD ranges per thread; cut or not, every row is the same."""
    monkeypatch.setattr(compiled.numba.config, "NUMBA_NUM_THREADS", threads)
    kernel = RowKernel(_scaled_rows, rows=(0, 2, 3))
    x = np.random.default_rng(0).random((5000, 3))
    shift = np.array([0.0, 10.0, 20.0])
    whole, cut = np.empty_like(x), np.empty_like(x)
    seen_whole, seen_cut = np.zeros(5000, np.int64), np.zeros(5000, np.int64)
    kernel(x, shift, whole, seen_whole)
    kernel(x, shift, cut, seen_cut, work=PARALLEL_MIN)
    np.testing.assert_array_equal(whole, 2.0 * x + shift)
    np.testing.assert_array_equal(cut, whole)
    assert (seen_whole == 5000).all()
    pieces = 1 if threads == 1 else PIECES_PER_THREAD * threads
    assert np.unique(seen_cut).tolist() in ([5000 // pieces, 5000 // pieces + 1], [5000 // pieces])
    assert len(kernel.kernel.signatures) == 1     # slices of C arrays: no second specialisation


def test_a_row_kernel_is_compiled_once_without_the_gil():
    kernel = RowKernel(_scaled_rows, rows=(0, 2, 3))
    assert kernel.kernel.targetoptions.get("nogil") and not kernel.kernel.targetoptions.get("parallel")

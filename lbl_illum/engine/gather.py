"""Rows of ray and record arrays picked by index: the gather every stage of the engine does.

``a[index]`` on an (n, 3) array with an integer index goes through numpy's general
fancy-indexing machinery, row by row; ``np.take(a, index, axis=0)`` copies the same rows
with one loop.  Measured with numpy 2.1 on the 2-core machine of docs/performance, for
10⁶ rows of (n, 3) float64: 12.7 ms against 2.5 ms (sorted indices), 33 ms against 12 ms
(random ones); a boolean mask, ``a[mask]``, 16 ms against 3.6 ms for
``np.flatnonzero`` and ``np.take``.  One-dimensional arrays gain nothing (0.85 ms either
way), so only rows of two or more columns go through :func:`rows`.  The values are the
same bits either way.
"""

from __future__ import annotations

import numpy as np

__all__ = ["rows"]


def rows(a: np.ndarray, index) -> np.ndarray:
    """``a[index]`` along the first axis: ``index`` an integer array (negative entries
    count from the end, as in indexing) or a boolean mask of ``len(a)``."""
    index = np.asarray(index)
    if index.dtype == bool:
        if len(index) != len(a):
            raise IndexError(f"boolean index of length {len(index)} for {len(a)} rows")
        index = np.flatnonzero(index)
    return np.take(a, index, axis=0)

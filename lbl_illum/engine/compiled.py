"""Compiling array kernels with numba, serial and parallel.

numba's ``parallel=True`` kernels run on a thread pool that costs milliseconds to wake
on a busy machine: more than a loop over a few thousand items takes on one core.  The
engine makes many small calls (a placement pass over a few hundred queries, a level of
a few records), so every kernel written with ``prange`` is compiled twice and the call
picks the parallel one only for large inputs.
"""

from __future__ import annotations

import types

from numba import njit

__all__ = ["PARALLEL_MIN", "serial_and_parallel"]

#: Items (rays, queries) from which a kernel runs on every core.
PARALLEL_MIN = 100_000


def serial_and_parallel(func):
    """``(serial, parallel)`` compiled versions of ``func`` (written with ``prange``).

    Index the pair with ``n >= threshold`` to pick one.  The parallel version is compiled
    from a renamed copy of the function: numba's on-disk cache is keyed by the function's
    name, not by its compile options, and one would overwrite the other.
    """
    twin = types.FunctionType(func.__code__, func.__globals__, func.__name__ + "_parallel")
    twin.__qualname__ = func.__qualname__ + "_parallel"
    return njit(cache=True)(func), njit(cache=True, parallel=True)(twin)

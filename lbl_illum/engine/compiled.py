"""Compiling array kernels with numba, serial and parallel.

numba's ``parallel=True`` kernels run on a thread pool that costs milliseconds to wake
on a busy machine: more than a loop over a few thousand items takes on one core.  The
engine makes many small calls (a placement pass over a few hundred queries, a level of
a few records), so a kernel written with ``prange`` is either compiled twice, the call
picking the parallel one only for large inputs (:func:`serial_and_parallel`), or
compiled once without the GIL and run over ranges of its items on Python threads
(:func:`nogil_kernel`, :func:`in_threads`).  The second costs one compilation instead
of two: the parallel twins of the cache lookups and gradients took 8.4 of the 22.6 s of
the office example's first run (the kernels' compile times measured one by one).
"""

from __future__ import annotations

import types
from concurrent.futures import ThreadPoolExecutor

import numba
from numba import njit

__all__ = ["PARALLEL_MIN", "serial_and_parallel", "nogil_kernel", "in_threads"]

#: Items (rays, queries) from which a kernel runs on every core.
PARALLEL_MIN = 100_000
_POOL: list[ThreadPoolExecutor] = []


def nogil_kernel(func):
    """``func`` compiled once, cached on disk, releasing the GIL (for :func:`in_threads`)."""
    return njit(cache=True, nogil=True)(func)


def in_threads(n: int, pieces: int, call) -> None:
    """``call(lo, hi)`` for ``pieces`` consecutive ranges that cover items 0…n − 1
    (piece p is [p n / pieces, (p + 1) n / pieces), as a ``prange`` over blocks splits
    them), on numba's number of threads (``NUMBA_NUM_THREADS``); ``call`` runs a
    :func:`nogil_kernel` on its range.  Returns when every piece is done; an exception
    in one is raised here."""
    if not _POOL:
        _POOL.append(ThreadPoolExecutor(max_workers=numba.config.NUMBA_NUM_THREADS,
                                         thread_name_prefix="lbl-illum-kernel"))
    bounds = [p * n // pieces for p in range(pieces + 1)]
    for _ in _POOL[0].map(lambda p: call(bounds[p], bounds[p + 1]), range(pieces)):
        pass


def serial_and_parallel(func):
    """``(serial, parallel)`` compiled versions of ``func`` (written with ``prange``).

    Index the pair with ``n >= threshold`` to pick one.  The parallel version is compiled
    from a renamed copy of the function: numba's on-disk cache is keyed by the function's
    name, not by its compile options, and one would overwrite the other.
    """
    twin = types.FunctionType(func.__code__, func.__globals__, func.__name__ + "_parallel")
    twin.__qualname__ = func.__qualname__ + "_parallel"
    return njit(cache=True)(func), njit(cache=True, parallel=True)(twin)


def kernels_on_disk() -> bool:
    """Whether numba's on-disk cache already holds the kernels every cached run uses (the
    cache lookups and record layout, the hemisphere directions): False on the first run
    after installing, when compiling them takes most of half a minute.  Read from the
    index files numba keeps beside each kernel; when numba's layout is not the one
    expected, True (say nothing rather than something wrong)."""
    import os

    from . import hemisphere, octree

    try:
        kernels = (octree._lookup_kernel, octree._covered_kernel, octree.freeze, hemisphere._stratified_kernels[0])
        return all(os.path.exists(k._cache._cache_file._index_path) for k in kernels)
    except AttributeError:
        return True

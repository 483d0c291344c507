"""Compiling array kernels with numba, each once, run on every core for large inputs.

numba's ``parallel=True`` kernels run on a thread pool that costs milliseconds to wake
on a busy machine: more than a loop over a few thousand items takes on one core; and a
parallel kernel compiles twice as slowly as a serial one, and had to be compiled a second
time, serial, for the engine's many small calls (a placement pass over a few hundred
queries, a level of a few records).  So every kernel is compiled once, without the GIL,
and a large call runs it over ranges of its items on Python threads:
:func:`nogil_kernel` with :func:`in_threads` where the kernel takes its range itself,
:class:`RowKernel` where its iterations are the rows of some of its arrays (written with
``prange``, which a serial kernel runs as ``range``).  The parallel twins of the cache
lookups and gradients took 8.4 of the 22.6 s of the office example's first run, those of
the hemisphere directions and hit points another 1.0 s (each kernel's compile time measured
one by one, ``numba:compile`` events).
"""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor

import numba
from numba import njit

__all__ = ["PARALLEL_MIN", "RowKernel", "nogil_kernel", "in_threads"]

#: Items (rays, queries) from which a kernel runs on every core.
PARALLEL_MIN = 100_000
#: Ranges per thread a :class:`RowKernel` call is cut into (rows of unequal cost balance out).
PIECES_PER_THREAD = 4
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


class RowKernel:
    """A kernel whose iterations are independent rows of some of its arrays, compiled once
    (:func:`nogil_kernel`).

    ``rows`` are the positions of the arguments cut by rows (their first axis is the
    kernel's ``prange``); the others are passed whole.  A call with ``work`` of at least
    PARALLEL_MIN (default: the number of rows) runs the kernel on consecutive row ranges
    on every thread, a smaller one on the calling thread; each row is computed alike
    either way, so results do not depend on the split.
    """

    def __init__(self, func, rows: tuple[int, ...]):
        self.kernel = nogil_kernel(func)
        self.rows = tuple(rows)

    def __call__(self, *args, work: int | None = None) -> None:
        n = args[self.rows[0]].shape[0]
        threads = numba.config.NUMBA_NUM_THREADS
        if (n if work is None else work) < PARALLEL_MIN or threads < 2 or n < 2:
            self.kernel(*args)
            return

        def rows(lo: int, hi: int) -> None:
            cut = list(args)
            for k in self.rows:
                cut[k] = args[k][lo:hi]
            self.kernel(*cut)

        in_threads(n, min(n, PIECES_PER_THREAD * threads), rows)


def kernels_on_disk() -> bool:
    """Whether numba's on-disk cache already holds the kernels every cached run uses (the
    cache lookups and record layout, the hemisphere directions): False on the first run
    after installing, when compiling them takes most of half a minute.  Read from the
    index files numba keeps beside each kernel; when numba's layout is not the one
    expected, True (say nothing rather than something wrong)."""
    import os

    from . import hemisphere, octree

    try:
        kernels = (octree._lookup_kernel, octree._covered_kernel, octree._layout, hemisphere._stratified_kernel.kernel)
        return all(os.path.exists(k._cache._cache_file._index_path) for k in kernels)
    except AttributeError:
        return True

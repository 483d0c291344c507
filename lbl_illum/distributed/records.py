"""The record sets that travel between the driver and the workers, and their merging.

A round's record set is a cache file's contents (:class:`~lbl_illum.io.cachefile.CacheData`:
a header and the record arrays of every level), never a live cache: the driver sends
those arrays to every worker, each task builds its cache from them
(:func:`~lbl_illum.io.cachefile.cache_from_data`) and returns only the records it added
(:func:`record_delta`), and the driver merges the deltas into the set in chunk order
(:func:`merge_round`, :func:`~lbl_illum.io.cachefile.merge_cache_parts`: a record made
twice, at the same position and normal, is kept once).  Because every task of a round,
on any worker or in the driver's own process, starts from the same arrays and the merge
order is the chunks' order, the next round's set does not depend on who ran what.

Records of annual runs carry their daylight-coefficient vectors as one more array per
level (``L{k}_C``, (n, channels, sources) float32), merged with the others.  Cache files
do not hold them (:func:`file_contents`).
"""

from __future__ import annotations

import numpy as np

from ..engine.cache import IrradianceCache
from ..io.cachefile import CacheData, cache_data, merge_cache_parts, save_cache_data

__all__ = ["record_delta", "record_set", "merge_round", "file_contents", "save_round"]


def record_delta(cache: IrradianceCache, base: CacheData, coefficients=None) -> CacheData:
    """The records ``cache`` holds beyond those of ``base`` (the set it was built from), as
    a :class:`CacheData` whose levels keep ``cache``'s root cubes; levels without
    interpolation are left empty, as in a file (their records serve only their own
    points).  ``coefficients`` (a :class:`~lbl_illum.engine.coefficients.CoefficientRecords`):
    the new records' vectors too, as ``L{k}_C``."""
    start = base.record_counts
    arrays, levels = {}, []
    for k, lv in enumerate(cache.levels):
        lo = start[k]
        hi = lv.count if lv.accuracy > 0 else lo
        names = ("P", "N", "E", "R", "Gr", "Gt", "zone") + (("W", "leak") if lv.anisotropic else ())
        for name in names:
            arrays[f"L{k}_{name}"] = getattr(lv, name)[lo:hi].copy()
        if coefficients is not None:
            arrays[f"L{k}_C"] = coefficients.values[k][lo:hi].copy()
        levels.append({"accuracy": lv.accuracy, "records": int(hi - lo), "center": lv.node_center[0].tolist(),
                       "half": float(lv.node_half[0])})
    header = {**base.header, "levels": levels}
    header.pop("checksum", None)
    return CacheData(header, arrays)


def merge_round(base: CacheData, deltas) -> CacheData:
    """``base`` with the records of each delta added, in the order given (the chunks'):
    :func:`~lbl_illum.io.cachefile.merge_cache_parts`, which is :func:`merge_cache_data`
    of each in turn done in one pass."""
    return merge_cache_parts(base, deltas)


def file_contents(data: CacheData) -> CacheData:
    """``data`` as a cache file holds it: without the coefficient arrays."""
    return CacheData(data.header, {name: arr for name, arr in data.arrays.items() if not name.endswith("_C")})


def record_set(cache: IrradianceCache, coefficients=None) -> CacheData:
    """The record set that travels for ``cache`` (:func:`cache_data`: a file's contents),
    with ``coefficients``' arrays of its records when given (zeros where it has none)."""
    data = cache_data(cache)
    if coefficients is not None:
        for k, n in enumerate(data.record_counts):
            arrays = coefficients.values[k]
            shape = (n, coefficients.channels, coefficients.sources)
            data.arrays[f"L{k}_C"] = arrays[:n].copy() if len(arrays) >= n else np.zeros(shape, np.float32)
    return data


def save_round(path, data: CacheData, merge: bool = True) -> list[int]:
    """Write a round's record set to the cache file ``path``, merged under its lock with
    what other processes wrote (:func:`~lbl_illum.io.cachefile.save_cache_data`); the
    records per level the file now holds."""
    return save_cache_data(file_contents(data), path, merge)

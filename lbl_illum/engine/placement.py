"""Compiled helpers that choose where new records go (the placement passes of
:mod:`lbl_illum.engine.integrator`).

A pass takes, among the queries no record covers yet, one per cell of a grid; the
cell side doubles with each power-of-two band of distance outside the box around the
sensor points (where records may be larger), and cells are told apart by the query's
dominant normal direction too, so a floor and a wall meeting in one cell each get a
record.  In each cell the query nearest the cell's centre is taken, and the picks come
in key order: the choice depends on where the queries are, never on their order.
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

from .compiled import RowKernel

__all__ = ["distance_bands", "pick_per_cell"]

_HASH = (np.int64(73856093), np.int64(19349663), np.int64(83492791))


def _distance_bands(P, lo, hi, max_spacing, out):
    """Compiled body of :func:`distance_bands`."""
    for q in prange(P.shape[0]):
        d2 = 0.0
        for c in range(3):
            e = max(0.0, max(lo[c] - P[q, c], P[q, c] - hi[c]))
            d2 += e * e
        out[q] = np.int64(np.ceil(np.log2(1.0 + np.sqrt(d2) / max_spacing)))


_distance_bands_kernel = RowKernel(_distance_bands, rows=(0, 4))


def distance_bands(P, lo, hi, max_spacing):
    """(n,) int64: ⌈log2(1 + δ / max_spacing)⌉, δ the distance from P to the box [lo, hi]."""
    out = np.empty(len(P), np.int64)
    _distance_bands_kernel(P, lo, hi, max_spacing, out)
    return out


def _cell_keys(P, N, band, cell, key, off_centre):
    for q in prange(P.shape[0]):
        size = cell * 2.0 ** band[q]
        axis = 0
        best = abs(N[q, 0])
        for c in range(1, 3):
            if abs(N[q, c]) > best:
                best = abs(N[q, c])
                axis = c
        sign = 1 if N[q, axis] > 0 else 0
        h = np.int64(0)
        off = 0.0
        for c in range(3):
            s = P[q, c] / size
            i = np.int64(np.floor(s))
            h ^= i * _HASH[c]
            f = s - i - 0.5
            off += f * f
        key[q] = h * np.int64(64) + (axis * 2 + sign) * np.int64(8) + min(band[q], 7)
        off_centre[q] = off


_cell_keys_kernel = RowKernel(_cell_keys, rows=(0, 1, 2, 4, 5))


@njit(cache=True)
def _nearest_per_key(key, off_centre):
    """For each distinct key, the query nearest its cell's centre (the lowest index among
    ties), and the distinct keys.  One pass through an open-addressing hash table."""
    n = key.shape[0]
    size = 16
    while size < 2 * n:
        size *= 2
    mask = size - 1
    slot_key = np.empty(size, np.int64)
    slot_best = np.empty(size, np.int64)      # a loop, not np.full: 0.12 s less of a first run's compiling
    for s in range(size):
        slot_best[s] = -1
    distinct = 0
    for q in range(n):
        h = (key[q] * np.int64(-7046029254386353131)) >> np.int64(17)
        s = h & mask
        while True:
            b = slot_best[s]
            if b < 0:
                slot_key[s] = key[q]
                slot_best[s] = q
                distinct += 1
                break
            if slot_key[s] == key[q]:
                if off_centre[q] < off_centre[b]:
                    slot_best[s] = q
                break
            s = (s + 1) & mask
    keys = np.empty(distinct, np.int64)
    best = np.empty(distinct, np.int64)
    m = 0
    for s in range(size):
        if slot_best[s] >= 0:
            keys[m] = slot_key[s]
            best[m] = slot_best[s]
            m += 1
    return best, keys


def pick_per_cell(P: np.ndarray, N: np.ndarray, band: np.ndarray, cell: float) -> np.ndarray:
    """Indices of one query per cell (side ``cell`` · 2^band) and normal direction.

    Cells are hashed to one 64-bit key; a collision only merges two cells for one pass.
    Ties in distance to the centre keep the query with the lowest index.  The picks
    come in ascending key order.
    """
    n = len(P)
    key = np.empty(n, np.int64)
    off_centre = np.empty(n, np.float64)
    _cell_keys_kernel(np.ascontiguousarray(P), np.ascontiguousarray(N), band, float(cell), key, off_centre)
    best, keys = _nearest_per_key(key, off_centre)
    return best[np.argsort(keys)]                # distinct keys: any sort gives this order

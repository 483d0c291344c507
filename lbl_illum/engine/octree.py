"""Compiled octree kernels for the irradiance records (the paper's §3.3 and Eqs. 5–6).

Records are structure-of-arrays: position P (n, 3) float64, unit normal N (n, 3)
float32, irradiance E (n, 3) float32, radius R (n,) float32.  A record i is valid
for a query (P, N) when its error estimate is below the accuracy ``a`` (Eq. 5),

    ε_i(P, N) = |P − P_i| / R_i + sqrt(1 − N · N_i)  <  a        ⇔  w_i = 1/ε_i > 1/a,

and it is not "in front" of the query (Eq. 6):

    d_i(P) = (P − P_i) · (N + N_i) / 2  ≥  −FRONT_TOLERANCE · R_i.

The tolerance only absorbs floating-point round-off for records on the same plane.

Octree (insertion, §3.3).  Each record lives in the node that contains P_i and whose
side s satisfies 2 a R_i < s ≤ 4 a R_i (records larger than the root stay in the
root).  Nodes are arrays: centre, half side and eight child indices (-1: none); the
node of each record is kept in ``rec_node``.

Lookup layout (:func:`freeze`, redone after insertions).  The paper searches the
octree itself: test a node's records, descend into each child whose cube, grown by
half the child's side, contains P.  Here the octree only orders the records: depth
first (so records of one size class and one region are adjacent), along a Morton
curve within each node.  In that order the records are cut into chunks of LANES and
their P (float64), N and R (float32) copied by axis, so a search reads them
sequentially.  Over the chunks sits a tree of boxes: each chunk has the box around
its records' valid domains P_i ± a R_i, and each box of level l + 1 is the union of
LANES consecutive boxes of level l, up to a single root.  The tree is balanced
whatever the octree's depth, and a node's LANES child boxes are tested together,
without branches.  A record serves only queries inside its domain, which lies inside
every box above it, so the search finds exactly the records the paper's search finds;
boxes are stored as float32 rounded outwards and grown by BOX_MARGIN of a R_i, so
round-off never drops a record.

Lookups (:func:`lookup`).  Queries are visited in Morton order of their positions
(:func:`query_order`) and searched in packets of nearby queries: the box tree is
walked once per packet, and each query of the packet tests only the level-1 boxes
that walk listed.  Irradiance and gradients are read through the layout's
permutation from the caller's record array, so values written there after freezing
are used by the next lookup.  Each answer is computed alone with its sums in layout
order and written at its query's index: results do not depend on the order of the
queries, on the batch, the packets or the number of threads.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit

from .compiled import in_threads, kernel_threads, nogil_kernel
from .hessian import LEAK_SECTORS

__all__ = ["FRONT_TOLERANCE", "MAX_DEPTH", "MIN_ERROR", "LANES", "Layout", "insert_records", "freeze",
           "query_order", "lookup", "covered"]

#: Records at most this far (relative to R_i) behind the query's tangent plane still count as level.
FRONT_TOLERANCE = 1e-3
#: Deepest octree level (a cube 2^-48 of the root's side is far below float resolution).
MAX_DEPTH = 48
#: Smallest error estimate used in a weight: a query on a record gets weight 1e6, not a
#: value decided by round-off in sqrt(1 − N·N_i).
MIN_ERROR = 1e-6
#: Records per chunk and children per box of the lookup layout.
LANES = 8
#: Relative growth of a record's domain a R_i in the layout's boxes (round-off guard).
BOX_MARGIN = 1e-6
#: Candidates (records past the cheap distance test) buffered per query before evaluation.
CANDIDATES = 256
#: Most queries per packet, and a packet's largest side relative to a level-1 box.
PACKET = 32
PACKET_SCALE = 0.5
#: Morton bits per axis of the query sort key.
QUERY_BITS = 10
#: Index of the lowest and of the highest set bit of an 8-bit mask.
_LOW_BIT = np.array([0] + [(m & -m).bit_length() - 1 for m in range(1, 256)], np.int64)
_HIGH_BIT = np.array([0] + [m.bit_length() - 1 for m in range(1, 256)], np.int64)


class Layout(NamedTuple):
    """The frozen lookup layout of one level (see the module docstring).

    perm : (n_pad,) int32, the record index at each layout position (n_pad: records
        rounded up to a multiple of LANES)
    pos : (3, n_pad) float64, P of ``perm`` by axis;  nr : (5, n_pad) float32, N, R and the
        record's zone (:meth:`lbl_illum.engine.portals.PortalSet.zone`; -1 in padding)
    box : (g, 6, LANES) float32, groups of LANES sibling boxes, rows lo_x, lo_y, lo_z,
        hi_x, hi_y, hi_z
    level_start : (levels + 1,) int64, the groups of level l are ``level_start[l]:level_start[l + 1]``
    packet_extent : largest side [m] of a packet of queries searched together: PACKET_SCALE
        times the median largest side of the level-1 boxes
    """
    perm: np.ndarray
    pos: np.ndarray
    nr: np.ndarray
    box: np.ndarray
    level_start: np.ndarray
    packet_extent: float


# -- insertion ---------------------------------------------------------------------------

@njit(cache=True)
def insert_records(start, stop, P, R, accuracy, rec_node, node_center, node_half, node_child, n_nodes):
    """Insert records ``start:stop`` into the octree; return (n_nodes, next record).

    Record i descends from the root while the node's side exceeds 4 a R_i (at most
    MAX_DEPTH levels), creating the nodes it needs; ``rec_node[i]`` gets its node.
    Stops early (next record < stop) when the node arrays are full; the caller grows
    them and calls again from the returned record.
    """
    capacity = node_half.shape[0]
    for i in range(start, stop):
        domain = accuracy * R[i]
        node = 0
        depth = 0
        while 2.0 * node_half[node] > 4.0 * domain and depth < MAX_DEPTH:
            octant = 0
            if P[i, 0] >= node_center[node, 0]:
                octant |= 1
            if P[i, 1] >= node_center[node, 1]:
                octant |= 2
            if P[i, 2] >= node_center[node, 2]:
                octant |= 4
            child = node_child[node, octant]
            if child < 0:
                if n_nodes >= capacity:
                    return n_nodes, i
                child = n_nodes
                n_nodes += 1
                h = 0.5 * node_half[node]
                node_half[child] = h
                node_center[child, 0] = node_center[node, 0] + (h if octant & 1 else -h)
                node_center[child, 1] = node_center[node, 1] + (h if octant & 2 else -h)
                node_center[child, 2] = node_center[node, 2] + (h if octant & 4 else -h)
                for c in range(8):
                    node_child[child, c] = -1
                node_child[node, octant] = child
            node = child
            depth += 1
        rec_node[i] = node
    return n_nodes, stop


# -- Morton keys and sorting ------------------------------------------------------------------

@njit(cache=True)
def _spread3(x):
    """Bits 0..20 of x moved to bits 0, 3, 6, ... (one axis of a 63-bit Morton code)."""
    x = np.uint64(x) & np.uint64(0x1FFFFF)
    x = (x | (x << np.uint64(32))) & np.uint64(0x1F00000000FFFF)
    x = (x | (x << np.uint64(16))) & np.uint64(0x1F0000FF0000FF)
    x = (x | (x << np.uint64(8))) & np.uint64(0x100F00F00F00F00F)
    x = (x | (x << np.uint64(4))) & np.uint64(0x10C30C30C30C30C3)
    x = (x | (x << np.uint64(2))) & np.uint64(0x1249249249249249)
    return x


@njit(cache=True)
def _morton(px, py, pz, lo_x, lo_y, lo_z, scale, bits):
    """Morton code of a point in the cube with corner ``lo`` and ``2^bits`` cells of
    side 1/scale per axis (x in the lowest bit, as the octants); outside points clamp."""
    top = (1 << bits) - 1
    cx = min(max(int((px - lo_x) * scale), 0), top)
    cy = min(max(int((py - lo_y) * scale), 0), top)
    cz = min(max(int((pz - lo_z) * scale), 0), top)
    return _spread3(cx) | (_spread3(cy) << np.uint64(1)) | (_spread3(cz) << np.uint64(2))


#: Keys from which :func:`_stable_order` sorts by radix (numpy's stable sort is a timsort
#: on 64-bit keys: 16 ms for 200,000 of them, the radix sort 3 ms).
RADIX_MIN = 32768


def _stable_order(keys: np.ndarray) -> np.ndarray:
    """Indices that sort uint64 ``keys`` with ties in index order: numpy's stable sort for
    a few keys, a radix sort (:func:`_radix_order`) for many.  (numba's compiled
    ``np.argsort`` cost seconds of a first run's compilation.)"""
    if len(keys) < RADIX_MIN:
        return np.argsort(keys, kind="stable")
    return _radix_order(keys)


@njit(cache=True)
def _radix_order(keys):
    """Stable argsort of uint64 keys: least-significant-digit radix sort on 16-bit digits,
    skipping digits all keys share."""
    n = keys.shape[0]
    order = np.empty(n, np.int64)           # loops, not np.arange and np.zeros: 0.2 s less compiling
    for i in range(n):
        order[i] = i
    k_in = keys.copy()
    k_out = np.empty(n, np.uint64)
    o_out = np.empty(n, np.int64)
    top = np.uint64(0)
    for i in range(n):
        top |= keys[i]
    mask = np.uint64(0xFFFF)
    shift = 0
    while shift < 64 and (top >> np.uint64(shift)) != np.uint64(0):
        s = np.uint64(shift)
        count = np.empty(65537, np.int64)
        for d in range(65537):
            count[d] = 0
        for i in range(n):
            count[np.int64((k_in[i] >> s) & mask) + 1] += 1
        same = False                        # do all keys share this digit?
        for d in range(65537):
            same |= count[d] == n
        if not same:
            for d in range(65536):
                count[d + 1] += count[d]
            for i in range(n):
                d = np.int64((k_in[i] >> s) & mask)
                j = count[d]
                count[d] = j + 1
                k_out[j] = k_in[i]
                o_out[j] = order[i]
            k_in, k_out = k_out, k_in
            order, o_out = o_out, order
        shift += 16
    return order


def query_order(qP, center, half) -> np.ndarray:
    """Order in which to visit queries: by the Morton code of their positions on a grid
    of 2^QUERY_BITS cells per axis over the root cube (``center`` ± ``half`` [m]), ties
    in index order."""
    return _stable_order(_query_keys(qP, center, half))


@njit(cache=True)
def _query_keys(qP, center, half):
    """The sort keys of :func:`query_order`."""
    n = qP.shape[0]
    keys = np.empty(n, np.uint64)
    scale = (1 << QUERY_BITS) / (2.0 * half)
    bits = np.int64(QUERY_BITS)     # not the literal 10: _morton's one specialisation, shared with _record_keys
    for q in range(n):
        keys[q] = _morton(qP[q, 0], qP[q, 1], qP[q, 2], center[0] - half, center[1] - half, center[2] - half,
                          scale, bits)
    return keys


# -- freezing -----------------------------------------------------------------------------------

@njit(cache=True)
def _outward(lo, hi, box, g, t):
    """Store the float64 box [lo, hi] as float32 lane t of group g of ``box`` (rows lo_x,
    lo_y, lo_z, hi_x, hi_y, hi_z), rounded outwards: the float32 box contains it."""
    for c in range(3):
        a = np.float32(lo[c])
        if np.float64(a) > lo[c]:
            a = np.nextafter(a, np.float32(-np.inf))
        b = np.float32(hi[c])
        if np.float64(b) < hi[c]:
            b = np.nextafter(b, np.float32(np.inf))
        box[g, c, t] = a
        box[g, 3 + c, t] = b


@njit(cache=True)
def _record_keys(count, n_nodes, rec_node, node_child, node_center, node_half, P):
    """Sort keys of the layout order of records ``0:count`` (ties go by record index): the
    depth-first index of their node (octant 0 first, a node before its children), then
    the Morton code of P_i on the finest grid over the node's cube that fits a 63-bit key."""
    m = n_nodes
    dfs_of = np.empty(m, np.int64)
    stack = np.empty(8 * (MAX_DEPTH + 2), np.int32)
    stack[0] = 0
    top = 1
    pos = 0
    while top > 0:
        top -= 1
        node = stack[top]
        dfs_of[node] = pos
        pos += 1
        for c in range(7, -1, -1):
            ch = node_child[node, c]
            if ch >= 0:
                stack[top] = ch
                top += 1
    node_bits = 1
    while (1 << node_bits) < m:
        node_bits += 1
    bits = min(20, (63 - node_bits) // 3)
    keys = np.empty(count, np.uint64)
    for i in range(count):
        nd = rec_node[i]
        h = node_half[nd]
        keys[i] = (np.uint64(dfs_of[nd]) << np.uint64(3 * bits)) | _morton(
            P[i, 0], P[i, 1], P[i, 2], node_center[nd, 0] - h, node_center[nd, 1] - h, node_center[nd, 2] - h,
            (1 << bits) / (2.0 * h), bits)
    return keys


def freeze(count, n_nodes, rec_node, node_child, node_center, node_half, P, N, R, zone, accuracy) -> tuple:
    """Lay records ``0:count`` out for lookups; return the fields of :class:`Layout`.

    Records go in the order of :func:`_record_keys`, in chunks of LANES (the last one padded with
    NaN positions, which no test accepts).  Boxes: at level 0 each chunk's box around
    its records' domains P_i ± a R_i (1 + BOX_MARGIN), at level l + 1 the union of
    each LANES consecutive boxes of level l, up to one box (at least two levels).
    Boxes are stored in groups of LANES siblings, padded with empty boxes
    (lo = +inf, hi = -inf): the children of box k of level l + 1 are group
    ``level_start[l] + k``.
    """
    order = _stable_order(_record_keys(count, n_nodes, rec_node, node_child, node_center, node_half, P))
    perm, pos, nr, box, level_start, sides = _layout(order, count, P, N, R, zone, accuracy)
    extent = PACKET_SCALE * float(np.median(sides)) if len(sides) else 0.0
    return perm, pos, nr, box, level_start, extent


@njit(cache=True)
def _layout(order, count, P, N, R, zone, accuracy):
    """The arrays of :func:`freeze` for records in ``order``, and the largest side [m] of
    each level-1 box."""
    n_chunks = (count + LANES - 1) // LANES
    n_pad = n_chunks * LANES
    # explicit loops: numba compiles slice assignments, np.full and np.zeros slowly (first run)
    perm = np.empty(n_pad, np.int32)
    pos = np.empty((3, n_pad))
    nr = np.empty((5, n_pad), np.float32)
    for j in range(count, n_pad):
        perm[j] = 0
        for c in range(3):
            pos[c, j] = np.nan
            nr[c, j] = 0.0
        nr[3, j] = 1.0
        nr[4, j] = -1.0
    for j in range(count):
        i = order[j]
        perm[j] = i
        for c in range(3):
            pos[c, j] = P[i, c]
            nr[c, j] = N[i, c]
        nr[3, j] = R[i]
        nr[4, j] = zone[i]
    # levels: boxes per level and the first group of each
    n_levels = 1
    k = n_chunks
    while k > 1 or n_levels < 2:
        k = (k + LANES - 1) // LANES
        n_levels += 1
    level_start = np.empty(n_levels + 1, np.int64)
    level_start[0] = 0
    level_count = np.empty(n_levels, np.int64)
    k = n_chunks
    for lev in range(n_levels):
        level_count[lev] = k
        level_start[lev + 1] = level_start[lev] + (k + LANES - 1) // LANES
        k = (k + LANES - 1) // LANES
    box = np.empty((level_start[n_levels], 6, LANES), np.float32)
    for g in range(box.shape[0]):
        for t in range(LANES):
            for c in range(3):
                box[g, c, t] = np.inf
                box[g, 3 + c, t] = -np.inf
    lo = np.empty(3)
    hi = np.empty(3)
    for k in range(n_chunks):
        for c in range(3):
            lo[c] = np.inf
            hi[c] = -np.inf
        for j in range(k * LANES, min(count, (k + 1) * LANES)):
            reach = accuracy * np.float64(nr[3, j]) * (1.0 + BOX_MARGIN)
            for c in range(3):
                lo[c] = min(lo[c], pos[c, j] - reach)
                hi[c] = max(hi[c], pos[c, j] + reach)
        _outward(lo, hi, box, k // LANES, k % LANES)
    for lev in range(1, n_levels):
        for k in range(level_count[lev - 1]):
            g = level_start[lev - 1] + k // LANES        # the box's group ...
            t = k % LANES
            pg = level_start[lev] + k // (LANES * LANES)  # ... and its parent's
            pt = (k // LANES) % LANES
            for c in range(3):
                box[pg, c, pt] = min(box[pg, c, pt], box[g, c, t])
                box[pg, 3 + c, pt] = max(box[pg, 3 + c, pt], box[g, 3 + c, t])
    sides = np.empty(level_count[1])
    for k in range(level_count[1]):
        g = level_start[1] + k // LANES
        t = k % LANES
        sides[k] = max(box[g, 3, t] - box[g, 0, t], box[g, 4, t] - box[g, 1, t], box[g, 5, t] - box[g, 2, t])
    return perm, pos, nr, box, level_start, sides


# -- lookup ------------------------------------------------------------------------------------

@njit(cache=True, inline="always")
def _f32_below(x):
    """A float32 ≤ x (within 3 float32 ulps): x moved down by about 2 ulps, rounded."""
    return np.float32(x - (abs(x) * 2.0 ** -22 + 1e-37))


@njit(cache=True, inline="always")
def _f32_above(x):
    """A float32 ≥ x (within 3 float32 ulps)."""
    return np.float32(x + (abs(x) * 2.0 ** -22 + 1e-37))


@njit(cache=True)         # called, not inlined into both kernels: 0.3 s less of a first run's compiling
def _sector_open(mask, dx, dy, dz, mx, my, mz, Ri):
    """Whether displacement d from a record with unit normal m avoids its leak sectors
    (:func:`lbl_illum.engine.hessian.leak_sectors`: LEAK_SECTORS sectors of the tangent
    plane, from the first tangent of the Duff et al. basis).  A query within 10⁻³ R_i of
    the record's normal line has no direction and is always admitted."""
    sign = 1.0 if mz >= 0.0 else -1.0
    a = -1.0 / (sign + mz)
    b = mx * my * a
    u = dx * (1.0 + sign * mx * mx * a) + dy * (sign * b) - dz * sign * mx
    v = dx * b + dy * (sign + my * my * a) - dz * my
    if u * u + v * v <= 1e-6 * Ri * Ri:
        return True
    phi = np.arctan2(v, u)
    sector = int(np.floor(phi * (LEAK_SECTORS / (2.0 * np.pi)))) % LEAK_SECTORS
    return (mask >> np.uint32(sector)) & np.uint32(1) == 0


def _lookup(qP, qN, qZ, order, n_blocks, accuracy, gradients, shaped, taper, V, leak, perm, pos, nr, box,
            level_start, packet_extent, out_E, out_w, out_n, pair_record, pair_weight):
    """Eq. 5 at each query ``order[k]``, the queries split into ``n_blocks`` runs (one
    per parallel task), each with its own buffers.

    Packets.  Consecutive queries (in ``order``) whose bounding box stays within
    ``packet_extent`` on every axis, at most PACKET of them, form a packet.  The box
    tree is searched once per packet, depth first with an explicit stack (entries
    ``level << 48 | index``), children in index order: a node is entered when its box
    overlaps the packet's box (rounded outwards to float32), and the level-1 nodes
    reached are listed with their boxes, in index order.

    Queries.  For each query of the packet, the listed level-1 nodes whose box contains
    the query have their LANES chunk boxes tested together into a bit mask; each record
    of a chunk that passes and that passes the cheap test |P − P_i|² ≤ (a R_i)²
    (1 + 1e-9) is appended to a candidate buffer.  When the buffer could overflow, and
    at the end, the candidates are evaluated in two loops without data-dependent
    branches (error and weight of each, keeping the valid ones; then their values,
    summed in order; with ``taper`` the weights 1 − ε_i/a).  Records are met in layout order whatever the packet, so each
    answer depends on its query alone.  Everything is written out in one function: a
    call per query or per chunk would cost two atomic reference counts per array argument.

    Pairs.  When ``pair_record`` has columns (K of them), each query's valid records and
    their weights are also written there, in layout order, -1 and 0 after the last; a
    query served by more than K records keeps the K of largest weight.
    """
    pairs = pair_record.shape[1]
    nq = order.shape[0]
    n_levels = level_start.shape[0] - 1
    root = level_start[n_levels - 1]             # the top level's group; the root is lane 0
    n_level1 = (level_start[2] - level_start[1]) * LANES
    for b in range(n_blocks):
        stack = np.empty(LANES * (n_levels + 1), np.int64)
        cand = np.empty(CANDIDATES, np.int64)
        hit_j = np.empty(CANDIDATES, np.int64)
        hit_w = np.empty(CANDIDATES)
        near_node = np.empty(n_level1, np.int64)
        near_box = np.empty((n_level1 // LANES, 6, LANES), np.float32)
        k = b * nq // n_blocks
        end = (b + 1) * nq // n_blocks
        while k < end:
            # -- the packet: queries order[k:k_end] ---------------------------------------
            q = order[k]
            lx, ly, lz = qP[q, 0], qP[q, 1], qP[q, 2]
            hx, hy, hz = lx, ly, lz
            k_end = k + 1
            while k_end < end and k_end - k < PACKET:
                q = order[k_end]
                ax, ay, az = min(lx, qP[q, 0]), min(ly, qP[q, 1]), min(lz, qP[q, 2])
                bx, by, bz = max(hx, qP[q, 0]), max(hy, qP[q, 1]), max(hz, qP[q, 2])
                if max(bx - ax, by - ay, bz - az) > packet_extent:
                    break
                lx, ly, lz, hx, hy, hz = ax, ay, az, bx, by, bz
                k_end += 1
            xlo, xhi = _f32_below(lx), _f32_above(hx)
            ylo, yhi = _f32_below(ly), _f32_above(hy)
            zlo, zhi = _f32_below(lz), _f32_above(hz)
            n_near = 0
            top = 0
            if ((box[root, 0, 0] <= xhi) & (box[root, 3, 0] >= xlo) & (box[root, 1, 0] <= yhi)
                    & (box[root, 4, 0] >= ylo) & (box[root, 2, 0] <= zhi) & (box[root, 5, 0] >= zlo)):
                stack[0] = (n_levels - 1) << 48
                top = 1
            while top > 0:
                top -= 1
                lev = stack[top] >> 48
                node = stack[top] & 0xFFFFFFFFFFFF
                if lev == 1:
                    g = level_start[1] + node // LANES
                    t = node % LANES
                    near_node[n_near] = node
                    for c in range(6):
                        near_box[n_near // LANES, c, n_near % LANES] = box[g, c, t]
                    n_near += 1
                    continue
                g = level_start[lev - 1] + node         # the group of its children
                mask = 0
                for t in range(LANES):
                    overlap = ((box[g, 0, t] <= xhi) & (box[g, 3, t] >= xlo) & (box[g, 1, t] <= yhi)
                               & (box[g, 4, t] >= ylo) & (box[g, 2, t] <= zhi) & (box[g, 5, t] >= zlo))
                    mask |= np.int64(overlap) << t
                child = (lev - 1) << 48
                while mask:                             # high bits first: popped in index order
                    t = _HIGH_BIT[mask]
                    mask ^= 1 << t
                    stack[top] = child | (node * LANES + t)
                    top += 1
            for t in range(n_near, (n_near + LANES - 1) // LANES * LANES):     # pad the last group
                for c in range(3):
                    near_box[t // LANES, c, t % LANES] = np.inf
                    near_box[t // LANES, 3 + c, t % LANES] = -np.inf
            n_groups = (n_near + LANES - 1) // LANES
            # -- each query of the packet ---------------------------------------------------
            for kq in range(k, k_end):
                q = order[kq]
                px, py, pz = qP[q, 0], qP[q, 1], qP[q, 2]
                nx, ny, nz = qN[q, 0], qN[q, 1], qN[q, 2]
                qz = np.float32(qZ[q])
                xlo, xhi = _f32_below(px), _f32_above(px)
                ylo, yhi = _f32_below(py), _f32_above(py)
                zlo, zhi = _f32_below(pz), _f32_above(pz)
                sw = 0.0
                s0 = 0.0
                s1 = 0.0
                s2 = 0.0
                count = 0
                written = 0
                n_cand = 0
                gi = 0
                mask = 0
                while True:
                    if mask == 0 and gi < n_groups:     # which listed level-1 boxes contain the query
                        for t in range(LANES):
                            inside = ((near_box[gi, 0, t] <= xhi) & (near_box[gi, 3, t] >= xlo)
                                      & (near_box[gi, 1, t] <= yhi) & (near_box[gi, 4, t] >= ylo)
                                      & (near_box[gi, 2, t] <= zhi) & (near_box[gi, 5, t] >= zlo))
                            mask |= np.int64(inside) << t
                        gi += 1
                        continue
                    if mask != 0 and n_cand <= CANDIDATES - LANES * LANES:
                        t = _LOW_BIT[mask]
                        mask &= mask - 1
                        node = near_node[(gi - 1) * LANES + t]
                        g = level_start[0] + node           # the group of its chunks
                        chunks = 0
                        for t in range(LANES):
                            inside = ((box[g, 0, t] <= xhi) & (box[g, 3, t] >= xlo) & (box[g, 1, t] <= yhi)
                                      & (box[g, 4, t] >= ylo) & (box[g, 2, t] <= zhi) & (box[g, 5, t] >= zlo))
                            chunks |= np.int64(inside) << t
                        while chunks:
                            t = _LOW_BIT[chunks]
                            chunks &= chunks - 1
                            j0 = (node * LANES + t) * LANES
                            for j in range(j0, j0 + LANES):
                                dx = px - pos[0, j]
                                dy = py - pos[1, j]
                                dz = pz - pos[2, j]
                                reach = accuracy * np.float64(nr[3, j])
                                cand[n_cand] = j
                                n_cand += dx * dx + dy * dy + dz * dz <= reach * reach * (1.0 + 1e-9)
                        continue
                    # all nodes seen or the buffer nearly full: Eqs. 5 and 6 for the candidates
                    n_hit = 0
                    for c in range(n_cand):
                        j = cand[c]
                        dx = px - pos[0, j]
                        dy = py - pos[1, j]
                        dz = pz - pos[2, j]
                        Ri = np.float64(nr[3, j])
                        mx = np.float64(nr[0, j])
                        my = np.float64(nr[1, j])
                        mz = np.float64(nr[2, j])
                        ndot = min(nx * mx + ny * my + nz * mz, 1.0)
                        d2 = dx * dx + dy * dy + dz * dz
                        ok = True
                        if shaped:              # elliptical domain and leak sectors
                            i = perm[j]
                            dw = dx * V[i, 7, 0] + dy * V[i, 7, 1] + dz * V[i, 7, 2]
                            d2 += dw * dw
                            if leak[i] != 0:
                                ok = _sector_open(leak[i], dx, dy, dz, mx, my, mz, Ri)
                        err = np.sqrt(d2) / Ri + np.sqrt(1.0 - ndot)
                        front = 0.5 * (dx * (nx + mx) + dy * (ny + my) + dz * (nz + mz))
                        hit_j[n_hit] = j
                        if taper:
                            hit_w[n_hit] = 1.0 - err / accuracy
                        else:
                            hit_w[n_hit] = 1.0 / max(err, MIN_ERROR)
                        n_hit += (err < accuracy) & (front >= -FRONT_TOLERANCE * Ri) & ok & (nr[4, j] == qz)
                    for c in range(n_hit):
                        j = hit_j[c]
                        w = hit_w[c]
                        i = perm[j]
                        e0 = np.float64(V[i, 0, 0])
                        e1 = np.float64(V[i, 0, 1])
                        e2 = np.float64(V[i, 0, 2])
                        if gradients:
                            dx = px - pos[0, j]
                            dy = py - pos[1, j]
                            dz = pz - pos[2, j]
                            mx = np.float64(nr[0, j])
                            my = np.float64(nr[1, j])
                            mz = np.float64(nr[2, j])
                            cx = my * nz - mz * ny      # N_i × N
                            cy = mz * nx - mx * nz
                            cz = mx * ny - my * nx
                            # V[i, 1 + c] = ∇_r E_c, V[i, 4 + c] = ∇_t E_c (channel c)
                            e0 = max(0.0, e0 + V[i, 1, 0] * cx + V[i, 1, 1] * cy + V[i, 1, 2] * cz
                                     + V[i, 4, 0] * dx + V[i, 4, 1] * dy + V[i, 4, 2] * dz)
                            e1 = max(0.0, e1 + V[i, 2, 0] * cx + V[i, 2, 1] * cy + V[i, 2, 2] * cz
                                     + V[i, 5, 0] * dx + V[i, 5, 1] * dy + V[i, 5, 2] * dz)
                            e2 = max(0.0, e2 + V[i, 3, 0] * cx + V[i, 3, 1] * cy + V[i, 3, 2] * cz
                                     + V[i, 6, 0] * dx + V[i, 6, 1] * dy + V[i, 6, 2] * dz)
                        if pairs > 0:
                            if written < pairs:
                                pair_record[q, written] = i
                                pair_weight[q, written] = w
                                written += 1
                            else:                       # full: replace the smallest
                                low = 0
                                for t in range(1, pairs):
                                    if pair_weight[q, t] < pair_weight[q, low]:
                                        low = t
                                if w > pair_weight[q, low]:
                                    pair_record[q, low] = i
                                    pair_weight[q, low] = w
                        sw += w
                        s0 += w * e0
                        s1 += w * e1
                        s2 += w * e2
                    count += n_hit
                    n_cand = 0
                    if mask == 0 and gi >= n_groups:
                        break
                out_w[q] = sw
                out_n[q] = count
                for t in range(written, pairs):
                    pair_record[q, t] = -1
                    pair_weight[q, t] = 0.0
                if sw > 0.0:
                    out_E[q, 0] = s0 / sw
                    out_E[q, 1] = s1 / sw
                    out_E[q, 2] = s2 / sw
                else:
                    out_E[q, 0] = 0.0
                    out_E[q, 1] = 0.0
                    out_E[q, 2] = 0.0
            k = k_end


_lookup_kernel = nogil_kernel(_lookup)


def _covered(qP, qN, qZ, accuracy, shaped, V, leak, perm, pos, nr, box, level_start, out):
    """Compiled body of :func:`covered`: each query walks the box tree alone, depth
    first, and stops at the first record that serves it."""
    n_levels = level_start.shape[0] - 1
    root = level_start[n_levels - 1]
    for q in range(qP.shape[0]):
        px, py, pz = qP[q, 0], qP[q, 1], qP[q, 2]
        nx, ny, nz = qN[q, 0], qN[q, 1], qN[q, 2]
        qz = np.float32(qZ[q])
        xlo, xhi = _f32_below(px), _f32_above(px)
        ylo, yhi = _f32_below(py), _f32_above(py)
        zlo, zhi = _f32_below(pz), _f32_above(pz)
        found = False
        stack = np.empty(LANES * (n_levels + 1), np.int64)
        top = 0
        if ((box[root, 0, 0] <= xhi) & (box[root, 3, 0] >= xlo) & (box[root, 1, 0] <= yhi)
                & (box[root, 4, 0] >= ylo) & (box[root, 2, 0] <= zhi) & (box[root, 5, 0] >= zlo)):
            stack[0] = (n_levels - 1) << 48
            top = 1
        while top > 0 and not found:
            top -= 1
            lev = stack[top] >> 48
            node = stack[top] & 0xFFFFFFFFFFFF
            g = level_start[lev - 1] + node           # the group of its children
            for t in range(LANES):
                if not ((box[g, 0, t] <= xhi) & (box[g, 3, t] >= xlo) & (box[g, 1, t] <= yhi)
                        & (box[g, 4, t] >= ylo) & (box[g, 2, t] <= zhi) & (box[g, 5, t] >= zlo)):
                    continue
                if lev > 1:
                    stack[top] = ((lev - 1) << 48) | (node * LANES + t)
                    top += 1
                    continue
                j0 = (node * LANES + t) * LANES      # a chunk: its records
                for j in range(j0, j0 + LANES):
                    dx = px - pos[0, j]
                    dy = py - pos[1, j]
                    dz = pz - pos[2, j]
                    Ri = np.float64(nr[3, j])
                    d2 = dx * dx + dy * dy + dz * dz
                    if not d2 <= (accuracy * Ri) ** 2 * (1.0 + 1e-9) or nr[4, j] != qz:
                        continue                      # (NaN padding fails here too)
                    mx = np.float64(nr[0, j])
                    my = np.float64(nr[1, j])
                    mz = np.float64(nr[2, j])
                    ok = True
                    if shaped:
                        i = perm[j]
                        dw = dx * V[i, 7, 0] + dy * V[i, 7, 1] + dz * V[i, 7, 2]
                        d2 += dw * dw
                        if leak[i] != 0:
                            ok = _sector_open(leak[i], dx, dy, dz, mx, my, mz, Ri)
                    ndot = min(nx * mx + ny * my + nz * mz, 1.0)
                    err = np.sqrt(d2) / Ri + np.sqrt(1.0 - ndot)
                    front = 0.5 * (dx * (nx + mx) + dy * (ny + my) + dz * (nz + mz))
                    if ok and err < accuracy and front >= -FRONT_TOLERANCE * Ri:
                        found = True
                        break
                if found:
                    break
        out[q] = found


_covered_kernel = nogil_kernel(_covered)


def covered(qP, qN, qZ, layout: Layout, V, leak, shaped, accuracy, out, parallel):
    """Whether any record serves each query (``count > 0`` of :func:`lookup`, exactly).

    For placement, where most queries meet few records: each query walks the box tree
    on its own (no sort, no packets) and stops at the first record that passes Eqs. 5
    and 6 (elliptical, and outside its leak sectors, when ``shaped``).  ``out``: (q,) bool.
    """
    shared = (accuracy, bool(shaped), V, leak, layout.perm, layout.pos, layout.nr, layout.box, layout.level_start)
    if not parallel:
        _covered_kernel(qP, qN, qZ, *shared, out)
        return
    in_threads(len(qP), kernel_threads(),
               lambda lo, hi: _covered_kernel(qP[lo:hi], qN[lo:hi], qZ[lo:hi], *shared, out[lo:hi]))


def lookup(qP, qN, qZ, order, layout: Layout, V, leak, gradients, shaped, accuracy, out_E, out_w, out_n, parallel,
           taper=False, pairs=None):
    """Interpolate (Eq. 5) the records valid at each query on a :func:`freeze` layout.

    qP, qN : (q, 3) float64 query positions [m] and unit normals
    qZ : (q,) uint8 zone of each query: only records of its zone serve it
        (:meth:`lbl_illum.engine.portals.PortalSet.zone`: inside the building's windows or not)
    order : (q,) int, the order in which to visit the queries (a permutation)
    V : (n, 8, 3) float32, by record: irradiance E_i (row 0), rotational gradient ∇_r E_i
        (rows 1–3, one per channel), translational gradient ∇_t E_i (rows 4–6) and the
        shape vector W_i of an elliptical domain (row 7)
    leak : (n,) uint32 leak sectors per record
    out_E, out_w, out_n : (q, 3), (q,), (q,) outputs, written at each query's index

    With ``gradients`` a record contributes E_i + (N_i × N)·∇_r E_i + (P − P_i)·∇_t E_i
    (Ward & Heckbert 1992), each channel kept ≥ 0.  For query q: ``out_E[q] = Σ w_i E_i
    / Σ w_i`` over the set S, ``out_w[q] = Σ w_i`` and ``out_n[q] = |S|``; a query with
    ``out_n[q] == 0`` is not covered.  A record farther than a R_i is rejected before
    Eq. 5 is evaluated (its ε_i ≥ |P − P_i|/R_i ≥ a); the margin keeps that cheap test
    from ever deciding a boundary case.  ``parallel`` runs the queries on numba's
    threads (worth it only for batches of thousands of queries).

    With ``shaped`` (Hessian-based records, :func:`lbl_illum.engine.hessian.hessian_radii`)
    the distance term of Eq. 5 is elliptical, sqrt(|d|² + (d·W_i)²)/R_i with R_i the long
    radius, and a record is not used for queries in its leak sectors.

    With ``taper`` the weights are w_i = 1 − ε_i/a, which fall to zero at the edge of a
    record's domain instead of jumping there from 0 to 1/a, and stay finite at the record
    (Radiance 5 weighs its records with such ramps, ``tfunc`` in ``ambient.c``).  The
    paper's weights make a visible step where a record's domain ends, a circle on a wall
    in an image, and a peak at each record; the ramp leaves the average continuous.  (The
    renderer asks for it without ``gradients``: :meth:`lbl_illum.engine.integrator.Integrator.compute`.)  Images use it (:meth:`lbl_illum.engine.integrator.Integrator.compute`'s
    ``taper``); sensor values keep the paper's weights.

    ``pairs = (record, weight)``, (q, K) int32 and float64: each query's records and their
    weights w_i (not normalised), -1 and 0 after the last (the K largest if more serve it),
    for callers that interpolate other values with the same weights (daylight
    coefficients: :mod:`lbl_illum.engine.coefficients`).
    """
    if pairs is None:
        pairs = (np.zeros((0, 0), np.int32), np.zeros((0, 0)))
    # a few blocks per thread: each block allocates its own buffers (the list of
    # level-1 boxes is sized for all of them)
    n_blocks = min(len(qP) // 256 + 1, 8 * kernel_threads()) if parallel else 1
    shared = (accuracy, bool(gradients), bool(shaped), bool(taper), V, leak, layout.perm, layout.pos, layout.nr, layout.box,
              layout.level_start, float(layout.packet_extent), out_E, out_w, out_n, *pairs)
    if n_blocks == 1:
        _lookup_kernel(qP, qN, qZ, order, 1, *shared)
        return
    # each block, a range of ``order``, on a thread: its queries' answers are its own
    in_threads(len(order), n_blocks, lambda lo, hi: _lookup_kernel(qP, qN, qZ, order[lo:hi], 1, *shared))

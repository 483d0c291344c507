"""Compiled octree kernels for the irradiance records (the paper's §3.3 and Eqs. 5–6).

Records are structure-of-arrays: position P (n, 3) float64, unit normal N (n, 3)
float32, irradiance E (n, 3) float32, radius R (n,) float32.  A record i is valid
for a query (P, N) when its error estimate is below the accuracy ``a`` (Eq. 5),

    ε_i(P, N) = |P − P_i| / R_i + sqrt(1 − N · N_i)  <  a        ⇔  w_i = 1/ε_i > 1/a,

and it is not "in front" of the query (Eq. 6):

    d_i(P) = (P − P_i) · (N + N_i) / 2  ≥  −FRONT_TOLERANCE · R_i.

The tolerance only absorbs floating-point round-off for records on the same plane.

Octree: each record lives in the node that contains P_i and whose side s satisfies
2 a R_i < s ≤ 4 a R_i (records larger than the root stay in the root).  The paper's
search tests a node's records and descends into each child whose cube, grown by half
the child's side on every face, contains P.  Here each node also keeps the box around
the valid domains (P_i ± a R_i) of every record in its subtree, and the search
descends into a child only when that box contains P.  This is exact — a record
serves only queries inside its domain, which lies inside every box on its path —
and tighter than the grown cube (which it implies), so a query far from all records
stops at the root.  Nodes are arrays: centre, half side, domain box, eight child
indices (-1: none) and the head of a singly linked list of records.  For lookups the
tree is frozen (:func:`freeze`): each node's records are laid out contiguously, one
64-byte row (P, N, R, a R) each, so a record test reads one cache line.
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

__all__ = ["FRONT_TOLERANCE", "MAX_DEPTH", "insert_records", "freeze", "lookup"]

#: Records at most this far (relative to R_i) behind the query's tangent plane still count as level.
FRONT_TOLERANCE = 1e-3
#: Deepest octree level (a cube 2^-48 of the root's side is far below float resolution).
MAX_DEPTH = 48
#: Smallest error estimate used in a weight: a query on a record gets weight 1e6, not a
#: value decided by round-off in sqrt(1 − N·N_i).
MIN_ERROR = 1e-6


@njit(cache=True)
def insert_records(start, stop, P, R, accuracy, rec_next, node_center, node_half, node_child,
                   node_first, node_lo, node_hi, n_nodes):
    """Insert records ``start:stop`` into the octree; return (n_nodes, next record).

    Stops early (next record < stop) when the node arrays are full; the caller grows
    them and calls again from the returned record.
    """
    capacity = node_half.shape[0]
    for i in range(start, stop):
        domain = accuracy * R[i]
        node = 0
        depth = 0
        while True:
            for c in range(3):
                if P[i, c] - domain < node_lo[node, c]:
                    node_lo[node, c] = P[i, c] - domain
                if P[i, c] + domain > node_hi[node, c]:
                    node_hi[node, c] = P[i, c] + domain
            if not (2.0 * node_half[node] > 4.0 * domain and depth < MAX_DEPTH):
                break
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
                for c in range(3):
                    node_lo[child, c] = np.inf
                    node_hi[child, c] = -np.inf
                node_first[child] = -1
                node_child[node, octant] = child
            node = child
            depth += 1
        rec_next[i] = node_first[node]
        node_first[node] = i
    return n_nodes, stop


@njit(cache=True)
def freeze(n_nodes, node_first, rec_next, P, N, R, accuracy, node_lo, node_hi,
           node_start, node_count, node_box, perm, packed):
    """Lay the records out for lookups: contiguous per node, one 64-byte row each.

    ``packed[j] = (P, N, R, a R)`` of record ``perm[j]``; the records of a node are
    ``node_start[node] : node_start[node] + node_count[node]``, in the order of its
    list.  ``node_box[node]`` is the node's domain box (lo, hi).
    """
    pos = 0
    for node in range(n_nodes):
        node_start[node] = pos
        for c in range(3):
            node_box[node, c] = node_lo[node, c]
            node_box[node, 3 + c] = node_hi[node, c]
        i = node_first[node]
        while i >= 0:
            perm[pos] = i
            for c in range(3):
                packed[pos, c] = P[i, c]
                packed[pos, 3 + c] = N[i, c]
            packed[pos, 6] = R[i]
            packed[pos, 7] = accuracy * R[i]
            pos += 1
            i = rec_next[i]
        node_count[node] = pos - node_start[node]


@njit(cache=True, parallel=True)
def lookup(qP, qN, packed, E, Gr, Gt, gradients, node_start, node_count, node_child, node_box, accuracy,
           out_E, out_w, out_n):
    """Interpolate (Eq. 5) the records valid at each query, on a :func:`freeze` layout.

    ``E``, ``Gr``, ``Gt`` hold the records' irradiance and gradients in the frozen
    order.  With ``gradients`` a record contributes E_i + (N_i × N)·∇_r E_i +
    (P − P_i)·∇_t E_i (Ward & Heckbert 1992), each channel kept ≥ 0.  For query q:
    ``out_E[q] = Σ w_i E_i / Σ w_i`` over the set S, ``out_w[q] = Σ w_i`` and
    ``out_n[q] = |S|``.  A query with ``out_n[q] == 0`` is not covered.  A record
    farther than a R_i is rejected before Eq. 5 is evaluated (its ε_i ≥ |P − P_i|/R_i
    ≥ a); the margin keeps that cheap test from ever deciding a boundary case.
    """
    nq = qP.shape[0]
    n_blocks = min(nq, 256)
    for b in prange(n_blocks):
        stack = np.empty(8 * MAX_DEPTH + 8, dtype=np.int32)
        for q in range(b * nq // n_blocks, (b + 1) * nq // n_blocks):
            px, py, pz = qP[q, 0], qP[q, 1], qP[q, 2]
            nx, ny, nz = qN[q, 0], qN[q, 1], qN[q, 2]
            sw = 0.0
            s0 = 0.0
            s1 = 0.0
            s2 = 0.0
            count = 0
            top = 0
            if (node_box[0, 0] <= px <= node_box[0, 3] and node_box[0, 1] <= py <= node_box[0, 4]
                    and node_box[0, 2] <= pz <= node_box[0, 5]):
                stack[0] = 0
                top = 1
            while top > 0:
                top -= 1
                node = stack[top]
                start = node_start[node]
                for j in range(start, start + node_count[node]):
                    dx = px - packed[j, 0]
                    dy = py - packed[j, 1]
                    dz = pz - packed[j, 2]
                    d2 = dx * dx + dy * dy + dz * dz
                    reach = packed[j, 7]
                    if d2 > reach * reach * (1.0 + 1e-9):
                        continue
                    ndot = nx * packed[j, 3] + ny * packed[j, 4] + nz * packed[j, 5]
                    if ndot > 1.0:
                        ndot = 1.0
                    err = np.sqrt(d2) / packed[j, 6] + np.sqrt(1.0 - ndot)
                    front = 0.5 * (dx * (nx + packed[j, 3]) + dy * (ny + packed[j, 4]) + dz * (nz + packed[j, 5]))
                    if err < accuracy and front >= -FRONT_TOLERANCE * packed[j, 6]:
                        w = 1.0 / max(err, MIN_ERROR)
                        sw += w
                        e0 = E[j, 0]
                        e1 = E[j, 1]
                        e2 = E[j, 2]
                        if gradients:
                            cx = packed[j, 4] * nz - packed[j, 5] * ny      # N_i × N
                            cy = packed[j, 5] * nx - packed[j, 3] * nz
                            cz = packed[j, 3] * ny - packed[j, 4] * nx
                            e0 = max(0.0, e0 + Gr[j, 0, 0] * cx + Gr[j, 0, 1] * cy + Gr[j, 0, 2] * cz
                                     + Gt[j, 0, 0] * dx + Gt[j, 0, 1] * dy + Gt[j, 0, 2] * dz)
                            e1 = max(0.0, e1 + Gr[j, 1, 0] * cx + Gr[j, 1, 1] * cy + Gr[j, 1, 2] * cz
                                     + Gt[j, 1, 0] * dx + Gt[j, 1, 1] * dy + Gt[j, 1, 2] * dz)
                            e2 = max(0.0, e2 + Gr[j, 2, 0] * cx + Gr[j, 2, 1] * cy + Gr[j, 2, 2] * cz
                                     + Gt[j, 2, 0] * dx + Gt[j, 2, 1] * dy + Gt[j, 2, 2] * dz)
                        s0 += w * e0
                        s1 += w * e1
                        s2 += w * e2
                        count += 1
                for c in range(8):
                    child = node_child[node, c]
                    if child >= 0:
                        if (node_box[child, 0] <= px <= node_box[child, 3]
                                and node_box[child, 1] <= py <= node_box[child, 4]
                                and node_box[child, 2] <= pz <= node_box[child, 5]):
                            stack[top] = child
                            top += 1
            out_w[q] = sw
            out_n[q] = count
            if sw > 0.0:
                out_E[q, 0] = s0 / sw
                out_E[q, 1] = s1 / sw
                out_E[q, 2] = s2 / sw
            else:
                out_E[q, 0] = 0.0
                out_E[q, 1] = 0.0
                out_E[q, 2] = 0.0

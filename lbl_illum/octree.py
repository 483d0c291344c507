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
indices (-1: none) and the head of a singly linked list of records.
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

__all__ = ["FRONT_TOLERANCE", "MAX_DEPTH", "insert_records", "lookup", "weight_terms"]

#: Records at most this far (relative to R_i) behind the query's tangent plane still count as level.
FRONT_TOLERANCE = 1e-3
#: Deepest octree level (a cube 2^-48 of the root's side is far below float resolution).
MAX_DEPTH = 48
#: Smallest error estimate used in a weight: a query on a record gets weight 1e6, not a
#: value decided by round-off in sqrt(1 − N·N_i).
MIN_ERROR = 1e-6


@njit(cache=True, inline="always")
def weight_terms(px, py, pz, nx, ny, nz, P, N, R, i):
    """(ε_i, d_i) of Eqs. 5 and 6 for record ``i`` and the query (p, n)."""
    dx = px - P[i, 0]
    dy = py - P[i, 1]
    dz = pz - P[i, 2]
    dist = np.sqrt(dx * dx + dy * dy + dz * dz)
    ndot = nx * N[i, 0] + ny * N[i, 1] + nz * N[i, 2]
    if ndot > 1.0:
        ndot = 1.0
    err = dist / R[i] + np.sqrt(1.0 - ndot)
    front = 0.5 * (dx * (nx + N[i, 0]) + dy * (ny + N[i, 1]) + dz * (nz + N[i, 2]))
    return err, front


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


@njit(cache=True, parallel=True)
def lookup(qP, qN, P, N, E, R, accuracy, rec_next, node_center, node_half, node_child, node_first,
           node_lo, node_hi, out_E, out_w, out_n):
    """Interpolate (Eq. 5) the records valid at each query.

    For query q: ``out_E[q] = Σ w_i E_i / Σ w_i`` over the set S, ``out_w[q] = Σ w_i``
    and ``out_n[q] = |S|``.  A query with ``out_n[q] == 0`` is not covered.
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
            if (node_lo[0, 0] <= px <= node_hi[0, 0] and node_lo[0, 1] <= py <= node_hi[0, 1]
                    and node_lo[0, 2] <= pz <= node_hi[0, 2]):
                stack[0] = 0
                top = 1
            while top > 0:
                top -= 1
                node = stack[top]
                i = node_first[node]
                while i >= 0:
                    err, front = weight_terms(px, py, pz, nx, ny, nz, P, N, R, i)
                    if err < accuracy and front >= -FRONT_TOLERANCE * R[i]:
                        w = 1.0 / max(err, MIN_ERROR)
                        sw += w
                        s0 += w * E[i, 0]
                        s1 += w * E[i, 1]
                        s2 += w * E[i, 2]
                        count += 1
                    i = rec_next[i]
                for c in range(8):
                    child = node_child[node, c]
                    if child >= 0:
                        if (node_lo[child, 0] <= px <= node_hi[child, 0]
                                and node_lo[child, 1] <= py <= node_hi[child, 1]
                                and node_lo[child, 2] <= pz <= node_hi[child, 2]):
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

"""Stratified sampling of the projected hemisphere (the paper's Eq. 2).

For a point with unit normal N, the illuminance integral (Eq. 1)
``E = ∫∫ L(θ, φ) cos θ sin θ dθ dφ`` is estimated with M × N cells,

    E ≈ π / (M N) · Σ_j Σ_k L(θ_j, φ_k),
    θ_j = asin( sqrt( (j − X_jk) / M ) ),   φ_k = 2π (k − Y_jk) / N,

X, Y uniform in [0, 1).  The θ-spacing makes every cell carry the same projected
solid angle, so the estimate is an unweighted mean.  N ≈ π M keeps cells square.

What a record's rays give beyond E — its gradients (:mod:`lbl_illum.engine.gradients`),
its Hessian, Hessian radii and leak sectors (:mod:`lbl_illum.engine.hessian`) — is
computed from the same stratified cells in those modules.
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

from .compiled import RowKernel
from ..scene.geometry import orthonormal_basis

__all__ = ["orthonormal_basis", "cell_counts", "stratified_directions", "cosine_directions"]


def cell_counts(samples: int) -> tuple[int, int]:
    """(M, N) for about ``samples`` cells with N ≈ π M (Eq. 2); M·N ≥ 1."""
    samples = max(1, int(samples))
    m = max(1, int(round(np.sqrt(samples / np.pi))))
    n = max(1, int(round(samples / m)))
    return m, n


@njit(cache=True, inline="always")
def _tangents(nx, ny, nz):
    """The two tangents of :func:`orthonormal_basis` for one unit normal (Duff et al. 2017)."""
    sign = 1.0 if nz >= 0.0 else -1.0
    a = -1.0 / (sign + nz)
    b = nx * ny * a
    return 1.0 + sign * nx * nx * a, sign * b, -sign * nx, b, sign + ny * ny * a, -ny


def _stratified(normals, u, v, m, n, out):
    """Compiled body of :func:`stratified_directions`."""
    for i in prange(normals.shape[0]):
        nx, ny, nz = normals[i, 0], normals[i, 1], normals[i, 2]
        tx, ty, tz, bx, by, bz = _tangents(nx, ny, nz)
        for j in range(m):
            for k in range(n):
                c = j * n + k
                sin2 = (j + 1 - u[i, c]) / m
                sin_t = np.sqrt(sin2)
                cos_t = np.sqrt(max(0.0, 1.0 - sin2))
                phi = 2.0 * np.pi * (k + 1 - v[i, c]) / n
                x = sin_t * np.cos(phi)
                y = sin_t * np.sin(phi)
                out[i, c, 0] = x * tx + y * bx + cos_t * nx
                out[i, c, 1] = x * ty + y * by + cos_t * ny
                out[i, c, 2] = x * tz + y * bz + cos_t * nz


_stratified_kernel = RowKernel(_stratified, rows=(0, 1, 2, 5))


def stratified_directions(normals: np.ndarray, m: int, n: int, rng: np.random.Generator) -> np.ndarray:
    """(r, m·n, 3) unit directions of Eq. 2 over the hemispheres of (r, 3) ``normals``.

    Each of the m·n cells of every hemisphere receives one jittered direction;
    every direction carries the weight π / (m n) of the estimate: cell (j, k) (0-based,
    index j·n + k) has sin²θ = (j + 1 − X)/M and φ = 2π (k + 1 − Y)/N.
    """
    normals = np.ascontiguousarray(normals, dtype=np.float64).reshape(-1, 3)
    r = normals.shape[0]
    u = rng.random((r, m * n))
    v = rng.random((r, m * n))
    out = np.empty((r, m * n, 3))
    _stratified_kernel(normals, u, v, m, n, out, work=r * m * n)
    return out


def cosine_directions(normals: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """(r, 3) cosine-distributed directions, one per normal (Eq. 2 with M = N = 1)."""
    return stratified_directions(normals, 1, 1, rng)[:, 0, :]

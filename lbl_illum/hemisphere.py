"""Stratified sampling of the projected hemisphere (the paper's Eq. 2).

For a point with unit normal N, the illuminance integral (Eq. 1)
``E = ∫∫ L(θ, φ) cos θ sin θ dθ dφ`` is estimated with M × N cells,

    E ≈ π / (M N) · Σ_j Σ_k L(θ_j, φ_k),
    θ_j = asin( sqrt( (j − X_jk) / M ) ),   φ_k = 2π (k − Y_jk) / N,

X, Y uniform in [0, 1).  The θ-spacing makes every cell carry the same projected
solid angle, so the estimate is an unweighted mean.  N ≈ π M keeps cells square.
"""

from __future__ import annotations

import numpy as np

__all__ = ["orthonormal_basis", "cell_counts", "stratified_directions", "cosine_directions"]


def orthonormal_basis(normals: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Two (n, 3) unit tangents completing (n, 3) unit ``normals`` to a right-handed frame.

    Branch-free construction of Duff et al., "Building an Orthonormal Basis,
    Revisited", JCGT 6(1), 2017.
    """
    n = np.asarray(normals, dtype=np.float64)
    x, y, z = n[:, 0], n[:, 1], n[:, 2]
    sign = np.where(z >= 0.0, 1.0, -1.0)
    a = -1.0 / (sign + z)
    b = x * y * a
    t = np.stack([1.0 + sign * x * x * a, sign * b, -sign * x], axis=1)
    s = np.stack([b, sign + y * y * a, -y], axis=1)
    return t, s


def cell_counts(samples: int) -> tuple[int, int]:
    """(M, N) for about ``samples`` cells with N ≈ π M (Eq. 2); M·N ≥ 1."""
    samples = max(1, int(samples))
    m = max(1, int(round(np.sqrt(samples / np.pi))))
    n = max(1, int(round(samples / m)))
    return m, n


def _to_world(normals, local):
    t, s = orthonormal_basis(normals)
    return (local[..., 0:1] * t[:, None, :] + local[..., 1:2] * s[:, None, :]
            + local[..., 2:3] * normals[:, None, :])


def stratified_directions(normals: np.ndarray, m: int, n: int, rng: np.random.Generator) -> np.ndarray:
    """(r, m·n, 3) unit directions of Eq. 2 over the hemispheres of (r, 3) ``normals``.

    Each of the m·n cells of every hemisphere receives one jittered direction;
    every direction carries the weight π / (m n) of the estimate.
    """
    normals = np.asarray(normals, dtype=np.float64)
    r = normals.shape[0]
    j = np.repeat(np.arange(1, m + 1), n)[None, :]
    k = np.tile(np.arange(1, n + 1), m)[None, :]
    u = rng.random((r, m * n))
    v = rng.random((r, m * n))
    sin2 = (j - u) / m
    sin_t = np.sqrt(sin2)
    cos_t = np.sqrt(np.maximum(0.0, 1.0 - sin2))
    phi = 2.0 * np.pi * (k - v) / n
    local = np.stack([sin_t * np.cos(phi), sin_t * np.sin(phi), cos_t], axis=-1)
    return _to_world(normals, local)


def cosine_directions(normals: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """(r, 3) cosine-distributed directions, one per normal (Eq. 2 with M = N = 1)."""
    return stratified_directions(normals, 1, 1, rng)[:, 0, :]

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

__all__ = ["orthonormal_basis", "cell_counts", "stratified_directions", "cosine_directions",
           "irradiance_gradients", "limit_gradients"]


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


#: Hit distances below this [m] count as this in the gradients' 1/r (a ray leaving a
#: corner may hit the adjacent surface at t ≈ 0).
MIN_GRADIENT_DISTANCE = 1e-9


def limit_gradients(E: np.ndarray, rotational: np.ndarray, translational: np.ndarray,
                    domain: np.ndarray, accuracy: float) -> tuple[np.ndarray, np.ndarray]:
    """Gradients no record can use to change its value by more than 100 % inside its
    valid domain: |∇_t E|·a R_i ≤ E and |∇_r E|·a ≤ E per channel (a R_i = ``domain``,
    the largest |P − P_i| and, roughly, the largest rotation Eq. 5 admits).  Non-finite
    gradients become 0.

    E : (r, 3); rotational, translational : (r, 3, 3); domain : (r,) [m].
    """
    rot = np.where(np.isfinite(rotational), rotational, 0.0)
    trans = np.where(np.isfinite(translational), translational, 0.0)
    E = np.maximum(np.asarray(E, np.float64), 0.0)
    for g, reach in ((trans, domain[:, None]), (rot, np.full((len(E), 1), accuracy))):
        size = np.linalg.norm(g, axis=2) * reach
        scale = np.where(size > E, E / np.maximum(size, 1e-300), 1.0)
        g *= scale[:, :, None]
    return rot, trans


def irradiance_gradients(normals: np.ndarray, directions: np.ndarray, radiance: np.ndarray,
                         distances: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Rotational and translational irradiance gradients from one Eq. 2 sample set.

    Ward & Heckbert, "Irradiance Gradients", Eurographics Workshop on Rendering 1992,
    for an M × N stratification with sin²θ in [j/M, (j+1)/M) and φ in [2πk/N, 2π(k+1)/N):

    * rotational:    ∇_r E = π/(M N) Σ_jk tan θ_jk L_jk v(φ_jk),  v(φ) = n × u(φ) the
      tangent direction at φ + π/2, so that E(n) ≈ E + (n_i × n) · ∇_r E (rotating n by δ
      about a ⊥ n changes E by δ a · ∫ L (n × ω) dω, and n × ω = sin θ v(φ));
    * translational: ∇_t E = Σ_k [ u_k (2π/N) Σ_{j≥1} sin θ_j− cos²θ_j− / min(r_jk, r_j−1,k)
      · (L_jk − L_j−1,k)  +  v_k− Σ_j (sin θ_j+ − sin θ_j−) / min(r_jk, r_j,k−1)
      · (L_jk − L_j,k−1) ],  u_k the tangent direction at the stratum's centre φ and v_k−
      the one perpendicular to its boundary 2πk/N; r the hit distances (the sky: ∞) and
      θ_j± the stratum's bounds.  Each term is the projected solid angle a cell boundary
      sweeps when the point moves: a θ boundary shifts by dθ = cos θ dx / r, a φ boundary
      by dφ = dx / (r sin θ), and ∫ cos θ sin θ dφ dθ over the stratum gives the
      coefficients.  (The φ coefficient is derived here from that rule; checked against
      central differences of converged Monte Carlo values in the tests.)

    so that E(P) ≈ E + (P − P_i) · ∇_t E.

    Parameters
    ----------
    normals : (r, 3) unit normals of the records
    directions : (r, M, N, 3) the sample directions, stratum (j, k) at [:, j, k]
    radiance : (r, M, N, C) radiance along them [cd/m²], C channels (3 for RGB)
    distances : (r, M, N) hit distances [m], inf for rays that reach the sky

    Returns
    -------
    (rotational, translational) : (r, C, 3) each — [record, channel, axis], in lux per
    radian and lux per metre.
    """
    r, m, n = distances.shape
    t, b = orthonormal_basis(normals)
    cos = np.clip(np.einsum("rjkx,rx->rjk", directions, normals), 1e-3, 1.0)
    sin = np.sqrt(1.0 - cos * cos)
    x = np.einsum("rjkx,rx->rjk", directions, t)
    y = np.einsum("rjkx,rx->rjk", directions, b)
    phi = np.arctan2(y, x)
    v = -np.sin(phi)[..., None] * t[:, None, None, :] + np.cos(phi)[..., None] * b[:, None, None, :]
    rot = np.pi / (m * n) * np.einsum("rjk,rjkc,rjkx->rcx", sin / cos, radiance, v)

    distances = np.asarray(distances, np.float64)
    inv = np.where(np.isfinite(distances), 1.0 / np.maximum(distances, MIN_GRADIENT_DISTANCE), 0.0)
    trans = np.zeros((r, radiance.shape[-1], 3))
    if m > 1:   # differences across θ boundaries, along the stratum's centre direction
        j = np.arange(1, m)
        s2 = j / m
        coef = np.sqrt(s2) * (1.0 - s2)                                     # sin θ− cos² θ−
        near = np.maximum(inv[:, 1:, :], inv[:, :-1, :])                    # 1 / min(r, r')
        dL = radiance[:, 1:, :, :] - radiance[:, :-1, :, :]
        phi_c = 2.0 * np.pi * (np.arange(n) + 0.5) / n
        u = np.cos(phi_c)[None, :, None] * t[:, None, :] + np.sin(phi_c)[None, :, None] * b[:, None, :]
        A = (2.0 * np.pi / n) * np.einsum("j,rjk,rjkc->rkc", coef, near, dL)
        trans += np.einsum("rkc,rkx->rcx", A, u)
    if n > 1:   # differences across φ boundaries, perpendicular to them
        j = np.arange(m)
        coef = np.sqrt((j + 1) / m) - np.sqrt(j / m)                       # sin θ+ − sin θ−
        near = np.maximum(inv, np.roll(inv, 1, axis=2))
        dL = radiance - np.roll(radiance, 1, axis=2)
        phi_b = 2.0 * np.pi * np.arange(n) / n
        vb = -np.sin(phi_b)[None, :, None] * t[:, None, :] + np.cos(phi_b)[None, :, None] * b[:, None, :]
        B = np.einsum("j,rjk,rjkc->rkc", coef, near, dL)
        trans += np.einsum("rkc,rkx->rcx", B, vb)
    return rot, trans

"""Irradiance gradients from a record's hemisphere samples (Ward & Heckbert, "Irradiance
Gradients", Eurographics Rendering Workshop 1992), and their limit for interpolation.

The rotational gradient (how E changes as the normal turns, [lux/rad]) and the
translational gradient (as the point moves, [lux/m]) follow from the stratified cells of
Eq. 2 (:mod:`lbl_illum.engine.hemisphere`) and the distances of their first hits; the
paper's Eq. 5 interpolation uses them as first-order corrections.
"""

from __future__ import annotations

import numpy as np

from .compiled import RowKernel
from .hemisphere import _tangents

__all__ = ["MIN_GRADIENT_DISTANCE", "irradiance_gradients", "limit_gradients"]


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
    directions = np.asarray(directions)
    radiance = np.asarray(radiance)
    distances = np.asarray(distances)
    r = distances.shape[0]
    C = radiance.shape[-1]
    rot = np.zeros((r, C, 3))
    trans = np.zeros((r, C, 3))
    if r:
        # float64 throughout: one compiled specialisation (float32 inputs widen exactly,
        # and the kernel's arithmetic is float64 either way)
        _gradients_kernel(np.ascontiguousarray(normals, np.float64), np.ascontiguousarray(directions, np.float64),
                          np.ascontiguousarray(radiance, np.float64), np.ascontiguousarray(distances, np.float64),
                          rot, trans, work=r * distances.shape[1] * distances.shape[2])
    return rot, trans


def _gradients(normals, directions, radiance, distances, rot, trans):
    """Compiled body of :func:`irradiance_gradients`: one record per iteration."""
    r, m, n = distances.shape
    C = radiance.shape[3]
    for i in range(r):
        nx, ny, nz = normals[i, 0], normals[i, 1], normals[i, 2]
        tx, ty, tz, bx, by, bz = _tangents(nx, ny, nz)
        scale = np.pi / (m * n)
        inv = np.empty((m, n))
        for j in range(m):
            for k in range(n):
                dx, dy, dz = directions[i, j, k, 0], directions[i, j, k, 1], directions[i, j, k, 2]
                cos = min(max(dx * nx + dy * ny + dz * nz, 1e-3), 1.0)
                tan = np.sqrt(1.0 - cos * cos) / cos
                phi = np.arctan2(dx * bx + dy * by + dz * bz, dx * tx + dy * ty + dz * tz)
                s, c = np.sin(phi), np.cos(phi)
                vx, vy, vz = -s * tx + c * bx, -s * ty + c * by, -s * tz + c * bz
                for ch in range(C):
                    w = scale * tan * radiance[i, j, k, ch]
                    rot[i, ch, 0] += w * vx
                    rot[i, ch, 1] += w * vy
                    rot[i, ch, 2] += w * vz
                dist = distances[i, j, k]
                inv[j, k] = 1.0 / max(dist, MIN_GRADIENT_DISTANCE) if np.isfinite(dist) else 0.0
        for k in range(n):
            if m > 1:      # θ boundaries, along the stratum's centre direction
                phi = 2.0 * np.pi * (k + 0.5) / n
                ux, uy, uz = (np.cos(phi) * tx + np.sin(phi) * bx, np.cos(phi) * ty + np.sin(phi) * by,
                              np.cos(phi) * tz + np.sin(phi) * bz)
                for ch in range(C):
                    acc = 0.0
                    for j in range(1, m):
                        s2 = j / m
                        near = max(inv[j, k], inv[j - 1, k])
                        acc += np.sqrt(s2) * (1.0 - s2) * near * (radiance[i, j, k, ch] - radiance[i, j - 1, k, ch])
                    acc *= 2.0 * np.pi / n
                    trans[i, ch, 0] += acc * ux
                    trans[i, ch, 1] += acc * uy
                    trans[i, ch, 2] += acc * uz
            if n > 1:      # φ boundaries, perpendicular to them
                phi = 2.0 * np.pi * k / n
                ux, uy, uz = (-np.sin(phi) * tx + np.cos(phi) * bx, -np.sin(phi) * ty + np.cos(phi) * by,
                              -np.sin(phi) * tz + np.cos(phi) * bz)
                kp = k - 1 if k > 0 else n - 1
                for ch in range(C):
                    acc = 0.0
                    for j in range(m):
                        coef = np.sqrt((j + 1) / m) - np.sqrt(j / m)
                        near = max(inv[j, k], inv[j, kp])
                        acc += coef * near * (radiance[i, j, k, ch] - radiance[i, j, kp, ch])
                    trans[i, ch, 0] += acc * ux
                    trans[i, ch, 1] += acc * uy
                    trans[i, ch, 2] += acc * uz


_gradients_kernel = RowKernel(_gradients, rows=(0, 1, 2, 3, 4, 5))

"""Lambert's formula: the irradiance from a polygon of uniform luminance in closed form,
with its gradient and Hessian with respect to the receiver's position.

A polygon of luminance L [cd/m²] seen from a receiver with unit normal n, wholly above
its tangent plane, gives E = L · Σ_edges ½ γ_e (n · ĉ_e) [lux] (Lambert 1760; Arvo,
"Applications of irradiance tensors to the simulation of non-Lambertian phenomena",
SIGGRAPH 1995, §3): γ_e the angle the edge subtends, ĉ_e the unit normal of the plane
through the receiver and the edge.  :func:`lambert_edge` gives one edge's term and its
first and second derivatives in closed form; the irradiance Hessian of a record's
hemisphere (:func:`lbl_illum.engine.hessian.irradiance_hessian`) and the light of window
portals (:func:`portal_irradiance`) are sums of it.
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

from .compiled import RowKernel

__all__ = ["lambert_edge", "portal_irradiance"]


@njit(cache=True, inline="always")
def lambert_edge(acc, coef, p, q, nx, ny, nz, tx, ty, tz, bx, by, bz):
    """Irradiance term of one polygon edge and its derivatives in the tangent plane.

    For an edge from r0 to r1 (vertex positions relative to the receiver, which has unit
    normal n), Lambert's formula gives the edge's share of the projected solid angle,
    f = ½ (n·c) I1 with c = r0 × r1 and I1 = ∫₀¹ |r0 + s e|⁻² ds = γ/|c| (γ the angle
    between r0 and r1, e = r1 − r0).  Moving the receiver by x moves every r by −x, so
    with I2 = ∫|r|⁻⁴, J2 = ∫ s|r|⁻⁴, I3 = ∫|r|⁻⁶, J3 = ∫ s|r|⁻⁶, K3 = ∫ s²|r|⁻⁶
    (closed forms by the reduction ∫Q⁻ⁿ⁻¹ = ([(a s + b)/Qⁿ] + a(2n − 1)∫Q⁻ⁿ)/(2nΔ),
    Q = a s² + 2 b s + c₀, Δ = a c₀ − b² = |c|²) and V2 = I2 r0 + J2 e, m = n × e:

        ∇f  = ½ I1 m + (n·c) V2
        ∇∇f = m V2ᵀ + V2 mᵀ − (n·c) I2 Id + 4 (n·c)(I3 r0 r0ᵀ + J3 (r0 eᵀ + e r0ᵀ) + K3 e eᵀ)

    (the edge formulas of Schwarzhaupt, Jensen & Jarosz, "Practical Hessian-Based Error
    Control for Irradiance Caching", SIGGRAPH Asia 2012, derived here).  Adds ``coef``
    times f, ∇f·t, ∇f·b, t∇∇f t, t∇∇f b, b∇∇f b to ``acc`` for the edge from ``p`` to
    ``q``; nothing for a degenerate edge or a zero ``coef``.
    """
    if coef == 0.0:
        return
    r0x, r0y, r0z, r1x, r1y, r1z = p[0], p[1], p[2], q[0], q[1], q[2]
    ex, ey, ez = r1x - r0x, r1y - r0y, r1z - r0z
    cx, cy, cz = r0y * r1z - r0z * r1y, r0z * r1x - r0x * r1z, r0x * r1y - r0y * r1x
    D = cx * cx + cy * cy + cz * cz
    a = ex * ex + ey * ey + ez * ez
    c0 = r0x * r0x + r0y * r0y + r0z * r0z
    c1 = r1x * r1x + r1y * r1y + r1z * r1z
    if D <= 1e-24 * c0 * c1 or a <= 1e-30 * (c0 + c1):
        return
    b = ex * r0x + ey * r0y + ez * r0z
    er1 = ex * r1x + ey * r1y + ez * r1z
    sD = np.sqrt(D)
    I1 = np.arctan2(sD, r0x * r1x + r0y * r1y + r0z * r1z) / sD
    I2 = (er1 / c1 - b / c0 + a * I1) / (2.0 * D)
    J2 = (0.5 * (1.0 / c0 - 1.0 / c1) - b * I2) / a
    I3 = (er1 / (c1 * c1) - b / (c0 * c0) + 3.0 * a * I2) / (4.0 * D)
    J3 = (0.25 * (1.0 / (c0 * c0) - 1.0 / (c1 * c1)) - b * I3) / a
    K3 = (I2 - 2.0 * b * J3 - c0 * I3) / a
    nc = nx * cx + ny * cy + nz * cz
    mx, my, mz = ny * ez - nz * ey, nz * ex - nx * ez, nx * ey - ny * ex
    # projections on the tangents
    m_t, m_b = mx * tx + my * ty + mz * tz, mx * bx + my * by + mz * bz
    r_t, r_b = r0x * tx + r0y * ty + r0z * tz, r0x * bx + r0y * by + r0z * bz
    e_t, e_b = ex * tx + ey * ty + ez * tz, ex * bx + ey * by + ez * bz
    v_t, v_b = I2 * r_t + J2 * e_t, I2 * r_b + J2 * e_b
    acc[0] += coef * 0.5 * nc * I1
    acc[1] += coef * (0.5 * I1 * m_t + nc * v_t)
    acc[2] += coef * (0.5 * I1 * m_b + nc * v_b)
    w = 4.0 * nc
    acc[3] += coef * (2.0 * m_t * v_t - nc * I2 + w * (I3 * r_t * r_t + 2.0 * J3 * r_t * e_t + K3 * e_t * e_t))
    acc[4] += coef * (m_t * v_b + v_t * m_b + w * (I3 * r_t * r_b + J3 * (r_t * e_b + e_t * r_b) + K3 * e_t * e_b))
    acc[5] += coef * (2.0 * m_b * v_b - nc * I2 + w * (I3 * r_b * r_b + 2.0 * J3 * r_b * e_b + K3 * e_b * e_b))


@njit(cache=True, inline="always")
def lambert_polygon(poly, m, nx, ny, nz):
    """Signed projected solid angle [sr] of the polygon ``poly[:m]`` (vertices relative to
    the receiver, wholly above its tangent plane) seen from a receiver of unit normal n:
    Σ_edges ½ γ_e (n · ĉ_e), the value of :func:`lambert_edge` without its derivatives.
    Positive when the polygon winds counter-clockwise seen from the receiver."""
    total = 0.0
    for a in range(m):
        b = (a + 1) % m
        r0x, r0y, r0z = poly[a, 0], poly[a, 1], poly[a, 2]
        r1x, r1y, r1z = poly[b, 0], poly[b, 1], poly[b, 2]
        cx, cy, cz = r0y * r1z - r0z * r1y, r0z * r1x - r0x * r1z, r0x * r1y - r0y * r1x
        sc = np.sqrt(cx * cx + cy * cy + cz * cz)
        if sc <= 0.0:
            continue
        gamma = np.arctan2(sc, r0x * r1x + r0y * r1y + r0z * r1z)
        total += 0.5 * gamma * (nx * cx + ny * cy + nz * cz) / sc
    return total


@njit(cache=True, inline="always")
def _clip_above(v, nx, ny, nz, out):
    """The part of triangle ``v`` (3, 3; relative to the receiver) above the receiver's
    tangent plane, into ``out`` (4, 3) by Sutherland–Hodgman; returns its vertex count."""
    m = 0
    for i in range(3):
        j = (i + 1) % 3
        hi = v[i, 0] * nx + v[i, 1] * ny + v[i, 2] * nz
        hj = v[j, 0] * nx + v[j, 1] * ny + v[j, 2] * nz
        if hi > 0.0:
            for c in range(3):
                out[m, c] = v[i, c]
            m += 1
        if (hi > 0.0) != (hj > 0.0):
            s = hi / (hi - hj)
            for c in range(3):
                out[m, c] = v[i, c] + s * (v[j, c] - v[i, c])
            m += 1
    return m


def _portals(P, N, T, B, vertices, weight, outward, out):
    """Compiled body of :func:`portal_irradiance`: one receiver per iteration."""
    for i in prange(P.shape[0]):
        nx, ny, nz = N[i, 0], N[i, 1], N[i, 2]
        tx, ty, tz = T[i, 0], T[i, 1], T[i, 2]
        bx, by, bz = B[i, 0], B[i, 1], B[i, 2]
        rel = np.empty((3, 3))
        poly = np.empty((4, 3))
        acc = np.empty(6)                  # zeroed per portal below
        total = np.empty(6)                # np.empty and a loop: numba's np.zeros compiles its own code
        for c in range(6):
            total[c] = 0.0
        for k in range(vertices.shape[0]):
            if weight[k] == 0.0:
                continue
            side = 0.0                      # (P - centroid) . outward: > 0 in front of the window
            for c in range(3):
                side += (P[i, c] - (vertices[k, 0, c] + vertices[k, 1, c] + vertices[k, 2, c]) / 3.0) * outward[k, c]
            if side >= 0.0:
                continue
            for a in range(3):
                for c in range(3):
                    rel[a, c] = vertices[k, a, c] - P[i, c]
            m = _clip_above(rel, nx, ny, nz, poly)
            if m < 3:
                continue
            for c in range(6):
                acc[c] = 0.0
            for a in range(m):
                lambert_edge(acc, 1.0, poly[a], poly[(a + 1) % m], nx, ny, nz, tx, ty, tz, bx, by, bz)
            sign = weight[k] if acc[0] >= 0.0 else -weight[k]      # the winding seen from the receiver
            for c in range(6):
                total[c] += sign * acc[c]
        for c in range(6):
            out[i, c] = total[c]


_portal_kernel = RowKernel(_portals, rows=(0, 1, 2, 3, 7))


def portal_irradiance(points: np.ndarray, normals: np.ndarray, tangents, triangles: np.ndarray,
                      luminance: np.ndarray, outward: np.ndarray) -> np.ndarray:
    """Irradiance from window portals at receivers, unoccluded, with its gradient and Hessian.

    Each portal triangle k is a uniform source of luminance ``luminance[k]`` towards the
    side opposite its ``outward`` normal (k, 3) (the sky lies beyond it); a receiver on the
    outer side gets nothing from it.  The part of it above a receiver's tangent plane
    gives Lambert's closed form (module text).  What lies between the receiver and a
    window is ignored, so the result depends on the geometry alone, never on sampled rays.

    points, normals : (r, 3) receivers [m] and unit normals; tangents : ``(t, b)``, two
    (r, 3) unit tangents completing each normal; triangles : (k, 3, 3) [m];
    luminance : (k,) [cd/m²].  Returns (r, 6): E [lux], ∂E/∂t, ∂E/∂b [lux/m], ∂²E/∂t²,
    ∂²E/∂t∂b, ∂²E/∂b² [lux/m²] — the layout of
    :func:`~lbl_illum.engine.hessian.irradiance_hessian`, which :func:`~lbl_illum.engine.hessian.hessian_radii` reads.
    """
    points = np.ascontiguousarray(points, np.float64)
    r = len(points)
    out = np.zeros((r, 6))
    if r and len(triangles):
        t, b = tangents
        _portal_kernel(
            points, np.ascontiguousarray(normals, np.float64), np.ascontiguousarray(t, np.float64),
            np.ascontiguousarray(b, np.float64), np.ascontiguousarray(triangles, np.float64),
            np.ascontiguousarray(luminance, np.float64), np.ascontiguousarray(outward, np.float64), out, work=r * len(triangles))
    return out

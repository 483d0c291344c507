"""The irradiance Hessian of a record's hemisphere, Hessian-based record radii and leak
sectors: elliptical record domains (Schwarzhaupt, Jensen & Jarosz, "Practical
Hessian-Based Error Control for Irradiance Caching", ACM TOG 31(6), 2012; the project's
``interpolation = "hessian"``, docs/architecture.md).

The Hessian comes from Lambert's closed form over the triangles that the stratified
cells' first hits span (:func:`lbl_illum.engine.lambert.lambert_edge`), in the record's
tangent frame (:mod:`lbl_illum.engine.hemisphere`); units of the values times sr, per m
and per m².
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

from .compiled import RowKernel
from .gradients import MIN_GRADIENT_DISTANCE
from .hemisphere import _tangents
from .lambert import lambert_edge
from ..scene.geometry import orthonormal_basis

__all__ = ["LEAK_SECTORS", "MAX_ANISOTROPY", "irradiance_hessian", "hessian_radii", "leak_sectors"]


#: Sectors of a record's tangent plane that the leak test flags (one bit each).
LEAK_SECTORS = 32


@njit(cache=True, inline="always")
def _farthest(d0, v0, d1, v1, d2, v2):
    """The value of the farthest of three vertices (the first on ties)."""
    if d1 > d0 and d1 >= d2:
        return v1
    if d2 > d0 and d2 > d1:
        return v2
    return v0


def _hessian(normals, directions, values, distances, far, out):
    """Compiled body of :func:`irradiance_hessian`: one record per iteration."""
    r, m, n = distances.shape
    for i in prange(r):
        nx, ny, nz = normals[i, 0], normals[i, 1], normals[i, 2]
        tx, ty, tz, bx, by, bz = _tangents(nx, ny, nz)
        hit = np.empty((m, n, 3))
        dist = np.empty((m, n))
        for j in range(m):
            for k in range(n):
                d = distances[i, j, k]
                d = far if not np.isfinite(d) or d > far else max(d, MIN_GRADIENT_DISTANCE)
                dist[j, k] = d
                for c in range(3):
                    hit[j, k, c] = d * directions[i, j, k, c]
        # apex of the polar cap: along the normal at the mean distance of the first ring
        apex_d = 0.0
        apex_v = 0.0
        for k in range(n):
            apex_d += dist[0, k]
            apex_v += values[i, 0, k]
        apex_d /= n
        apex_v /= n
        # triangle values: the value at the farthest vertex (what lies behind a depth step)
        t1 = np.zeros((m, n))        # T1(j, k) = (j, k) (j, k+1) (j+1, k)
        t2 = np.zeros((m, n))        # T2(j, k) = (j+1, k+1) (j+1, k) (j, k+1)
        cap = np.zeros(n)            # C(k) = (0, k+1) (0, k) apex
        for k in range(n):
            kp = k + 1 if k + 1 < n else 0
            cap[k] = _farthest(apex_d, apex_v, dist[0, kp], values[i, 0, kp], dist[0, k], values[i, 0, k])
            for j in range(m - 1):
                t1[j, k] = _farthest(dist[j, k], values[i, j, k], dist[j, kp], values[i, j, kp],
                                     dist[j + 1, k], values[i, j + 1, k])
                t2[j, k] = _farthest(dist[j + 1, kp], values[i, j + 1, kp], dist[j + 1, k], values[i, j + 1, k],
                                     dist[j, kp], values[i, j, kp])
        acc = np.zeros(6)
        apex = np.array([apex_d * nx, apex_d * ny, apex_d * nz])
        for k in range(n):
            kp = k + 1 if k + 1 < n else 0
            km = k - 1 if k > 0 else n - 1
            # spoke apex -> (0, k): + C(k-1), - C(k)
            lambert_edge(acc, cap[km] - cap[k], apex, hit[0, k], nx, ny, nz, tx, ty, tz, bx, by, bz)
            for j in range(m):
                # ring edge (j, k) -> (j, k+1): + T1(j, k), - T2(j-1, k) (the cap above row 0)
                coef = (t1[j, k] if j < m - 1 else 0.0) - (t2[j - 1, k] if j > 0 else cap[k])
                lambert_edge(acc, coef, hit[j, k], hit[j, kp], nx, ny, nz, tx, ty, tz, bx, by, bz)
                if j < m - 1:
                    # diagonal (j, k+1) -> (j+1, k): + T1(j, k), - T2(j, k)
                    lambert_edge(acc, t1[j, k] - t2[j, k], hit[j, kp], hit[j + 1, k], nx, ny, nz, tx, ty, tz,
                              bx, by, bz)
                    # meridian (j, k) -> (j+1, k): + T2(j, k-1), - T1(j, k)
                    lambert_edge(acc, t2[j, km] - t1[j, k], hit[j, k], hit[j + 1, k], nx, ny, nz, tx, ty, tz,
                              bx, by, bz)
        sign = 1.0 if acc[0] >= 0.0 else -1.0    # the grid's orientation as seen from the receiver
        for c in range(6):
            out[i, c] = sign * acc[c]


_hessian_kernel = RowKernel(_hessian, rows=(0, 1, 2, 3, 5))


def irradiance_hessian(normals: np.ndarray, directions: np.ndarray, values: np.ndarray,
                       distances: np.ndarray, far: float) -> np.ndarray:
    """Irradiance, its gradient and its Hessian in the tangent plane, from one Eq. 2 sample set.

    The hemisphere's hit points, joined into triangles along the M × N strata (two per
    cell, and a fan from a point on the normal over the polar cap), make a polygonal
    model of what the record sees; each triangle carries the value at its farthest
    vertex (across a depth step, the farther surface is the one a moving receiver
    uncovers).  The irradiance of that model and its first and second derivatives with
    respect to the receiver's position follow in closed form edge by edge
    (:func:`~lbl_illum.engine.lambert.lambert_edge`): Schwarzhaupt, Jensen & Jarosz, "Practical Hessian-Based Error
    Control for Irradiance Caching", ACM TOG 31(6), 2012; Radiance 5 builds its record
    radii the same way.  Rays that reach the sky are hits at distance ``far``.

    Parameters
    ----------
    normals : (r, 3) unit normals;  directions : (r, M, N, 3), stratum (j, k) at [:, j, k]
    values : (r, M, N) radiance along them (one channel; any unit)
    distances : (r, M, N) hit distances [m], inf for the sky;  far : [m]

    Returns
    -------
    (r, 6): E, ∂E/∂t, ∂E/∂b, ∂²E/∂t², ∂²E/∂t∂b, ∂²E/∂b², with (t, b) the tangents of
    :func:`orthonormal_basis`; in the unit of ``values`` times sr, per m and per m².
    """
    distances = np.ascontiguousarray(distances, np.float64)
    r = distances.shape[0]
    out = np.zeros((r, 6))
    if r:
        # a record costs about 4 rays' work per stratum: threads from PARALLEL_MIN / 4 strata
        _hessian_kernel(np.ascontiguousarray(normals, np.float64), np.ascontiguousarray(directions, np.float64),
                        np.ascontiguousarray(values, np.float64), distances, float(far), out,
                        work=4 * r * distances.shape[1] * distances.shape[2])
    return out


#: Largest ratio of a record's long radius to its short one (Radiance 5 uses 2 too).
MAX_ANISOTROPY = 2.0


def hessian_radii(normals: np.ndarray, terms: np.ndarray, accuracy: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Anisotropic record radii from :func:`irradiance_hessian`'s ``terms``.

    With the relative gradient g = ∇E/E and Hessian H = ∇∇E/E in the tangent plane, a
    value carried a distance x along an eigenvector of H (eigenvalue λ) by its gradient
    is wrong by about ½ |λ| x² (Schwarzhaupt, Jensen & Jarosz 2012).  Eq. 5 admits
    queries up to a R from a record, so the radius along that axis is chosen to make
    the error there equal a:

        R = sqrt(2 / (a |λ|)),    and R ≤ 1 / |g · axis|

    (the second limit, as in Radiance 5, keeps a noisy gradient from moving the value
    by more than a across the domain).  The long radius is at most MAX_ANISOTROPY times
    the short one.

    Returns (R_short, R_long, short_axis): (r,), (r,) [m] — inf where nothing limits
    them — and (r, 3) unit vectors in the tangent plane along the short radius.
    """
    normals = np.asarray(normals, np.float64)
    E = terms[:, 0]
    ok = E > 0.0
    inv = np.where(ok, 1.0 / np.where(ok, E, 1.0), 0.0)
    gt, gb = terms[:, 1] * inv, terms[:, 2] * inv
    htt, htb, hbb = terms[:, 3] * inv, terms[:, 4] * inv, terms[:, 5] * inv
    mean = 0.5 * (htt + hbb)
    half = np.hypot(0.5 * (htt - hbb), htb)
    l1, l2 = mean + half, mean - half
    big_first = np.abs(l1) >= np.abs(l2)
    lam_s = np.where(big_first, np.abs(l1), np.abs(l2))     # the larger |λ|: the short radius
    lam_l = np.where(big_first, np.abs(l2), np.abs(l1))
    l_s = np.where(big_first, l1, l2)
    # eigenvector of l_s: (htb, l_s − htt), or (l_s − hbb, htb); the better conditioned one
    v1t, v1b = htb, l_s - htt
    v2t, v2b = l_s - hbb, htb
    first = v1t * v1t + v1b * v1b >= v2t * v2t + v2b * v2b
    ct, cb = np.where(first, v1t, v2t), np.where(first, v1b, v2b)
    norm = np.hypot(ct, cb)
    round_ = norm <= 1e-12 * np.maximum(np.abs(l_s), 1e-300)
    ct, cb = np.where(round_, 1.0, ct / np.where(round_, 1.0, norm)), np.where(round_, 0.0, cb / np.where(round_, 1.0, norm))
    a = max(float(accuracy), 1e-12)
    with np.errstate(divide="ignore"):
        # along (ct, cb), the eigenvector of the larger |λ|, and across it
        R_c = np.minimum(np.sqrt(2.0 / (a * lam_s)), 1.0 / np.abs(gt * ct + gb * cb))
        R_p = np.minimum(np.sqrt(2.0 / (a * lam_l)), 1.0 / np.abs(gb * ct - gt * cb))
    swap = R_p < R_c                 # the gradient limit made the other axis the short one
    ct, cb = np.where(swap, -cb, ct), np.where(swap, ct, cb)
    R_s, R_l = np.minimum(R_c, R_p), np.maximum(R_c, R_p)
    R_l = np.minimum(R_l, MAX_ANISOTROPY * R_s)
    t, b = orthonormal_basis(normals)
    axis = ct[:, None] * t + cb[:, None] * b
    return np.where(ok, R_s, np.inf), np.where(ok, R_l, np.inf), axis


#: Hemisphere rays at most this far above the tangent plane (sin of 20°) can mark an
#: occluder that stands between a record and its queries.
LEAK_SIN_ELEVATION = 0.342


def _leaks(normals, directions, distances, reach_s, reach_l, axis, n_phi, out):
    """Compiled body of :func:`leak_sectors`."""
    r, S = distances.shape
    half = np.pi / n_phi
    width = 2.0 * np.pi / LEAK_SECTORS
    for i in prange(r):
        nx, ny, nz = normals[i, 0], normals[i, 1], normals[i, 2]
        tx, ty, tz, bx, by, bz = _tangents(nx, ny, nz)
        ux, uy, uz = axis[i, 0], axis[i, 1], axis[i, 2]
        vx, vy, vz = ny * uz - nz * uy, nz * ux - nx * uz, nx * uy - ny * ux
        # a ceiling lower than the domain: everything near is an "occluder"; no flags
        inv = 0.0
        count = 0
        for s in range(S):
            dx, dy, dz = directions[i, s, 0], directions[i, s, 1], directions[i, s, 2]
            if dx * nx + dy * ny + dz * nz >= 0.7:
                d = distances[i, s]
                inv += 1.0 / d if np.isfinite(d) and d > 0.0 else 0.0
                count += 1
        if count and inv / count * reach_s[i] >= 1.0:
            out[i] = 0
            continue
        mask = np.uint32(0)
        for s in range(S):
            dx, dy, dz = directions[i, s, 0], directions[i, s, 1], directions[i, s, 2]
            d = distances[i, s]
            if dx * nx + dy * ny + dz * nz > LEAK_SIN_ELEVATION or not np.isfinite(d) or d <= 0.0:
                continue
            qu = d * (dx * ux + dy * uy + dz * uz)
            qv = d * (dx * vx + dy * vy + dz * vz)
            if (qu / reach_s[i]) ** 2 + (qv / reach_l[i]) ** 2 > 1.0:
                continue        # the occluder lies outside the domain
            phi = np.arctan2(d * (dx * bx + dy * by + dz * bz), d * (dx * tx + dy * ty + dz * tz))
            lo = int(np.floor((phi - half) / width))
            hi = int(np.floor((phi + half) / width))
            for sec in range(lo, hi + 1):
                mask |= np.uint32(1) << np.uint32(sec % LEAK_SECTORS)
        out[i] = mask


_leak_kernel = RowKernel(_leaks, rows=(0, 1, 2, 3, 4, 5, 7))


def leak_sectors(normals, directions, distances, reach_short, reach_long, axis, n_phi) -> np.ndarray:
    """Directions in which a record must not be used: occluders inside its domain.

    A hemisphere ray that leaves a record at less than 20° above its tangent plane and
    hits something inside the record's domain (the ellipse of semi-axes ``reach_short``
    along ``axis`` and ``reach_long`` across it, a R) has found an occluder between the
    record and the queries beyond it — a wall standing on the floor, a partition — so
    the record's value may not hold there ("light leaks").  The tangent plane is cut
    into LEAK_SECTORS sectors around the normal, measured from the first tangent of
    :func:`orthonormal_basis`; every sector within half a stratum (π/``n_phi``) of such
    a ray is flagged.  Under a ceiling lower than the domain every direction would be
    flagged, so nothing is (Radiance 5's ambcorral makes both choices).

    normals : (r, 3); directions : (r, S, 3); distances : (r, S) [m], inf for the sky;
    reach_short, reach_long : (r,) [m]; axis : (r, 3).  Returns (r,) uint32 bit masks.
    """
    distances = np.ascontiguousarray(distances, np.float64)
    r = distances.shape[0]
    out = np.zeros(r, np.uint32)
    if r:
        _leak_kernel(np.ascontiguousarray(normals, np.float64), np.ascontiguousarray(directions, np.float64), distances,
                     np.ascontiguousarray(reach_short, np.float64), np.ascontiguousarray(reach_long, np.float64),
                     np.ascontiguousarray(axis, np.float64), int(n_phi), out, work=r * distances.shape[1])
    return out

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
from numba import njit, prange

from .compiled import PARALLEL_MIN, serial_and_parallel
from .lambert import lambert_edge
from ..scene.geometry import orthonormal_basis

__all__ = ["orthonormal_basis", "cell_counts", "stratified_directions", "cosine_directions", "irradiance_hessian",
           "irradiance_gradients", "limit_gradients"]


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


_stratified_kernels = serial_and_parallel(_stratified)


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
    _stratified_kernels[r * m * n >= PARALLEL_MIN](normals, u, v, m, n, out)
    return out


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
    directions = np.asarray(directions)
    radiance = np.asarray(radiance)
    distances = np.asarray(distances)
    r = distances.shape[0]
    C = radiance.shape[-1]
    rot = np.zeros((r, C, 3))
    trans = np.zeros((r, C, 3))
    if r:
        kernel = _gradients_kernels[r * distances.shape[1] * distances.shape[2] >= PARALLEL_MIN]
        kernel(np.ascontiguousarray(normals, np.float64), np.ascontiguousarray(directions),
               np.ascontiguousarray(radiance), np.ascontiguousarray(distances), rot, trans)
    return rot, trans


def _gradients(normals, directions, radiance, distances, rot, trans):
    """Compiled body of :func:`irradiance_gradients`: one record per iteration."""
    r, m, n = distances.shape
    C = radiance.shape[3]
    for i in prange(r):
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


_gradients_kernels = serial_and_parallel(_gradients)


# -- Hessian-based record radii (Schwarzhaupt, Jensen & Jarosz 2012) ---------------------------

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


_hessian_kernels = serial_and_parallel(_hessian)


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
        kernel = _hessian_kernels[r * distances.shape[1] * distances.shape[2] >= PARALLEL_MIN // 4]
        kernel(np.ascontiguousarray(normals, np.float64), np.ascontiguousarray(directions, np.float64),
               np.ascontiguousarray(values, np.float64), distances, float(far), out)
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


_leak_kernels = serial_and_parallel(_leaks)


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
        _leak_kernels[r * distances.shape[1] >= PARALLEL_MIN](
            np.ascontiguousarray(normals, np.float64), np.ascontiguousarray(directions, np.float64), distances,
            np.ascontiguousarray(reach_short, np.float64), np.ascontiguousarray(reach_long, np.float64),
            np.ascontiguousarray(axis, np.float64), int(n_phi), out)
    return out

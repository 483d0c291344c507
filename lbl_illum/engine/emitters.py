"""Direct illuminance from ``light`` surfaces: closed form for what is in view, shadow rays
for what is hidden.

A light surface of luminance L (two-sided, Lambertian) gives a receiver of unit normal n

    E = ∫ L V(ω) max(0, n·ω) dω = E₀ · S,   S = ∫ L V max(0, n·ω) dω / E₀,

E₀ the irradiance with nothing in the way, V(ω) ∈ [0, 1] the transmittance of the segment
towards the source (0 behind an opaque surface, the product of the panes' τ(θ) through
glass) and S the visible share.  E₀ is known in closed form, so shadow rays estimate only
S, as the ratio Σ T w / Σ w of the same rays' weights with and without the things in the
way (Heitz, Hill & McGuire, "Combining analytic direct illumination and stochastic
shadows", I3D 2018).  A source in full view gets its closed form, with no noise; per-point
noise is left only in penumbrae and behind glass.

Closed forms of E₀ [lux]:

* a triangle: Lambert's formula (:func:`~lbl_illum.engine.lambert.lambert_polygon`) of the
  part above the receiver's tangent plane, the sign taken from the winding (both faces
  emit).  A triangle farther than :data:`FAR_RATIO` times its longest edge is a point
  source, E₀ = L A cos θ_r cos θ_l / d² at its centroid (relative error below 1e-3 there).
* a sphere primitive (its true centre and radius, not its facets): E₀ = π L sin²α cos θ_c
  when wholly above the tangent plane (Nusselt: a uniform sphere lights like a point at its
  centre), α the half-angle of its cone and θ_c the angle to its centre; Snyder's closed
  form when the plane cuts the cone (:func:`_sphere_unoccluded`).

The hidden part is sampled with the sources chosen in proportion to their E₀ at the
point (photometric, Y), stratified over a jittered grid: the grid's first axis runs along
the sources' cumulative shares and, within a source, along its solid angle (triangles:
uniform over the spherical triangle by Arvo's construction, pdf 1/Ω; below
:data:`MIN_SOLID_ANGLE`, uniform in area by the square-to-triangle map; spheres: uniform in
the cone of half-angle α, pdf 1/Ω, Ω = 2π(1 − cos α)).  A point gets ``samples`` rays
times ⌈Ω_p/:data:`SPLIT_SOLID_ANGLE`⌉ (at most :data:`MORE_FOR_LARGE` times), Ω_p the
projected solid angle of the sources it sees: a large panel overhead gets more rays than
a small one across the room (the idea of Radiance's ``-ds``).  Where some of a point's
rays are blocked and some not (a penumbra) and ``samples`` > 1 (sensor points, pixels),
the estimate is replaced by one of :data:`PENUMBRA_LIGHT_SAMPLES` rays; the test also
looks along the sources' edges (:data:`RIM_LIGHT_RAYS` rays shared by the sources as their
contributions are), so that an occluder that hides only an edge of a source is seen.

**Cost.**  The closed forms cost about 23 ns per source and point, at every hit of the
indirect calculation too: a room under a luminous ceiling of 1,200 triangles took 31 times
as long at 3 bounces as with area sampling (validation/bench/direct_emitters.py).  Area
sampling at those hits was tried as the remedy for many sources and dropped: one point per
hit on 240 small panels left the interreflected light 11 % low over four seeds (its
weights L cos θ_r cos θ_l / (d² p_A) are unbounded near an emitter, so a finite sample
mostly misses the tail).  A light hierarchy that treats far clusters as one source is the
way to lift this cost.
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

from .compiled import RowKernel
from .hemisphere import _tangents
from .lambert import _clip_above, lambert_polygon
from ..photometry import luminance

__all__ = ["LightSurfaces", "FAR_RATIO", "PENUMBRA_LIGHT_SAMPLES"]

#: A triangle farther than this many times its longest edge is a point source.
FAR_RATIO = 30.0
#: Solid angle [sr] under which a triangle is sampled uniformly in area, not in solid angle.
MIN_SOLID_ANGLE = 1e-4
#: Projected solid angle [sr] of the sources in view per multiple of the base sample count.
SPLIT_SOLID_ANGLE = 0.25
#: Most multiples of the base sample count for large sources.
MORE_FOR_LARGE = 4
#: Shadow rays per point in a penumbra (sensor points and pixels).
PENUMBRA_LIGHT_SAMPLES = 1024
#: Rays along the sources' edges at sensor points and pixels, for the penumbra test only.
RIM_LIGHT_RAYS = 32
#: How far rim rays aim inside an edge, as a fraction of the way to the triangle's centroid
#: (or of the cone's angle).
RIM_INSET = 1e-3
#: Most shadow rays planned at once (memory: about 80 bytes each).
MAX_RAYS_PER_BLOCK = 1 << 20


@njit(cache=True, inline="always")
def _sphere_unoccluded(px, py, pz, nx, ny, nz, cx, cy, cz, r):
    """Projected solid angle [sr] of a sphere (centre c, radius r) from a receiver at p of
    unit normal n, 0 from inside (module text).  When the receiver's plane cuts the cone of
    half-angle α around the centre direction (cos² θ < sin² α, θ the angle from n to the
    centre), Snyder's closed form ("Area light sources for real-time graphics", Microsoft
    Research MSR-TR-96-11, 1996; as written in Lagarde & de Rousiers, "Moving Frostbite
    to physically based rendering", SIGGRAPH 2014 course, §4.7.2):
    x = cot α, y = −x cot θ, E/L = (cos θ acos y − x sin θ √(1 − y²)) sin² α + atan(sin θ √(1 − y²) / x)."""
    wx, wy, wz = cx - px, cy - py, cz - pz
    d = np.sqrt(wx * wx + wy * wy + wz * wz)
    if d <= r:
        return 0.0
    s2 = (r / d) ** 2
    cos_t = (nx * wx + ny * wy + nz * wz) / d
    if cos_t * cos_t >= s2:
        return np.pi * s2 * cos_t if cos_t > 0.0 else 0.0
    sin_t = np.sqrt(max(0.0, 1.0 - cos_t * cos_t))
    x = np.sqrt(max(0.0, 1.0 / s2 - 1.0))
    y = min(1.0, max(-1.0, -x * cos_t / sin_t))
    sy = sin_t * np.sqrt(max(0.0, 1.0 - y * y))
    return max(0.0, (cos_t * np.arccos(y) - x * sy) * s2 + np.arctan2(sy, x))


@njit(cache=True, inline="always")
def _unit_tangent(ax, ay, az, bx, by, bz):
    """The unit vector along b's part orthogonal to the unit vector a (0 if none)."""
    d = ax * bx + ay * by + az * bz
    tx, ty, tz = bx - d * ax, by - d * ay, bz - d * az
    n = np.sqrt(tx * tx + ty * ty + tz * tz)
    if n <= 0.0:
        return 0.0, 0.0, 0.0
    return tx / n, ty / n, tz / n


@njit(cache=True, inline="always")
def _corner_angle(ax, ay, az, bx, by, bz, cx, cy, cz):
    """Angle [rad] at the corner a of the spherical triangle (a, b, c) of unit vectors."""
    ux, uy, uz = _unit_tangent(ax, ay, az, bx, by, bz)
    vx, vy, vz = _unit_tangent(ax, ay, az, cx, cy, cz)
    return np.arccos(min(1.0, max(-1.0, ux * vx + uy * vy + uz * vz)))


@njit(cache=True, inline="always")
def _spherical_triangle(ax, ay, az, bx, by, bz, cx, cy, cz, u1, u2):
    """A direction uniform in solid angle over the spherical triangle of the unit vectors
    a, b, c, from two uniform numbers (Arvo, "Stratified sampling of spherical triangles",
    SIGGRAPH 1995: u1 picks the sub-triangle of area u1·Ω, u2 the point along its arc),
    and the triangle's solid angle Ω [sr] (α + β + γ − π)."""
    alpha = _corner_angle(ax, ay, az, bx, by, bz, cx, cy, cz)
    beta = _corner_angle(bx, by, bz, cx, cy, cz, ax, ay, az)
    gamma = _corner_angle(cx, cy, cz, ax, ay, az, bx, by, bz)
    area = alpha + beta + gamma - np.pi
    if area <= 0.0:
        return 0.0, 0.0, 0.0, 0.0
    sub = u1 * area
    s, t = np.sin(sub - alpha), np.cos(sub - alpha)
    u = t - np.cos(alpha)
    v = s + np.sin(alpha) * (ax * bx + ay * by + az * bz)
    den = (v * s + u * t) * np.sin(alpha)
    q = ((v * t - u * s) * np.cos(alpha) - v) / den if den != 0.0 else 1.0
    q = min(1.0, max(-1.0, q))
    ex, ey, ez = _unit_tangent(ax, ay, az, cx, cy, cz)
    r = np.sqrt(max(0.0, 1.0 - q * q))
    hx, hy, hz = q * ax + r * ex, q * ay + r * ey, q * az + r * ez
    z = 1.0 - u2 * (1.0 - (hx * bx + hy * by + hz * bz))
    z = min(1.0, max(-1.0, z))
    fx, fy, fz = _unit_tangent(bx, by, bz, hx, hy, hz)
    w = np.sqrt(max(0.0, 1.0 - z * z))
    return z * bx + w * fx, z * by + w * fy, z * bz + w * fz, area


@njit(cache=True, inline="always")
def _pick(cum, a):
    """The source whose stretch [cum[k-1], cum[k]) of the cumulative shares holds a
    (bisection), with a's position in [0, 1] along that stretch and the stretch's length."""
    lo, hi = 0, cum.shape[0] - 1
    while lo < hi:
        mid = (lo + hi) // 2
        if cum[mid] > a:
            hi = mid
        else:
            lo = mid + 1
    start = cum[lo - 1] if lo > 0 else 0.0
    share = cum[lo] - start
    return lo, (min(1.0, max(0.0, (a - start) / share)) if share > 0.0 else 0.0), share


@njit(cache=True, inline="always")
def _toward_sphere(ox, oy, oz, cx, cy, cz, r, u, v):
    """A direction in the cone from o around the sphere (c, r), at cos θ = 1 − u (1 − cos α)
    from its axis and azimuth 2π v, the distance [m] to the true sphere along it and the
    cone's solid angle Ω [sr]; Ω = 0 from inside the sphere."""
    wx, wy, wz = cx - ox, cy - oy, cz - oz
    dc = np.sqrt(wx * wx + wy * wy + wz * wz)
    if dc <= r:
        return 0.0, 0.0, 0.0, 0.0, 0.0
    ax, ay, az = wx / dc, wy / dc, wz / dc
    ca = np.sqrt(max(0.0, 1.0 - (r / dc) ** 2))
    ct = 1.0 - u * (1.0 - ca)
    st = np.sqrt(max(0.0, 1.0 - ct * ct))
    tx, ty, tz, bx, by, bz = _tangents(ax, ay, az)
    cp, sp = np.cos(2.0 * np.pi * v), np.sin(2.0 * np.pi * v)
    # the true sphere, not its facets (they lie inside it)
    length = dc * ct - np.sqrt(max(0.0, r * r - dc * dc * st * st))
    return (ct * ax + st * (cp * tx + sp * bx), ct * ay + st * (cp * ty + sp * by),
            ct * az + st * (cp * tz + sp * bz), length, 2.0 * np.pi * (1.0 - ca))


def _plan(P, N, O, U, tri_v, tri_n, tri_area, tri_far2, tri_L, tri_Y, sph_c, sph_r, sph_L, sph_Y, base, rim,
          E0, src, out_d, out_t, out_w):
    """Compiled body of :meth:`LightSurfaces.plan`: one receiver per iteration.

    Writes ``E0`` (n, 3), the unoccluded illuminance [lux], and per shadow ray its source
    ``src``, direction ``out_d``, length ``out_t`` [m] (≤ 0: no ray) and weight ``out_w``
    [sr]: the factor that turns the hidden part L (1 − V) of one ray into lux.  The
    last ``rim`` rays of a point go to the sources' edges and weigh nothing.
    """
    K = tri_v.shape[0]
    S = sph_c.shape[0]
    M = out_t.shape[1]
    for i in prange(P.shape[0]):
        px, py, pz = P[i, 0], P[i, 1], P[i, 2]
        nx, ny, nz = N[i, 0], N[i, 1], N[i, 2]
        rel = np.empty((3, 3))
        poly = np.empty((4, 3))
        cum = np.empty(K + S)
        total_sel = 0.0
        omega_p = 0.0
        for k in range(K):
            g = 0.0
            gx = (tri_v[k, 0, 0] + tri_v[k, 1, 0] + tri_v[k, 2, 0]) / 3.0 - px
            gy = (tri_v[k, 0, 1] + tri_v[k, 1, 1] + tri_v[k, 2, 1]) / 3.0 - py
            gz = (tri_v[k, 0, 2] + tri_v[k, 1, 2] + tri_v[k, 2, 2]) / 3.0 - pz
            d2 = gx * gx + gy * gy + gz * gz
            if d2 > tri_far2[k]:
                cr = (nx * gx + ny * gy + nz * gz)
                if cr > 0.0:
                    cl = abs(tri_n[k, 0] * gx + tri_n[k, 1] * gy + tri_n[k, 2] * gz)
                    g = tri_area[k] * cr * cl / (d2 * d2)
            else:
                for a in range(3):
                    rel[a, 0] = tri_v[k, a, 0] - px
                    rel[a, 1] = tri_v[k, a, 1] - py
                    rel[a, 2] = tri_v[k, a, 2] - pz
                m = _clip_above(rel, nx, ny, nz, poly)
                if m >= 3:
                    g = abs(lambert_polygon(poly, m, nx, ny, nz))
            for c in range(3):
                E0[i, c] += g * tri_L[k, c]
            omega_p += g
            total_sel += g * tri_Y[k]
            cum[k] = total_sel
        for s in range(S):
            g = _sphere_unoccluded(px, py, pz, nx, ny, nz, sph_c[s, 0], sph_c[s, 1], sph_c[s, 2], sph_r[s])
            for c in range(3):
                E0[i, c] += g * sph_L[s, c]
            omega_p += g
            total_sel += g * sph_Y[s]
            cum[K + s] = total_sel
        if total_sel <= 0.0:
            continue
        want = base * min(MORE_FOR_LARGE, max(1, int(np.ceil(omega_p / SPLIT_SOLID_ANGLE))))
        want = min(want, M - rim)
        gx_n = max(1, int(np.sqrt(want)))
        gy_n = max(1, want // gx_n)
        m_i = gx_n * gy_n
        ox, oy, oz = O[i, 0], O[i, 1], O[i, 2]
        for j in range(m_i):
            a = (j // gy_n + U[i, j, 0]) / gx_n * total_sel
            b = (j % gy_n + U[i, j, 1]) / gy_n
            k, a1, share = _pick(cum, a)
            src[i, j] = k
            out_t[i, j] = -1.0
            if share <= 0.0:
                continue
            p_k = share / total_sel
            if k < K:
                # uniform in solid angle over the spherical triangle when it is large enough
                # for the construction to be accurate, else uniform in area
                ax, ay, az = tri_v[k, 0, 0] - ox, tri_v[k, 0, 1] - oy, tri_v[k, 0, 2] - oz
                bx, by, bz = tri_v[k, 1, 0] - ox, tri_v[k, 1, 1] - oy, tri_v[k, 1, 2] - oz
                cx, cy, cz = tri_v[k, 2, 0] - ox, tri_v[k, 2, 1] - oy, tri_v[k, 2, 2] - oz
                la = np.sqrt(ax * ax + ay * ay + az * az)
                lb = np.sqrt(bx * bx + by * by + bz * bz)
                lc = np.sqrt(cx * cx + cy * cy + cz * cz)
                h = tri_n[k, 0] * ax + tri_n[k, 1] * ay + tri_n[k, 2] * az   # signed plane distance
                area = 0.0
                if min(la, lb, lc) > 0.0 and abs(h) > 0.0 and tri_area[k] > MIN_SOLID_ANGLE * min(la, lb, lc) ** 2:
                    wx, wy, wz, area = _spherical_triangle(ax / la, ay / la, az / la, bx / lb, by / lb, bz / lb,
                                                           cx / lc, cy / lc, cz / lc, a1, b)
                if area > MIN_SOLID_ANGLE:
                    cr = nx * wx + ny * wy + nz * wz
                    cl = tri_n[k, 0] * wx + tri_n[k, 1] * wy + tri_n[k, 2] * wz
                    if cr <= 0.0 or cl * h <= 0.0:
                        continue
                    weight = cr * area / (p_k * m_i)
                    length = h / cl * (1.0 - 1e-6) - 1e-9
                else:
                    sq = np.sqrt(a1)
                    u, v = sq * (1.0 - b), sq * b
                    wx = ax + u * (bx - ax) + v * (cx - ax)
                    wy = ay + u * (by - ay) + v * (cy - ay)
                    wz = az + u * (bz - az) + v * (cz - az)
                    dist = np.sqrt(wx * wx + wy * wy + wz * wz)
                    if dist <= 0.0:
                        continue
                    wx, wy, wz = wx / dist, wy / dist, wz / dist
                    cr = nx * wx + ny * wy + nz * wz
                    cl = abs(tri_n[k, 0] * wx + tri_n[k, 1] * wy + tri_n[k, 2] * wz)
                    if cr <= 0.0 or cl <= 0.0:
                        continue
                    # solid-angle density p_k d² / (A cos θ_l)
                    weight = cr * tri_area[k] * cl / (dist * dist * p_k * m_i)
                    length = dist * (1.0 - 1e-6) - 1e-9
            else:
                s = k - K
                wx, wy, wz, length, omega = _toward_sphere(ox, oy, oz, sph_c[s, 0], sph_c[s, 1], sph_c[s, 2],
                                                           sph_r[s], a1, b)
                cr = nx * wx + ny * wy + nz * wz
                if omega <= 0.0 or cr <= 0.0:
                    continue
                weight = cr * omega / (p_k * m_i)
                length = length * (1.0 - 1e-6) - 1e-9
            if length <= 0.0:
                continue
            out_d[i, j, 0], out_d[i, j, 1], out_d[i, j, 2] = wx, wy, wz
            out_t[i, j] = length
            out_w[i, j] = weight
        # rim rays (weight 0): along the sources' edges, in proportion to their shares, so
        # that a shadow edge across a source is seen by the penumbra test
        for r_ in range(rim):
            j = M - rim + r_
            k, a1, share = _pick(cum, (r_ + U[i, j, 0]) / rim * total_sel)
            src[i, j] = k
            out_t[i, j] = -1.0
            if share <= 0.0:
                continue
            if k < K:
                e = min(2, int(3.0 * a1))
                f = 3.0 * a1 - e
                e1 = (e + 1) % 3
                length = 0.0
                wx = wy = wz = 0.0
                for c in range(3):
                    x = tri_v[k, e, c] + f * (tri_v[k, e1, c] - tri_v[k, e, c])
                    x += RIM_INSET * ((tri_v[k, 0, c] + tri_v[k, 1, c] + tri_v[k, 2, c]) / 3.0 - x)
                    out_d[i, j, c] = x - O[i, c]
                    length += out_d[i, j, c] ** 2
                length = np.sqrt(length)
                if length <= 0.0:
                    continue
                for c in range(3):
                    out_d[i, j, c] /= length
            else:
                s = k - K
                wx, wy, wz, length, omega = _toward_sphere(ox, oy, oz, sph_c[s, 0], sph_c[s, 1], sph_c[s, 2],
                                                           sph_r[s], 1.0 - RIM_INSET, a1)
                if omega <= 0.0:
                    continue
                out_d[i, j, 0], out_d[i, j, 1], out_d[i, j, 2] = wx, wy, wz
            out_t[i, j] = length * (1.0 - 1e-6) - 1e-9
            out_w[i, j] = 0.0


_plan_kernel = RowKernel(_plan, rows=(0, 1, 2, 3, 16, 17, 18, 19, 20))


class LightSurfaces:
    """The ``light`` surfaces of a scene as sources of direct light (module text).

    Triangles of sphere primitives are replaced by their spheres; every other light
    triangle is a source of its own.  ``luminance`` (materials, 3) [cd/m²] per material.
    """

    def __init__(self, triangles, light_ids: np.ndarray, material_luminance: np.ndarray):
        ids = np.asarray(light_ids, np.int64)
        sphere_of = triangles.sphere[ids] if len(ids) else np.zeros(0, np.int32)
        flat = ids[sphere_of < 0]
        self.tri_vertices = np.ascontiguousarray(triangles.vertices[flat], np.float64)
        self.tri_normals = np.ascontiguousarray(triangles.normals[flat], np.float64)
        self.tri_area = np.ascontiguousarray(triangles.areas[flat], np.float64)
        v = self.tri_vertices
        edge = np.max(np.linalg.norm(v - np.roll(v, 1, axis=1), axis=2), axis=1) if len(v) else np.zeros(0)
        self.tri_far2 = np.ascontiguousarray((FAR_RATIO * edge) ** 2)
        self.tri_L = np.ascontiguousarray(material_luminance[triangles.material[flat]], np.float64).reshape(-1, 3)
        spheres = np.unique(sphere_of[sphere_of >= 0])
        self.sph_centre = np.ascontiguousarray(triangles.sphere_center[spheres], np.float64).reshape(-1, 3)
        self.sph_radius = np.ascontiguousarray(triangles.sphere_radius[spheres], np.float64)
        first = np.array([ids[sphere_of == s][0] for s in spheres], np.int64)
        self.sph_L = np.ascontiguousarray(material_luminance[triangles.material[first]], np.float64).reshape(-1, 3)
        self.L = np.concatenate([self.tri_L, self.sph_L])
        Y = np.maximum(luminance(self.L), 0.0)
        self._tri_Y = np.ascontiguousarray(Y[:len(flat)])
        self._sph_Y = np.ascontiguousarray(Y[len(flat):])

    def __len__(self) -> int:
        return len(self.tri_area) + len(self.sph_radius)

    def plan(self, points, normals, origins, rng: np.random.Generator, samples: int):
        """The closed form and the shadow rays of :meth:`illuminance`.

        Returns ``(E0, directions, lengths, weights)``: (n, 3) unoccluded illuminance
        [lux]; (n, M, 3) ray directions, (n, M) lengths [m] (≤ 0: no ray) and (n, M, 3)
        weights [lux per unit of hidden fraction], M = ``samples`` · :data:`MORE_FOR_LARGE`.
        """
        n = len(points)
        rim = RIM_LIGHT_RAYS if samples > 1 else 0
        M = max(1, samples) * MORE_FOR_LARGE + rim
        U = rng.random((n, M, 2))
        E0 = np.zeros((n, 3))
        d = np.zeros((n, M, 3))
        t = np.full((n, M), -1.0)
        w = np.zeros((n, M))
        src = np.zeros((n, M), np.int64)
        if n:
            _plan_kernel(
                np.ascontiguousarray(points, np.float64), np.ascontiguousarray(normals, np.float64),
                np.ascontiguousarray(origins, np.float64), U, self.tri_vertices, self.tri_normals,
                self.tri_area, self.tri_far2, self.tri_L, self._tri_Y, self.sph_centre, self.sph_radius,
                self.sph_L, self._sph_Y, int(max(1, samples)), rim, E0, src, d, t, w,
                         work=n * max(1, len(self)))
        return E0, d, t, w[:, :, None] * self.L[src]

    def illuminance(self, points, normals, origins, rng: np.random.Generator, samples: int,
                    transmittance) -> np.ndarray:
        """(n, 3) direct illuminance [lux] from the light surfaces (module text).

        ``transmittance(origins, directions, tmax)`` gives the (k, 3) transmittance of
        segments (:meth:`lbl_illum.engine.direct.DirectLight.transmittance`).  Points go
        in blocks of at most :data:`MAX_RAYS_PER_BLOCK` planned rays.
        """
        points = np.asarray(points, np.float64)
        normals = np.asarray(normals, np.float64)
        origins = np.asarray(origins, np.float64)
        E, mixed = self._blocks(points, normals, origins, rng, samples, transmittance)
        part = np.flatnonzero(mixed) if 1 < samples < PENUMBRA_LIGHT_SAMPLES else ()
        if len(part):
            E[part] = self._blocks(points[part], normals[part], origins[part], rng, PENUMBRA_LIGHT_SAMPLES,
                                   transmittance)[0]
        return E

    def _blocks(self, points, normals, origins, rng, samples, transmittance):
        """:meth:`_estimate` over blocks of points."""
        n = len(points)
        E = np.zeros((n, 3))
        mixed = np.zeros(n, bool)
        block = max(1, MAX_RAYS_PER_BLOCK // (max(1, samples) * MORE_FOR_LARGE))
        for lo in range(0, n, block):
            sl = slice(lo, lo + block)
            E[sl], mixed[sl] = self._estimate(points[sl], normals[sl], origins[sl], rng, samples, transmittance)
        return E, mixed

    def _estimate(self, points, normals, origins, rng, samples, transmittance):
        """E = E₀ · Σ T w / Σ w over a point's rays (weights w, transmittances T): the
        closed form times the estimated visible share (Heitz, Hill & McGuire, "Combining
        analytic direct illumination and stochastic shadows", I3D 2018), per channel.  It
        lies in [0, E₀], is E₀ exactly where every ray is open and 0 where every ray is
        blocked; its bias is of order 1/(rays) where some are (negligible at the 1,024
        rays of a penumbra at sensor points) and, at a single ray, the difference
        between the visible share by solid angle and by projected solid angle within one
        source.  (The unbiased control variate E₀ − Σ w (1 − T) was tried first: at one
        ray per hit it went below zero behind occluders.)  A point without a live ray
        keeps E₀.  Returns E (n, 3) and per point whether its rays were mixed (some
        blocked, some open, or partly transmitted)."""
        E0, d, t, weights = self.plan(points, normals, origins, rng, samples)
        n, M = t.shape
        live = np.flatnonzero(t.ravel() > 0.0)
        mixed = np.zeros(n, bool)
        if len(live) == 0:
            return E0, mixed
        owner = live // M
        T = transmittance(origins[owner], d.reshape(-1, 3)[live], t.ravel()[live])
        w = weights.reshape(-1, 3)[live]
        seen = np.stack([np.bincount(owner, T[:, c] * w[:, c], minlength=n) for c in range(3)], axis=1)
        every = np.stack([np.bincount(owner, w[:, c], minlength=n) for c in range(3)], axis=1)
        E = np.where(every > 0.0, E0 * np.divide(seen, every, out=np.ones_like(seen), where=every > 0.0), E0)
        reach = T.max(axis=1) > 0.0
        blocked = np.zeros(n, bool)
        open_ = np.zeros(n, bool)
        blocked[owner[~reach]] = True
        open_[owner[reach]] = True
        # partly transmitted rays (glass) also leave noise: resample them too
        mixed[owner[reach & (T.min(axis=1) < 1.0)]] = True
        mixed |= blocked & open_
        return E, mixed

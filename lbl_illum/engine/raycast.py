"""Ray casting with Embree (through embreex), on arrays of rays.

Embree works in float32 and embreex fixes each ray's ``tnear`` at 0, so a ray
leaving a surface must start a little off it.  This module owns that problem:

* hit points are reconstructed in float64 as ``o + t d`` and then projected onto
  the plane of the triangle hit (so their distance from the surface is float64
  round-off, not float32); hit points on sphere primitives are projected onto the
  true sphere, whose normal is the shading normal;
* a ray leaving a surface point P starts at ``P + ε n`` with n the geometric normal
  on the side the ray leaves towards and ``ε = SELF_HIT_EPSILON · (|P|∞ + ℓ)``,
  ℓ the scene's median edge length: scale-aware, so the same room in mm or km
  behaves the same.

Shadow rays use Embree's ``OCCLUDED`` query against the opaque surfaces only, and
glass along a shadow ray multiplies it by the glass's transmittance at normal incidence;
:func:`through_panes` follows rays pane by pane for τ at each pane's angle of incidence.

embreex releases the GIL inside ``run``, so large batches are split into chunks
traced by a thread pool and every core is used.
"""

from __future__ import annotations

import os
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from functools import cached_property, lru_cache

import numpy as np
from numba import prange
from embreex import rtcore_scene
from embreex.mesh_construction import TriangleMesh

from .compiled import RowKernel
from .gather import rows as take
from ..scene.geometry import SPHERE_MAX_DEVIATION, Triangles
from ..scene.geometry import orthonormal_basis
from ..scene.materials import GLASS

__all__ = ["Tracer", "RayCaster", "Hits", "SELF_HIT_EPSILON", "thread_count", "step_past", "through_panes",
           "PanePath"]

#: Relative offset of ray origins off the surface they leave (see module docstring).
SELF_HIT_EPSILON = 1e-5
#: A sensor closer than this fraction of its ε to a surface in front of it lies on that
#: surface (embree's float32 distances for such a point are a few ulps, ~1e-7 relative).
ON_SURFACE_FRACTION = 0.05
#: Glass layers a shadow ray may cross before it is considered blocked.
MAX_GLASS_LAYERS = 16
#: Rays per chunk handed to one embree call from one thread.
CHUNK_RAYS = 32768
#: In a scene with glass, closest-hit rays per triangle after which a BVH over every
#: triangle is built for them.  Until then a closest hit is the nearer of the opaque and
#: the glass BVHs' (which shadow rays need anyway): that costs about 0.1 µs more a ray
#: (the office at ``draft``: 6 % of its calculation), a BVH about 0.9 µs a triangle
#: (embreex fills Embree's buffers holding the GIL: 0.18 s for the cabin's 204,216, more
#: than a small run's whole calculation).  Building once the extra cost has reached the
#: build's costs at most about twice the better choice made in advance.
ALL_BVH_RAYS_PER_TRIANGLE = 9


def thread_count() -> int:
    """Threads used for ray casting: ``$LBL_ILLUM_THREADS`` or every core."""
    env = os.environ.get("LBL_ILLUM_THREADS")
    if env:
        try:
            return max(1, int(env))
        except ValueError:
            pass
    return max(1, os.cpu_count() or 1)


@lru_cache(maxsize=4)
def _pool(threads: int) -> ThreadPoolExecutor:
    return ThreadPoolExecutor(max_workers=threads, thread_name_prefix="lbl-illum-trace")


def _plane_hits_kernel(o, d, t, prim, index, normals, v0, p, ng):
    """Hit points o + t d projected onto the plane of the triangle hit (float64), and its
    normal turned towards the incoming ray."""
    for q in prange(index.shape[0]):
        i = index[q]
        f = prim[i]
        nx, ny, nz = normals[f, 0], normals[f, 1], normals[f, 2]
        x = o[i, 0] + t[i] * d[i, 0]
        y = o[i, 1] + t[i] * d[i, 1]
        z = o[i, 2] + t[i] * d[i, 2]
        h = (x - v0[f, 0]) * nx + (y - v0[f, 1]) * ny + (z - v0[f, 2]) * nz
        p[q, 0] = x - h * nx
        p[q, 1] = y - h * ny
        p[q, 2] = z - h * nz
        if nx * d[i, 0] + ny * d[i, 1] + nz * d[i, 2] > 0.0:
            nx, ny, nz = -nx, -ny, -nz
        ng[q, 0] = nx
        ng[q, 1] = ny
        ng[q, 2] = nz


_plane_hits = RowKernel(_plane_hits_kernel, rows=(4, 7, 8))


def step_past(origins: np.ndarray, directions: np.ndarray, t: np.ndarray, length_scale: float):
    """Rays that hit a surface at distances ``t`` [m] (a pane, an opening) continue
    beyond it: ``(new origins, step)``, the origins moved along ``directions`` by
    step = t + ε, ε = SELF_HIT_EPSILON · (|o|∞ + t + the scene's length scale), so that
    the next query does not find the same surface again.  The one rule for stepping
    past a surface along a ray (shadow rays through glass, portal densities through
    openings)."""
    step = t + SELF_HIT_EPSILON * (np.abs(origins).max(axis=1) + t + length_scale)
    return origins + step[:, None] * directions, step


@dataclass
class PanePath:
    """What :func:`through_panes` found along k rays.

    reached : (k,) bool — the ray ended where its caller wanted: on a ``stop`` triangle, or
        (without ``stop``) past its last pane with nothing more before ``tmax``
    blocked : (k,) bool — the ray ended on an opaque surface (no ``stop`` triangle) before ``tmax``
    prim : (k,) int64 — the triangle that ended the ray (a ``stop`` or opaque one), −1 for none
    distance : (k,) float64 — distance [m] from the origin to ``prim`` along the ray, ``inf`` where ``prim`` is −1
    product : (k, 3) float64 — the product of τ(θ) over the panes crossed, 1 for none
    """

    reached: np.ndarray
    blocked: np.ndarray
    prim: np.ndarray
    distance: np.ndarray
    product: np.ndarray


def through_panes(tracer: "Tracer", materials, origins: np.ndarray, directions: np.ndarray, *,
                  tmax: np.ndarray | None = None, stop=None, layers: int = MAX_GLASS_LAYERS) -> PanePath:
    """Follow k rays through the panes of glass on their way, multiplying each pane's
    transmittance at its own angle of incidence: the one glass step of the shadow rays
    (:meth:`lbl_illum.engine.direct.DirectLight.transmittance`) and of the rays to the sun's
    images (:mod:`lbl_illum.engine.sunmirrors`).

    Light along a ray through panes 1 … m keeps T = Π_j τ_j(θ_j), τ_j the (3,) transmittance
    of pane j at the incidence angle θ_j between the ray and the pane's normal
    (cos θ_j = |n_j · d|; Fresnel glazing depends on it, constant glass does not:
    ``materials.glass_transmittance``, :meth:`~lbl_illum.scene.materials.MaterialTable.specular`).
    Each step is a closest-hit query against every surface (``tracer.intersect``); the ray
    then continues just beyond the pane (:func:`step_past`).  A hit before ``tmax`` is, in this order:

    * on a triangle that ``stop(prim, ray)`` accepts ((m,) bool for the hit triangles
      ``prim`` of the rays ``ray``, indices into ``origins``): the end, reached;
    * on glass: crossed, τ(θ) multiplied in, the ray goes on;
    * on anything else (opaque): the end, blocked.

    A ray that meets nothing before ``tmax`` ends there, reached if there is no ``stop``
    (the segment is clear), not reached otherwise.  After ``layers`` queries a ray still in
    glass is neither reached nor blocked; its product holds the panes crossed.

    origins, directions : (k, 3) [m] and unit;  tmax : (k,) [m] segment lengths, None for
    none;  the distances along a ray add each query's hit distance and step, in metres.
    """
    origins = np.asarray(origins, np.float64)
    directions = np.asarray(directions, np.float64)
    k = len(origins)
    reached = np.zeros(k, bool)
    blocked = np.zeros(k, bool)
    prim = np.full(k, -1, np.int64)
    distance = np.zeros(k)
    product = np.ones((k, 3))
    material = tracer.triangles.material
    is_glass = materials.kind[material] == GLASS
    live = np.arange(k)
    o, d = origins, directions
    tm = None if tmax is None else np.asarray(tmax, np.float64)
    for _ in range(layers):
        if len(live) == 0:
            break
        hits = tracer.intersect(o, d)
        near = hits.hit if tm is None else hits.hit & (hits.t < tm)
        goal = np.zeros(len(live), bool)
        if stop is not None:
            goal[near] = stop(hits.prim[near], live[near])
        glass = near & ~goal
        glass[glass] = is_glass[hits.prim[glass]]
        opaque = near & ~goal & ~glass
        end = goal | opaque
        prim[live[end]] = hits.prim[end]
        distance[live[end]] += hits.t[end]
        reached[live[goal]] = True
        blocked[live[opaque]] = True
        if stop is None:
            reached[live[~near]] = True
        live, o, d, t, pr = live[glass], o[glass], d[glass], hits.t[glass], hits.prim[glass]
        if tm is not None:
            tm = tm[glass]
        if len(live) == 0:
            break
        cos_i = np.abs(np.einsum("ij,ij->i", tracer.normals[pr], d))
        product[live] *= materials.glass_transmittance(material[pr], cos_i)
        o, step = step_past(o, d, t, tracer.length_scale)
        distance[live] += step
        if tm is not None:
            tm = tm - step
    return PanePath(reached, blocked, prim, np.where(prim >= 0, distance, np.inf), product)


@dataclass
class Hits:
    """Result of a batch of closest-hit queries.

    t : (n,) float64 — distance along the (unit) direction, ``inf`` for a miss
    prim : (n,) int32 — index of the triangle hit, -1 for a miss
    """

    t: np.ndarray
    prim: np.ndarray

    @property
    def hit(self) -> np.ndarray:
        return self.prim >= 0


def self_hit_epsilon(points: np.ndarray, length_scale: float) -> np.ndarray:
    """(n,) self-hit offset ε = ``SELF_HIT_EPSILON`` · (|P|∞ + ℓ) [m] of ``points`` [m] in a
    scene of median edge ℓ = ``length_scale`` [m] (module docstring)."""
    a = np.abs(np.asarray(points, np.float64))
    # |P|∞ by columns: numpy's max over rows of three took 6× as long
    return SELF_HIT_EPSILON * (np.maximum(np.maximum(a[:, 0], a[:, 1]), a[:, 2]) + length_scale)


def median_edge(vertices: np.ndarray) -> float:
    """ℓ [m] of the self-hit offset: the median length of the triangles' first edges (1 m for none)."""
    edges = np.linalg.norm(vertices[:, 1] - vertices[:, 0], axis=1)
    return float(np.median(edges)) if len(edges) else 1.0


class RayCaster:
    """Closest-hit and occlusion queries against (T, 3, 3) triangles [m]: the package's one
    wrapper of Embree (the scene's :class:`Tracer` holds three, the workplane grids build
    their own over parts of a scene).

    Embree works in float32, so ``vertices`` are handed to it in float32; hit distances
    come back in float64.  Large batches are split into chunks traced on a thread pool
    (embreex releases the GIL).  ``rays_traced`` counts every ray.
    """

    def __init__(self, vertices: np.ndarray, threads: int | None = None):
        self.vertices = np.asarray(vertices, dtype=np.float64).reshape(-1, 3, 3)
        self.threads = threads or thread_count()
        self.rays_traced = 0
        self._scene = None
        if len(self.vertices):
            self._scene = rtcore_scene.EmbreeScene()
            TriangleMesh(self._scene, np.ascontiguousarray(self.vertices, dtype=np.float32))

    @cached_property
    def length_scale(self) -> float:
        """ℓ [m] of the self-hit offset (:func:`median_edge`), found when first asked for: a
        scene's :class:`Tracer` keeps its own over every triangle, and its opaque and glass
        casters never ask (0.01 s for the cabin's 204,216 triangles)."""
        return median_edge(self.vertices)

    @property
    def empty(self) -> bool:
        return self._scene is None

    @property
    def normals(self) -> np.ndarray:
        """(T, 3) unit geometric normals, (v₁ − v₀) × (v₂ − v₀) normalised."""
        if getattr(self, "_normals", None) is None:
            v = self.vertices
            n = np.cross(v[:, 1] - v[:, 0], v[:, 2] - v[:, 0])
            self._normals = n / np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-300)
        return self._normals

    def _run(self, origins, directions, tmax, occluded):
        """Trace (n, 3) rays in chunks on the thread pool; ``tmax`` (n,) or a number or None."""
        n = len(origins)
        self.rays_traced += n
        o = np.ascontiguousarray(origins, dtype=np.float32)
        d = np.ascontiguousarray(np.broadcast_to(directions, (n, 3)), dtype=np.float32)
        dist = None if tmax is None else np.ascontiguousarray(
            np.broadcast_to(np.minimum(tmax, 3e38), (n,)), dtype=np.float32)
        if occluded:
            out = np.empty(n, dtype=bool)
        else:
            t_out = np.empty(n, dtype=np.float64)
            p_out = np.empty(n, dtype=np.int32)
        scene = self._scene

        def work(s):
            ds = None if dist is None else dist[s]
            if occluded:
                out[s] = scene.run(o[s], d[s], dists=ds, query="OCCLUDED") != -1
            else:
                res = scene.run(o[s], d[s], dists=ds, output=1)
                prim = res["primID"]
                t_out[s] = np.where(prim >= 0, res["tfar"], np.inf)
                p_out[s] = prim

        chunk = max(4096, min(CHUNK_RAYS, -(-n // self.threads)))
        slices = [slice(i, min(n, i + chunk)) for i in range(0, n, chunk)]
        if len(slices) <= 1:
            for s in slices:
                work(s)
        else:
            list(_pool(self.threads).map(work, slices))
        return out if occluded else (t_out, p_out)

    def first_hit(self, origins: np.ndarray, directions: np.ndarray, tmax=None,
                  counted: bool = True) -> tuple[np.ndarray, np.ndarray]:
        """(t (n,) [m], ``inf`` for none; prim (n,) int32, -1 for none) of the closest hit of
        rays with unit ``directions`` ((n, 3) or one (3,) for all), up to ``tmax``;
        ``counted=False``: the rays are already counted in :attr:`rays_traced` (the same
        rays traced against another part of the scene)."""
        n = len(origins)
        if n == 0 or self._scene is None:
            return np.full(n, np.inf), np.full(n, -1, np.int32)
        if not counted:
            self.rays_traced -= n
        return self._run(origins, directions, tmax, occluded=False)

    def occluded(self, origins: np.ndarray, directions: np.ndarray, tmax=None) -> np.ndarray:
        """(n,) bool: a triangle lies on the ray before ``tmax``."""
        n = len(origins)
        if n == 0 or self._scene is None:
            return np.zeros(n, bool)
        return self._run(origins, directions, tmax, occluded=True)

    def epsilon(self, points: np.ndarray) -> np.ndarray:
        """(n,) self-hit offset ε = ``SELF_HIT_EPSILON`` · (|P|∞ + ℓ) [m] (module docstring)."""
        return self_hit_epsilon(points, self.length_scale)


class Tracer:
    """Closest-hit and shadow queries against a scene's triangles.

    Parameters
    ----------
    triangles : the scene's geometry [m]
    material_kind : (m,) int8 material kind per material id (``materials.GLASS`` …)
    transmittance : (m, 3) float64 glass transmittance per material id
    threads : worker threads (default :func:`thread_count`)
    """

    def __init__(self, triangles: Triangles, material_kind: np.ndarray, transmittance: np.ndarray,
                 threads: int | None = None):
        self.triangles = triangles
        self.threads = threads or thread_count()
        verts = triangles.vertices
        kind = np.asarray(material_kind)[triangles.material]
        self._glass_ids = np.flatnonzero(kind == GLASS).astype(np.int32)
        self._opaque_ids = np.flatnonzero(kind != GLASS).astype(np.int32)
        self._opaque = RayCaster(verts[self._opaque_ids] if len(self._glass_ids) else verts, self.threads)
        self._glass = RayCaster(verts[self._glass_ids], self.threads)
        # closest hits: without glass, the opaque BVH is every triangle's; with glass, a
        # third BVH over every triangle is built only once closest-hit rays pay for it
        # (:data:`ALL_BVH_RAYS_PER_TRIANGLE`); until then a hit is the nearer of the parts'
        self._all = self._opaque if len(self._glass_ids) == 0 else None
        self._rays_without_all = 0
        self._glass_tau = np.asarray(transmittance, dtype=np.float64)[triangles.material[self._glass_ids]]
        self.normals = np.ascontiguousarray(triangles.normals, np.float64)
        self._v0 = np.ascontiguousarray(verts[:, 0], np.float64)
        self._has_spheres = bool(np.any(triangles.sphere >= 0))
        self.length_scale = median_edge(verts)

    @property
    def rays_traced(self) -> int:
        """Rays traced so far, shadow rays and glass steps included."""
        casters = (self._opaque, self._glass) if self._all in (None, self._opaque) else (
            self._opaque, self._glass, self._all)
        return sum(c.rays_traced for c in casters)

    def epsilon(self, points: np.ndarray) -> np.ndarray:
        """(n,) self-hit offset ε [m] at ``points`` in this scene (module docstring)."""
        return self_hit_epsilon(points, self.length_scale)

    # -- queries --------------------------------------------------------------
    def intersect(self, origins: np.ndarray, directions: np.ndarray) -> Hits:
        """Closest hit of (n, 3) rays with unit ``directions`` against every surface: the
        opaque surfaces' closest hit, or the glass's where that is nearer (at an equal
        distance, the opaque surface), or once built, the BVH over every triangle's (which
        may take either at an equal distance)."""
        if self._all is None and self._rays_without_all >= ALL_BVH_RAYS_PER_TRIANGLE * len(self.triangles):
            self._all = RayCaster(self.triangles.vertices, self.threads)
        if self._all is not None:
            return Hits(*self._all.first_hit(origins, directions))
        self._rays_without_all += len(origins)
        t, prim = self._opaque.first_hit(origins, directions)
        hit = prim >= 0
        prim[hit] = self._opaque_ids[prim[hit]]
        t_glass, prim_glass = self._glass.first_hit(origins, directions, t, counted=False)
        nearer = np.flatnonzero((prim_glass >= 0) & (t_glass < t))
        t[nearer] = t_glass[nearer]
        prim[nearer] = self._glass_ids[prim_glass[nearer]]
        return Hits(t, prim)

    def transmittance(self, origins: np.ndarray, directions: np.ndarray, tmax: np.ndarray | None = None) -> np.ndarray:
        """(n, 3) fraction of light passing along each segment: 0 if an opaque surface
        blocks it, else the product of the transmittances of the glass it crosses."""
        n = len(origins)
        result = np.ones((n, 3))
        if n == 0:
            return result
        if tmax is None:
            tmax = np.full(n, np.inf)
        if not self._opaque.empty:
            result[self._opaque.occluded(origins, directions, tmax)] = 0.0
        if self._glass.empty:
            return result
        live = np.flatnonzero(result[:, 0] > 0)
        o = take(np.asarray(origins, dtype=np.float64), live)
        d = take(np.asarray(directions, dtype=np.float64), live)
        tm = np.asarray(tmax, dtype=np.float64)[live]
        for _ in range(MAX_GLASS_LAYERS):
            if len(live) == 0:
                break
            t, prim = self._glass.first_hit(o, d, tm)
            crossed = np.flatnonzero(prim >= 0)
            live, o, d = live[crossed], take(o, crossed), take(d, crossed)
            tm, t, prim = tm[crossed], t[crossed], prim[crossed]
            result[live] *= self._glass_tau[prim]
            o, step = step_past(o, d, t, self.length_scale)
            tm = tm - step
        else:
            result[live] = 0.0     # more layers than a window has: treat as blocked
        return result

    # -- hit geometry -----------------------------------------------------------
    def surface(self, origins: np.ndarray, directions: np.ndarray, hits: Hits, index: np.ndarray | None = None):
        """Positions and normals at the hits of the rays selected by ``index``.

        Returns ``(points, geometric_normals, shading_normals)``, each (k, 3) float64,
        with both normals turned to face the incoming ray (surfaces are two-sided).
        """
        if index is None:
            index = np.flatnonzero(hits.hit)
        index = np.asarray(index, np.int64)
        p = np.empty((len(index), 3))
        ng = np.empty((len(index), 3))
        _plane_hits(np.ascontiguousarray(origins, np.float64), np.ascontiguousarray(directions, np.float64),
                    hits.t, hits.prim, index, self.normals, self._v0, p, ng)
        ns = ng.copy()
        if not self._has_spheres:
            return p, ng, ns
        d = np.asarray(directions, dtype=np.float64)[index]
        sphere = self.triangles.sphere[hits.prim[index]]
        on_sphere = np.flatnonzero(sphere >= 0)
        if len(on_sphere):
            c = self.triangles.sphere_center[sphere[on_sphere]]
            r = self.triangles.sphere_radius[sphere[on_sphere]]
            radial = p[on_sphere] - c
            radial /= np.linalg.norm(radial, axis=1, keepdims=True)
            p[on_sphere] = c + r[:, None] * radial                     # onto the true sphere
            outward = np.einsum("ij,ij->i", radial, d[on_sphere]) < 0.0
            ns[on_sphere] = np.where(outward[:, None], radial, -radial)
            ng[on_sphere] = ns[on_sphere]
        return p, ng, ns

    def offset(self, points: np.ndarray, normals: np.ndarray) -> np.ndarray:
        """Ray origins just off the surface at ``points`` on the side of ``normals``.

        Points on a sphere primitive's true surface that leave towards its inside get
        ``SPHERE_MAX_DEVIATION`` · radius more: the facets lie up to that far inside the
        true sphere, so the plain offset would leave the origin between the true sphere
        and the facets, where every ray and shadow ray hits the sphere's own facet.
        """
        points = np.asarray(points, dtype=np.float64)
        normals = np.asarray(normals, dtype=np.float64)
        eps = self.epsilon(points)
        for c, r in zip(self.triangles.sphere_center, self.triangles.sphere_radius):
            radial = points - c
            dist = np.linalg.norm(radial, axis=1)
            on = np.abs(dist - r) <= 2.0 * SPHERE_MAX_DEVIATION * r + eps
            inward = np.einsum("ij,ij->i", radial, normals) < 0.0
            eps = eps + np.where(on & inward, SPHERE_MAX_DEVIATION * r, 0.0)
        return points + eps[:, None] * normals

    def sensor_origins(self, points: np.ndarray, normals: np.ndarray) -> np.ndarray:
        """Ray origins for sensor points: :meth:`offset`, kept clear of the surfaces near them.

        The offset ε·n (ε = ``SELF_HIT_EPSILON`` · (|P|∞ + ℓ)) suits a point on a surface.
        A sensor can also lie just in front of a surface or on an edge, and then:

        * a surface less than ε in front of it is crossed (a sensor 1 mm from a 200 m
          wall and facing it, where ε = 3 mm, saw the sky behind the wall);
        * on an edge or in a corner the origin lies in the plane of the adjacent
          surface, and rays slip through between its triangles (a sensor in the floor
          corner of a closed room saw the sun and the sky outside).

        Probe rays correct this; a distance below ``ON_SURFACE_FRACTION``·ε counts as 0
        (float32 round-off), i.e. the point lies on that surface.

        1. Along n from P: a surface at 0 < t < 2ε (not parallel to n) puts the origin
           halfway to it, P + t/2·n.  Facets of a sphere the point lies on are passed,
           as :meth:`offset` does.
        2. If a probe along ±t₁ or ±t₂ (the tangent plane) from the origin meets a
           surface at t = 0, the origin lies in that surface's plane.  It then moves ε
           within the tangent plane, in the first of 12 directions (30° apart) from
           which no such probe meets a surface at t = 0 and a probe along −n still meets
           the surface the sensor lies on: off the edge, into the face.  A sensor on no
           surface has no such direction and keeps its origin.
        3. Along ±t₁, ±t₂ again: a surface whose plane lies 0 < d < ε from the origin
           pushes it along that surface's normal, turned towards it, to ε from the plane.

        points, normals : (n, 3) [m] and unit; returns (n, 3) origins [m].
        """
        points = np.asarray(points, dtype=np.float64)
        normals = np.asarray(normals, dtype=np.float64)
        origins = self.offset(points, normals)
        if len(points) == 0 or len(self.triangles) == 0:
            return origins
        eps = self.epsilon(points)
        zero = ON_SURFACE_FRACTION * eps
        # 1. a surface just in front
        hits = self.intersect(points, normals)
        t, prim = hits.t, np.maximum(hits.prim, 0)
        facing = np.abs(np.einsum("ij,ij->i", self.normals[prim], normals)) > 1e-6
        ahead = hits.hit & facing & (t > zero) & (t < 2.0 * eps)
        sphere = np.where(ahead, self.triangles.sphere[prim], -1)
        for s in np.unique(sphere[sphere >= 0]):
            c, r = self.triangles.sphere_center[s], self.triangles.sphere_radius[s]
            on = np.abs(np.linalg.norm(points - c, axis=1) - r) <= 2.0 * SPHERE_MAX_DEVIATION * r + eps
            ahead &= ~((sphere == s) & on)
        origins[ahead] = points[ahead] + 0.5 * t[ahead, None] * normals[ahead]
        t1, t2 = orthonormal_basis(normals)

        def in_a_plane(o, i):
            """Which origins ``o`` of points ``i`` lie in the plane of a surface beside them."""
            out = np.zeros(len(i), bool)
            for u in (t1[i], -t1[i], t2[i], -t2[i]):
                out |= self.intersect(o, u).t <= zero[i]
            return out

        # 2. an origin in the plane of an adjacent surface: off the edge, into the face
        todo = np.flatnonzero(in_a_plane(origins, np.arange(len(points))))
        if len(todo):
            lift = np.linalg.norm(origins[todo] - points[todo], axis=1)
            for angle in np.radians(np.arange(0.0, 360.0, 30.0) + 15.0):
                if len(todo) == 0:
                    break
                step = np.cos(angle) * t1[todo] + np.sin(angle) * t2[todo]
                c = origins[todo] + eps[todo, None] * step
                back = self.intersect(c, -normals[todo])
                ok = ~in_a_plane(c, todo) & (back.t <= lift + zero[todo])
                origins[todo[ok]] = c[ok]
                todo, lift = todo[~ok], lift[~ok]
        # 3. a surface nearer than ε beside the origin
        for u in (t1, -t1, t2, -t2):
            hits = self.intersect(origins, u)
            near = np.flatnonzero(hits.t < 2.0 * eps)
            if len(near) == 0:
                continue
            ns = self.normals[hits.prim[near]]
            cos = np.einsum("ij,ij->i", ns, u[near])
            ns = np.where((cos > 0.0)[:, None], -ns, ns)               # towards the origin
            d = hits.t[near] * np.abs(cos)
            push = np.where(d > zero[near], np.maximum(eps[near] - d, 0.0), 0.0)
            origins[near] += push[:, None] * ns
        return origins

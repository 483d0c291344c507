"""Direct illuminance from the sun and from ``light`` surfaces, by shadow rays.

* Sun (DESIGN.md §2): E = E_dn · max(0, N·s) · V, s the disk's centre and V the mean
  transmittance of shadow rays sampled uniformly over the 6.8e-5 sr disk (0 behind an
  opaque surface, the product of τ(θ) over the panes of glass crossed, θ each pane's angle
  of incidence: :meth:`lbl_illum.materials.MaterialTable.specular`).  When the disk
  straddles the surface's horizon (|N·s| < sin δ, δ = 0.27° the disk's radius) each ray
  carries its own max(0, N·d): E = E_dn · mean(max(0, N·d) T(d)), the part below the
  horizon adding nothing.
* Light surfaces (Lambertian emitters, two-sided): area sampling,
  E = (1/n) Σ L cos θ_r cos θ_l / d² / p_A, with triangles chosen in proportion to
  area × luminance and points uniform on them (Pharr, Jakob & Humphreys,
  *Physically Based Rendering*, 4th ed., §12.2 and §6.5).

The indirect calculation never counts these sources again: a hemisphere ray that
reaches a light surface or the sun directly contributes nothing (paper §5).
"""

from __future__ import annotations

import numpy as np

from .geometry import TriangleSampler
from .materials import GLASS, LIGHT, MaterialTable
from .raycast import MAX_GLASS_LAYERS, SELF_HIT_EPSILON, Tracer
from .sun import SUN_COS_HALF_ANGLE, Sun

#: sin δ of the sun disk's angular radius δ: the disk straddles the horizon of a surface
#: whose N·s lies within ± this.
SUN_SIN_HALF_ANGLE = float(np.sqrt(1.0 - SUN_COS_HALF_ANGLE ** 2))

__all__ = ["DirectLight"]


class DirectLight:
    """Shadow-ray estimates of direct illuminance at arrays of points."""

    def __init__(self, tracer: Tracer, materials: MaterialTable, sun: Sun | None):
        self.tracer = tracer
        self.materials = materials
        self.sun = sun if (sun is not None and sun.is_up) else None
        tri = tracer.triangles
        #: some glass of the scene transmits by the angle of incidence (Fresnel glazing)
        self._angular = bool(np.any(materials.fresnel[np.unique(tri.material)])) if len(tri) else False
        light_ids = np.flatnonzero(materials.kind[tri.material] == LIGHT)
        self.lights = None
        if len(light_ids):
            self.light_luminance = materials.luminance[tri.material[light_ids]]
            power = tri.areas[light_ids] * np.maximum(self.light_luminance.mean(axis=1), 0.0)
            self.lights = TriangleSampler(tri, light_ids, power)

    @property
    def has_lights(self) -> bool:
        return self.lights is not None

    @property
    def is_dark(self) -> bool:
        return self.sun is None and not self.has_lights

    def illuminance(self, points, shading_normals, geometric_normals, rng: np.random.Generator,
                    light_samples: int = 1, origins=None) -> np.ndarray:
        """(n, 3) direct illuminance [lux] at points with the given facing normals.

        ``origins`` (n, 3): where the shadow rays start (default: the points offset
        along ``geometric_normals``, :meth:`Tracer.offset`).
        """
        points = np.asarray(points, np.float64)
        n = len(points)
        E = np.zeros((n, 3))
        if n == 0 or self.is_dark:
            return E
        if origins is None:
            origins = self.tracer.offset(points, geometric_normals)
        if self.sun is not None:
            # cosine at the disk's centre (its mean over a whole disk differs by < 1e-5);
            # the jittered rays decide only visibility, so penumbrae are soft.  A disk cut
            # by the surface's horizon (|N·s| < sin δ: sun within 0.27° of the plane) gets
            # each ray's own cosine, max(0, N·d): at 0.1° altitude the centre's cosine
            # was 15 % low on an open horizontal surface
            cos = shading_normals @ self.sun.direction
            for lit, cut in ((np.flatnonzero(cos > 0.0), False),
                             (np.flatnonzero((cos > -SUN_SIN_HALF_ANGLE) & (cos <= 0.0)), True)):
                if len(lit) == 0:
                    continue
                cut = cut | (cos[lit] < SUN_SIN_HALF_ANGLE)
                T = np.zeros((len(lit), 3))
                for _ in range(light_samples):
                    d = self.sun.sample_directions(rng.random(len(lit)), rng.random(len(lit)))
                    w = np.where(cut, np.maximum(np.einsum("ij,ij->i", shading_normals[lit], d), 0.0), 1.0)
                    T += self.transmittance(origins[lit], d) * w[:, None]
                E[lit] += self.sun.direct_normal_illuminance * np.where(cut, 1.0, cos[lit])[:, None] * T / light_samples
        if self.has_lights:
            for _ in range(light_samples):
                E += self._light_sample(points, origins, shading_normals, rng) / light_samples
        return E

    def transmittance(self, origins, directions, tmax=None) -> np.ndarray:
        """(n, 3) fraction of light passing along each segment: 0 behind an opaque
        surface, else the product over the glass crossed of its transmittance at the
        ray's angle of incidence.

        Without angle-dependent glass this is :meth:`Tracer.transmittance`.  With it, the
        segments that the tracer finds unblocked and through glass (0 < T < 1) are followed
        again, pane by pane, with closest-hit queries, and each pane's normal-incidence
        τ_n is replaced by τ(θ) (:meth:`~lbl_illum.materials.MaterialTable.specular`).
        """
        T = self.tracer.transmittance(origins, directions, tmax)
        if not self._angular or len(T) == 0:
            return T
        todo = np.flatnonzero((T.max(axis=1) > 0.0) & (T.min(axis=1) < 1.0))
        if len(todo) == 0:
            return T
        o = np.asarray(origins, np.float64)[todo]
        d = np.asarray(directions, np.float64)[todo]
        tm = np.full(len(todo), np.inf) if tmax is None else np.asarray(tmax, np.float64)[todo]
        product = np.ones((len(todo), 3))
        live = np.arange(len(todo))
        kind = self.materials.kind[self.tracer.triangles.material]
        for _ in range(MAX_GLASS_LAYERS):
            if len(live) == 0:
                break
            hits = self.tracer.intersect(o, d)
            glass = hits.hit & (hits.t < tm)
            glass[glass] = kind[hits.prim[glass]] == GLASS      # an opaque hit here is round-off
            live, o, d, tm, t, prim = (live[glass], o[glass], d[glass], tm[glass], hits.t[glass],
                                       hits.prim[glass])
            if len(live) == 0:
                break
            cos_i = np.abs(np.einsum("ij,ij->i", self.tracer.normals[prim], d))
            product[live] *= self.materials.glass_transmittance(self.tracer.triangles.material[prim], cos_i)
            step = t + SELF_HIT_EPSILON * (np.abs(o).max(axis=1) + t + self.tracer.length_scale)
            o = o + step[:, None] * d
            tm = tm - step
        T[todo] = np.where(T[todo] > 0.0, product, 0.0)
        return T

    def _light_sample(self, points, origins, normals, rng):
        n = len(points)
        tri, x, pdf_area = self.lights.sample(rng, n)
        w = x - origins
        dist = np.linalg.norm(w, axis=1)
        ok = dist > 0
        w[ok] /= dist[ok, None]
        cos_r = np.einsum("ij,ij->i", normals, w)
        cos_l = np.abs(np.einsum("ij,ij->i", self.lights.normals[tri], w))
        use = np.flatnonzero(ok & (cos_r > 0.0) & (cos_l > 0.0))
        E = np.zeros((n, 3))
        if len(use) == 0:
            return E
        geom = cos_r[use] * cos_l[use] / (dist[use] ** 2 * pdf_area[use])
        tmax = dist[use] * (1.0 - 1e-6) - 1e-9
        T = self.transmittance(origins[use], w[use], tmax)
        E[use] = self.light_luminance[tri[use]] * geom[:, None] * T
        return E

"""Direct illuminance from the sun and from ``light`` surfaces, by shadow rays.

* Sun (docs/design.md §2): E = E_dn · max(0, N·s) · V, s the disk's centre and V the mean
  transmittance of shadow rays over the 6.8e-5 sr disk (0 behind an opaque surface, the
  product of τ(θ) over the panes of glass crossed, θ each pane's angle of incidence:
  :meth:`lbl_illum.scene.materials.MaterialTable.specular`): one ray at a hemisphere hit, a
  jittered 4 × 4 grid over the disk at a sensor point, and where those or :data:`RIM_RAYS`
  rays along the disk's rim find it partly hidden (a penumbra) :data:`PENUMBRA_SAMPLES`
  stratified rays instead.  (A shadow edge that cuts off less than a rim segment between
  two rim rays, 0.16 % of the disk, is not seen and keeps the 16 rays' value.)  When the disk
  straddles the surface's horizon (|N·s| < sin δ, δ = 0.27° the disk's radius) each ray
  carries its own max(0, N·d): E = E_dn · mean(max(0, N·d) T(d)), the part below the
  horizon adding nothing.
* The sun's images in flat mirrors, panes of glass and polished plastic (virtual suns,
  :mod:`lbl_illum.engine.sunmirrors`): one direction over the disk per light sample, at most
  :data:`MAX_MIRROR_SAMPLES`.
* The sun's highlight on rough plastic (:meth:`DirectLight.sun_highlight`): the luminance
  a path sees at a glossy hit, by one shadow ray toward the disk.
* Light surfaces (Lambertian emitters, two-sided): the closed form of what a point would
  see of them with nothing in the way, less a shadow-ray estimate of the part hidden
  (:mod:`lbl_illum.engine.emitters`).
* Luminaires of photometric files: point sources, I(ω) cos θ / d² by one shadow ray each
  (:mod:`lbl_illum.engine.luminaires`).

The indirect calculation never counts these sources again: a hemisphere ray that
reaches a light surface or the sun directly contributes nothing (paper §5), nor one that
reaches the sun after a specular reflection (the images and highlights above count it).
"""

from __future__ import annotations

import numpy as np

from ..scene.materials import LIGHT, MaterialTable, ward_brdf
from .gather import rows as take
from .emitters import LightSurfaces
from .luminaires import LuminaireLight
from .raycast import Tracer, through_panes
from ..daylight.sun import SUN_COS_HALF_ANGLE, Sun
from .sunmirrors import NOTE_SHARE, SunMirrors

#: Shadow rays over the sun's disk, stratified (32 × 32), at sensor points the first rays
#: found partly shaded: a penumbra, where a few random rays are off by tens of percent.
PENUMBRA_SAMPLES = 1024
#: sin δ of the sun disk's angular radius δ: the disk straddles the horizon of a surface
#: whose N·s lies within ± this.
SUN_SIN_HALF_ANGLE = float(np.sqrt(1.0 - SUN_COS_HALF_ANGLE ** 2))

#: Rays along the rim of the sun's disk in the partial-shade test at sensor points.
RIM_RAYS = 16
#: Most sun directions per point for the sun reflected by mirrors and panes.
MAX_MIRROR_SAMPLES = 16
#: Most shadow rays traced in one call.
MAX_SHADOW_BATCH = 1 << 20

__all__ = ["DirectLight"]


def _concentric(a, b):
    """Shirley & Chiu's concentric map of the unit square onto the unit disk ("A low
    distortion map between disk and square", JGT 2(3), 1997), as (r², φ / 2π): uniform
    numbers for :meth:`lbl_illum.daylight.sun.Sun.sample_directions`, whose first argument is
    linear in the disk's area."""
    x, y = 2.0 * np.asarray(a) - 1.0, 2.0 * np.asarray(b) - 1.0
    big = np.abs(x) > np.abs(y)
    r = np.where(big, x, y)
    with np.errstate(divide="ignore", invalid="ignore"):
        phi = np.where(big, (np.pi / 4) * (y / np.where(x == 0, 1.0, x)),
                       np.pi / 2 - (np.pi / 4) * (x / np.where(y == 0, 1.0, y)))
    phi = np.where((x == 0) & (y == 0), 0.0, phi)
    phi = np.where(r < 0, phi + np.pi, phi)
    return r * r, (phi / (2.0 * np.pi)) % 1.0


class DirectLight:
    """Shadow-ray estimates of direct illuminance at arrays of points."""

    def __init__(self, tracer: Tracer, materials: MaterialTable, sun: Sun | None, luminaires=()):
        self.tracer = tracer
        self.materials = materials
        self.sun = sun if (sun is not None and sun.is_up) else None
        tri = tracer.triangles
        #: some glass of the scene transmits by the angle of incidence (Fresnel glazing)
        self._angular = bool(np.any(materials.fresnel[np.unique(tri.material)])) if len(tri) else False
        light_ids = np.flatnonzero(materials.kind[tri.material] == LIGHT)
        #: the light surfaces (None without any)
        self.lights = LightSurfaces(tri, light_ids, materials.luminance) if len(light_ids) else None
        #: the luminaires of photometric files (None without any)
        self.luminaires = LuminaireLight(luminaires) if len(luminaires) else None
        #: the sun's images in flat mirrors and panes (:mod:`lbl_illum.engine.sunmirrors`)
        self.mirrors = SunMirrors(tracer, materials) if self.sun is not None else None
        if self.mirrors is not None and len(self.mirrors) == 0:
            self.mirrors = None

    def notes(self, unit_scale: float = 1.0, units: str = "m") -> list[str]:
        """What the user should hear of the direct light: reflecting planes the sun's
        images leave out, luminaires whose light meets a surface at once."""
        out = []
        if self.mirrors is not None and self.mirrors.dropped_share > NOTE_SHARE:
            out.append(f"the sun's reflection is followed in the {len(self.mirrors)} largest planes of mirrors, glass "
                       f"and polished plastic; {self.mirrors.dropped} smaller planes "
                       f"({100 * self.mirrors.dropped_share:.0f} % of their area) reflect no sun")
        if self.luminaires is not None:
            out += self.luminaires.notes(self.tracer, unit_scale, units)
        return out

    @property
    def has_lights(self) -> bool:
        return self.lights is not None

    @property
    def is_dark(self) -> bool:
        return self.sun is None and not self.has_lights and self.luminaires is None

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
                o_lit, n_lit = take(origins, lit), take(shading_normals, lit)
                T, mixed = self._sun_transmittance(o_lit, n_lit, cut, light_samples, rng,
                                                   stratified=light_samples > 1)
                part = np.flatnonzero(mixed) if light_samples > 1 else ()
                if len(part):
                    # a penumbra: some of the stratified rays were blocked and some not; the
                    # estimate is replaced by one of PENUMBRA_SAMPLES stratified rays
                    T[part] = self._sun_transmittance(take(o_lit, part), take(n_lit, part), cut[part],
                                                      max(PENUMBRA_SAMPLES, light_samples), rng, stratified=True)[0]
                E[lit] += self.sun.direct_normal_illuminance * np.where(cut, 1.0, cos[lit])[:, None] * T
            if self.mirrors is not None:
                m = max(1, min(light_samples, MAX_MIRROR_SAMPLES))
                for _ in range(m):
                    d = self.sun.sample_directions(rng.random(n), rng.random(n))
                    E += self.mirrors.illuminance(origins, shading_normals, d, self.sun.direction,
                                                  self.sun.direct_normal_illuminance, self.transmittance) / m
        if self.has_lights:
            E += self.lights.illuminance(points, shading_normals, origins, rng, light_samples, self.transmittance)
        if self.luminaires is not None:
            E += self.luminaires.illuminance(points, shading_normals, origins, self.transmittance)
        return E

    def sun_highlight(self, d, P, Ng, Ns, mat, rng: np.random.Generator) -> np.ndarray:
        """(k, 3) luminance [cd/m²] of the sun reflected by the lobes of rough plastic hits.

        d : (k, 3) arriving ray directions;  P, Ng, Ns : (k, 3) hit points [m] and normals
        facing the rays;  mat : (k,) their (rough plastic) materials.  The sun disk of
        luminance E_dn/Ω gives L = ∫_disk ρ_s f_s(v, ω) cos θ_ω E_dn/Ω dω; one direction s
        drawn uniformly in the disk estimates it without bias as
        ρ_s f_s(v, s) cos θ_s E_dn T(s) (:func:`~lbl_illum.scene.materials.ward_brdf`), T the
        transmittance of a shadow ray toward s (0 behind an opaque surface, τ(θ) through glass:
        :meth:`transmittance`).  Used wherever a path meets rough plastic: camera rays
        (:func:`lbl_illum.engine.render.trace_view_paths`) and hemisphere rays
        (:meth:`lbl_illum.engine.integrator.Integrator.trace_paths`), whose continuations into the
        lobe then count no sun.  Zero without a sun.
        """
        k = len(d)
        L = np.zeros((k, 3))
        if self.sun is None or k == 0:
            return L
        mats = self.materials
        u = rng.random((2, k))
        s = self.sun.sample_directions(u[0], u[1])
        cos_s = np.einsum("ij,ij->i", Ns, s)
        f = mats.specularity[mat] * ward_brdf(Ns, d, s, mats.roughness[mat])
        use = np.flatnonzero(f * cos_s > 0.0)
        if len(use):
            T = self.transmittance(self.tracer.offset(P[use], Ng[use]), s[use])
            # the lobe's colour: 1 for plastic, C for metal (Radiance's normal.c)
            L[use] = (self.sun.direct_normal_illuminance * f[use] * cos_s[use])[:, None] * T \
                * mats.specular_colour(mat[use])
        return L

    def _sun_transmittance(self, origins, normals, cut, samples, rng, stratified=False):
        """Mean over ``samples`` shadow rays across the sun's disk of T(d) (times
        max(0, N·d) where ``cut``: the disk straddles the horizon), (n, 3), and (n,) bool:
        the disk is partly hidden.  ``stratified``: a jittered g × g grid (g² = ``samples``)
        mapped onto the disk by the concentric map, whose cells stay compact; the
        partial-shade test then also looks along the disk's rim (:data:`RIM_RAYS` rays), so
        that an edge across the disk goes unseen only if it cuts off less than a rim
        segment between two of them (0.16 % of the disk for 16)."""
        n = len(origins)
        g = int(round(np.sqrt(samples))) if stratified else 0
        count = g * g if stratified else samples
        if stratified:
            cell = np.arange(count)
            r2, v = _concentric((cell[:, None] // g + rng.random((count, n))) / g,
                                (cell[:, None] % g + rng.random((count, n))) / g)
            turn = rng.random(n)
            rim = (np.arange(RIM_RAYS)[:, None] + turn) / RIM_RAYS
            r2 = np.concatenate([r2, np.full((RIM_RAYS, n), 1.0 - 1e-9)])
            v = np.concatenate([v, rim])
        else:
            r2, v = rng.random((count, n)), rng.random((count, n))
        rays = len(r2)
        T = np.zeros((n, 3))
        blocked = np.zeros(n, bool)
        open_ = np.zeros(n, bool)
        per = max(1, MAX_SHADOW_BATCH // max(1, n))          # samples traced together
        for start in range(0, rays, per):
            stop = min(rays, start + per)
            d = self.sun.sample_directions(r2[start:stop].ravel(), v[start:stop].ravel())
            t = self.transmittance(np.tile(origins, (stop - start, 1)), d).reshape(stop - start, n, 3)
            reach = t.max(axis=2) > 0.0
            blocked |= (~reach).any(axis=0)
            open_ |= reach.any(axis=0)
            weigh = min(stop, count) - start                  # the rim rays only test for shade
            if weigh > 0:
                w = np.where(cut, np.maximum(np.einsum("kij,ij->ki", d.reshape(stop - start, n, 3)[:weigh], normals),
                                             0.0), 1.0)
                T += (t[:weigh] * w[:, :, None]).sum(axis=0)
        return T / count, blocked & open_

    def transmittance(self, origins, directions, tmax=None) -> np.ndarray:
        """(n, 3) fraction of light passing along each segment: 0 behind an opaque
        surface, else the product over the glass crossed of its transmittance at the
        ray's angle of incidence.

        Without angle-dependent glass this is :meth:`Tracer.transmittance`.  With it, the
        segments that the tracer finds unblocked and through glass (0 < T < 1) are followed
        again, pane by pane, with closest-hit queries (:func:`~lbl_illum.engine.raycast.through_panes`),
        and each pane's normal-incidence τ_n is replaced by τ(θ)
        (:meth:`~lbl_illum.scene.materials.MaterialTable.specular`).
        """
        T = self.tracer.transmittance(origins, directions, tmax)
        if not self._angular or len(T) == 0:
            return T
        todo = np.flatnonzero((T.max(axis=1) > 0.0) & (T.min(axis=1) < 1.0))
        if len(todo) == 0:
            return T
        # an opaque hit on the way is round-off here: the tracer found the segment unblocked
        product = through_panes(self.tracer, self.materials, np.asarray(origins, np.float64)[todo],
                                np.asarray(directions, np.float64)[todo],
                                tmax=None if tmax is None else np.asarray(tmax, np.float64)[todo]).product
        T[todo] = np.where(T[todo] > 0.0, product, 0.0)
        return T

"""The lighting context of a scene: everything about its light that no option changes.

Built once per scene (:meth:`LightingContext.of`) and never changed afterwards, it is
shared by every calculation on the scene — grids, images, several option sets, several
runs: the ray tracer over the scene's triangles, the material table, the sky, the sun
and the light surfaces (:class:`~lbl_illum.engine.direct.DirectLight`), the window
portals and unglazed openings sampled in the indirect step (the paper's §5;
:mod:`lbl_illum.engine.portals`), and a few facts about the materials that decide which
stages of the path follower a scene needs (a scene computes only what it requires).

What depends on one run — the options, the record spacing limits found from the query
points, the portals' luminance seen from those points — is the run plan of
:class:`~lbl_illum.engine.integrator.Integrator.compute`, never stored here.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .compiled import start_first_run
from .direct import DirectLight
from .portals import PortalSet, build_portals
from .raycast import Tracer
from ..photometry import luminance
from ..scene.geometry import TriangleSampler, Triangles
from ..scene.materials import GLASS, MIRROR, PLASTIC, MaterialTable
from ..scene.scenefile import Scene

__all__ = ["LightingContext"]


def _frozen(a: np.ndarray) -> np.ndarray:
    a.flags.writeable = False
    return a


@dataclass(frozen=True, eq=False)
class LightingContext:
    """A scene's tracer, materials, light sources and portals (see the module docstring).

    Attributes
    ----------
    scene : the scene (lengths in metres)
    materials : its material table
    tracer : the Embree tracer over its triangles (glass and light surfaces known to it)
    direct : the sun and the light surfaces (direct light, §5)
    portal_set : the window portals and openings (None under a dark sky, or without any)
    openings : a tracer over the opening triangles alone (None without openings): rays
        cross openings, which nothing else sees, and the portal density of a ray counts
        the openings it crosses
    opening_first : portal index of the first opening triangle (the glass ones come first)
    portal_index : (T,) per scene triangle, its portal index (-1: not a portal)
    translucent_portal : (T,) per scene triangle, a translucent sheet sampled as a portal
        (a ray that meets it ends there on both faces: :mod:`lbl_illum.engine.portal_sampling`)
    diffuse_reflector : (materials,) reflects diffusely (ends a path at a diffuse level:
        a diffuse surface or the diffuse part of plastic)
    rho_over_pi : (materials, 3) ρ_d/π [1/sr]
    diffuse_transmitter : (materials,) transmits diffusely (``translucent``: a path that
        meets it also ends on its far side)
    tau_over_pi : (materials, 3) τ_d/π [1/sr]
    reflects : some surface of the scene reflects specularly (a mirror, glass with
        reflectance, plastic with a specular part)
    plastic : some plastic is in the scene (its specular branches play Russian roulette)
    sun_glossy : a sun and some rough plastic (paths meeting it see the sun's highlight)
    plastic_fresnel : some polished plastic's diffuse reflectance depends on incidence
    """

    scene: Scene
    materials: MaterialTable
    tracer: Tracer
    direct: DirectLight
    portal_set: PortalSet | None
    openings: Tracer | None
    opening_first: int
    portal_index: np.ndarray
    translucent_portal: np.ndarray
    diffuse_reflector: np.ndarray
    rho_over_pi: np.ndarray
    diffuse_transmitter: np.ndarray
    tau_over_pi: np.ndarray
    reflects: bool
    plastic: bool
    sun_glossy: bool
    plastic_fresnel: bool

    @classmethod
    def of(cls, scene: Scene) -> "LightingContext":
        """The context of ``scene``: its tracer, direct light and portals, built once."""
        start_first_run()       # on a first run, half the kernels compile meanwhile in another process
        materials: MaterialTable = scene.material_table
        tracer = Tracer(scene.triangles, materials.kind, materials.transmittance)
        direct = DirectLight(tracer, materials, scene.sun, scene.luminaires)
        # portal glass first, then openings (lbl_illum.engine.portals)
        portal_set = None if scene.sky.is_dark else build_portals(scene, tracer, materials,
                                                                  find=scene.find_openings)
        prim = portal_set.prim if portal_set is not None else np.zeros(0, np.int64)
        glass_ids = prim[prim >= 0]
        portal_index = np.full(len(scene.triangles), -1, np.int64)
        portal_index[glass_ids] = np.arange(len(glass_ids))
        openings_tracer = None
        if portal_set is not None and len(portal_set.sampler.vertices) > len(glass_ids):
            opening_tris = portal_set.sampler.vertices[len(glass_ids):]
            openings_tracer = Tracer(Triangles(opening_tris, np.zeros(len(opening_tris), np.int32),
                                               np.full(len(opening_tris), -1, np.int32)),
                                     np.zeros(1, np.int8), np.zeros((1, 3)), threads=tracer.threads)
        diffuse_transmitter = materials.diffuse_transmittance.max(axis=1) > 0.0
        translucent_portal = (portal_index >= 0) & diffuse_transmitter[scene.triangles.material]
        used = np.unique(scene.triangles.material)
        specular = np.isin(materials.kind[used], (MIRROR, GLASS)) & (materials.reflectance[used].max(axis=1) > 0)
        specular |= materials.specularity[used] > 0.0
        return cls(scene=scene, materials=materials, tracer=tracer, direct=direct, portal_set=portal_set,
                   openings=openings_tracer, opening_first=len(glass_ids), portal_index=_frozen(portal_index),
                   translucent_portal=_frozen(translucent_portal),
                   diffuse_reflector=_frozen(materials.diffuse_reflectance.max(axis=1) > 0.0),
                   rho_over_pi=_frozen(materials.diffuse_reflectance / np.pi),
                   diffuse_transmitter=_frozen(diffuse_transmitter),
                   tau_over_pi=_frozen(materials.diffuse_transmittance / np.pi),
                   reflects=bool(specular.any()),
                   plastic=bool(np.any(materials.kind[used] == PLASTIC)),
                   sun_glossy=direct.sun is not None and bool(np.any(materials.glossy[used])),
                   plastic_fresnel=bool(np.any(materials.plastic_fresnel[used])))

    # -- what the scene holds --------------------------------------------------------
    @property
    def sky(self):
        """The sky (and ground glow) model."""
        return self.scene.sky

    @property
    def sun(self):
        """The sun as the direct calculation sees it (None without one)."""
        return self.direct.sun

    @property
    def luminous_openings(self):
        """The luminaires' luminous openings that camera rays and specular paths see
        (:class:`~lbl_illum.engine.luminous_openings.LuminousOpenings`; None without any)."""
        lum = self.direct.luminaires
        return None if lum is None else lum.openings

    @property
    def portals(self) -> TriangleSampler | None:
        """The portal triangles as a sampler (None without portals)."""
        return self.portal_set.sampler if self.portal_set is not None else None

    @property
    def portal_prim(self) -> np.ndarray:
        """Per portal triangle: its scene triangle (portal glass), or -1 (an opening)."""
        return self.portal_set.prim if self.portal_set is not None else np.zeros(0, np.int64)

    def zone(self, P) -> np.ndarray:
        """(n,) uint8 cache zone of each point (:meth:`lbl_illum.engine.portals.PortalSet.zone`;
        0 for all without portals)."""
        if self.portal_set is None:
            return np.zeros(len(P), np.uint8)
        return self.portal_set.zone(P)

    def level_active(self, k: int, bounces: int, ambient: float) -> bool:
        """Whether records of diffuse level k can be non-zero with ``bounces`` levels below
        the first and ``ambient`` lux at the limit (else they are never made)."""
        sky_light = not self.sky.is_dark
        if k == bounces:
            # at the bounce limit a record sees the sky, the ambient value, light surfaces
            # and luminaires' openings by specular reflection (a mirror, the outside of a pane) and the sun's
            # highlight on rough plastic (the sun's images in flat reflectors are direct
            # light at the hits, which the bounce limit does not reach)
            emitters = self.direct.has_lights or self.luminous_openings is not None
            reflected_light = (emitters and self.reflects) or self.sun_glossy
            return sky_light or ambient > 0 or reflected_light
        return sky_light or not self.direct.is_dark or ambient > 0

    # -- the portals seen from a run's query points -------------------------------------
    def portal_luminance(self, roi) -> np.ndarray:
        """Per portal triangle, the luminance [cd/m²] seen through it from the centre of
        the box ``roi = (lo, hi)`` [m] around a run's query points: the sky (or ground
        glow) in the direction of the triangle's centroid, times the glass's
        transmittance at that incidence (1 for an opening; a translucent sheet's diffuse
        τ, its far face's luminance τ E/π under a uniform sky of luminance E/π)."""
        centre = 0.5 * (roi[0] + roi[1])
        d = self.portals.vertices.mean(axis=1) - centre
        d /= np.maximum(np.linalg.norm(d, axis=1), 1e-300)[:, None]
        L = luminance(self.sky.luminance(d))
        prim = self.portal_prim
        glass = prim >= 0
        if glass.any():
            p = prim[glass]
            cos = np.abs(np.einsum("ij,ij->i", self.tracer.normals[p], d[glass]))
            mat = self.scene.triangles.material[p]
            tau = self.materials.glass_transmittance(mat, cos)
            diffuse = self.diffuse_transmitter[mat]
            tau[diffuse] = self.materials.diffuse_transmittance[mat[diffuse]]
            L[glass] *= luminance(tau)
        return L

    def inside_stats(self, portal_luminance) -> tuple[float, float]:
        """(Φ ρ / A [lux], ρ) of the inside zone for the split-flux estimate of the
        interreflected light (Sumpner's law of the integrating sphere): Φ = π Σ L_k A_k
        over the portal triangles (``portal_luminance`` L_k, :meth:`portal_luminance`), A
        and ρ the area [m²] and the area-weighted diffuse reflectance of the triangles
        wholly inside (:meth:`zone`)."""
        tri = self.scene.triangles
        inside = (self.zone(tri.vertices.reshape(-1, 3)).reshape(-1, 3) == 1).all(axis=1)
        area = tri.areas[inside]
        A = float(area.sum())
        if A <= 0.0:
            return 0.0, 0.0
        rho = float((area * luminance(self.materials.diffuse_reflectance)[tri.material[inside]]).sum() / A)
        flux = float(np.pi * (portal_luminance * self.portals.area).sum())
        return flux * rho / A, rho

    def notes(self) -> list[str]:
        """What the user should hear of the portals and the direct light: openings found in
        the geometry, panes left out because no sky lies behind them
        (:mod:`lbl_illum.engine.portals`), the direct calculation's own notes."""
        ps = self.portal_set
        scene = self.scene
        if ps is None:
            return self.direct.notes(scene.unit_scale, scene.units)
        notes = [f"unglazed opening found, sampled as a portal: {o.describe(scene.unit_scale, scene.units)} "
                 "(find_openings = false to turn this off)" for o in ps.openings]
        notes += self.direct.notes(scene.unit_scale, scene.units)
        if ps.dropped:
            notes.append(f"{ps.dropped} glass {'triangle is' if ps.dropped == 1 else 'triangles are'} not sampled as "
                         "a portal: no sky behind them (portal = true on the material samples them anyway)")
        return notes

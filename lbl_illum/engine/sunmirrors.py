"""The sun reflected by flat mirrors, panes of glass and polished plastic: virtual suns.

A flat specular reflector (a ``mirror``, the front reflection of a ``glass`` pane, or the
specular part of polished ``plastic``) seen from a point P along u = s − 2 (s·n) n, s the
direction to the sun and n the reflector's normal, shows P the sun's image.  The
illuminance it adds at P is

    E = E_dn · ρ(θ) · max(0, N·u) · T(X → sun),

X the point where the ray from P along u meets the reflector, ρ(θ) its specular
reflectance at the sun's angle of incidence (:meth:`MaterialTable.specular`: a mirror's
ρ, a pane's Fresnel or constant reflectance, plastic's ρ_s(θ)) and T the transmittance
of both legs, P to X and X to the sun (0 behind an opaque surface, else the product of
τ(θ) of the panes crossed: a light shelf's mirror outside the window lights the ceiling
through the pane above it).  This
is the "virtual light source" of Radiance's ``mirror`` material (G. J. Ward, "The RADIANCE
Lighting Simulation and Rendering System", SIGGRAPH 1994, §2.2), applied here to panes and
polished plastic as well.

Hemisphere rays could find the same light by reaching the sun's 6.8e-5 sr disk after a
reflection, but only one ray in about 10⁵ does, carrying 10⁵ times the rest: on the
office under a clear sky one such ray put 2.7e9 lux into a record on the ground outside
the window and 8,500 lux (+370 %) into a sensor.  So those rays add nothing
(:meth:`Integrator.trace_paths`) and this estimate replaces them.  Rough plastic's lobe
is too wide for an image: paths that meet it take the sun's highlight by a shadow ray
(:meth:`lbl_illum.engine.direct.DirectLight.sun_highlight`).  Not counted: the sun reflected by
curved mirrors or panes, and by two mirrors in a row.

Reflectors are grouped by plane (normals and offsets equal to 1e-4); a point is tested
only against planes whose sun-side it lies on and where the reflected ray meets the
plane inside the group's bounding box, so a room of windows costs a few rays at the
points that can see a reflection.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ..scene.materials import GLASS, MIRROR, PLASTIC, MaterialTable
from .raycast import MAX_GLASS_LAYERS, SELF_HIT_EPSILON, Tracer, through_panes

__all__ = ["SunMirrors", "MAX_PLANES"]

#: Most reflector planes kept (the largest by area); a scene whose others hold more than
#: :data:`NOTE_SHARE` of the reflecting area is told so.
MAX_PLANES = 64
#: Share of the reflecting area left out above which the user hears of it.
NOTE_SHARE = 0.01
#: Normals and offsets (as fractions of the scene's length scale) that round to the same
#: multiple of this make one plane.
PLANE_TOLERANCE = 1e-4


class SunMirrors:
    """Flat specular reflectors grouped by plane, and the sun they reflect."""

    def __init__(self, tracer: Tracer, materials: MaterialTable):
        self.tracer = tracer
        self.materials = materials
        tri = tracer.triangles
        kind = materials.kind[tri.material] if len(tri) else np.zeros(0, np.int8)
        polished = (kind == PLASTIC) & (materials.specularity[tri.material] > 0.0) & ~materials.glossy[tri.material]
        ids = np.flatnonzero((kind == MIRROR) | (kind == GLASS) | polished)
        if len(ids):                                # (a degenerate triangle has no plane)
            ids = ids[np.linalg.norm(tracer.normals[ids], axis=1) > 0.5]
        self.planes: list[dict] = []
        self.dropped = 0
        self.dropped_share = 0.0
        #: (n_triangles,) int32: the plane of each reflecting triangle, −1 for the others
        self.plane_of = np.full(len(tri), -1, np.int32)
        if len(ids) == 0:
            self._pack()
            return
        n = tracer.normals[ids].astype(np.float64)
        big = np.argmax(np.abs(n), axis=1)
        n = n * np.sign(n[np.arange(len(n)), big])[:, None]          # one orientation per plane
        v = tri.vertices[ids]                                        # (k, 3, 3)
        c = np.einsum("ij,ij->i", n, v[:, 0])
        scale = tracer.length_scale
        key = np.round(np.column_stack([n, c / scale]) / PLANE_TOLERANCE).astype(np.int64)
        group = np.unique(key, axis=0, return_inverse=True)[1].ravel()
        area = tri.areas[ids]
        order = np.argsort(-np.bincount(group, weights=area))
        keep = order[:MAX_PLANES]
        self.dropped = int(len(order) - len(keep))
        #: share of the reflecting area in the planes left out (curved or small surfaces)
        self.dropped_share = float(1.0 - np.bincount(group, weights=area)[keep].sum() / area.sum())
        for g in keep:
            sel = np.flatnonzero(group == g)
            w = area[sel] / area[sel].sum()
            normal = (n[sel] * w[:, None]).sum(axis=0)
            normal /= np.linalg.norm(normal)
            pts = v[sel].reshape(-1, 3)
            pad = 1e-3 * scale
            self.plane_of[ids[sel]] = len(self.planes)
            self.planes.append({"normal": normal, "offset": float(np.dot(normal, pts.mean(axis=0))),
                                "lo": pts.min(axis=0) - pad, "hi": pts.max(axis=0) + pad})
        self._pack()

    def _pack(self) -> None:
        """The planes as arrays for :func:`_candidates`."""
        self._normals = np.array([p["normal"] for p in self.planes], np.float64).reshape(-1, 3)
        self._offsets = np.array([p["offset"] for p in self.planes], np.float64)
        self._lo = np.array([p["lo"] for p in self.planes], np.float64).reshape(-1, 3)
        self._hi = np.array([p["hi"] for p in self.planes], np.float64).reshape(-1, 3)

    def __len__(self) -> int:
        return len(self.planes)

    def illuminance(self, origins, normals, sun_directions, sun_centre, direct_normal_illuminance: float,
                    transmittance):
        """(n, 3) illuminance [lux] of the sun's images at ``origins`` (n, 3) facing
        ``normals`` (n, 3).  The rays follow one direction of the sun's disk per point
        (``sun_directions`` (n, 3)); cosine and reflectance are those of the disk's centre
        ``sun_centre`` (3,) (as for the sun itself, :mod:`lbl_illum.engine.direct`), so the rays
        decide only what is seen.  ``transmittance(origins, directions)`` is the shadow-ray
        transmittance of :class:`lbl_illum.engine.direct.DirectLight`."""
        origins = np.asarray(origins, np.float64)
        E = np.zeros((len(origins), 3))
        if len(origins) == 0:
            return E
        sun_directions = np.ascontiguousarray(sun_directions, np.float64)
        nrm = self._normals
        c_n = nrm @ np.asarray(sun_centre, np.float64)                           # (planes,)
        mirrored = sun_centre[None, :] - 2.0 * c_n[:, None] * nrm                 # (planes, 3)
        point, plane, side, cos_p = _candidates(origins, sun_directions, np.ascontiguousarray(normals, np.float64),
                                                mirrored, nrm, self._offsets, self._lo, self._hi)
        if len(point) == 0:
            return E
        s = sun_directions[point]
        u = s - 2.0 * np.einsum("ij,ij->i", s, nrm[plane])[:, None] * nrm[plane]
        ok, prim, t_hit, T_near = self._reach_reflector(origins[point], u, plane)
        point, plane, side, cos_p, u, s, prim, t_hit, T_near = (point[ok], plane[ok], side[ok], cos_p[ok], u[ok],
                                                                s[ok], prim[ok], t_hit[ok], T_near[ok])
        if len(point) == 0:
            return E
        mat = self.tracer.triangles.material[prim]
        rho = self.materials.specular(mat, np.abs(c_n[plane]))[1]
        back = np.sign(side)[:, None] * nrm[plane]                            # the reflector's side of P
        X = origins[point] + t_hit[:, None] * u
        step = SELF_HIT_EPSILON * (np.abs(X).max(axis=1) + self.tracer.length_scale)
        T = transmittance(X + step[:, None] * back, s)
        add = direct_normal_illuminance * rho * cos_p[:, None] * T_near * T
        for c in range(3):                      # (in plane order at each point)
            E[:, c] = np.bincount(point, add[:, c], minlength=len(E))
        return E

    def _reach_reflector(self, origins, u, plane):
        """Follow the rays from the points along u to their reflector planes ``plane``,
        through any panes on the way (:func:`~lbl_illum.engine.raycast.through_panes`:
        MAX_GLASS_LAYERS + 1 closest-hit queries, room for that many panes and the reflector).  Returns ``(ok, prim, t, T_near)``: (k,) whether the
        ray reaches a triangle of its plane, that triangle (−1 if not), the distance [m] to it (inf), and
        (k, 3) the product of τ(θ) of the panes crossed before it (glass of other planes,
        :meth:`MaterialTable.glass_transmittance`; Radiance's shadow rays to a virtual
        source pass through glass likewise).  An opaque surface on the way ends the ray."""
        plane_of = self.plane_of
        path = through_panes(self.tracer, self.materials, origins, u,
                             stop=lambda prim, ray: plane_of[prim] == plane[ray], layers=MAX_GLASS_LAYERS + 1)
        ok = path.reached
        return ok, np.where(ok, path.prim, -1), np.where(ok, path.distance, np.inf), path.product


@njit(cache=True)
def _candidates(origins, sun_directions, normals, mirrored, plane_normals, offsets, lo, hi):
    """(point, plane, side, cos) of the pairs where a point may see the sun in a plane: it
    faces the mirrored direction of the disk's centre (cos = N·``mirrored[plane]`` > 0),
    lies on the plane's sun side (side = signed distance, same sign as s·n, so the ray along
    the mirrored direction u of its disk direction s meets the plane at t = side / (s·n) > 0),
    and that meeting point lies in the plane's box."""
    n, m = len(origins), len(plane_normals)
    count = 0
    for stage in range(2):
        if stage == 1:
            point = np.empty(count, np.int64)
            plane = np.empty(count, np.int64)
            side_out = np.empty(count)
            cos_out = np.empty(count)
            count = 0
        for i in range(n):
            for k in range(m):
                cos = normals[i, 0] * mirrored[k, 0] + normals[i, 1] * mirrored[k, 1] + normals[i, 2] * mirrored[k, 2]
                if cos <= 0.0:
                    continue
                s_n = (sun_directions[i, 0] * plane_normals[k, 0] + sun_directions[i, 1] * plane_normals[k, 1]
                       + sun_directions[i, 2] * plane_normals[k, 2])
                if abs(s_n) <= 1e-9:
                    continue
                side = (origins[i, 0] * plane_normals[k, 0] + origins[i, 1] * plane_normals[k, 1]
                        + origins[i, 2] * plane_normals[k, 2]) - offsets[k]
                t = side / s_n
                if t <= 0.0:
                    continue
                inside = True
                for c in range(3):
                    x = origins[i, c] + t * (sun_directions[i, c] - 2.0 * s_n * plane_normals[k, c])
                    if x < lo[k, c] or x > hi[k, c]:
                        inside = False
                        break
                if inside:
                    if stage == 1:
                        point[count] = i
                        plane[count] = k
                        side_out[count] = side
                        cos_out[count] = cos
                    count += 1
    return point, plane, side_out, cos_out

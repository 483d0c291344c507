"""Window portals: which glazing and openings the indirect calculation samples by area,
and which way each faces.

The paper's §5 puts large sources such as the sky seen through a window into the indirect
step, sampled well; :mod:`lbl_illum.engine.portal_sampling` does so by multiple
importance sampling over the portals of this module.  A portal is worth its samples only
where the sky lies behind it, and only for what lies in front of it:

* **Candidates**: glass whose material says ``portal = "auto"`` (the default) or ``true``,
  translucent sheets likewise (a diffusing skylight: its far face's light, τ E/π, is
  what the portal samples find there),
  the ``[[portals]]`` polygons and ``opening`` faces of the scene file, and the unglazed
  openings :func:`lbl_illum.engine.openings.find_openings` finds in the geometry (unless the scene
  sets ``find_openings = false``).
* **Which way out**: from the centre of every candidate triangle :data:`PROBE_RAYS` rays,
  cosine-distributed about each side's normal, are traced to infinity through glass; the
  side from which more of them reach the sky is the outside, and the triangle's
  ``outward`` normal points there.
* **Glass that does not pay** — an ``"auto"`` pane through which less than
  :data:`MIN_SKY_FRACTION` of the rays from either side reach the sky (glass between two
  rooms, a vitrine), or which sees as much sky on both sides (a free-standing screen) —
  is not a portal.  ``portal = true`` keeps it anyway; ``false`` leaves any pane out.
* **Zones**: a point behind every portal plane and within the box of what rays from the
  portals into the room meet is in zone 1 (inside), any other point in zone 0
  (:meth:`PortalSet.zone`); a cache record serves only queries of its own zone.
* **Who samples them**: a record or sensor samples the portals only when it lies on the
  inner side (behind the outward normal) of at least half of their area
  (:meth:`PortalSet.inside`); the ground outside a building does not sample its windows.
  The rule depends on position alone, so every estimate stays unbiased; the light known
  from the windows (:func:`lbl_illum.engine.lambert.portal_irradiance`) counts, per triangle, only
  for points on its inner side.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..scene.geometry import TriangleSampler, Triangles
from ..scene.materials import GLASS, TRANSLUCENT

__all__ = ["PortalSet", "build_portals", "PROBE_RAYS", "MIN_SKY_FRACTION"]

#: Rays per side of a candidate triangle that decide which way is out.
PROBE_RAYS = 32
#: Share of those rays that must reach the sky on the outer side of an ``"auto"`` pane.
MIN_SKY_FRACTION = 0.1
#: Share of the portal area a point must lie behind to sample the portals.
INSIDE_AREA_FRACTION = 0.5


@dataclass
class PortalSet:
    """The portals of a scene.

    sampler : points on them, by area;  prim : (k,) the scene triangle of each portal
    triangle (portal glass) or -1 (an opening, invisible to rays);  outward : (k, 3) unit
    normals towards the sky;  centre : (k, 3) [m];  openings : the openings found in the
    geometry (:class:`~lbl_illum.engine.openings.Opening`);  dropped : panes left out (no sky behind)
    """

    sampler: TriangleSampler
    prim: np.ndarray
    outward: np.ndarray
    centre: np.ndarray
    openings: list = field(default_factory=list)
    dropped: int = 0
    #: (2, 3) [m] the box around what the portals see of the inside (:func:`_enclosure`)
    enclosure: np.ndarray | None = None
    #: [m] points this close in front of a portal plane still count as behind it (the
    #: floor and walls that meet a window in its plane are inside)
    tolerance: float = 0.0

    def __len__(self) -> int:
        return len(self.prim)

    def facing(self, points: np.ndarray) -> np.ndarray:
        """(n, k) bool: each point lies on the inner side of each portal triangle."""
        rel = np.asarray(points, np.float64)[:, None, :] - self.centre[None]
        return np.einsum("nkc,kc->nk", rel, self.outward) < 0.0

    def planes(self) -> tuple[np.ndarray, np.ndarray]:
        """The portals' distinct planes: (p, 3) outward unit normals and (p,) offsets d, a
        point x lying behind a plane when n·x ≤ d (+ :attr:`tolerance`).  Found once."""
        if getattr(self, "_planes", None) is not None:
            return self._planes
        d = np.einsum("ij,ij->i", self.outward, self.centre)
        key = np.column_stack([np.round(self.outward * 1e4), np.round(d * 1e4)]).astype(np.int64)
        _, first = np.unique(key, axis=0, return_index=True)
        first = np.sort(first)
        self._planes = (self.outward[first], d[first])
        return self._planes

    def zone(self, points: np.ndarray) -> np.ndarray:
        """(n,) uint8: 1 for points behind every portal plane (inside the building's
        windows) and within the :attr:`enclosure`, else 0.  A cache record serves only queries of its own zone, so that the
        bright ground outside a façade is never interpolated into the room behind it
        (the wall between them stands in neither's tangent plane)."""
        points = np.asarray(points, np.float64).reshape(-1, 3)
        normals, d = self.planes()
        out = np.ones(len(points), bool)
        for n, offset in zip(normals, d):
            out &= points @ n <= offset + self.tolerance
        if self.enclosure is not None:      # by axis: np.all over rows of 3 took 4/5 of the time
            lo, hi = self.enclosure
            for c in range(3):
                out &= points[:, c] >= lo[c]
                out &= points[:, c] <= hi[c]
        return out.view(np.uint8)

    def inside(self, points: np.ndarray) -> np.ndarray:
        """(n,) bool: each point lies behind at least half of the portals' area."""
        points = np.asarray(points, np.float64)
        out = np.empty(len(points), bool)
        area = self.sampler.area
        step = max(1, 4_000_000 // max(1, len(self.prim)))
        for start in range(0, len(points), step):
            part = points[start:start + step]
            out[start:start + step] = self.facing(part) @ area >= INSIDE_AREA_FRACTION * area.sum()
        return out


def _sky_fractions(tracer, centres, normals, rng) -> np.ndarray:
    """(k, 2) share of cosine rays from each centre, about +normal and -normal, that reach
    the sky through glass."""
    from .hemisphere import stratified_directions

    k = len(centres)
    out = np.zeros((k, 2))
    m = max(1, int(round(np.sqrt(PROBE_RAYS / np.pi))))
    n = max(1, PROBE_RAYS // m)
    for j, sign in enumerate((1.0, -1.0)):
        side = sign * normals
        dirs = stratified_directions(side, m, n, rng).reshape(-1, 3)
        o = np.repeat(tracer.offset(centres, side), m * n, axis=0)
        reach = tracer.transmittance(o, dirs)[:, 0] > 0.0
        out[:, j] = reach.reshape(k, m * n).mean(axis=1)
    return out


def _covered(point: np.ndarray, triangles: np.ndarray, tolerance: float = 1e-3) -> bool:
    """Whether ``point`` lies on one of (k, 3, 3) ``triangles`` (within ``tolerance`` [m] of
    its plane, inside its edges)."""
    if len(triangles) == 0:
        return False
    a, b, c = triangles[:, 0], triangles[:, 1], triangles[:, 2]
    n = np.cross(b - a, c - a)
    n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-300)
    near = np.abs(np.einsum("ij,ij->i", point - a, n)) <= tolerance
    inside = np.ones(len(triangles), bool)
    for p, q in ((a, b), (b, c), (c, a)):
        inside &= np.einsum("ij,ij->i", np.cross(q - p, point - p), n) >= -tolerance * np.linalg.norm(q - p, axis=1)
    return bool(np.any(near & inside))


#: Rays from each portal triangle into the room that find the enclosure, and its margin
#: (a fraction of its diagonal, plus 1 cm).
ENCLOSURE_RAYS = 64
ENCLOSURE_MARGIN = 0.02


def _enclosure(tracer, portal: "PortalSet", rng) -> np.ndarray | None:
    """(2, 3) [m] the box around the first surfaces that rays from the portals into the
    room meet (those behind every portal plane), grown by :data:`ENCLOSURE_MARGIN`: the
    room the windows light, which the zones keep apart from the ground and buildings
    outside.  None when no ray meets anything inside."""
    from .hemisphere import stratified_directions

    k = len(portal.prim)
    m = max(1, int(round(np.sqrt(ENCLOSURE_RAYS / np.pi))))
    n = max(1, ENCLOSURE_RAYS // m)
    inward = -portal.outward
    dirs = stratified_directions(inward, m, n, rng).reshape(-1, 3)
    o = np.repeat(tracer.offset(portal.centre, inward), m * n, axis=0)
    hits = tracer.intersect(o, dirs)
    P = o[hits.hit] + hits.t[hits.hit, None] * dirs[hits.hit]
    saved, portal.enclosure = portal.enclosure, None
    behind = portal.zone(P) == 1
    portal.enclosure = saved
    P = np.concatenate([P[behind], portal.centre])
    if len(P) <= k:
        return None
    lo, hi = P.min(axis=0), P.max(axis=0)
    margin = ENCLOSURE_MARGIN * float(np.linalg.norm(hi - lo)) + 0.01
    return np.stack([lo - margin, hi + margin])


def build_portals(scene, tracer, materials, find: bool = True, rng: np.random.Generator | None = None
                  ) -> PortalSet | None:
    """The portals of ``scene`` (module text), or None when it has none.

    ``tracer`` traces the scene's triangles; ``materials`` is its
    :class:`~lbl_illum.scene.materials.MaterialTable`; ``find``: look for unglazed openings.
    """
    from .openings import find_openings

    rng = rng or np.random.default_rng(0)
    tri = scene.triangles
    mat = tri.material
    # glass and translucent sheets close an opening; those whose material allows it are candidates
    glazing = (materials.kind[mat] == GLASS) | (materials.kind[mat] == TRANSLUCENT)
    candidate = np.flatnonzero(glazing & materials.portal[mat])
    forced = materials.portal_forced[mat[candidate]]
    openings = np.asarray(scene.portals, np.float64).reshape(-1, 3, 3)
    found = find_openings(tri.vertices, glazing, tracer, rng) if find else []
    # an opening already drawn as a portal is not found again (two portals over one opening
    # would be sampled twice, while a ray crossing them counts one)
    found = [o for o in found if not _covered(o.centre, openings)]
    found_tri = np.concatenate([o.triangles for o in found]) if found else np.zeros((0, 3, 3))
    declared = np.concatenate([openings, found_tri])
    if len(candidate) == 0 and len(declared) == 0:
        return None
    vertices = np.concatenate([tri.vertices[candidate], declared])
    prim = np.concatenate([candidate, np.full(len(declared), -1)]).astype(np.int64)
    sampler_tris = Triangles(vertices, np.zeros(len(vertices), np.int32), np.full(len(vertices), -1, np.int32))
    normals, centres = sampler_tris.normals, vertices.mean(axis=1)
    sky = _sky_fractions(tracer, centres, normals, rng)
    out_side = np.where(sky[:, 0] >= sky[:, 1], 1.0, -1.0)
    outward = normals * out_side[:, None]
    keep = np.ones(len(vertices), bool)
    auto = np.zeros(len(vertices), bool)
    auto[:len(candidate)] = ~forced
    sky_out, sky_in = sky.max(axis=1), sky.min(axis=1)
    pays = (sky_out >= MIN_SKY_FRACTION) & (sky_in <= 0.5 * sky_out)
    keep[auto] = pays[auto]
    if found:      # the openings found know which way is out
        start = len(candidate) + len(openings)
        stop = start
        for o in found:
            outward[stop:stop + len(o.triangles)] = o.normal
            stop += len(o.triangles)
    dropped = int(np.count_nonzero(~keep))
    if not keep.any():
        return None
    vertices, prim, outward, centres = vertices[keep], prim[keep], outward[keep], centres[keep]
    sampler = TriangleSampler(Triangles(vertices, np.zeros(len(vertices), np.int32),
                                        np.full(len(vertices), -1, np.int32)), np.arange(len(vertices)))
    portals = PortalSet(sampler, prim, outward, centres, found, dropped)
    portals.tolerance = 1e-6 * float(np.max(np.diff(tri.bounds, axis=0)))
    portals.enclosure = _enclosure(tracer, portals, rng)
    return portals

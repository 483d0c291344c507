"""Unglazed openings found in the geometry, to be sampled as window portals.

The paper's §5 puts large sources such as the sky seen through a window into the indirect
calculation, to be sampled well; :mod:`lbl_illum.engine.portal_sampling` samples the area of every
portal by multiple importance sampling.  Glass is a portal by itself; an *unglazed*
opening is a hole in the geometry, which a modeller does not think of drawing.  A hole is
found here the way a modeller makes one — cut out of a wall or a roof:

1. the triangles are grouped by plane (normal within :data:`NORMAL_TOLERANCE`, offset within
   :data:`PLANE_TOLERANCE` of the scene's size, at least 1 mm);
2. each plane of at least :data:`MIN_PLANE_AREA` and :data:`MIN_PLANE_TRIANGLES` gets the union
   of its triangles in its own 2-D frame (``shapely``, snapped to the same tolerance, so
   T-junctions and seams close);
3. every hole of that union of at least :data:`MIN_OPENING_AREA` is a candidate; glass set in
   the hole, a door leaf in its plane and the like fill it, and those are not holes;
4. a candidate is an opening to the outside when rays from its centre, cosine-distributed
   about its normal, reach the sky on one side (at least :data:`MIN_SKY_FRACTION` of them,
   the way out) and much less on the other (the room): an opening between two rooms, or
   with glass a few centimetres behind it in a thick wall (more than
   :data:`MAX_GLAZED_FRACTION` of the inner rays meet glass), is left alone.

What is found depends only on the triangles, which are glass and the random numbers, so
it is kept in the cache folder (:mod:`lbl_illum.scene.geometry_cache`), keyed by their
SHA-256 with the random generator's state, and with the state it leaves: a run of the same
scene skips the search (0.3 s of every run of the cabin's 204,216 triangles) and gives the
same bits as one that searches.

An opening that reaches the edge of its wall (a door cut down to the floor, a gap between
two walls) is no hole and is not found: draw a ``[[portals]]`` polygon over it, or give a
face over it the ``opening`` material (docs/windows.md).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["Opening", "find_openings", "NORMAL_TOLERANCE", "PLANE_TOLERANCE", "MIN_OPENING_AREA"]

#: Normals of one plane agree within this (components of unit vectors; about 0.06°).
NORMAL_TOLERANCE = 1e-3
#: Offsets of one plane agree within this fraction of the scene's size (and 1 mm at least).
PLANE_TOLERANCE = 1e-6
#: A plane is searched for holes when its triangles cover this much [m²] ...
MIN_PLANE_AREA = 1.0
#: ... with at least this many triangles (a wall around a hole has at least 4) ...
MIN_PLANE_TRIANGLES = 4
#: ... and at most this many (beyond it, a tessellated surface rather than a wall).
MAX_PLANE_TRIANGLES = 20_000
#: Smallest hole [m²] taken for an opening.
MIN_OPENING_AREA = 0.05
#: Rays from a hole's centre per side, and the share of them that must reach the sky on
#: its outer side (and be at least twice the share on the inner side).
PROBE_RAYS = 64
MIN_SKY_FRACTION = 0.2
#: A hole whose inner-side probe rays meet glass this often is a glazed window's recess.
MAX_GLAZED_FRACTION = 0.3
#: Raised whenever :func:`find_openings` changes what it finds (kept searches are redone).
FINDER_VERSION = 1


@dataclass
class Opening:
    """An opening found in the geometry.

    triangles : (k, 3, 3) [m] over the hole;  area [m²];  normal : (3,) unit, pointing out
    (towards the sky);  centre : (3,) [m];  sky_fraction : share of the probe rays from the
    centre that reach the sky on the outer side
    """

    triangles: np.ndarray
    area: float
    normal: np.ndarray
    centre: np.ndarray
    sky_fraction: float

    def describe(self, unit_scale: float = 1.0, units: str = "m") -> str:
        """``"4.50 m² at (2.00, 0.00, 1.75) m, facing south"``, the position in the scene's
        ``units`` (``unit_scale`` metres each)."""
        c = self.centre / unit_scale
        n = self.normal
        facing = "a roof opening" if n[2] > 0.7 else f"facing {_compass(n)}"
        return f"{self.area:.2f} m² at ({c[0]:.2f}, {c[1]:.2f}, {c[2]:.2f}) {units}, {facing}"


def _compass(n: np.ndarray) -> str:
    azimuth = np.degrees(np.arctan2(n[0], n[1])) % 360.0
    return ("north", "north-east", "east", "south-east", "south", "south-west", "west", "north-west")[
        int((azimuth + 22.5) // 45) % 8]


def _planes(vertices: np.ndarray, tolerance: float):
    """The planes worth searching for holes (:data:`MIN_PLANE_AREA`, :data:`MIN_PLANE_TRIANGLES`,
    :data:`MAX_PLANE_TRIANGLES`): (triangle indices, unit normal with its largest component
    positive, offset) each."""
    e1 = vertices[:, 1] - vertices[:, 0]
    e2 = vertices[:, 2] - vertices[:, 0]
    cross = np.cross(e1, e2)
    area2 = np.linalg.norm(cross, axis=1)
    index = np.flatnonzero(area2 > 0.0)
    n = cross[index] / area2[index, None]
    big = np.take_along_axis(n, np.abs(n).argmax(axis=1)[:, None], axis=1)
    n *= np.where(big < 0, -1.0, 1.0)
    d = np.einsum("ij,ij->i", n, vertices[index, 0])
    key = np.column_stack([np.round(n / NORMAL_TOLERANCE), np.round(d / tolerance)]).astype(np.int64)
    # planes = distinct keys, numbered in the keys' lexicographic order (as np.unique over
    # rows numbers them, which sorts the rows as records: ten times slower); lexsort is
    # stable, so each plane's triangles stay in index order
    order = np.lexsort(key.T[::-1])
    ordered = key[order]
    first = np.ones(len(order), bool)
    for c in range(key.shape[1]):
        first[1:] &= ordered[1:, c] == ordered[:-1, c]
    first = ~first
    first[:1] = True
    group = np.empty(len(order), np.int64)
    group[order] = np.cumsum(first) - 1
    counts = np.bincount(group)
    area = np.bincount(group, 0.5 * area2[index], minlength=len(counts))
    wanted = np.flatnonzero((area >= MIN_PLANE_AREA) & (counts >= MIN_PLANE_TRIANGLES)
                            & (counts <= MAX_PLANE_TRIANGLES))
    bounds = np.concatenate([[0], np.cumsum(counts)])
    for g in wanted:
        local = order[bounds[g]:bounds[g + 1]]
        yield index[local], n[local[0]], float(np.mean(d[local]))


def _rng_state(rng: np.random.Generator):
    """The state of ``rng``'s bit generator as JSON values."""
    import json

    return json.loads(json.dumps(rng.bit_generator.state, default=lambda x: np.asarray(x).tolist()))


def _search_key(vertices: np.ndarray, glass: np.ndarray, rng: np.random.Generator) -> str | None:
    """The cache key of a search (module text), or None when nothing is kept."""
    import hashlib
    import json
    from importlib import metadata

    from .._version import __version__
    from ..scene.geometry_cache import cache_folder

    if cache_folder() is None:
        return None
    try:
        geos = metadata.version("shapely")
    except metadata.PackageNotFoundError:
        geos = None
    digest = hashlib.sha256(np.ascontiguousarray(vertices, np.float64))
    digest.update(np.ascontiguousarray(glass, bool))
    digest.update(json.dumps(["openings", __version__, FINDER_VERSION, geos, _rng_state(rng),
                              NORMAL_TOLERANCE, PLANE_TOLERANCE, MIN_PLANE_AREA, MIN_PLANE_TRIANGLES,
                              MAX_PLANE_TRIANGLES, MIN_OPENING_AREA, PROBE_RAYS, MIN_SKY_FRACTION,
                              MAX_GLAZED_FRACTION]).encode())
    return digest.hexdigest()


def _kept_search(key: str | None, rng: np.random.Generator) -> list[Opening] | None:
    """The openings a search kept under ``key``, with ``rng`` put in the state that search
    left it in; None when there is no such entry."""
    from ..scene.geometry_cache import load_kept

    kept = load_kept(key)
    if kept is None:
        return None
    meta, arrays = kept
    try:
        found = [Opening(np.array(arrays[f"t{k}"], np.float64), float(o["area"]), np.array(o["normal"], np.float64),
                         np.array(o["centre"], np.float64), float(o["sky_fraction"]))
                 for k, o in enumerate(meta["openings"])]
        rng.bit_generator.state = meta["rng"]
    except (KeyError, TypeError, ValueError):
        return None
    return found


def find_openings(vertices: np.ndarray, glass: np.ndarray, tracer, rng: np.random.Generator | None = None
                  ) -> list[Opening]:
    """The unglazed openings to the outside among (T, 3, 3) triangles ``vertices`` [m]
    (module text); ``glass`` (T,) marks the glazing, ``tracer`` (:class:`~lbl_illum.engine.raycast.Tracer`
    of the same triangles) tests where rays from a hole reach the sky.  A search of the
    same triangles made before is read from the cache folder (module text)."""
    from ..scene.geometry_cache import store_kept

    vertices = np.asarray(vertices, np.float64)
    if len(vertices) == 0:
        return []
    rng = rng or np.random.default_rng(0)
    key = _search_key(vertices, glass, rng)
    found = _kept_search(key, rng)
    if found is not None:
        return found
    found = _search(vertices, glass, tracer, rng)
    store_kept(key, {"rng": _rng_state(rng),
                     "openings": [{"area": o.area, "normal": o.normal.tolist(), "centre": o.centre.tolist(),
                                   "sky_fraction": o.sky_fraction} for o in found]},
               {f"t{k}": np.ascontiguousarray(o.triangles, np.float64) for k, o in enumerate(found)})
    return found


def _search(vertices: np.ndarray, glass: np.ndarray, tracer, rng: np.random.Generator) -> list[Opening]:
    """:func:`find_openings` without the cache."""
    import shapely

    from ..scene.geometry import corner_bounds, orthonormal_basis
    from .hemisphere import stratified_directions
    from ..scene.polygons import triangulate_face
    size = float(np.max(np.diff(corner_bounds(vertices), axis=0)))
    tolerance = max(1e-3, PLANE_TOLERANCE * size)
    found = []
    for members, normal, offset in _planes(vertices, tolerance):
        t, b = (x[0] for x in orthonormal_basis(normal[None]))
        tri = vertices[members]
        xy = np.stack([tri @ t, tri @ b], axis=-1)                      # (k, 3, 2)
        polygons = shapely.polygons(np.concatenate([xy, xy[:, :1]], axis=1))
        union = shapely.union_all(polygons, grid_size=tolerance)
        for part in getattr(union, "geoms", [union]):
            for ring in getattr(part, "interiors", ()):
                hole = shapely.Polygon(ring)
                if hole.area < MIN_OPENING_AREA:
                    continue
                inside = np.array(hole.representative_point().coords[0])
                outline = np.array(ring.coords)[:-1]
                points = outline[:, :1] * t + outline[:, 1:] * b + offset * normal
                centre = inside[0] * t + inside[1] * b + offset * normal
                fractions, glazed = [], []
                for side in (normal, -normal):
                    dirs = stratified_directions(side[None], 8, PROBE_RAYS // 8, rng)[0]
                    o = np.repeat(tracer.offset(centre[None], side[None]), len(dirs), axis=0)
                    hits = tracer.intersect(o, dirs)
                    fractions.append(float(np.mean(~hits.hit)))
                    glazed.append(float(np.mean(hits.hit & glass[np.where(hits.hit, hits.prim, 0)])))
                out = 0 if fractions[0] >= fractions[1] else 1
                sky, room = fractions[out], fractions[1 - out]
                # glass right behind the hole (a pane set back in a thick wall) glazes it
                if sky < MIN_SKY_FRACTION or room > 0.5 * sky or glazed[1 - out] > MAX_GLAZED_FRACTION:
                    continue
                index, hole_area = triangulate_face(points)
                if len(index) == 0:
                    continue
                found.append(Opening(points[index], hole_area, normal if out == 0 else -normal, centre, sky))
    return found

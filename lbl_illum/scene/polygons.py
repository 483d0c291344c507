"""Planar polygons as drawn: faces with more than three vertices, holes and keyhole seams,
cut into triangles.

Architectural models describe a wall with a window hole as *one* polygon.  Radiance has
no polygon with holes, so exporters (SketchUp's, Rhino's, ``obj2rad``) join each hole
to the outer boundary by a *seam*: an edge walked in and, later, walked back out, which
makes a "keyhole" polygon.  Radiance's ray test counts crossings (``src/common/face.c``,
even–odd rule), so a hole is a hole whichever way it is wound, and exporters do wind
holes either way.  A fan of triangles from the first vertex — what trimesh does for OBJ
faces — is right for convex faces only: it turns an L-shaped face of 3 m² into 4 m² and
fills the windows of keyhole walls.

:func:`triangulate_faces` reads every face by the even–odd rule:

1. the face's plane from Newell's normal (the mean plane of its vertices when Newell's
   area vanishes), and its vertices in that plane's 2-D frame;
2. vertices that coincide (within 10⁻⁷ of the face's diameter) are one vertex; an edge
   whose reverse is also an edge of the face is a seam (or a spike), and both go;
3. the remaining edges close into rings; a ring inside an odd number of other rings
   bounds a hole of the ring around it;
4. each outer ring and its holes are triangulated by ear clipping with hole bridges,
   the ``mapbox_earcut`` library (a C++ port of Mapbox's earcut.js, ISC licence);
5. every triangle is wound like the face (its normal along the face's normal).

The polygon's area by the same rule, Σ (−1)^depth |A_ring|, is returned beside the
triangles' area; the scene loader warns when they differ by more than
:data:`AREA_TOLERANCE` (a face whose edges cross, which no rule can fill as drawn).
Convex faces without repeated vertices — nearly every face of a real model — take a
vectorised fan instead (the same triangles an ear clipper would give, and exact).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["FaceTriangles", "triangulate_faces", "triangulate_face", "AREA_TOLERANCE", "face_frame", "area_warnings"]

#: Relative difference between a face's triangulated area and its polygon area above which
#: the loader warns (0.1 %).
AREA_TOLERANCE = 1e-3
#: Vertices of one face closer than this fraction of its diameter are one vertex.
MERGE_TOLERANCE = 1e-7
#: Cross products below this fraction of the squared diameter count as zero.
_EPS = 1e-12
#: Faces named one by one in a warning about triangulated areas; the rest are counted.
FACES_NAMED = 5


@dataclass
class FaceTriangles:
    """The triangles of many faces.

    triangles : (m, 3) int64 — indices into the faces' vertex array, wound like each face
    face : (m,) int64 — the face each triangle comes from
    polygon_area : (F,) float64 — each face's area by the even–odd rule [unit²]
    triangle_area : (F,) float64 — the area of its triangles [unit²]
    """

    triangles: np.ndarray
    face: np.ndarray
    polygon_area: np.ndarray
    triangle_area: np.ndarray

    def mismatched(self, tolerance: float = AREA_TOLERANCE) -> np.ndarray:
        """Indices of the faces whose triangles' area differs from their polygon's by
        more than ``tolerance`` (relative), faces of zero area excluded."""
        area = self.polygon_area
        diff = np.abs(self.triangle_area - area)
        return np.flatnonzero((diff > tolerance * np.maximum(area, 0.0)) & (area > 0.0))


def area_warnings(result: FaceTriangles, where: str, face_label, area_scale: float = 1.0) -> list[str]:
    """The loader's warnings about ``result``: faces whose triangles' area differs from the
    polygon's by more than :data:`AREA_TOLERANCE` (edges that cross), and faces of zero
    area (which give no triangles).  ``face_label(f)`` names face f (``"line 12 (5
    vertices)"``); areas are reported in m² (``area_scale`` m² per unit²)."""
    out = []
    bad = result.mismatched(AREA_TOLERANCE)
    if len(bad):
        named = "; ".join(f"{face_label(f)}: triangles {result.triangle_area[f] * area_scale:.6g} m², polygon "
                          f"{result.polygon_area[f] * area_scale:.6g} m²" for f in bad[:FACES_NAMED])
        more = f"; and {len(bad) - FACES_NAMED} more" if len(bad) > FACES_NAMED else ""
        out.append(f"{where}: {len(bad)} {'face' if len(bad) == 1 else 'faces'} whose triangles' area differs "
                   f"from the polygon's by more than {100 * AREA_TOLERANCE:g} % (edges that cross?): {named}{more}")
    empty = np.flatnonzero(result.polygon_area <= 0.0)
    if len(empty):
        named = ", ".join(face_label(f) for f in empty[:FACES_NAMED])
        more = f" and {len(empty) - FACES_NAMED} more" if len(empty) > FACES_NAMED else ""
        out.append(f"{where}: dropped {len(empty)} {'face' if len(empty) == 1 else 'faces'} of zero area: "
                   f"{named}{more}")
    return out


def face_frame(points: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(normal, u, v) of a planar face given by its (n, 3) vertices: Newell's normal (the
    mean plane's when Newell's area is zero, as for a figure eight) and two tangents with
    (u, v, normal) right-handed.  The normal of a face that spans no plane is zero."""
    p = np.asarray(points, np.float64)
    normal = 0.5 * np.cross(p, np.roll(p, -1, axis=0)).sum(axis=0)
    diameter = float(np.linalg.norm(np.ptp(p, axis=0))) if len(p) else 0.0
    size = float(np.linalg.norm(normal))
    if size <= _EPS * diameter * diameter and len(p) >= 3:
        centred = p - p.mean(axis=0)
        _, s, vt = np.linalg.svd(centred, full_matrices=False)
        normal = vt[-1] if s[1] > _EPS * max(diameter, 1e-300) else np.zeros(3)
        size = float(np.linalg.norm(normal))
    if size == 0.0:
        return np.zeros(3), np.zeros(3), np.zeros(3)
    normal = normal / size
    u = np.cross(normal, np.eye(3)[int(np.argmin(np.abs(normal)))])
    u /= np.linalg.norm(u)
    return normal, u, np.cross(normal, u)


def triangulate_faces(vertices: np.ndarray, faces: list[np.ndarray] | np.ndarray) -> FaceTriangles:
    """Triangles of polygon faces, read by the even–odd rule (module text).

    vertices : (V, 3) float — the vertex positions (any length unit)
    faces : a list of (k,) int arrays of vertex indices (k ≥ 3), or one (F, k) array

    Returns a :class:`FaceTriangles` whose triangles index ``vertices``.
    """
    vertices = np.asarray(vertices, np.float64).reshape(-1, 3)
    if isinstance(faces, np.ndarray) and faces.ndim == 2:
        groups = {faces.shape[1]: (np.arange(len(faces)), faces.astype(np.int64))}
        count = len(faces)
    else:
        count = len(faces)
        sizes = np.array([len(f) for f in faces], np.int64)
        groups = {}
        for k in np.unique(sizes):
            which = np.flatnonzero(sizes == k)
            groups[int(k)] = (which, np.array([faces[i] for i in which], np.int64).reshape(len(which), int(k)))
    polygon_area = np.zeros(count)
    general = np.zeros(count, bool)            # faces that took the general path
    tris, owners = [], []
    for k, (which, index) in groups.items():
        if k < 3:
            continue
        fast, t, o = _fan_convex(vertices, which, index)
        tris.append(t)
        owners.append(o)
        for f in np.flatnonzero(~fast):
            face = int(which[f])
            t, polygon_area[face] = triangulate_face(vertices[index[f]])
            general[face] = True
            tris.append(index[f][t])
            owners.append(np.full(len(t), face, np.int64))
    triangles = np.concatenate(tris).reshape(-1, 3) if tris else np.zeros((0, 3), np.int64)
    face = np.concatenate(owners) if owners else np.zeros(0, np.int64)
    v = vertices[triangles]
    area = 0.5 * np.linalg.norm(np.cross(v[:, 1] - v[:, 0], v[:, 2] - v[:, 0]), axis=1)
    triangle_area = np.bincount(face, area, minlength=count)
    # a fan of a strictly convex face is exact: its polygon area is its triangles'
    polygon_area[~general] = triangle_area[~general]
    return FaceTriangles(triangles, face, polygon_area, triangle_area)


def _fan_convex(vertices, which, index):
    """The faces of one size k that are strictly convex with distinct vertices, as fans.

    Returns (mask of those faces, (m, 3) triangles, (m,) owners).  A face is taken when
    every turn of its boundary, in its Newell plane, has the sign of its area and no two
    of its vertices coincide."""
    F, k = index.shape
    p = vertices[index]                                           # (F, k, 3)
    normal = 0.5 * np.cross(p, np.roll(p, -1, axis=1)).sum(axis=1)
    size = np.linalg.norm(normal, axis=1)
    diameter = np.linalg.norm(np.ptp(p, axis=1), axis=1)
    ok = size > _EPS * diameter * diameter
    if k > 3:
        n = normal / np.where(ok, size, 1.0)[:, None]
        e = np.roll(p, -1, axis=1) - p                            # edges
        turn = np.einsum("fij,fj->fi", np.cross(e, np.roll(e, -1, axis=1)), n)
        ok &= (turn > _EPS * diameter[:, None] ** 2).all(axis=1)
        # a strictly convex boundary that winds more than once (a star) has turns of one
        # sign too: its Newell area then exceeds the fan's, which catches it below
        edge = np.linalg.norm(e, axis=2)
        ok &= edge.min(axis=1) > MERGE_TOLERANCE * diameter
    fan = np.stack([np.zeros(k - 2, np.int64), np.arange(1, k - 1), np.arange(2, k)], axis=1)
    if k > 3 and ok.any():
        sel = np.flatnonzero(ok)
        q = p[sel][:, fan]                                        # (f, k-2, 3, 3)
        fan_area = 0.5 * np.linalg.norm(np.cross(q[:, :, 1] - q[:, :, 0], q[:, :, 2] - q[:, :, 0]), axis=2).sum(axis=1)
        ok[sel[np.abs(fan_area - size[sel]) > 1e-9 * size[sel]]] = False
    sel = np.flatnonzero(ok)
    tri = index[sel][:, fan].reshape(-1, 3)
    owner = np.repeat(which[sel], k - 2)
    return ok, tri, owner


def triangulate_face(points: np.ndarray) -> tuple[np.ndarray, float]:
    """Triangles of one polygon face by the even–odd rule (module text).

    points : (n, 3) float — the face's vertices in order (any length unit)

    Returns ``(triangles, area)``: (m, 3) int64 indices into ``points``, wound like the
    face, and the polygon's area by the even–odd rule [unit²].  A face of zero area
    gives no triangles and area 0.
    """
    import mapbox_earcut

    p = np.asarray(points, np.float64).reshape(-1, 3)
    none = np.zeros((0, 3), np.int64)
    if len(p) < 3:
        return none, 0.0
    normal, u, v = face_frame(p)
    if not normal.any():
        return none, 0.0
    xy = np.stack([p @ u, p @ v], axis=1)
    diameter = float(np.linalg.norm(np.ptp(p, axis=0)))
    # one id per distinct vertex (the first index it appears at)
    keys = np.round((p - p.min(axis=0)) / (MERGE_TOLERANCE * diameter)).astype(np.int64)
    _, first, ids = np.unique(keys, axis=0, return_index=True, return_inverse=True)
    ids = ids.ravel()
    rep = first[ids]                                               # representative point index
    rings = _rings(rep)
    if not rings:
        return none, 0.0
    areas = np.array([_signed_area(xy[r]) for r in rings])
    keep = np.abs(areas) > _EPS * diameter * diameter
    rings = [r for r, k in zip(rings, keep) if k]
    areas = areas[keep]
    if not rings:
        return none, 0.0
    inside = _containment(rings, xy)                               # inside[i, j]: ring i lies in ring j
    depth = inside.sum(axis=1)
    area = float(np.sum(np.where(depth % 2 == 0, 1.0, -1.0) * np.abs(areas)))
    out = []
    for i in np.flatnonzero(depth % 2 == 0):
        holes = [j for j in np.flatnonzero(depth == depth[i] + 1) if inside[j, i]
                 and _innermost_outer(j, inside, depth, np.abs(areas)) == i]
        loop = [rings[i]] + [rings[j] for j in holes]
        flat = np.concatenate(loop)
        ends = np.cumsum([len(r) for r in loop]).astype(np.uint32)
        local = np.asarray(mapbox_earcut.triangulate_float64(xy[flat], ends), np.int64).reshape(-1, 3)
        out.append(flat[local])
    tri = np.concatenate(out) if out else none
    if len(tri):
        a, b, c = xy[tri[:, 0]], xy[tri[:, 1]], xy[tri[:, 2]]
        cross = (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0])
        flip = cross < 0.0
        tri[flip] = tri[flip][:, [0, 2, 1]]
        tri = tri[np.abs(cross) > 0.0]
    return tri, area


def _rings(rep: np.ndarray) -> list[np.ndarray]:
    """Closed rings of a face's boundary once seams are removed.

    ``rep`` holds each boundary vertex's representative index (equal for coinciding
    vertices).  Edges of zero length go; an edge (a → b) and an edge (b → a) cancel (a
    keyhole seam walked in and out, or a spike).  The rest is split into cycles,
    continuing at each vertex along the boundary's own order where it can.
    """
    n = len(rep)
    src = rep
    dst = np.roll(rep, -1)
    live = src != dst
    # cancel each edge against a reverse one
    pending: dict[tuple[int, int], list[int]] = {}
    for e in np.flatnonzero(live):
        a, b = int(src[e]), int(dst[e])
        back = pending.get((b, a))
        if back:
            live[back.pop()] = False
            live[e] = False
        else:
            pending.setdefault((a, b), []).append(int(e))
    edges = np.flatnonzero(live)
    if len(edges) < 3:
        return []
    outgoing: dict[int, list[int]] = {}
    for e in edges:
        outgoing.setdefault(int(src[e]), []).append(int(e))
    used = np.zeros(n, bool)
    rings = []
    for start in edges:
        if used[start]:
            continue
        ring = []
        e = int(start)
        while True:
            used[e] = True
            ring.append(int(src[e]))
            head = int(dst[e])
            if head == int(src[start]):
                break
            choices = [x for x in outgoing.get(head, ()) if not used[x]]
            if not choices:                     # an open chain: the boundary is broken
                ring = []
                break
            after = [x for x in choices if x > e]
            e = after[0] if after else choices[0]
        if len(ring) >= 3:
            rings.append(np.array(ring, np.int64))
    return rings


def _signed_area(xy: np.ndarray) -> float:
    """Shoelace area of a 2-D ring (positive counter-clockwise)."""
    x, y = xy[:, 0], xy[:, 1]
    return 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(np.roll(x, -1), y))


def _containment(rings: list[np.ndarray], xy: np.ndarray) -> np.ndarray:
    """(R, R) bool: ring i lies inside ring j (tested at a vertex of i that j does not
    share, by the crossing number)."""
    R = len(rings)
    inside = np.zeros((R, R), bool)
    for i in range(R):
        for j in range(R):
            if i == j:
                continue
            own = np.setdiff1d(rings[i], rings[j], assume_unique=False)
            if len(own) == 0:
                continue
            inside[i, j] = _point_in_ring(xy[own[0]], xy[rings[j]])
    return inside


def _point_in_ring(q: np.ndarray, ring: np.ndarray) -> bool:
    """Crossing-number test of a 2-D point against a ring."""
    x0, y0 = ring[:, 0], ring[:, 1]
    x1, y1 = np.roll(x0, -1), np.roll(y0, -1)
    straddle = (y0 > q[1]) != (y1 > q[1])
    with np.errstate(divide="ignore", invalid="ignore"):
        cross_x = x0 + (q[1] - y0) * (x1 - x0) / (y1 - y0)
    return bool(np.count_nonzero(straddle & (q[0] < cross_x)) % 2)


def _innermost_outer(j: int, inside: np.ndarray, depth: np.ndarray, area: np.ndarray) -> int:
    """The smallest even-depth ring that contains hole ``j``."""
    outers = [i for i in np.flatnonzero(inside[j]) if depth[i] % 2 == 0 and depth[i] == depth[j] - 1]
    return min(outers, key=lambda i: area[i]) if outers else -1

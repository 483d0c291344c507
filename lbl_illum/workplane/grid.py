"""Workplane sensor grids: points at a height above the floor or above named surfaces.

A grid is laid over an *area*, a set of horizontal triangles of the scene (within
``HORIZONTAL_DEGREES`` of level), at ``height`` above them, with normals up (+z).

Which triangles
    ``surfaces`` given: each name is a material of the scene file, and its horizontal
    triangles form one area of that name (at every level where it has any).
    Otherwise the area ``floor`` is the *lowest usable level*: among the horizontal
    triangles of opaque materials (not glass, not light sources, not sphere
    primitives), those at the lowest height (within ``LEVEL_TOLERANCE``) at which at
    least one triangle is *indoor* and *clear*; of that level, the indoor and clear
    triangles.  A triangle is indoor when, at most of its ``TRIANGLE_SAMPLES`` points
    lifted by ``height``, at least ``COVERED_FRACTION`` of ``SKY_PROBES`` directions
    spread evenly over the upper hemisphere (equal solid angle) meet a surface: a
    ceiling, roof or glass is above it.  The ground outside a building, even at the
    floor's height, sees the sky and is left out; a floor under a roof opening still
    sees mostly roof.  A triangle is clear when nothing but surfaces of its own level
    lies within max(``CLEARANCE_FRACTION`` · height, ``MIN_CLEARANCE``) above it, so a
    ground plane running under a raised floor is not taken for the floor.  Winding
    does not matter for this choice (surfaces are two-sided).

Where the points go
    Each piece of an area gets its own lattice.  A piece is a set of triangles joined
    along their edges (or along parts of them, so T-junctions do not split a floor)
    where no wall stands on the shared edge (see :func:`_pieces`): two rooms whose floors
    meet under a wall get a lattice each, centred in each room.  A piece's lattice is
    aligned with its *outline direction*: the length-weighted mean direction,
    modulo 90°, of its outline edges (edges of one triangle only); rooms drawn along the
    scene axes get grids along the scene axes, a rotated building a rotated grid.
    ``align="scene"`` keeps the scene axes.  In that frame the piece's bounding
    rectangle less a band of width ``margin`` on every side is the calculation area,
    of sides L_u and L_v.  Following EN 12464-1:2011 §4.4 (from EN 12193), the largest
    spacing is

        p = 0.2 · 5^log10(d)  [m],   p ≤ 10 m,   d = max(L_u, L_v)  [m]

    (or the ``spacing`` given), each side gets n = ⌈L / p⌉ cells of size L / n ≤ p, and
    the points sit at the cell centres, so the lattice is centred in the calculation
    area and its outer points lie margin + half a cell from the bounding rectangle.  Of
    that lattice a point is kept when (the names in brackets count the points each
    rule left out, in :attr:`AreaLattice.dropped`):

    1. it lies over a triangle of its own piece, by a vertical ray (``outside``), and
       the disk of radius ``margin`` around it lies over the area, by ``DISK_PROBES``
       points on its rim (``margin``);
    2. no wall lies within ``margin`` of it horizontally (``wall``): of ``WALL_PROBES``
       horizontal rays at the point's height (at least ``PROBE_LIFT`` above the
       surface), the first along the grid's u axis, none meets a surface within
       ``margin`` whose ray ``WALL_RISE`` higher meets one within ``margin`` as well.
       Walls parallel to the grid are measured exactly, others to within 2 %;
       furniture that only just rises through the grid height (a chair back) is not a
       wall, a cabinet is;
    3. it is not enclosed (``enclosed``): a point from which every one of those rays
       meets a surface within ``ENCLOSED_RADIUS`` (1.5 m) is inside a solid (a column)
       or in a space too small to be a workplane;
    4. it is not inside a solid by the surfaces' winding (``inside``): when the surface
       under the point faces up by the right-hand rule (as when a room's surfaces face
       into the room) and at least ``INSIDE_FRACTION`` of the rays hit surfaces from
       behind, the point is inside an outward-facing solid such as a column of any
       size.  A piece where this rule alone would drop most points is taken to be wound
       the other way, and the rule is not used there (the grid warns);
    5. nothing but the surfaces of its own level lies between the surface and
       max(``CLEARANCE_FRACTION`` · height, ``MIN_CLEARANCE``) above it (``covered``):
       the surface under the point is the exposed one (not a drawer pedestal under a
       desk top, nor a ground under a raised floor); a desk top at 0.72 m keeps a point
       at 0.8 m, and a rug on the floor hides nothing;
    6. it does not lie over a larger piece of the same area that was laid out before it
       and kept points (``overlap``; pieces go largest first): the bottom face of a
       column or a cabinet lying on the floor is a horizontal piece at the floor's
       level, and its own lattice would repeat points.

    A column standing on a floor that runs under it is thus removed by rule 2 when it is
    narrower than twice the margin, by rule 3 when it is up to 1.06 m across (up to
    2.1 m at its middle), and by rule 4 at any size when the scene is wound
    consistently; a floor with a hole for the column by rule 1.

All lengths are in metres; the command line converts from the scene's units.
"""

from __future__ import annotations

import difflib
import math
from dataclasses import dataclass, field

import numpy as np

from ..errors import InputError
from ..scene.materials import GLASS, LIGHT
from ..engine.raycast import RayCaster

__all__ = [
    "Grid", "AreaLattice", "workplane_grid", "en12464_spacing", "cell_layout", "section_segments",
    "outline_angle", "plan_outline", "fibonacci_hemisphere", "HORIZONTAL_DEGREES", "LEVEL_TOLERANCE", "ENCLOSED_RADIUS",
    "MAX_SPACING", "MAX_POINTS",
]

#: Triangles whose normal is within this many degrees of vertical are horizontal.
HORIZONTAL_DEGREES = 2.0
#: Horizontal triangles within this height [m] of the lowest one form one level.
LEVEL_TOLERANCE = 0.1
#: Points per triangle at which the indoor and clear tests are made (barycentric centre and
#: the three points (2/3, 1/6, 1/6)); a triangle passes when half or more of them pass.
TRIANGLE_SAMPLES = 4
#: Upper-hemisphere directions of the indoor test.
SKY_PROBES = 32
#: Share of those directions that must meet a surface for a point to be indoor.
COVERED_FRACTION = 0.5
#: Free height above the surface, as a fraction of the grid height (rule 5) ...
CLEARANCE_FRACTION = 0.5
#: ... and at least this [m].
MIN_CLEARANCE = 0.25
#: Horizontal rays of the wall, enclosure and winding tests (rules 2 to 4).
WALL_PROBES = 16
#: Height [m] above the grid at which a surface near a point must still be near it to count as
#: a wall (rule 2): walls, columns and tall cabinets do, chair backs and low partitions do not.
WALL_RISE = 1.0
#: Points along an edge shared by two triangles of an area at which a wall is looked for.
EDGE_SAMPLES = 8
#: Length [m] of the probes across a shared edge, on each side.
EDGE_REACH = 0.05
#: Points on the rim of the margin disk (rule 1).
DISK_PROBES = 16
#: A point whose horizontal rays all meet a surface within this distance [m] is enclosed.
ENCLOSED_RADIUS = 1.5
#: Share of horizontal rays hitting surfaces from behind that marks a point inside a solid.
INSIDE_FRACTION = 0.75
#: Least height [m] of the horizontal probes above the surface (for grids at height 0).
PROBE_LIFT = 0.01
#: Upper bound of the EN 12464-1 spacing [m].
MAX_SPACING = 10.0
#: Largest lattice a grid may have (a guard against a spacing far too small).
MAX_POINTS = 2_000_000
#: Outline directions within this angle [°] of the scene axes are snapped to them.
SNAP_DEGREES = 0.05
#: Relative length of the mean outline direction below which the outline has none
#: (a triangle, a circle): the scene axes are used.
MIN_DIRECTIONALITY = 0.2


# ---------------------------------------------------------------------------
# The spacing rule
# ---------------------------------------------------------------------------

def en12464_spacing(d: float) -> float:
    """Largest grid spacing p [m] of EN 12464-1:2011 §4.4 for an area of longer side ``d`` [m].

    p = 0.2 · 5^log10(d), capped at ``MAX_SPACING`` (10 m).  Examples: d = 1 m gives
    0.2 m, d = 10 m gives 1 m, d = 100 m gives 5 m.

    References: EN 12464-1:2011 *Light and lighting — Lighting of work places — Part 1:
    Indoor work places*, §4.4 (the rule taken from EN 12193).
    """
    d = float(d)
    if not math.isfinite(d) or d <= 0.0:
        raise ValueError(f"the area's longer side must be a positive length, got {d!r}")
    return min(MAX_SPACING, 0.2 * 5.0 ** math.log10(d))


def cell_layout(length: float, p: float) -> tuple[int, float]:
    """Cells along one side: n = ⌈length / p⌉ (at least 1) and their size length / n ≤ p.

    Points go at the cell centres.  A ratio within 1e-9 of a whole number is not rounded
    up (4 m at 0.5 m gives 8 cells, not 9).
    """
    if p <= 0.0:
        raise ValueError(f"spacing must be > 0, got {p!r}")
    ratio = length / p
    n = max(1, math.ceil(ratio - 1e-9 * max(1.0, ratio)))
    return n, length / n


# ---------------------------------------------------------------------------
# Results
# ---------------------------------------------------------------------------

@dataclass
class AreaLattice:
    """The lattice of one connected piece of an area.

    name : area name; level : height of the surface [m]; angle : grid direction [°]
    (u axis, counter-clockwise from +x); p : largest spacing [m] (EN 12464-1 or given);
    d : the calculation area's longer side [m]; counts : cells along u and v;
    spacing : cell sizes along u and v [m]; points : how many points were kept;
    dropped : points of the lattice removed, by rule; winding_ignored : rule 4 was not
    used on this piece.
    """

    name: str
    level: float
    angle: float
    p: float
    d: float
    counts: tuple[int, int]
    spacing: tuple[float, float]
    points: int = 0
    dropped: dict = field(default_factory=dict)
    winding_ignored: bool = False


@dataclass
class Grid:
    """Sensor points [m], unit normals (all +z) and the area name of each point.

    points, normals : (n, 3) float64;  areas : (n,) str (object array);
    lattices : one :class:`AreaLattice` per piece, in output order;
    warnings : things worth telling the user.
    """

    points: np.ndarray
    normals: np.ndarray
    areas: np.ndarray
    lattices: list[AreaLattice]
    height: float
    margin: float
    warnings: list[str] = field(default_factory=list)

    @property
    def area_names(self) -> list[str]:
        """Area names in the order of first appearance."""
        return list(dict.fromkeys(self.areas.tolist()))


def fibonacci_hemisphere(n: int) -> np.ndarray:
    """(n, 3) unit directions spread evenly in solid angle over the upper hemisphere (z > 0).

    Point i sits at z = 1 − (i + ½)/n (equal-area bands) and azimuth i·π(3 − √5)
    (the golden angle), so every direction stands for 2π/n sr.
    """
    i = np.arange(n) + 0.5
    z = 1.0 - i / n
    r = np.sqrt(1.0 - z * z)
    phi = i * math.pi * (3.0 - math.sqrt(5.0))
    return np.column_stack([r * np.cos(phi), r * np.sin(phi), z])


def _horizontal_directions(angle: float, n: int) -> np.ndarray:
    """(n, 3) horizontal unit vectors, the first at ``angle`` [rad] from +x, evenly spaced."""
    a = angle + 2.0 * math.pi * np.arange(n) / n
    return np.column_stack([np.cos(a), np.sin(a), np.zeros(n)])


# ---------------------------------------------------------------------------
# Plane geometry of triangle sets
# ---------------------------------------------------------------------------

def _vertex_keys(vertices: np.ndarray, tol: float = 1e-6) -> np.ndarray:
    """(T, 3) integer ids of the corners; corners within ``tol`` [m] (on a lattice) share an id."""
    flat = np.round(vertices.reshape(-1, 3) / tol).astype(np.int64)
    _, ids = np.unique(flat, axis=0, return_inverse=True)
    return ids.reshape(-1, 3)


def _union_find(n: int, pairs: np.ndarray) -> np.ndarray:
    """(n,) labels 0, 1, … of the groups joined by the (k, 2) index ``pairs``."""
    parent = np.arange(n)

    def find(a):
        while parent[a] != a:
            parent[a] = parent[parent[a]]
            a = parent[a]
        return a

    for a, b in pairs:
        ra, rb = find(a), find(b)
        if ra != rb:
            parent[max(ra, rb)] = min(ra, rb)
    roots = np.array([find(i) for i in range(n)], dtype=np.int64)
    return np.unique(roots, return_inverse=True)[1].reshape(-1)


def _touching_edges(vertices: np.ndarray):
    """Pairs of triangles whose edges touch along a length, in plan.

    Returns (pairs (k, 2), segments (k, 2, 2)): the two triangles and the plan segment
    they share.  Edges with the same two corners pair up directly; the other edges are
    grouped by their supporting line and paired where they overlap (a T-junction, or two
    rooms whose floors meet along part of a wall).
    """
    keys = _vertex_keys(vertices)
    T = len(vertices)
    owner = np.tile(np.arange(T), 3)
    ends = np.concatenate([vertices[:, [0, 1], :2], vertices[:, [1, 2], :2], vertices[:, [2, 0], :2]])
    pairs_key = np.sort(np.concatenate([keys[:, [0, 1]], keys[:, [1, 2]], keys[:, [2, 0]]]), axis=1)
    _, inverse, counts = np.unique(pairs_key, axis=0, return_inverse=True, return_counts=True)
    inverse = inverse.reshape(-1)
    order = np.argsort(inverse, kind="stable")
    same = inverse[order[1:]] == inverse[order[:-1]]
    pairs = [np.column_stack([owner[order[:-1]][same], owner[order[1:]][same]])]
    segments = [ends[order[1:]][same]]
    # edges of one triangle only: collinear overlaps
    lone = np.flatnonzero(counts[inverse] == 1)
    if len(lone) > 1:
        a, b = ends[lone, 0], ends[lone, 1]
        d = b - a
        length = np.hypot(d[:, 0], d[:, 1])
        u = d / np.maximum(length, 1e-300)[:, None]
        flip = (u[:, 0] < -1e-12) | ((np.abs(u[:, 0]) <= 1e-12) & (u[:, 1] < 0))
        u[flip] *= -1.0
        theta = np.round(np.arctan2(u[:, 1], u[:, 0]) / 1e-6).astype(np.int64)
        offset = np.round((a[:, 1] * u[:, 0] - a[:, 0] * u[:, 1]) / 1e-5).astype(np.int64)
        s0, s1 = np.sort(np.column_stack([np.einsum("ij,ij->i", a, u), np.einsum("ij,ij->i", b, u)]), axis=1).T
        line = np.unique(np.column_stack([theta, offset]), axis=0, return_inverse=True)[1].reshape(-1)
        for group in np.split(np.argsort(line, kind="stable"), np.flatnonzero(np.diff(np.sort(line))) + 1):
            if len(group) < 2:
                continue
            g = group[np.argsort(s0[group], kind="stable")]
            for i in range(len(g)):           # sweep: each edge against the later ones that start before it ends
                for j in g[i + 1:]:
                    if s0[j] >= s1[g[i]] - 1e-9:
                        break
                    lo, hi = s0[j], min(s1[g[i]], s1[j])
                    if hi - lo > 1e-6 and owner[lone[g[i]]] != owner[lone[j]]:
                        pairs.append(np.array([[owner[lone[g[i]]], owner[lone[j]]]]))
                        n = np.array([-u[j, 1], u[j, 0]])
                        base = n * (a[j] @ n)
                        segments.append(np.array([[base + lo * u[j], base + hi * u[j]]]))
    return np.concatenate(pairs).astype(np.int64), np.concatenate(segments)


def _pieces(vertices: np.ndarray, caster: "RayCaster", lift: float) -> np.ndarray:
    """(T,) label of the piece of each triangle: triangles joined along an edge (or part
    of one) that no wall stands on.

    A wall stands on a shared segment when, at ``EDGE_SAMPLES`` points along it, short
    horizontal rays across it (from ``EDGE_REACH`` on one side to as far on the other)
    at ``lift`` above the surface and ``WALL_RISE`` higher both meet a surface at half or
    more of the points: two rooms whose floors meet under a wall are two pieces, while a
    door or a column on the line does not split a floor.
    """
    T = len(vertices)
    pairs, segments = _touching_edges(vertices)
    if len(pairs) == 0:
        return np.arange(T)
    k = len(pairs)
    f = (np.arange(EDGE_SAMPLES) + 0.5) / EDGE_SAMPLES
    at = segments[:, None, 0] + f[None, :, None] * (segments[:, None, 1] - segments[:, None, 0])   # (k, S, 2)
    d = segments[:, 1] - segments[:, 0]
    n = np.column_stack([-d[:, 1], d[:, 0]]) / np.maximum(np.hypot(d[:, 0], d[:, 1]), 1e-300)[:, None]
    z = vertices[pairs[:, 0], :, 2].mean(axis=1)
    start = at.reshape(-1, 2) - EDGE_REACH * np.repeat(n, EDGE_SAMPLES, axis=0)
    direction = np.column_stack([np.repeat(n, EDGE_SAMPLES, axis=0), np.zeros(k * EDGE_SAMPLES)])
    wall = np.ones(k * EDGE_SAMPLES, bool)
    for rise in (0.0, WALL_RISE):
        o = np.column_stack([start, np.repeat(z, EDGE_SAMPLES) + lift + rise])
        t, _ = caster.first_hit(o, direction, 2.0 * EDGE_REACH)
        wall &= np.isfinite(t)
    keep = wall.reshape(k, EDGE_SAMPLES).mean(axis=1) < 0.5
    return _union_find(T, pairs[keep])


def _outline_edges(vertices: np.ndarray) -> np.ndarray:
    """(k, 2, 2) plan (x, y) of the edges used by one triangle only: the outline of the set."""
    keys = _vertex_keys(vertices)
    pairs = np.concatenate([keys[:, [0, 1]], keys[:, [1, 2]], keys[:, [2, 0]]])
    ends = np.concatenate([vertices[:, [0, 1], :2], vertices[:, [1, 2], :2], vertices[:, [2, 0], :2]])
    sorted_pairs = np.sort(pairs, axis=1)
    _, inverse, counts = np.unique(sorted_pairs, axis=0, return_inverse=True, return_counts=True)
    return ends[counts[inverse.ravel()] == 1]


def outline_angle(vertices: np.ndarray) -> float:
    """Grid direction [rad] of a set of horizontal triangles: the length-weighted mean
    direction, modulo 90°, of its outline edges (0 when the outline has no dominant
    direction or is within ``SNAP_DEGREES`` of the scene axes).

    Directions modulo 90° are averaged as unit vectors of 4θ, so walls at 0° and 90°
    agree and the result lies in (−45°, 45°].
    """
    edges = _outline_edges(np.asarray(vertices, dtype=np.float64))
    if len(edges) == 0:
        return 0.0
    d = edges[:, 1] - edges[:, 0]
    length = np.hypot(d[:, 0], d[:, 1])
    theta = np.arctan2(d[:, 1], d[:, 0])
    c = np.sum(length * np.cos(4.0 * theta))
    s = np.sum(length * np.sin(4.0 * theta))
    if math.hypot(c, s) < MIN_DIRECTIONALITY * length.sum():
        return 0.0
    angle = 0.25 * math.atan2(s, c)
    return 0.0 if abs(math.degrees(angle)) < SNAP_DEGREES else angle


def section_segments(vertices: np.ndarray, z: float) -> np.ndarray:
    """(k, 2, 2) plan (x, y) segments where triangles cross the horizontal plane at ``z``.

    The section of the walls at the grid height is the room's outline in a plan.  A
    corner exactly at ``z`` counts as above the plane, so a triangle touching the plane
    at a corner gives no segment and one with an edge in it gives that edge once per
    side it borders.  Units are those of ``vertices``.
    """
    v = np.asarray(vertices, dtype=np.float64).reshape(-1, 3, 3)
    s = v[:, :, 2] - z
    above = s >= 0.0
    n_above = above.sum(axis=1)
    cut = (n_above == 1) | (n_above == 2)
    v, s, above = v[cut], s[cut], above[cut]
    if len(v) == 0:
        return np.zeros((0, 2, 2))
    # the lone corner (on its own side) and the two edges from it cross the plane
    lone = np.where(above.sum(axis=1) == 1, np.argmax(above, axis=1), np.argmin(above, axis=1))
    rows = np.arange(len(v))
    a = v[rows, lone]
    sa = s[rows, lone]
    ends = []
    for k in (1, 2):
        other = (lone + k) % 3
        b, sb = v[rows, other], s[rows, other]
        t = sa / (sa - sb)
        ends.append(a[:, :2] + t[:, None] * (b[:, :2] - a[:, :2]))
    return np.stack(ends, axis=1)


def plan_outline(scene, z: float) -> tuple[np.ndarray, np.ndarray]:
    """Plan lines of a scene at height ``z`` [m]: ``(walls, glazing)``, each (k, 2, 2) [m].

    walls : the section at ``z`` of every opaque surface that is not horizontal (walls,
    columns, furniture sides), i.e. the room outline at the grid height;
    glazing : for each glass triangle that is not horizontal the longest edge of its
    plan projection (a window seen from above), and the outline of horizontal glass
    (roof lights).
    """
    tri = scene.triangles
    horizontal = _horizontal_mask(tri)
    glass = scene.material_table.kind[tri.material] == GLASS
    walls = section_segments(tri.vertices[~horizontal & ~glass], z)
    upright = tri.vertices[~horizontal & glass][:, :, :2]
    if len(upright):
        edges = np.stack([upright[:, [0, 1]], upright[:, [1, 2]], upright[:, [2, 0]]], axis=1)
        length = np.linalg.norm(edges[:, :, 1] - edges[:, :, 0], axis=2)
        upright = edges[np.arange(len(edges)), np.argmax(length, axis=1)]
    else:
        upright = np.zeros((0, 2, 2))
    flat = tri.vertices[horizontal & glass]
    skylights = _outline_edges(flat) if len(flat) else np.zeros((0, 2, 2))
    return walls, np.concatenate([upright.reshape(-1, 2, 2), skylights])


# ---------------------------------------------------------------------------
# The grid
# ---------------------------------------------------------------------------

def _horizontal_mask(triangles) -> np.ndarray:
    return np.abs(triangles.normals[:, 2]) >= math.cos(math.radians(HORIZONTAL_DEGREES))


def _levels(z: np.ndarray) -> list[np.ndarray]:
    """Indices of ``z`` grouped into levels, lowest first: each level takes every value
    within ``LEVEL_TOLERANCE`` of its lowest one."""
    order = np.argsort(z, kind="stable")
    groups, start = [], 0
    while start < len(order):
        stop = start + int(np.searchsorted(z[order[start:]], z[order[start]] + LEVEL_TOLERANCE, side="right"))
        groups.append(order[start:stop])
        start = stop
    return groups


def _triangle_samples(vertices: np.ndarray) -> np.ndarray:
    """(T, TRIANGLE_SAMPLES, 3) points on each triangle (centre and three inner points)."""
    w = np.array([[1 / 3, 1 / 3, 1 / 3], [2 / 3, 1 / 6, 1 / 6], [1 / 6, 2 / 3, 1 / 6], [1 / 6, 1 / 6, 2 / 3]])
    return np.einsum("sk,tkc->tsc", w, vertices)


def _clear(caster: RayCaster, surface_points: np.ndarray, height: float) -> np.ndarray:
    """Nothing within max(``CLEARANCE_FRACTION`` · height, ``MIN_CLEARANCE``) above the points
    (rule 5); ``caster`` holds the scene less the surfaces of the points' own level."""
    reach = max(CLEARANCE_FRACTION * height, MIN_CLEARANCE)
    if len(surface_points) == 0:
        return np.ones(len(surface_points), bool)
    eps = caster.epsilon(surface_points)
    origins = surface_points + eps[:, None] * np.array([0.0, 0.0, 1.0])
    t, _ = caster.first_hit(origins, np.array([0.0, 0.0, 1.0]), reach)
    return ~np.isfinite(t)


def _usable_triangles(caster: RayCaster, others: RayCaster, vertices: np.ndarray, height: float) -> np.ndarray:
    """(T,) indoor and clear (see the module docstring), by ``TRIANGLE_SAMPLES`` points each;
    ``others`` holds the scene less the triangles of this level (a rug does not hide the floor)."""
    samples = _triangle_samples(vertices).reshape(-1, 3)
    lifted = samples + np.array([0.0, 0.0, max(height, PROBE_LIFT)])
    dirs = fibonacci_hemisphere(SKY_PROBES)
    origins = np.repeat(lifted + caster.epsilon(lifted)[:, None] * np.array([0.0, 0.0, 1.0]), SKY_PROBES, axis=0)
    t, _ = caster.first_hit(origins, np.tile(dirs, (len(lifted), 1)))
    covered = np.isfinite(t).reshape(-1, SKY_PROBES).mean(axis=1) >= COVERED_FRACTION
    ok = covered & _clear(others, samples, height)
    return ok.reshape(-1, TRIANGLE_SAMPLES).mean(axis=1) >= 0.5


def _without(vertices: np.ndarray, ids: np.ndarray) -> RayCaster:
    """A caster of every triangle but ``ids``."""
    keep = np.ones(len(vertices), bool)
    keep[ids] = False
    return RayCaster(vertices[keep])


def _material_ids(scene, names: list[str]) -> list[int]:
    known = {m.name: i for i, m in enumerate(scene.materials)}
    ids = []
    for name in names:
        if name not in known:
            near = difflib.get_close_matches(name, list(known), n=1)
            hint = f" (did you mean '{near[0]}'?)" if near else f" (materials: {', '.join(known)})"
            raise InputError(f"--surface: no material '{name}' in the scene{hint}")
        ids.append(known[name])
    return ids


def _select_areas(scene, surfaces, height, caster) -> tuple[list[tuple[str, np.ndarray]], list[str]]:
    """[(area name, triangle indices)] and warnings."""
    tri = scene.triangles
    horizontal = _horizontal_mask(tri)
    if surfaces:
        areas = []
        for name, mid in zip(surfaces, _material_ids(scene, list(surfaces))):
            own = np.flatnonzero(tri.material == mid)
            if len(own) == 0:
                raise InputError(f"--surface: material '{name}' is not used by any geometry")
            flat = own[horizontal[own]]
            if len(flat) == 0:
                raise InputError(f"--surface: material '{name}' has no horizontal triangles "
                                 f"(within {HORIZONTAL_DEGREES:g}° of level) to lay a grid on")
            areas.append((name, flat))
        return areas, []
    kind = scene.material_table.kind[tri.material]
    candidates = np.flatnonzero(horizontal & (kind != GLASS) & (kind != LIGHT) & (tri.sphere < 0))
    if len(candidates) == 0:
        raise InputError("no horizontal surface to lay a floor grid on (use --surface MATERIAL)")
    z = tri.vertices[candidates, :, 2].mean(axis=1)
    for level in _levels(z):
        ids = candidates[level]
        usable = _usable_triangles(caster, _without(tri.vertices, ids), tri.vertices[ids], height)
        if usable.any():
            return [("floor", ids[usable])], []
    raise InputError("no floor found: no horizontal surface has a ceiling or roof above it and "
                     f"{max(CLEARANCE_FRACTION * height, MIN_CLEARANCE):g} m clear above it "
                     "(use --surface MATERIAL)")


def workplane_grid(scene, height: float = 0.8, spacing: float | None = None, margin: float = 0.5,
                   surfaces: list[str] | None = None, align: str = "auto") -> Grid:
    """Sensor points at ``height`` [m] above the floor, or above the named ``surfaces``.

    Parameters
    ----------
    scene : a loaded :class:`~lbl_illum.scene.scenefile.Scene` (lengths in metres)
    height : height of the points above the surface [m], ≥ 0
    spacing : largest spacing [m]; None for the EN 12464-1 rule (see :func:`en12464_spacing`)
    margin : band along the area's boundary and around walls left without points [m], ≥ 0
    surfaces : material names, one area each; None for the floor (the lowest usable level)
    align : ``"auto"`` (each piece's outline direction) or ``"scene"`` (the x and y axes)

    Returns a :class:`Grid`; the rules are in the module docstring.  An area without any
    point is an :class:`InputError` when no area has points, otherwise a warning.
    """
    for label, value, low in (("height", height, 0.0), ("margin", margin, 0.0)):
        if not math.isfinite(value) or value < low:
            raise InputError(f"--{label} must be a length >= 0, got {value:g}")
    if spacing is not None and (not math.isfinite(spacing) or spacing <= 0.0):
        raise InputError(f"--spacing must be a length > 0, got {spacing:g}")
    if align not in ("auto", "scene"):
        raise InputError(f"--align must be auto or scene, got {align!r}")
    if surfaces is not None and len(set(surfaces)) != len(surfaces):
        raise InputError("--surface: a material is named twice")
    tri = scene.triangles
    caster = RayCaster(tri.vertices)
    areas, warnings = _select_areas(scene, surfaces, height, caster)

    pts, names, lattices = [], [], []
    for name, ids in areas:
        z = tri.vertices[ids, :, 2].mean(axis=1)
        found = 0
        for level in _levels(z):
            level_ids = ids[level]
            area_caster = RayCaster(tri.vertices[level_ids])
            others = _without(tri.vertices, level_ids)
            labels = _pieces(tri.vertices[level_ids], caster, max(height, PROBE_LIFT))
            area = np.bincount(labels, weights=tri.areas[level_ids])
            taken = []                              # triangles of the larger pieces already laid out
            for c in np.argsort(-area, kind="stable"):
                piece = level_ids[labels == c]
                p, lat = _piece_points(name, tri.vertices[piece], area_caster, caster, others, height, spacing,
                                       margin, align, RayCaster(tri.vertices[np.concatenate(taken)]) if taken else None)
                if lat is None:
                    continue
                if lat.points:
                    taken.append(piece)
                lattices.append(lat)
                pts.append(p)
                names += [name] * len(p)
                found += len(p)
        if found == 0:
            warnings.append(f"area '{name}': no point is at least {margin:g} m from its edges and walls "
                            "(try a smaller --margin)")
    for lat in lattices:
        if lat.winding_ignored:
            warnings.append(f"area '{lat.name}' at z = {lat.level:.3g} m: the walls are not wound towards the "
                            "room, so solids standing on it are found by size only (up to "
                            f"{ENCLOSED_RADIUS / math.sqrt(2):.2g} m across)")
    points = np.concatenate(pts) if pts else np.zeros((0, 3))
    if len(points) == 0:
        raise InputError(f"no grid point is at least {margin:g} m from the edges and walls of "
                         f"{', '.join(repr(a[0]) for a in areas)} (try a smaller --margin)")
    normals = np.tile([0.0, 0.0, 1.0], (len(points), 1))
    return Grid(points, normals, np.array(names, dtype=object), lattices, height, margin, warnings)


def _piece_points(name, vertices, area_caster, caster, others, height, spacing, margin, align, taken=None):
    """Points [m] of one connected piece and its :class:`AreaLattice` (None when it has no room).

    ``taken`` casts against the larger pieces of the area laid out before: points over
    them are left out (the footprint of a column's bottom face lying on the floor).
    """
    angle = outline_angle(vertices) if align == "auto" else 0.0
    c, s = math.cos(angle), math.sin(angle)
    u_axis, v_axis = np.array([c, s]), np.array([-s, c])
    xy = vertices[:, :, :2].reshape(-1, 2)
    u, v = xy @ u_axis, xy @ v_axis
    Lu, Lv = u.max() - u.min() - 2.0 * margin, v.max() - v.min() - 2.0 * margin
    level = float(vertices[:, :, 2].mean())
    if Lu <= 0.0 or Lv <= 0.0:
        return None, None
    d = float(max(Lu, Lv))
    p = spacing if spacing is not None else en12464_spacing(d)
    (nu, su), (nv, sv) = cell_layout(Lu, p), cell_layout(Lv, p)
    if nu * nv > MAX_POINTS:
        raise InputError(f"area '{name}': the grid would have {nu * nv:,} points at spacing {p:g} m "
                         f"(more than {MAX_POINTS:,}); give a larger --spacing")
    lat = AreaLattice(name, level, math.degrees(angle), float(p), d, (nu, nv), (float(su), float(sv)))
    uu = u.min() + margin + (np.arange(nu) + 0.5) * su
    vv = v.min() + margin + (np.arange(nv) + 0.5) * sv
    U, V = np.meshgrid(uu, vv)                 # rows along v, u fastest
    plan = U.ravel()[:, None] * u_axis + V.ravel()[:, None] * v_axis
    dropped = {}

    def drop(rule, keep):
        nonlocal plan, z_surface, up
        dropped[rule] = dropped.get(rule, 0) + int((~keep).sum())
        plan, z_surface, up = plan[keep], z_surface[keep], up[keep]

    # 1. over the piece, and the margin disk over the area
    top = float(vertices[:, :, 2].max()) + 1.0
    piece_caster = RayCaster(vertices)
    origins = np.column_stack([plan, np.full(len(plan), top)])
    t, prim = piece_caster.first_hit(origins, np.array([0.0, 0.0, -1.0]))
    z_surface = np.where(np.isfinite(t), _plane_z(vertices, np.maximum(prim, 0), plan), np.nan)
    up = np.where(prim >= 0, piece_caster.normals[np.maximum(prim, 0), 2] > 0.0, False)
    drop("outside", np.isfinite(t))
    if taken is not None and len(plan):
        t, _ = taken.first_hit(np.column_stack([plan, np.full(len(plan), top)]), np.array([0.0, 0.0, -1.0]))
        drop("overlap", ~np.isfinite(t))
    if margin > 0.0 and len(plan):
        rim = margin * _horizontal_directions(angle, DISK_PROBES)[:, :2]
        disk = (plan[:, None, :] + rim[None]).reshape(-1, 2)
        o = np.column_stack([disk, np.full(len(disk), top)])
        t, _ = area_caster.first_hit(o, np.array([0.0, 0.0, -1.0]))
        drop("margin", np.isfinite(t).reshape(-1, DISK_PROBES).all(axis=1))

    # 2-4. horizontal probes at the point's height
    if len(plan):
        dirs = _horizontal_directions(angle, WALL_PROBES)
        at = np.column_stack([plan, z_surface + max(height, PROBE_LIFT)])
        t, prim = caster.first_hit(np.repeat(at, WALL_PROBES, axis=0), np.tile(dirs, (len(at), 1)))
        t = t.reshape(-1, WALL_PROBES)
        behind = (np.einsum("pkc,kc->pk", caster.normals[np.maximum(prim, 0)].reshape(-1, WALL_PROBES, 3), dirs)
                  > 0.0) & (prim >= 0).reshape(-1, WALL_PROBES)
        near = np.zeros(len(t), bool)
        if margin > 0.0:
            # a wall rises above the grid: the same direction meets it WALL_RISE higher up too
            close = t < margin
            rows = np.flatnonzero(close.any(axis=1))
            if len(rows):
                high = at[rows] + np.array([0.0, 0.0, WALL_RISE])
                t_high, _ = caster.first_hit(np.repeat(high, WALL_PROBES, axis=0), np.tile(dirs, (len(rows), 1)))
                near[rows] = np.any(close[rows] & (t_high.reshape(-1, WALL_PROBES) < margin), axis=1)
        enclosed = np.all(t <= ENCLOSED_RADIUS, axis=1)
        inside = up & (behind.mean(axis=1) >= INSIDE_FRACTION)
        if inside.sum() > 0.5 * len(inside):
            lat.winding_ignored = True
            inside[:] = False
        for rule, bad in (("wall", near), ("enclosed", enclosed & ~near), ("inside", inside & ~near & ~enclosed)):
            dropped[rule] = int(bad.sum())
        keep = ~(near | enclosed | inside)
        plan, z_surface, up = plan[keep], z_surface[keep], up[keep]

    # 5. clear above the surface
    if len(plan):
        drop("covered", _clear(others, np.column_stack([plan, z_surface]), height))
    lat.dropped = {k: v for k, v in dropped.items() if v}
    lat.points = len(plan)
    return np.column_stack([plan, z_surface + height]), lat


def _plane_z(vertices: np.ndarray, prim: np.ndarray, plan: np.ndarray) -> np.ndarray:
    """Height [m] of the plane of triangle ``prim`` above the plan points (float64)."""
    v0 = vertices[prim, 0]
    n = np.cross(vertices[prim, 1] - v0, vertices[prim, 2] - v0)
    return v0[:, 2] - (n[:, 0] * (plan[:, 0] - v0[:, 0]) + n[:, 1] * (plan[:, 1] - v0[:, 1])) / n[:, 2]

"""The luminous opening of a luminaire: cells for its near-field direct light, and its
surface seen by camera rays and specular paths.

**Luminance of the opening.**  A photometric file gives the intensity I(ω) [cd] of the
whole luminaire and the size of its luminous opening (IES LM-63-2002, the width, length
and height fields and their shapes; EULUMDAT's luminous area).  The opening is taken to
show one luminance per direction over its whole surface,

    L(ω) = I(ω) / A_p(ω)   [cd/m²],

A_p(ω) [m²] the area it shows along ω (:meth:`~lbl_illum.scene.photometric.LuminousOpening.projected_area`):
the photometric definition of luminance, and what Radiance's ``ies2rad`` gives its
sources (the ``flatcorr``, ``boxcorr`` and ``cylcorr`` functions of ``source.cal``
divide the intensity by the projected area).  Where A_p = 0 (a flat opening seen
edge-on) the luminance is 0.

**Near field.**  A rectangle, a disk, a box or a cylinder is split into cells j of area
A_j (a fixed stratification, :func:`opening_cells`); cell j shows a_j(ω) [m²] along ω,
with Σ_j a_j(ω) = A_p(ω), and is a point source at its centre of intensity

    I_j(ω) = L(ω) · a_j(ω) = I(ω) · a_j(ω) / A_p(ω)   [cd],

so that the cells together give I(ω) in every direction (the far field is unchanged) and
near the opening each part of it lights a receiver from where it is, with one shadow
ray per cell (which also gives shadows their penumbra).  a_j(ω) is exact: A_j |n_j·ω| for
the cells of a flat opening (lit on both sides), A_j max(0, n_j·ω) on a box's faces and a
cylinder's ends, and on the cylinder's side, whose cells are arcs of half-angle s,
A_j sinθ ∫ max(0, cos(α − x)) dx / (2s) over the arc (α the azimuth of ω from the cell's
middle).  A sphere stays a point source: one of uniform luminance lights every receiver
that sees all of it exactly as a point source of the same intensity at its centre.

**How many cells.**  A receiver at distance d_n [m] from the opening's bounding box gets
k = ceil(:data:`NEAR_RATIO` · S / d_n) cells along the opening's largest size S [m] (at most
:data:`MAX_CELLS_PER_SIZE`), so each cell, about S/k in size, is seen from NEAR_RATIO
times its size or more: for a Lambertian square of side s at distance d on its axis the
point law errs by s²/(3 d²), 0.5 % at d = 8 s.  Beyond NEAR_RATIO · S a flat opening is
the single point source at the photometric centre, exactly as a luminaire without an
opening (the far-field law, IES LM-63's "five times rule" with a margin).  A box's or a
cylinder's faces lie up to S/2 from the photometric centre, an error of the point law of
first order (the bottom face of a box of height H at distance d from its centre lights
the floor below (1 + H/d) times the point law), so these keep at least one cell per face
(k = 1) up to :data:`SOLID_POINT_RATIO` · S.

**Seen by paths.**  The openings are triangle meshes (:func:`opening_triangles`, the
round ones as polygons of the circle's area) in a ray caster of their own
(:class:`LuminousOpenings`), never in the scene's: the fitting blocks no shadow ray and no
hemisphere ray, its light being the direct calculation's.  A camera ray, or a path after a
reflection, that meets an opening before the scene's surface sees L(−d) there and ends
(:func:`lbl_illum.engine.paths.follow_paths`, the rule of ``light`` surfaces).

Units: lengths [m], areas [m²], intensity [cd], luminance [cd/m²].
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from .raycast import SELF_HIT_EPSILON, RayCaster
from ..scene.photometric import LuminousOpening

__all__ = ["Cells", "LuminousOpenings", "opening_cells", "opening_triangles", "cell_counts", "opening_luminance",
           "NEAR_RATIO", "SOLID_POINT_RATIO", "MAX_CELLS_PER_SIZE", "SEGMENTS"]

#: A receiver nearer than this many times the opening's largest size gets cells; a cell
#: is seen from at least this many times its own size (module text).
NEAR_RATIO = 8.0
#: A box or a cylinder is a point source only beyond this many times its largest size:
#: its faces lie up to half its size from the photometric centre, an error of the point
#: law of first order (about S/d), 1 % at 100 S, where a flat opening's is of second order.
SOLID_POINT_RATIO = 100.0
#: Most cells along the opening's largest size (receivers within NEAR_RATIO / this of the
#: size get no more): a rectangle's up to k², a disk's about π k²/2, a box's up to 6 k², a
#: cylinder's up to about 3π k²/2.
MAX_CELLS_PER_SIZE = 12
#: Sides of the polygons standing for circles in the meshes of round openings.
SEGMENTS = 64


@dataclass(frozen=True)
class Cells:
    """The cells of an opening in the luminaire's frame [m]: ``centres`` (m, 3), outward
    unit ``normals`` (m, 3) (flat openings: −z), ``areas`` (m,) [m²], ``span`` (m,) the half
    angle [rad] of a cylinder side cell's arc (0 for flat cells), ``flat``: one plane lit on
    both sides (rectangle, disk)."""

    centres: np.ndarray
    normals: np.ndarray
    areas: np.ndarray
    span: np.ndarray
    flat: bool

    def __len__(self) -> int:
        return len(self.areas)

    def projected(self, j: np.ndarray, e: np.ndarray) -> np.ndarray:
        """(n,) area [m²] cell j[i] shows along the local unit direction e[i] (module text)."""
        n = self.normals[j]
        cos = np.einsum("ij,ij->i", n, e)
        if self.flat:
            return self.areas[j] * np.abs(cos)
        a = self.areas[j] * np.maximum(cos, 0.0)
        s = self.span[j]
        arc = np.flatnonzero(s > 0.0)
        if len(arc):
            # ∫ max(0, cos(α − x)) dx over the arc x ∈ [−s, s], α the azimuth of e from the
            # cell's normal: sin(α − lo) − sin(α − hi) over the lit part (s ≤ π/4)
            n, e, s = n[arc], e[arc], s[arc]
            sin_t = np.hypot(e[:, 0], e[:, 1])
            alpha = np.arctan2(n[:, 0] * e[:, 1] - n[:, 1] * e[:, 0], n[:, 0] * e[:, 0] + n[:, 1] * e[:, 1])
            lo = np.maximum(-s, alpha - np.pi / 2)
            hi = np.minimum(s, alpha + np.pi / 2)
            integral = np.where(hi > lo, np.sin(alpha - lo) - np.sin(alpha - hi), 0.0)
            a[arc] = self.areas[j[arc]] / (2.0 * s) * sin_t * integral
        return a

    def shares(self, opening: LuminousOpening, j: np.ndarray, e: np.ndarray) -> np.ndarray:
        """(n,) a_j(e)/A_p(e): cell j[i]'s part of the intensity along local unit e[i]
        (flat openings: A_j/A in every direction; 0 where the opening shows no area)."""
        if self.flat:
            return self.areas[j] / self.areas.sum()
        a = self.projected(j, e)
        total = opening.projected_area(e)
        return np.where(total > 0.0, a / np.where(total > 0.0, total, 1.0), 0.0)


def _count(k: int, extent: float, size: float, least: int = 1) -> int:
    """Cells along ``extent`` [m] when k cells span the opening's largest ``size`` [m]."""
    return max(least, math.ceil(k * extent / size - 1e-9))


def _grid(a: float, b: float, na: int, nb: int) -> np.ndarray:
    """(na·nb, 2) centres of an na × nb grid over the rectangle [−a/2, a/2] × [−b/2, b/2]."""
    u = (np.arange(na) + 0.5) / na * a - a / 2
    v = (np.arange(nb) + 0.5) / nb * b - b / 2
    U, V = np.meshgrid(u, v, indexing="ij")
    return np.column_stack([U.ravel(), V.ravel()])


def _polar(radius: float, rings: int) -> tuple[np.ndarray, np.ndarray]:
    """Cells of a disk: ``rings`` rings of equal width, ring i cut into
    max(1, round(π (i + ½))) sectors (about twice as long as wide); (m, 2) area centroids
    (r_c = ⅔ (r₂³ − r₁³)/(r₂² − r₁²) · sin(Δ/2)/(Δ/2) at mid-angle) and (m,) areas [m²]."""
    xy, area = [], []
    for i in range(rings):
        r1, r2 = radius * i / rings, radius * (i + 1) / rings
        m = 1 if i == 0 else int(round(math.pi * (i + 0.5)))
        delta = 2.0 * math.pi / m
        rc = 2.0 / 3.0 * (r2 ** 3 - r1 ** 3) / (r2 ** 2 - r1 ** 2) * math.sin(delta / 2) / (delta / 2)
        phi = (np.arange(m) + 0.5) * delta
        xy.append(np.column_stack([rc * np.cos(phi), rc * np.sin(phi)]))
        area.append(np.full(m, 0.5 * delta * (r2 ** 2 - r1 ** 2)))
    return np.vstack(xy), np.concatenate(area)


@lru_cache(maxsize=64)
def opening_cells(opening: LuminousOpening, k: int) -> Cells:
    """The cells of ``opening`` with k cells along its largest size (module text): a grid on
    a rectangle and on each of a box's faces, rings of sectors on a disk and on a
    cylinder's ends, arcs × rows on its side (a sphere has none: it stays a point)."""
    L, W, H = opening.length, opening.width, opening.height
    S = opening_size(opening)
    shape = opening.shape
    if shape in ("rectangle", "disk"):
        if shape == "rectangle":
            xy = _grid(L, W, _count(k, L, S), _count(k, W, S))
            area = np.full(len(xy), L * W / len(xy))
        else:
            xy, area = _polar(L / 2, _count(k, L, S))
        m = len(area)
        return Cells(np.column_stack([xy, np.zeros(m)]), np.tile([0.0, 0.0, -1.0], (m, 1)), area, np.zeros(m),
                     flat=True)
    centres, normals, areas, span = [], [], [], []

    def add(c, nrm, a, s=0.0):
        centres.append(c)
        normals.append(np.broadcast_to(nrm, c.shape) if np.ndim(nrm) == 1 else nrm)
        areas.append(np.broadcast_to(a, len(c)).astype(np.float64))
        span.append(np.full(len(c), s))

    if shape == "box":
        size = (L, W, H)
        for axis in range(3):
            u, v = [x for x in range(3) if x != axis]
            uv = _grid(size[u], size[v], _count(k, size[u], S), _count(k, size[v], S))
            for sign in (-1.0, 1.0):
                c = np.zeros((len(uv), 3))
                c[:, u], c[:, v], c[:, axis] = uv[:, 0], uv[:, 1], sign * size[axis] / 2
                nrm = np.zeros(3)
                nrm[axis] = sign
                add(c, nrm, size[u] * size[v] / len(uv))
    elif shape == "cylinder":
        r = L / 2
        n_phi = _count(k, math.pi * L, S, least=4)
        n_h = _count(k, H, S)
        phi = (np.arange(n_phi) + 0.5) * 2 * math.pi / n_phi
        z = (np.arange(n_h) + 0.5) / n_h * H - H / 2
        P, Z = np.meshgrid(phi, z, indexing="ij")
        radial = np.column_stack([np.cos(P.ravel()), np.sin(P.ravel()), np.zeros(P.size)])
        add(r * radial + np.column_stack([np.zeros((P.size, 2)), Z.ravel()]), radial,
            math.pi * L * H / P.size, math.pi / n_phi)
        xy, a = _polar(r, _count(k, L, S))
        for sign in (-1.0, 1.0):
            add(np.column_stack([xy, np.full(len(xy), sign * H / 2)]), np.array([0.0, 0.0, sign]), a)
    else:
        raise ValueError(f"no cells for a luminous opening of shape '{shape}'")
    return Cells(np.vstack(centres), np.vstack(normals), np.concatenate(areas), np.concatenate(span), flat=False)


def opening_size(opening: LuminousOpening) -> float:
    """The opening's largest size [m]: its length, width or height (a round one's diameter)."""
    return max(opening.length, opening.width, opening.height)


def half_extents(opening: LuminousOpening) -> np.ndarray:
    """(3,) half sizes [m] of the opening's bounding box in the luminaire's frame."""
    if opening.shape in ("rectangle", "disk"):
        return np.array([opening.length, opening.width, 0.0]) / 2
    return np.array([opening.length, opening.width, opening.height]) / 2


def cell_counts(opening: LuminousOpening, local: np.ndarray) -> np.ndarray:
    """(n,) cells k along the largest size for receivers at ``local`` (n, 3) [m] in the
    luminaire's frame (module text); 0 keeps the point source (a point or a sphere, a
    flat opening beyond NEAR_RATIO sizes, a box or a cylinder beyond SOLID_POINT_RATIO)."""
    n = len(local)
    if opening.shape in ("point", "sphere") or n == 0:
        return np.zeros(n, np.int64)
    S = opening_size(opening)
    outside = np.maximum(np.abs(local) - half_extents(opening), 0.0)
    near = np.sqrt(np.einsum("ij,ij->i", outside, outside))
    k = np.full(n, MAX_CELLS_PER_SIZE, np.int64)
    some = near > 0.0
    k[some] = np.clip(np.ceil(NEAR_RATIO * S / near[some]), 1, MAX_CELLS_PER_SIZE).astype(np.int64)
    flat = opening.shape in ("rectangle", "disk")
    k[near >= (NEAR_RATIO if flat else SOLID_POINT_RATIO) * S] = 0
    return k


def _circle(radius: float, same_area: bool = True) -> np.ndarray:
    """(SEGMENTS, 2) corners of a regular polygon inscribed in the circle, or (``same_area``)
    enlarged to the circle's area π r²."""
    phi = np.arange(SEGMENTS) * 2 * math.pi / SEGMENTS
    if same_area:
        radius *= math.sqrt(2 * math.pi / (SEGMENTS * math.sin(2 * math.pi / SEGMENTS)))
    return radius * np.column_stack([np.cos(phi), np.sin(phi)])


def _fan(ring: np.ndarray, centre: np.ndarray) -> np.ndarray:
    """(m, 3, 3) triangles joining ``centre`` to each edge of the closed polygon ``ring``."""
    return np.stack([np.broadcast_to(centre, ring.shape), ring, np.roll(ring, -1, axis=0)], axis=1)


def _quads(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(2m, 3, 3) triangles of the quadrilaterals a[i], a[i+1], b[i+1], b[i] (closed rings)."""
    a1, b1 = np.roll(a, -1, axis=0), np.roll(b, -1, axis=0)
    return np.concatenate([np.stack([a, a1, b1], axis=1), np.stack([a, b1, b], axis=1)])


@lru_cache(maxsize=64)
def opening_triangles(opening: LuminousOpening) -> np.ndarray:
    """(T, 3, 3) triangles [m] of the opening's surface in the luminaire's frame, centred on
    the photometric centre (a rectangle and a disk in the plane z = 0); circles are
    :data:`SEGMENTS`-sided polygons of the same area; none for a point."""
    L, W, H = opening.length, opening.width, opening.height
    shape = opening.shape
    if shape == "point":
        return np.zeros((0, 3, 3))
    if shape in ("rectangle", "box"):
        h = H / 2 if shape == "box" else 0.0
        x, y = L / 2, W / 2
        corners = np.array([[x, y], [-x, y], [-x, -y], [x, -y]])
        bottom = np.column_stack([corners, np.full(4, -h)])
        top = bottom + [0.0, 0.0, 2 * h]
        faces = [bottom[[0, 1, 2]], bottom[[0, 2, 3]]]
        if shape == "box":
            faces += [top[[0, 1, 2]], top[[0, 2, 3]]]
        return np.concatenate([np.stack(faces)] + ([_quads(bottom, top)] if shape == "box" else []))
    if shape in ("disk", "cylinder"):
        ring = _circle(L / 2)
        z = H / 2 if shape == "cylinder" else 0.0
        bottom = np.column_stack([ring, np.full(len(ring), -z)])
        tris = _fan(bottom, np.array([0.0, 0.0, -z]))
        if shape == "disk":
            return tris
        top = bottom + [0.0, 0.0, 2 * z]
        return np.concatenate([tris, _fan(top, np.array([0.0, 0.0, z])), _quads(bottom, top)])
    # sphere: latitude rings of SEGMENTS / 2 bands, the poles as fans
    r = L / 2
    theta = np.arange(1, SEGMENTS // 2) * math.pi / (SEGMENTS // 2)
    rings = [np.column_stack([_circle(r * math.sin(t), same_area=False), np.full(SEGMENTS, r * math.cos(t))])
             for t in theta]
    tris = [_fan(rings[0], np.array([0.0, 0.0, r])), _fan(rings[-1], np.array([0.0, 0.0, -r]))]
    tris += [_quads(a, b) for a, b in zip(rings[:-1], rings[1:])]
    return np.concatenate(tris)


def opening_luminance(lum, directions: np.ndarray) -> np.ndarray:
    """(n,) luminance [cd/m²] L(ω) = I(ω)/A_p(ω) the opening of luminaire ``lum``
    (:class:`~lbl_illum.scene.luminaires.Luminaire`, its multiplier applied) shows along the
    unit emission ``directions`` (n, 3) in scene coordinates; 0 where A_p = 0."""
    e = np.asarray(directions, np.float64)
    area = lum.photometry.opening.projected_area(e @ lum.frame.T)
    return np.where(area > 0.0, lum.intensity(e) / np.where(area > 0.0, area, 1.0), 0.0)


class LuminousOpenings:
    """The luminous openings of a scene's luminaires (those with one) in a ray caster of
    their own, apart from the scene's geometry (module text)."""

    def __init__(self, luminaires):
        self.luminaires = list(luminaires)
        tris, owner = [], []
        for i, lum in enumerate(self.luminaires):
            t = opening_triangles(lum.photometry.opening)
            if len(t):
                tris.append(lum.position + t @ lum.frame)
                owner.append(np.full(len(t), i, np.int64))
        self.caster = RayCaster(np.concatenate(tris) if tris else np.zeros((0, 3, 3)))
        self.owner = np.concatenate(owner) if owner else np.zeros(0, np.int64)

    @property
    def empty(self) -> bool:
        return self.caster.empty

    def seen(self, origins, directions, limit, eligible=None, length_scale: float = 0.0):
        """The rays that meet an opening before ``limit`` (n,) [m] (the scene's hit, inf: none,
        with the scene's self-hit slack ε = SELF_HIT_EPSILON · (|o|∞ + t + ``length_scale``),
        so that an opening flush with a ceiling shows): ``(rows, L)``, their indices among
        the ``eligible`` (n,) bool rays (None: all) and (k, 3) the luminance [cd/m²]
        L(−d) each sees (white light)."""
        rows = np.arange(len(origins)) if eligible is None else np.flatnonzero(eligible)
        if len(rows) == 0 or self.empty:
            return rows[:0], np.zeros((0, 3))
        o = np.asarray(origins, np.float64)[rows]
        d = np.asarray(directions, np.float64)[rows]
        t = np.asarray(limit, np.float64)[rows]
        slack = SELF_HIT_EPSILON * (np.abs(o).max(axis=1) + np.where(np.isfinite(t), t, 0.0) + length_scale)
        _, prim = self.caster.first_hit(o, d, t + slack)
        hit = np.flatnonzero(prim >= 0)
        rows, d, owner = rows[hit], d[hit], self.owner[prim[hit]]
        L = np.zeros(len(rows))
        for i in np.unique(owner):
            mine = owner == i
            L[mine] = opening_luminance(self.luminaires[i], -d[mine])
        return rows, np.repeat(L[:, None], 3, axis=1)

"""Discomfort glare from a 180° fisheye luminance image: vertical illuminance, glare
sources, the Guth/Iwata position index, DGP, DGI, UGR and the EN 17037 class.

Everything is computed from a luminance image [cd/m²] and its Radiance view, which must
be an angular (``-vta``, ``-vh`` and ``-vv`` ≥ 180°) or hemispherical (``-vth``,
180° × 180°) fisheye centred on the view direction: the image holds the whole
hemisphere in front of the eye.  The method follows Radiance's ``evalglare`` 3.06
(J. Wienold, ``src/util/evalglare.c`` and ``pictool.c`` in the Radiance sources; read
for its method, the code here is our own), the program the DGP was fitted with.  Where
it differs, it says so; docs/glare.md lists every difference and the validation study
``lbl-illum validate glare`` measures them.

**Pixels.**  A pixel counts when its centre looks into the front hemisphere (θ ≤ 90°
from the view direction ``d``; evalglare's ``pict_is_validpixel``).  In the image plane
of the projection, ``a = (x − ½)·s_h``, ``b = (y − ½)·s_v`` (``x``, ``y`` ∈ [0, 1]
from the left and bottom edges; :mod:`lbl_illum.scene.views`), a direction lies at
radius ρ = √(a² + b²) and azimuth φ = atan2(b, a) about ``d``, with

* ``-vta``: ``s = size/180°``, θ = πρ (equidistant: r ∝ θ), rim ρ = ½;
* ``-vth``: ``s = 2 sin(size/2)``, sin θ = ρ (orthographic: r ∝ sin θ), rim ρ = 1.

Both are symmetric about ``d``, so the solid angle of any region R of the plane is,
by Green's theorem in polar coordinates, a contour integral over its edge::

    ω(R) = ∬_R sin θ dθ dφ = ∮_∂R (1 − cos θ(ρ)) dφ                              [sr]
    ω_⊥(R) = ∬_R cos θ sin θ dθ dφ = ∮_∂R ½ sin² θ(ρ) dφ                          [sr]

(ω_⊥ the projected solid angle, the cosine-weighted one), with θ clipped at 90° so
that only the front hemisphere counts.  Each pixel's ω and ω_⊥ are these integrals
over its square's four edges: along a straight edge ``P(t) = P₀ + t(P₁ − P₀)``,
``dφ = (P₀ × (P₁ − P₀)) / |P(t)|² dt``; each edge is split where it crosses the rim,
the part outside adds ``F(rim)·Δφ`` exactly, the part inside is integrated by
8-point Gauss–Legendre after the substitution ``t = 3u² − 2u³`` (which removes the
square-root behaviour of ``-vth``'s 1 − cos θ at the rim).  Each edge is integrated
once and shared by its two pixels, so the pixels of the whole image sum to 2π and π
exactly; the valid pixels (centre in front) to a little less: what the rim pixels whose
centres lie outside the hemisphere would add (measured in tests/glare).

evalglare instead takes a pixel's ω as the spherical quadrilateral of the directions of
its four corners (``pict_get_sangle``) and its cosine at the pixel centre; a ``-vth``
pixel with a corner outside the circle gets ω = 0 there (about 10 % of the hemisphere's
solid angle and 1 % of its illuminance at 400 × 400 pixels).  ``method="corners"`` of
:func:`fisheye_geometry` computes that too, for the comparison.

**Vertical illuminance** at the eye, on the plane normal to ``d``::

    E_v = Σ_i L_i ω_⊥,i                                                        [lux]

(evalglare: Σ L_i ω_i cos θ_i at the pixel centres).  For a uniform luminance L
over the hemisphere it is πL.

**Glare sources** (evalglare's defaults): pixels brighter than a threshold — 2000 cd/m²
(evalglare's default since 2018, ``-b 2000``), or a factor times the average luminance
Σ L ω / Σ ω of the image (``-b 5``), or 5 × the luminance of a task area (``-t``) —
grouped so that two pixels within the search angle of each other (0.1 rad: evalglare
``-r 0.2`` compares twice the angle) belong to the same source: single-linkage
clusters, which evalglare's two scans (the first joining each pixel to a source within
reach, the second merging sources that come within reach of each other) approach.
Peak extraction (evalglare ``-y``, default): when a pixel exceeds 50 000 cd/m², the
pixels at or above it leave their source and form sources of their own, grouped the same
way (the sun's disk apart from the sky around it).  Per source: ω_s = Σ ω, L_s =
Σ L ω / ω_s, E_s = Σ L ω_⊥ (its direct vertical illuminance), and its position, the
L ω-weighted mean image coordinates, whose direction gives the position index.

**Position index** P (evalglare ``get_posindex``), from σ, the angle between the source
and the line of sight, and τ, the angle between the image's up direction and the
projection of the source on the plane normal to ``d`` (both in degrees):

* above the line of sight, Guth's formula as the IES Lighting Handbook gives it
  (Luckiesh & Guth 1949; Levin 1975)::

      P = exp[(35.2 − 0.31889 τ − 1.22 e^(−2τ/9))·10⁻³ σ + (21 + 0.26667 τ − 0.002963 τ²)·10⁻⁵ σ²]

* below it, Iwata & Osterhaus (2010, CIE x034) with Kikuchi's change of coordinates
  (evalglare 3.02)::

      β = atan(tan σ · √(1 + 0.3225 cos² τ)),   P = exp(6.49·10⁻³ β + 21·10⁻⁵ β²)

and P ≤ 16 in both.

**Indices.**  With the background luminance L_b = (E_v − Σ_s E_s)/π (the CIE method,
evalglare's default ``-q 0``):

* DGP (Wienold & Christoffersen, *Energy and Buildings* 38 (2006) 743–757, eq. 8)::

      DGP = 5.87·10⁻⁵ E_v + 9.18·10⁻² log₁₀(1 + Σ_s L_s² ω_s / (E_v^1.87 P_s²)) + 0.16

  at most 1, then the low-light correction for E_v < 1000 lux (Wienold 2009, *Building
  Simulation 2009*, 944–951; evalglare ``-C l+``, off by default in evalglare since
  2.14)::

      DGP · exp(0.024 E_v − 4) / (1 + exp(0.024 E_v − 4)).

  evalglare rounds the constants to 0.092 and 0.159 (``EVALGLARE_DGP_CONSTANTS``): its
  DGP is 0.001 lower without sources, and less lower the stronger they are (0.0002 per
  unit of the logarithm, which stays below 5 up to DGP = 1).
* DGI (Hopkinson 1972, Chauvel et al. 1982), as evalglare sums it over sources, with
  the position-modified solid angle Ω_s = ω_s / P_s²::

      DGI = 10 log₁₀ Σ_s 0.478 L_s^1.6 Ω_s^0.8 / (L_b + 0.07 ω_s^0.5 L_s)

* UGR (CIE 117-1995)::

      UGR = 8 log₁₀(0.25 / L_b · Σ_s L_s² ω_s / P_s²)

  Both are None without glare sources (evalglare prints 0) and UGR when L_b ≤ 0.

**EN 17037** (2018, Annex A, Table A.7) rates glare protection by the DGP exceeded in
no more than 5 % of the occupied hours: high ≤ 0.35, medium ≤ 0.40, minimum ≤ 0.45.  One
image is one hour: :func:`en17037_class` gives the best class whose limit its DGP meets
("none" above 0.45).  The DGP categories of Wienold et al. (2019): imperceptible < 0.35
≤ perceptible < 0.40 ≤ disturbing < 0.45 ≤ intolerable.

Bad input — a view that is not such a fisheye, no view, negative or non-finite
luminance, a non-positive exposure — raises :class:`~lbl_illum.errors.InputError`
with a one-line message.
"""

from __future__ import annotations

import functools
import math
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import InputError, plural
from ..scene.views import FTINY, View

__all__ = [
    "DGP_CONSTANTS", "EVALGLARE_DGP_CONSTANTS", "DEFAULT_THRESHOLD", "TASK_FACTOR", "SEARCH_ANGLE",
    "PEAK_LUMINANCE", "EN17037_LIMITS", "FisheyeGeometry", "GlareSource", "GlareResult",
    "check_fisheye", "fisheye_geometry", "find_glare_sources", "position_index", "low_light_factor",
    "daylight_glare_probability", "en17037_class", "dgp_category", "evaluate_glare", "glare_from_image",
]

#: (c1 [1/lux], c2, c3) of the DGP as published (Wienold & Christoffersen 2006, eq. 8).
DGP_CONSTANTS = (5.87e-5, 9.18e-2, 0.16)
#: The same as evalglare 3.06 has them (``c1``, ``c2``, ``c3`` in ``main``).
EVALGLARE_DGP_CONSTANTS = (5.87e-5, 0.092, 0.159)
#: Exponent of E_v in the DGP's glare term.
DGP_EV_EXPONENT = 1.87
#: Below this vertical illuminance [lux] the low-light correction applies.
LOW_LIGHT_LIMIT = 1000.0
#: evalglare's default source threshold [cd/m²] (``-b 2000``, since version 2.05).
DEFAULT_THRESHOLD = 2000.0
#: Factor of the task luminance when a task area is given without a factor (evalglare 2.06).
TASK_FACTOR = 5.0
#: Largest angle [rad] between two pixels of one source (evalglare ``-r 0.2``: it compares
#: twice the angle between two pixel directions with 0.2).
SEARCH_ANGLE = 0.1
#: Peak extraction [cd/m²]: pixels at or above it form sources of their own (evalglare ``-Y``).
PEAK_LUMINANCE = 50000.0
#: Largest position index (evalglare caps Guth's and Iwata's formulas there).
POSITION_INDEX_MAX = 16.0
#: EN 17037:2018 Table A.7: the largest DGP (exceeded in 5 % of the hours) of each class.
EN17037_LIMITS = {"high": 0.35, "medium": 0.40, "minimum": 0.45}
#: Upper bounds of the DGP categories of Wienold et al. 2019 (the last is open).
DGP_CATEGORIES = ((0.35, "imperceptible"), (0.40, "perceptible"), (0.45, "disturbing"), (math.inf, "intolerable"))
#: Gauss–Legendre nodes per edge of the contour integrals.
EDGE_NODES = 8
#: Node evaluations per block of edges (bounds the memory of a large image's integrals).
EDGE_BLOCK = 1 << 20
#: Share of the corners (outside the inscribed circle) of a -vtv image at most 2 cd/m² above
#: which it is taken for a fisheye with a perspective VIEW= line (evalglare's check: 70 %).
BLACK_CORNERS = 0.7
BLACK_LUMINANCE = 2.0


# ---------------------------------------------------------------------------
# The view and the pixels
# ---------------------------------------------------------------------------

def check_fisheye(view: View | None, where: str = "image") -> View:
    """``view`` if it is a fisheye holding the whole front hemisphere, else InputError:
    ``-vta`` with ``-vh`` and ``-vv`` at least 180°, or ``-vth`` 180° × 180°, not shifted
    or lifted."""
    if view is None:
        raise InputError(f"{where}: no view (the header has no VIEW= line); give the fisheye's view, "
                         "e.g. --view=\"-vta -vh 180 -vv 180 -vd 0 -1 0\"")
    if view.type not in "ah":
        raise InputError(f"{where}: the view is {'an' if view.type_name[0] in 'aeiou' else 'a'} {view.type_name} "
                         f"(-vt{view.type}), not a fisheye: glare needs a 180 degree -vta or -vth image")
    if view.horizontal < 180.0 - FTINY or view.vertical < 180.0 - FTINY:
        raise InputError(f"{where}: the fisheye covers {view.horizontal:g} x {view.vertical:g} degrees "
                         "(-vh, -vv); glare needs the whole hemisphere in front of the eye (180 x 180)")
    if view.shift != 0.0 or view.lift != 0.0:
        raise InputError(f"{where}: the fisheye is shifted (-vs {view.shift:g} -vl {view.lift:g}); glare needs "
                         "the view direction at the centre of the image")
    return view


def _plane_scales(view: View) -> tuple[float, float, float]:
    """(s_h, s_v, rim): the image plane a = (x − ½)·s_h, b = (y − ½)·s_v and the radius
    of the 90° circle there (module text)."""
    if view.type == "a":
        return view.horizontal / 180.0, view.vertical / 180.0, 0.5
    return (2.0 * math.sin(math.radians(view.horizontal) / 2.0),
            2.0 * math.sin(math.radians(view.vertical) / 2.0), 1.0)


def _cap_over_rho2(kind: str, rho2: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(1 − cos θ)/ρ² and (½ sin² θ)/ρ² at ρ² inside the rim, without cancellation and
    with their limits at ρ = 0."""
    rho2 = np.asarray(rho2, dtype=np.float64)
    if kind == "a":
        rho = np.sqrt(rho2)
        theta = np.pi * np.minimum(rho, 0.5)
        with np.errstate(divide="ignore", invalid="ignore"):
            h = 2.0 * np.sin(theta / 2.0) ** 2 / rho2
            k = 0.5 * np.sin(theta) ** 2 / rho2
        small = rho2 < 1e-24
        return np.where(small, np.pi ** 2 / 2.0, h), np.where(small, np.pi ** 2 / 2.0, k)
    s2 = np.minimum(rho2, 1.0)
    return 1.0 / (1.0 + np.sqrt(1.0 - s2)), np.full_like(s2, 0.5)


def _edge_integrals(kind: str, p0: np.ndarray, p1: np.ndarray, rim: float) -> tuple[np.ndarray, np.ndarray]:
    """∫ (1 − cos θ) dφ and ∫ ½ sin² θ dφ along straight edges p0 → p1 ((..., 2) image-plane
    points), θ clipped at the rim (module text)."""
    d = p1 - p0
    cross = p0[..., 0] * d[..., 1] - p0[..., 1] * d[..., 0]              # P(t) × P'(t), constant
    # where the edge is inside the rim: |p0 + t d|² < rim², t in (t_in, t_out) ∩ [0, 1]
    qa = np.einsum("...i,...i", d, d)
    qb = 2.0 * np.einsum("...i,...i", p0, d)
    qc = np.einsum("...i,...i", p0, p0) - rim * rim
    disc = qb * qb - 4.0 * qa * qc
    root = np.sqrt(np.maximum(disc, 0.0))
    with np.errstate(divide="ignore", invalid="ignore"):
        t_in = np.where(disc > 0.0, (-qb - root) / (2.0 * qa), 0.0)
        t_out = np.where(disc > 0.0, (-qb + root) / (2.0 * qa), 0.0)
    t_in = np.clip(t_in, 0.0, 1.0)
    t_out = np.clip(t_out, t_in, 1.0)

    def turn(ta, tb):
        pa = p0 + ta[..., None] * d
        pb = p0 + tb[..., None] * d
        return np.arctan2(pa[..., 0] * pb[..., 1] - pa[..., 1] * pb[..., 0], np.einsum("...i,...i", pa, pb))

    outside = turn(np.zeros_like(t_in), t_in) + turn(t_out, np.ones_like(t_out))
    h_rim, k_rim = 1.0, 0.5                                              # 1 − cos 90°, ½ sin² 90°
    # inside: Gauss–Legendre in u after t = t_in + (t_out − t_in)(3u² − 2u³)
    x, w = np.polynomial.legendre.leggauss(EDGE_NODES)
    u, w = 0.5 * (x + 1.0), 0.5 * w
    s, ds = 3.0 * u * u - 2.0 * u ** 3, 6.0 * u * (1.0 - u)
    span = (t_out - t_in)[..., None]
    t = t_in[..., None] + span * s                                        # (..., nodes)
    px = p0[..., 0, None] + t * d[..., 0, None]
    py = p0[..., 1, None] + t * d[..., 1, None]
    h_over, k_over = _cap_over_rho2(kind, px * px + py * py)
    weight = cross[..., None] * span * (w * ds)
    return (h_rim * outside + np.sum(h_over * weight, axis=-1),
            k_rim * outside + np.sum(k_over * weight, axis=-1))


def _pixel_integrals(view: View, width: int, height: int) -> tuple[np.ndarray, np.ndarray]:
    """(ω, ω_⊥) of every pixel, (height, width) each, over the part of its square in front
    of the eye (contour integrals over its edges, each edge once)."""
    sh, sv, rim = _plane_scales(view)
    a = (np.arange(width + 1) / width - 0.5) * sh                        # column edges, left to right
    b = (np.arange(height + 1) / height - 0.5) * sv                      # row edges, bottom to top
    # horizontal edges at b[k] from a[j] to a[j+1]: (height+1, width); vertical ones at a[j]
    # from b[k] to b[k+1]: (height, width+1)
    def edges(p0, p1):
        step = max(1, EDGE_BLOCK // (p0.shape[1] * EDGE_NODES))          # rows of edges a block
        parts = [_edge_integrals(view.type, p0[i:i + step], p1[i:i + step], rim) for i in range(0, len(p0), step)]
        return np.concatenate([h for h, _ in parts]), np.concatenate([k for _, k in parts])

    A0, B0 = np.meshgrid(a[:-1], b, indexing="xy")
    A1 = np.broadcast_to(a[1:], A0.shape)
    h_h, h_k = edges(np.stack([A0, B0], -1), np.stack([A1, B0], -1))
    A0, B0 = np.meshgrid(a, b[:-1], indexing="xy")
    B1 = np.broadcast_to(b[1:, None], A0.shape)
    v_h, v_k = edges(np.stack([A0, B0], -1), np.stack([A0, B1], -1))

    def around(horizontal, vertical):
        # rows from the top: pixel row i has its top edge at b[height − i], bottom at b[height − 1 − i]
        top = horizontal[::-1]
        side = vertical[::-1]
        return top[1:] - top[:-1] + side[:, 1:] - side[:, :-1]

    return around(h_h, v_h), around(h_k, v_k)


def _corner_solid_angles(view: View, width: int, height: int) -> np.ndarray:
    """evalglare's ω of every pixel: the spherical quadrilateral of its corners' directions
    (two triangles by Van Oosterom & Strackee 1983), 0 when a corner sees nothing."""
    xs = np.arange(width + 1) / width
    ys = 1.0 - np.arange(height + 1) / height
    X, Y = np.meshgrid(xs, ys)
    _, dirs, ok = view.image_rays(X.ravel(), Y.ravel())
    dirs = dirs.reshape(height + 1, width + 1, 3)
    ok = ok.reshape(height + 1, width + 1)
    c00, c01, c10, c11 = dirs[:-1, :-1], dirs[:-1, 1:], dirs[1:, :-1], dirs[1:, 1:]

    def triangle(p, q, r):
        num = np.abs(np.einsum("...i,...i", p, np.cross(q, r)))
        den = 1.0 + np.einsum("...i,...i", p, q) + np.einsum("...i,...i", q, r) + np.einsum("...i,...i", r, p)
        return 2.0 * np.arctan2(num, den)

    omega = triangle(c00, c01, c11) + triangle(c00, c11, c10)
    every = ok[:-1, :-1] & ok[:-1, 1:] & ok[1:, :-1] & ok[1:, 1:]
    return np.where(every, omega, 0.0)


@dataclass(frozen=True)
class FisheyeGeometry:
    """What every pixel of a fisheye image sees (arrays (height, width), top row first).

    directions : (h, w, 3) unit direction of the pixel centre (world frame)
    valid : the centre looks into the front hemisphere (θ ≤ 90°)
    solid_angle : ω [sr], 0 where not valid
    projected : ω_⊥ = ∫ cos θ dω [sr] (``method="corners"``: ω cos θ at the centre), 0 where not valid
    square_solid_angle, square_projected : the same of every pixel, valid or not (the part of
        its square in front of the eye; they sum to 2π and π over the image)
    cos_theta : cos θ of the centre direction
    x, y : image coordinates of the centres (from the left and bottom edges, [0, 1])
    """

    view: View
    width: int
    height: int
    method: str
    directions: np.ndarray
    valid: np.ndarray
    solid_angle: np.ndarray
    projected: np.ndarray
    square_solid_angle: np.ndarray
    square_projected: np.ndarray
    cos_theta: np.ndarray
    x: np.ndarray
    y: np.ndarray

    @property
    def pixel_angle(self) -> float:
        """Smallest angle [rad] between the directions of neighbouring pixels anywhere in
        the image, for a unit step in any direction of the image plane (the smallest
        singular value of the projection: -vta 2 s/w at the rim, -vth s/w)."""
        sh, sv, _ = _plane_scales(self.view)
        step = min(sh / self.width, sv / self.height)
        return (2.0 if self.view.type == "a" else 1.0) * step


def fisheye_geometry(view: View, width: int, height: int, method: str = "exact") -> FisheyeGeometry:
    """Directions, validity and solid angles of the pixels of a ``width`` × ``height``
    fisheye image of ``view`` (module text).  ``method``: ``"exact"`` (contour
    integrals, default) or ``"corners"`` (evalglare's spherical quadrilaterals)."""
    check_fisheye(view)
    if method not in ("exact", "corners"):
        raise ValueError(f"method must be 'exact' or 'corners', got {method!r}")
    x, y = view.pixel_coordinates(width, height)
    _, dirs, ok = view.image_rays(x, y)
    d = view.unit_direction
    cos_theta = (dirs @ d).reshape(height, width)
    valid = ok.reshape(height, width) & (cos_theta >= 0.0)
    if method == "exact":
        omega, projected = _pixel_integrals(view, width, height)
    else:
        omega = _corner_solid_angles(view, width, height)
        projected = omega * np.maximum(cos_theta, 0.0)
    omega, projected = np.maximum(omega, 0.0), np.maximum(projected, 0.0)
    return FisheyeGeometry(view=view, width=int(width), height=int(height), method=method,
                           directions=dirs.reshape(height, width, 3), valid=valid,
                           solid_angle=np.where(valid, omega, 0.0), projected=np.where(valid, projected, 0.0),
                           square_solid_angle=omega, square_projected=projected, cos_theta=cos_theta,
                           x=x.reshape(height, width), y=y.reshape(height, width))


# ---------------------------------------------------------------------------
# Glare sources
# ---------------------------------------------------------------------------

def _single_linkage(mask, directions, cos_limit, reach):
    """Labels (h, w) of the clusters of ``mask``'s pixels in which each pixel lies within
    the angle acos(cos_limit) of another (−1 off the mask), by union–find (compiled by numba
    when first used, :func:`_linkage`).  A pixel whose 8 neighbours are all in the mask
    looks only at them; the others look at every pixel ``reach`` rows and columns around
    them (``reach`` covers the angle anywhere).  Roots are the smallest index of their
    cluster, so ``parent[x] ≤ x`` throughout and one pass in index order ends every path."""
    h, w = mask.shape
    parent = np.arange(h * w)
    for i in range(h):
        for j in range(w):
            if not mask[i, j]:
                continue
            interior = True
            for ii in range(i - 1, i + 2):
                for jj in range(j - 1, j + 2):
                    if ii < 0 or ii >= h or jj < 0 or jj >= w or not mask[ii, jj]:
                        interior = False
            r = 1 if interior else reach
            p = i * w + j
            for ii in range(max(0, i - r), min(h, i + r + 1)):
                for jj in range(max(0, j - r), min(w, j + r + 1)):
                    q = ii * w + jj
                    if q == p or not mask[ii, jj]:
                        continue
                    dot = (directions[i, j, 0] * directions[ii, jj, 0] + directions[i, j, 1] * directions[ii, jj, 1]
                           + directions[i, j, 2] * directions[ii, jj, 2])
                    if dot < cos_limit:
                        continue
                    rp, rq = p, q                                     # the roots, halving the paths
                    while parent[rp] != rp:
                        parent[rp] = parent[parent[rp]]
                        rp = parent[rp]
                    while parent[rq] != rq:
                        parent[rq] = parent[parent[rq]]
                        rq = parent[rq]
                    if rp < rq:
                        parent[rq] = rp
                    elif rq < rp:
                        parent[rp] = rq
    labels = np.full((h, w), -1, dtype=np.int64)
    for k in range(h * w):
        parent[k] = parent[parent[k]]
        if mask[k // w, k % w]:
            labels[k // w, k % w] = parent[k]
    return labels


@functools.lru_cache(maxsize=1)
def _linkage():
    """:func:`_single_linkage` compiled by numba (cached on disk; numba is imported only
    here, so that the command line's parser starts without it)."""
    from numba import njit

    return njit(cache=True, nogil=True)(_single_linkage)


def _clusters(mask: np.ndarray, geometry: FisheyeGeometry, angle: float) -> np.ndarray:
    """Labels 0 … n−1 of the single-linkage clusters of ``mask`` within ``angle`` [rad],
    −1 off the mask."""
    if not mask.any():
        return np.full(mask.shape, -1, dtype=np.int64)
    reach = int(math.ceil(angle / geometry.pixel_angle)) + 1
    roots = _linkage()(np.ascontiguousarray(mask), np.ascontiguousarray(geometry.directions),
                            math.cos(angle), reach)
    out = np.full(mask.shape, -1, dtype=np.int64)
    out[mask] = np.unique(roots[mask], return_inverse=True)[1].ravel()
    return out


def find_glare_sources(luminance: np.ndarray, geometry: FisheyeGeometry, threshold: float,
                       search_angle: float = SEARCH_ANGLE, peak: float | None = PEAK_LUMINANCE) -> np.ndarray:
    """Source labels (h, w) of the valid pixels brighter than ``threshold`` [cd/m²], −1
    elsewhere: single-linkage clusters within ``search_angle`` [rad], and, when a pixel
    exceeds ``peak``, the pixels at or above it split off into clusters of their own
    (module text).  Labels are 0 … n−1 with no gaps."""
    L = np.asarray(luminance, dtype=np.float64)
    candidates = geometry.valid & (L > threshold)
    labels = _clusters(candidates, geometry, search_angle)
    if peak is not None and candidates.any() and L[candidates].max() > peak:
        peaks = candidates & (L >= peak)
        extra = _clusters(peaks, geometry, search_angle)
        labels[peaks] = labels.max() + 1 + extra[peaks]
        used = labels >= 0
        labels[used] = np.unique(labels[used], return_inverse=True)[1].ravel()
    return labels


# ---------------------------------------------------------------------------
# Position index and indices
# ---------------------------------------------------------------------------

def _view_angles(directions: np.ndarray, view: View) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(σ, τ [degrees], above) of unit ``directions`` (n, 3): σ from the view direction, τ
    of their projection on the plane normal to it from the image's up direction (0–180°),
    and whether they lie above the horizontal plane of the view (evalglare's φ ≥ 0)."""
    d, r, u = view.unit_direction, view.right, view.image_up
    dirs = np.asarray(directions, dtype=np.float64).reshape(-1, 3)
    along = dirs @ d
    sigma = np.degrees(np.arccos(np.clip(along, -1.0, 1.0)))
    across = dirs - along[:, None] * d
    tau = np.degrees(np.arctan2(np.abs(across @ r), across @ u))
    return sigma, tau, (dirs @ u) >= 0.0


def position_index(sigma, tau, above) -> np.ndarray:
    """Position index P of directions at σ, τ [degrees] (module text): Guth's formula
    above the line of sight, Iwata & Osterhaus's below it (``above`` False), at most 16."""
    s = np.asarray(sigma, dtype=np.float64)
    t = np.asarray(tau, dtype=np.float64)
    guth = np.exp((35.2 - 0.31889 * t - 1.22 * np.exp(-2.0 * t / 9.0)) * 1e-3 * s
                  + (21.0 + 0.26667 * t - 0.002963 * t * t) * 1e-5 * s * s)
    with np.errstate(over="ignore", invalid="ignore"):
        beta = np.degrees(np.arctan(np.tan(np.radians(s)) * np.sqrt(1.0 + 0.3225 * np.cos(np.radians(t)) ** 2)))
    iwata = np.exp(6.49e-3 * beta + 21e-5 * beta * beta)
    return np.minimum(np.where(np.asarray(above, dtype=bool), guth, iwata), POSITION_INDEX_MAX)


def low_light_factor(ev: float) -> float:
    """exp(0.024 E_v − 4)/(1 + exp(0.024 E_v − 4)) below 1000 lux, else 1 (Wienold 2009)."""
    if ev >= LOW_LIGHT_LIMIT:
        return 1.0
    return 1.0 / (1.0 + math.exp(4.0 - 0.024 * ev))


def daylight_glare_probability(ev: float, luminance, solid_angle, position, constants=DGP_CONSTANTS,
                               low_light: bool = True) -> float:
    """DGP of the sources (luminance [cd/m²], ω [sr], position index) at E_v [lux]
    (module text), at most 1, with the low-light correction unless ``low_light`` is False."""
    c1, c2, c3 = constants
    L = np.asarray(luminance, dtype=np.float64)
    glare = float(np.sum(L * L * np.asarray(solid_angle, dtype=np.float64) / np.asarray(position, dtype=np.float64) ** 2))
    dgp = c1 * ev + c3
    if glare > 0.0 and ev > 0.0:
        dgp += c2 * math.log10(1.0 + glare / ev ** DGP_EV_EXPONENT)
    dgp = min(dgp, 1.0)
    return dgp * low_light_factor(ev) if low_light else dgp


def en17037_class(dgp: float) -> str:
    """The EN 17037 glare-protection class whose DGP limit ``dgp`` meets: ``high`` (≤ 0.35),
    ``medium`` (≤ 0.40), ``minimum`` (≤ 0.45), else ``none``."""
    for name, limit in EN17037_LIMITS.items():
        if dgp <= limit:
            return name
    return "none"


def dgp_category(dgp: float) -> str:
    """``imperceptible`` (< 0.35), ``perceptible`` (< 0.40), ``disturbing`` (< 0.45) or
    ``intolerable`` glare (Wienold et al. 2019)."""
    return next(name for bound, name in DGP_CATEGORIES if dgp < bound)


# ---------------------------------------------------------------------------
# The evaluation
# ---------------------------------------------------------------------------

@dataclass(frozen=True)
class GlareSource:
    """One glare source.

    luminance : ω-weighted mean luminance L_s [cd/m²];  max_luminance [cd/m²]
    solid_angle : ω_s [sr];  illuminance : its direct vertical illuminance E_s [lux]
    direction : unit direction of its centre (world frame);  sigma, tau : its angles [°]
    above : above the view's horizontal plane;  position_index : P_s
    pixels : pixel count;  column, row : its centre in pixels (from the left and the top;
    the centre of the top-left pixel is (0, 0))
    """

    luminance: float
    max_luminance: float
    solid_angle: float
    illuminance: float
    direction: tuple
    sigma: float
    tau: float
    above: bool
    position_index: float
    pixels: int
    column: float
    row: float

    @property
    def dgp_term(self) -> float:
        """L_s² ω_s / P_s², the source's share of the DGP's glare sum [cd²/m⁴·sr]."""
        return self.luminance ** 2 * self.solid_angle / self.position_index ** 2

    def as_dict(self) -> dict:
        return {"luminance": self.luminance, "max_luminance": self.max_luminance,
                "solid_angle": self.solid_angle, "illuminance": self.illuminance,
                "direction": list(self.direction), "sigma_deg": self.sigma, "tau_deg": self.tau,
                "above_line_of_sight": self.above, "position_index": self.position_index,
                "pixels": self.pixels, "image_position": [self.column, self.row], "dgp_term": self.dgp_term}


@dataclass(frozen=True)
class GlareResult:
    """The glare figures of one fisheye image (module text for each)."""

    dgp: float
    dgp_uncorrected: float
    ev: float
    ev_sources: float
    background_luminance: float
    average_luminance: float
    dgi: float | None
    ugr: float | None
    threshold: float
    threshold_rule: str
    sources: tuple
    view: View
    width: int
    height: int
    solid_angle: float
    task_luminance: float | None = None
    settings: dict = field(default_factory=dict)

    @property
    def low_light_factor(self) -> float:
        return low_light_factor(self.ev)

    @property
    def en17037(self) -> str:
        return en17037_class(self.dgp)

    @property
    def category(self) -> str:
        return dgp_category(self.dgp)

    def as_dict(self) -> dict:
        """JSON-ready figures: dgp, ev [lux], sources (each with luminance, solid angle,
        direction, position index), ..."""
        return {
            "dgp": self.dgp, "dgp_uncorrected": self.dgp_uncorrected, "low_light_factor": self.low_light_factor,
            "dgp_category": self.category,
            "en17037": {"class": self.en17037, "limits": dict(EN17037_LIMITS),
                        "note": "one image: the best class whose DGP limit it meets (EN 17037 rates the DGP "
                                "exceeded in 5 % of the occupied hours)"},
            "ev": self.ev, "ev_sources": self.ev_sources, "background_luminance": self.background_luminance,
            "average_luminance": self.average_luminance, "task_luminance": self.task_luminance,
            "dgi": self.dgi, "ugr": self.ugr,
            "threshold": {"luminance": self.threshold, "rule": self.threshold_rule},
            "sources": [s.as_dict() for s in self.sources],
            "view": self.view.options(), "width": self.width, "height": self.height,
            "solid_angle": self.solid_angle, "settings": dict(self.settings),
        }

    def summary(self) -> str:
        """One line: DGP, its category and class, E_v, the sources, DGI and UGR."""
        def num(x, digits=1):
            return "-" if x is None else f"{x:.{digits}f}"
        count = plural(len(self.sources), "glare source") if self.sources else "no glare source"
        return (f"DGP {self.dgp:.3f} ({self.category}; EN 17037 {self.en17037}), Ev {self.ev:,.0f} lux, "
                f"{count} above {self.threshold:,.4g} cd/m2, "
                f"DGI {num(self.dgi)}, UGR {num(self.ugr)}")


def _check_luminance(luminance: Any, where: str) -> np.ndarray:
    L = np.asarray(luminance, dtype=np.float64)
    if L.ndim != 2 or L.size == 0:
        raise InputError(f"{where}: a luminance image must be a (height, width) array, got shape {L.shape}")
    if not np.all(np.isfinite(L)):
        raise InputError(f"{where}: {int((~np.isfinite(L)).sum()):,} pixels are not finite luminances")
    if np.any(L < 0.0):
        raise InputError(f"{where}: {int((L < 0.0).sum()):,} pixels have a negative luminance")
    return L


def _check_black_corners(L: np.ndarray, view: View | None, where: str) -> None:
    """A perspective VIEW= line on an image whose corners are black is a fisheye with the
    wrong header (evalglare's check): say so."""
    if view is None or view.type != "v":
        return
    h, w = L.shape
    i, j = np.mgrid[0:h, 0:w]
    r = np.hypot((j + 0.5 - w / 2) / (w / 2), (i + 0.5 - h / 2) / (h / 2))
    corners = L[r > 1.0]
    if corners.size and np.mean(corners <= BLACK_LUMINANCE) > BLACK_CORNERS:
        raise InputError(f"{where}: the VIEW= line says perspective (-vtv) but the corners outside the inscribed "
                         f"circle are black ({100 * np.mean(corners <= BLACK_LUMINANCE):.0f} % at most "
                         f"{BLACK_LUMINANCE:g} cd/m2): a fisheye with a wrong view? give it with --view=\"-vta ...\"")


def evaluate_glare(luminance, view: View, *, threshold: float | None = None, factor: float | None = None,
                   task: tuple[float, float, float] | None = None, search_angle: float = SEARCH_ANGLE,
                   peak: float | None = PEAK_LUMINANCE, low_light: bool = True, constants=DGP_CONSTANTS,
                   geometry: FisheyeGeometry | None = None, where: str = "image") -> GlareResult:
    """The glare figures of a fisheye luminance image (module text).

    luminance : (height, width) [cd/m²], row 0 the top of the image
    view : its view (:func:`check_fisheye`)
    threshold : source threshold [cd/m²]; or instead
    factor : sources above ``factor`` × the average luminance of the image, or of the task
        area with ``task``;  with neither, 2000 cd/m² (evalglare's default), with ``task``
        alone a factor of 5
    task : (column, row, angle): the task area, the pixels within a cone of full apex
        ``angle`` [°] around the centre of pixel (column from the left, row from the top)
    search_angle : largest angle [rad] between pixels of one source (evalglare -r / 2)
    peak : peak extraction luminance [cd/m²] (None: off)
    low_light : apply the low-light correction to ``dgp``
    constants : (c1, c2, c3) of the DGP
    geometry : the pixels' geometry if already computed for this view and size
    """
    L = _check_luminance(luminance, where)
    _check_black_corners(L, view, where)
    check_fisheye(view, where)
    h, w = L.shape
    if geometry is None or (geometry.view, geometry.width, geometry.height) != (view, w, h):
        geometry = fisheye_geometry(view, w, h)
    if threshold is not None and factor is not None:
        raise InputError(f"{where}: give a source threshold or a factor, not both")
    for name, value in (("threshold", threshold), ("factor", factor), ("search angle", search_angle),
                        ("peak", peak)):
        if value is not None and not (math.isfinite(value) and value > 0.0):
            raise InputError(f"{where}: the {name} must be a positive number, got {value:g}")
    valid, omega, projected = geometry.valid, geometry.solid_angle, geometry.projected
    total = float(omega.sum())
    ev = float(np.sum(L * projected))
    average = float(np.sum(L * omega) / total) if total > 0.0 else 0.0
    task_luminance = None
    if task is not None:
        column, row, angle = (float(v) for v in task)
        if not (0 <= column < w and 0 <= row < h) or not valid[int(row), int(column)]:
            raise InputError(f"{where}: the task's pixel ({column:g}, {row:g}) is not in the hemisphere of the "
                             f"{w} x {h} image")
        if not (math.isfinite(angle) and 0.0 < angle <= 180.0):
            raise InputError(f"{where}: the task's angle must be within 0 and 180 degrees, got {angle:g}")
        centre = geometry.directions[int(row), int(column)]
        inside = valid & (geometry.directions @ centre >= math.cos(math.radians(angle) / 2.0))
        task_luminance = float(np.sum(L * omega * inside) / np.sum(omega * inside))
    if threshold is not None:
        limit, rule = float(threshold), f"{threshold:g} cd/m2"
    elif factor is not None or task is not None:
        f = TASK_FACTOR if factor is None else float(factor)
        base = average if task is None else task_luminance
        limit, rule = f * base, f"{f:g} x the {'average' if task is None else 'task'} luminance"
    else:
        limit, rule = DEFAULT_THRESHOLD, f"{DEFAULT_THRESHOLD:g} cd/m2 (evalglare's default)"

    labels = find_glare_sources(L, geometry, limit, search_angle, peak)
    n = int(labels.max()) + 1
    sources: list[GlareSource] = []
    ev_sources = 0.0
    if n > 0:
        on = labels >= 0
        lab = labels[on]
        Lo, om, pr = L[on], omega[on], projected[on]
        rows, cols = np.nonzero(on)
        src_omega = np.bincount(lab, om, n)
        src_flux = np.bincount(lab, Lo * om, n)
        src_lum = src_flux / src_omega
        src_ev = np.bincount(lab, Lo * pr, n)
        src_max = np.full(n, 0.0)
        np.maximum.at(src_max, lab, Lo)
        src_pixels = np.bincount(lab, minlength=n)
        col = np.bincount(lab, cols * Lo * om, n) / src_flux
        row = np.bincount(lab, rows * Lo * om, n) / src_flux
        _, dirs, _ = view.image_rays((col + 0.5) / w, 1.0 - (row + 0.5) / h)
        sigma, tau, above = _view_angles(dirs, view)
        P = position_index(sigma, tau, above)
        ev_sources = float(src_ev.sum())
        order = np.argsort(-(src_lum ** 2 * src_omega / P ** 2), kind="stable")
        sources = [GlareSource(luminance=float(src_lum[k]), max_luminance=float(src_max[k]),
                               solid_angle=float(src_omega[k]), illuminance=float(src_ev[k]),
                               direction=tuple(float(c) for c in dirs[k]), sigma=float(sigma[k]), tau=float(tau[k]),
                               above=bool(above[k]), position_index=float(P[k]), pixels=int(src_pixels[k]),
                               column=float(col[k]), row=float(row[k])) for k in order]
    Ls = np.array([s.luminance for s in sources])
    ws = np.array([s.solid_angle for s in sources])
    Ps = np.array([s.position_index for s in sources])
    background = (ev - ev_sources) / math.pi
    dgp_raw = daylight_glare_probability(ev, Ls, ws, Ps, constants, low_light=False)
    dgp = dgp_raw * low_light_factor(ev) if low_light else dgp_raw
    dgi = ugr = None
    if sources:
        dgi_sum = float(np.sum(0.478 * Ls ** 1.6 * (ws / Ps ** 2) ** 0.8 / (background + 0.07 * np.sqrt(ws) * Ls)))
        dgi = 10.0 * math.log10(dgi_sum) if dgi_sum > 0.0 else None
        if background > 0.0:
            ugr = 8.0 * math.log10(0.25 / background * float(np.sum(Ls ** 2 * ws / Ps ** 2)))
    settings = {"search_angle_rad": search_angle, "peak_luminance": peak, "low_light_correction": low_light,
                "dgp_constants": list(constants), "solid_angles": geometry.method}
    return GlareResult(dgp=dgp, dgp_uncorrected=dgp_raw, ev=ev, ev_sources=ev_sources, background_luminance=background,
                       average_luminance=average, dgi=dgi, ugr=ugr, threshold=limit, threshold_rule=rule,
                       sources=tuple(sources), view=view, width=w, height=h, solid_angle=total,
                       task_luminance=task_luminance, settings=settings)


def glare_from_image(path: str | os.PathLike, view: View | None = None, **options) -> GlareResult:
    """:func:`evaluate_glare` of an image file (Radiance HDR with its ``VIEW=`` line, or an
    EXR/TIFF written by lbl_illum); ``view`` replaces the file's view."""
    from ..io.images import read_image

    path = Path(path)
    name = path.name
    if path.is_dir():
        raise InputError(f"{name}: is a folder, not an image")
    try:
        image = read_image(path)
    except InputError:
        raise
    except ValueError as exc:       # the pixels' conversion refuses a non-positive EXPOSURE=
        raise InputError(f"{name}: {exc} (the product of the header's EXPOSURE= lines)") from None
    if not (math.isfinite(image.exposure) and image.exposure > 0.0):
        raise InputError(f"{name}: the image's exposure is {image.exposure:g}; it must be positive")
    if view is None:
        _check_black_corners(_check_luminance(image.luminance, name), image.view, name)
        view = image.view
    return evaluate_glare(image.luminance, check_fisheye(view, name), where=name, **options)

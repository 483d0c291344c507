"""Numerical stability at the extremes of every setting and of the input.

Each case runs the engine at one extreme — of ``accuracy`` (the paper's a, Eq. 5),
``samples`` (M·N of Eq. 2), ``bounces`` (§3.4's levels), reflectance, scale, sensor
placement, sun position or input geometry — and checks two things:

* **plausibility**, on every run: every RGB value finite and ≥ 0, the photometric
  illuminance below the scene's upper bound E_max (below), and the record counts within
  what the placement guarantees (below);
* **the value**, against what it must be: a closed form where one exists, else an
  independent pure Monte Carlo run (``accuracy = 0``) of the same case.  Where the
  difference is Monte Carlo noise the tolerance is 4 standard errors of the mean over
  the sensors (from the spread of their differences, which holds the noise of both
  runs) plus a stated allowance for bias, which is 0 for unbiased estimators.

**Upper bound E_max (maximum principle).**  With sources of luminance at most L_max
(sky, ground glow, light surfaces), a sun of direct normal illuminance E_dn and diffuse
reflectances at most ρ_max < 1, no surface is brighter than ρ_max E_max/π, so every
illuminance obeys E ≤ E_dn + max(π L_max, ρ_max E_max), i.e.
E_max = max(E_dn + π L_max, E_dn / (1 − ρ_max)).  Without a sun, E_max = π L_max: in a
room lit by a uniform sky of horizontal illuminance E_h no point receives more than E_h.

**Record bound.**  Placement makes at most one record per query (a query no record
covers becomes one), and the queries of level k+1 are the diffuse hits of level k's new
records' rays, at most S_k per record (no window portals in these scenes).  So for every
level k: new_records[k] ≤ queries[k], queries[0] = the sensor count and
queries[k+1] ≤ S_k · new_records[k], S_k = M·N, the cells of Eq. 2 for the level's
samples ``Options.level_samples(k)`` (``hemisphere.cell_counts`` rounds: 32 → 3 × 11).

Lengths are in metres, illuminance in lux, luminance in cd/m², angles in degrees.
"""

from __future__ import annotations

import math
import os
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from lbl_illum import Integrator, Options
from lbl_illum.errors import InputError, plural
from lbl_illum.engine import ON_SURFACE_FRACTION, SELF_HIT_EPSILON, cell_counts
from lbl_illum.options import BOUNCE_ACCURACY_CAP
from lbl_illum.scene import scene_from_dict
from lbl_illum.daylight import SUN_SOLID_ANGLE

from .report import Report, StudyContext, fmt, pct

TITLE = "Extremes: numerical stability at the limits of every setting and input"

#: Sky horizontal illuminance of every daylit case [lux].
E_H = 10000.0
#: The roof-lit room: W × L × H [m] with a square opening of side HOLE in the middle of
#: the ceiling (an opening, not glass).  Floor 0.2, walls 0.5, ceiling 0.7.
ROOM = (4.0, 6.0, 3.0)
HOLE = 2.0
RHO_ROOM = (0.2, 0.5, 0.7)
#: Workplane height [m] and grid (4 × 3 sensors at the cell centres).
WORKPLANE = 0.8
GRID = (4, 3)
#: Standard errors of the mean a difference may reach before a case fails.
Z = 4.0
#: Bias allowed to cached runs at 50 bounces against the flux balance or a reference:
#: the office study measured +2.7 % at a = 0.15 and +3.3 % at a = 0.2 over 8 bounces,
#: from interpolation errors that accumulate over the levels.
CACHE_BIAS_50 = 0.05
#: Sun direct normal illuminance of the sun cases [lux].
E_DN = 80000.0
#: Scale-invariance tolerance: largest relative difference between the same scene in
#: other units or sizes, with the same seed (round-off of the unit conversion only).
SCALE_TOLERANCE = 1e-6
#: §4 sphere on a plane, upper half, bounces = 1: largest error allowed against the
#: closed form (the tolerance of tests/test_integrator.py).
SPHERE_TOLERANCE = 0.03


@dataclass(frozen=True)
class Plan:
    """What one version computes."""

    ref_samples: int          # samples of the pure Monte Carlo references
    a_small_samples: int      # samples of the a = 0.001 case
    a_small_bounces: int
    copies: int               # copies of each sensor in the samples = 1 and 4 pure Monte Carlo runs
    seeds: int                # seeds of the samples = 1 and 4 cached runs
    big_samples_points: int   # sensors of the samples = 65536 run (bounces 0)
    big_samples_paths: bool   # also samples = 65536, a = 0, bounces = 1 against the reference
    memory_samples: tuple     # samples of the memory probe (cached, 1 bounce), each in its own process
    cached_50: bool           # the cached 50-bounce run and the ρ = 0.999 box
    sphere_radii: tuple
    sphere_samples: int
    ground_points: int
    ref50_samples: int        # samples of the 50-bounce pure Monte Carlo reference
    scale_options: Options    # the mm / m / km runs
    box_options: Options      # the cached run in the closed box
    mesh_options: Options     # the degenerate-mesh runs


QUICK = Plan(ref_samples=4096, a_small_samples=32, a_small_bounces=1, copies=300, seeds=3,
             big_samples_points=4, big_samples_paths=False, memory_samples=(), cached_50=False,
             sphere_radii=(1e-4, 1e4),
             sphere_samples=256, ground_points=64, ref50_samples=1024,
             scale_options=Options(samples=64, bounces=1), box_options=Options(samples=64, bounces=2),
             mesh_options=Options(samples=64, bounces=1))
FULL = Plan(ref_samples=16384, a_small_samples=64, a_small_bounces=2, copies=2000, seeds=16,
            big_samples_points=12, big_samples_paths=True, memory_samples=(2048, 4096), cached_50=True,
            sphere_radii=(1e-4, 1.0, 1e4),
            sphere_samples=1024, ground_points=256, ref50_samples=4096,
            scale_options=Options(samples=256, bounces=2), box_options=Options(samples=256, bounces=2),
            mesh_options=Options(samples=256, bounces=2))


def describe(o: Options) -> str:
    """Settings of a run in words: ``a = 0.1, 256 samples, 2 bounces``."""
    return f"a = {o.accuracy:g}, {o.samples} sample{'s' * (o.samples != 1)}, {o.bounces} bounce{'s' * (o.bounces != 1)}"


# -- the record of one case ------------------------------------------------------------------
@dataclass
class Case:
    """One row of the table.  ``diff`` is relative unless ``absolute``; ``tol`` None means
    the case is checked against its plausibility bounds only."""

    group: str
    name: str
    settings: str
    expected: float | None
    source: str
    result: float | None
    diff: float | None
    tol: float | None
    plausible: bool
    records: int = 0
    rays: int = 0
    seconds: float = 0.0
    absolute: bool = False
    extra: dict = field(default_factory=dict)

    @property
    def passed(self) -> bool:
        ok = self.plausible
        if self.tol is not None:
            ok = ok and self.diff is not None and math.isfinite(self.diff) and abs(self.diff) <= self.tol
        return bool(ok)


@dataclass
class Run:
    """One engine run and its plausibility."""

    E: np.ndarray             # (n,) photometric illuminance [lux]
    rgb: np.ndarray           # (n, 3)
    direct: np.ndarray        # (n,) photometric
    stats: object
    seconds: float
    plausible: bool
    why: str                  # what failed, "" if nothing


def upper_bound(L_max: float, rho_max: float, E_dn: float = 0.0) -> float:
    """E_max of the maximum principle (module docstring) [lux]."""
    if E_dn <= 0.0:
        return math.pi * L_max
    return max(E_dn + math.pi * L_max, E_dn / (1.0 - rho_max))


def records_bounded(stats, options: Options, n: int) -> bool:
    """The placement's guarantees (module docstring) on one run's counts."""
    new, q = list(stats.new_records), list(stats.queries)
    if not q or q[0] != n:
        return n == 0 or sum(new) == 0
    ok = all(new[k] <= q[k] for k in range(len(q)))
    return ok and all(q[k + 1] <= rays_per_record(options, k) * new[k] for k in range(len(q) - 1))


def rays_per_record(options: Options, level: int) -> int:
    """Hemisphere rays of one primary evaluation at ``level``: M·N of Eq. 2 for the
    level's samples (``cell_counts`` rounds, e.g. 32 → 3 × 11 = 33)."""
    m, n = cell_counts(options.level_samples(level))
    return m * n


def run_engine(ctx, label, scene, P, N, options, E_max) -> Run:
    t0 = time.perf_counter()
    result = Integrator(scene, options).compute(P, N)
    seconds = time.perf_counter() - t0
    ctx.step(label, result.stats)
    rgb = np.asarray(result.rgb, np.float64)
    E = np.asarray(result.illuminance, np.float64)
    why = []
    if not np.all(np.isfinite(rgb)):
        why.append("non-finite value")
    elif np.any(rgb < 0.0):
        why.append("negative value")
    elif np.any(E > E_max * (1.0 + 1e-9)):
        why.append(f"E = {E.max():.6g} above E_max = {E_max:.6g}")
    if not records_bounded(result.stats, options, len(P)):
        why.append("record count above the placement bound")
    direct = np.asarray(result.direct, np.float64) @ np.array([0.2126, 0.7152, 0.0722])
    return Run(E, rgb, direct, result.stats, seconds, not why, "; ".join(why))


def mean_difference(E, ref):
    """Relative difference of the mean of ``E`` from the mean of ``ref`` and its standard
    error from the spread of the point-by-point differences."""
    E, ref = np.asarray(E, np.float64), np.asarray(ref, np.float64)
    d = E - ref
    diff = float(d.sum() / ref.sum())
    se = float(d.std(ddof=1) / math.sqrt(len(d)) / ref.mean()) if len(d) > 1 else 0.0
    return diff, se


def compared(group, name, settings, run: Run, expected, source, bias=0.0, z=Z, **extra) -> Case:
    """A case whose value is compared with ``expected`` (per sensor) by the mean test."""
    expected = np.broadcast_to(np.asarray(expected, np.float64), run.E.shape)
    diff, se = mean_difference(run.E, expected)
    with np.errstate(divide="ignore", invalid="ignore"):
        point = np.where(expected > 0, run.E / expected - 1.0, np.nan)
    extra = {"se": se, "bias_allowed": bias, "max_point_error": float(np.nanmax(np.abs(point)))
             if np.isfinite(point).any() else None, "records_per_level": list(run.stats.new_records),
             "queries_per_level": list(run.stats.queries),
             "why": run.why, **extra}
    return Case(group, name, settings, float(expected.mean()), source, float(run.E.mean()), diff,
                z * se + bias, run.plausible, int(sum(run.stats.new_records)), int(run.stats.rays), run.seconds,
                extra=extra)


def bounds_only(group, name, settings, run: Run, reference=None, source="", **extra) -> Case:
    """A case checked against its plausibility bounds only; the difference from
    ``reference`` (if given) is reported, not tested."""
    diff = se = None
    if reference is not None:
        diff, se = mean_difference(run.E, reference)
    return Case(group, name, settings, None if reference is None else float(np.mean(reference)), source,
                float(run.E.mean()), diff, None, run.plausible, int(sum(run.stats.new_records)),
                int(run.stats.rays), run.seconds, extra={"se": se, "why": run.why, **extra})


# -- scenes ---------------------------------------------------------------------------------
def _rect(o, u, v, m):
    return {"shape": "rectangle", "origin": list(o), "u": list(u), "v": list(v), "material": m}


def room_geometry(scale=1.0):
    """The roof-lit room's rectangles (scaled by ``scale``), floor at z = 0, x ∈ [0, W],
    y ∈ [0, L]; the ceiling is four strips around the opening."""
    W, L, H = ROOM
    x0, x1, y0, y1 = (W - HOLE) / 2, (W + HOLE) / 2, (L - HOLE) / 2, (L + HOLE) / 2
    g = [_rect([0, 0, 0], [W, 0, 0], [0, L, 0], "floor"),
         _rect([0, 0, 0], [W, 0, 0], [0, 0, H], "wall"), _rect([0, L, 0], [W, 0, 0], [0, 0, H], "wall"),
         _rect([0, 0, 0], [0, L, 0], [0, 0, H], "wall"), _rect([W, 0, 0], [0, L, 0], [0, 0, H], "wall"),
         _rect([0, 0, H], [W, 0, 0], [0, y0, 0], "ceiling"), _rect([0, y1, H], [W, 0, 0], [0, L - y1, 0], "ceiling"),
         _rect([0, y0, H], [x0, 0, 0], [0, y1 - y0, 0], "ceiling"),
         _rect([x1, y0, H], [W - x1, 0, 0], [0, y1 - y0, 0], "ceiling")]
    for e in g:
        for k in ("origin", "u", "v"):
            e[k] = [c * scale for c in e[k]]
    return g


def room_scene(rho=RHO_ROOM, scale=1.0, units="m", geometry=None, base_dir=None):
    mats = {"floor": {"type": "diffuse", "reflectance": rho[0]}, "wall": {"type": "diffuse", "reflectance": rho[1]},
            "ceiling": {"type": "diffuse", "reflectance": rho[2]}}
    data = {"units": units, "geometry": geometry or room_geometry(scale), "materials": mats,
            "sky": {"type": "uniform", "horizontal_illuminance": E_H, "ground_reflectance": 0.2}}
    return scene_from_dict(data, base_dir or Path.cwd(), "extremes-room.toml")


def workplane():
    """(P, N): the 4 × 3 grid at the workplane height, facing up [m]."""
    W, L, _ = ROOM
    x = (np.arange(GRID[0]) + 0.5) * W / GRID[0]
    y = (np.arange(GRID[1]) + 0.5) * L / GRID[1]
    X, Y = np.meshgrid(x, y)
    P = np.column_stack([X.ravel(), Y.ravel(), np.full(X.size, WORKPLANE)])
    return P, np.tile([0.0, 0.0, 1.0], (len(P), 1))


def _corner_factor(X, Y, h):
    """Configuration factor from a horizontal differential area to a parallel rectangle
    X × Y at height h with one corner straight above it (Howell's catalogue, C-11):
    F = 1/(2π) [A/√(1+A²) atan(B/√(1+A²)) + B/√(1+B²) atan(A/√(1+B²))], A = X/h, B = Y/h.
    Odd in X and in Y, so signed sums give any parallel rectangle."""
    A, B = X / h, Y / h
    a1, b1 = np.sqrt(1 + A * A), np.sqrt(1 + B * B)
    return (A / a1 * np.arctan(B / a1) + B / b1 * np.arctan(A / b1)) / (2 * np.pi)


def opening_illuminance(P):
    """Illuminance [lux] at upward-facing points P from the uniform sky (luminance E_h/π)
    seen through the roof opening: E = E_h · F(point → opening)."""
    W, L, H = ROOM
    x0, x1, y0, y1 = (W - HOLE) / 2, (W + HOLE) / 2, (L - HOLE) / 2, (L + HOLE) / 2
    h = H - P[:, 2]
    X0, X1, Y0, Y1 = x0 - P[:, 0], x1 - P[:, 0], y0 - P[:, 1], y1 - P[:, 1]
    F = _corner_factor(X1, Y1, h) - _corner_factor(X0, Y1, h) - _corner_factor(X1, Y0, h) + _corner_factor(X0, Y0, h)
    return E_H * F


GROUND = {"shape": "polygon", "material": "ground",
          "vertices": [[-50, -50, 0], [50, -50, 0], [50, 50, 0], [-50, 50, 0]]}


def open_ground(sky_type="uniform", sun=None, rho=0.2):
    data = {"geometry": [dict(GROUND)], "materials": {"ground": {"type": "diffuse", "reflectance": rho}},
            "sky": {"type": sky_type, "horizontal_illuminance": E_H, "ground_reflectance": 0.2}}
    if sun is not None:
        data["sun"] = sun
    return scene_from_dict(data, Path.cwd(), "extremes-ground.toml")


def sun_disk_radius() -> float:
    """Angular radius δ [rad] of the 6.8e-5 sr disk: Ω = 2π (1 − cos δ)."""
    return math.acos(1.0 - SUN_SOLID_ANGLE / (2.0 * math.pi))


def grazing_sun_illuminance(altitude_deg: float, E_dn: float = E_DN) -> tuple[float, float]:
    """Direct illuminance [lux] on a horizontal surface from a uniform disk of radius δ
    whose centre is α above the surface's plane, only the part above the plane counting
    (small angles: a plane disk, sin ≈ angle; relative error ~δ² = 2e-5):
    E = E_dn/(π δ²) · [α A + (2/3)(δ² − α²)^{3/2}], A the area of the disk above the
    plane (a circular segment) and the second term its first moment.  Also returns
    E_dn sin α · A/(π δ²): the disk centre's cosine times the visible fraction."""
    d, a = sun_disk_radius(), math.radians(altitude_deg)
    area = math.pi * d * d - (d * d * math.acos(a / d) - a * math.sqrt(d * d - a * a))
    exact = E_dn / (math.pi * d * d) * (a * area + 2.0 / 3.0 * (d * d - a * a) ** 1.5)
    return exact, E_dn * math.sin(a) * area / (math.pi * d * d)


def closed_box(sun=True, sky=True):
    """The room without its opening (a closed 4 × 6 × 3 m box, ρ = 0.7), under a sun
    (altitude 30°, azimuth 200°) and a uniform sky, or in the dark."""
    data = {"geometry": [{"shape": "box", "center": [2, 3, 1.5], "size": list(ROOM), "material": "wall"}],
            "materials": {"wall": {"type": "diffuse", "reflectance": 0.7}}}
    data["sky"] = {"type": "uniform", "horizontal_illuminance": E_H} if sky else {"type": "none"}
    if sun:
        data["sun"] = {"altitude": 30, "azimuth": 200, "direct_normal_illuminance": E_DN}
    return scene_from_dict(data, Path.cwd(), "extremes-box.toml")


#: Sensors of the closed box (room coordinates), each with what it tests.
BOX_SENSORS = [
    ([2, 3, 0], [0, 0, 1], "on the floor"),
    ([0, 0, 0], [0, 0, 1], "floor corner, facing up"),
    ([0, 0, 0], [1, 1, 1], "floor corner, facing the room's diagonal"),
    ([0, 0, 0], [1, 0, 0], "on a wall at the floor corner, facing in"),
    ([4, 6, 3], [-1, -1, -1], "ceiling corner, facing down the diagonal"),
    ([2, 0, 0], [0, 0, 1], "floor edge at a wall, facing up"),
    ([4, 0, 1.5], [-1, 1, 0], "wall edge (vertical corner), facing in"),
    ([2, 0.001, 1.5], [0, -1, 0], "1 mm from a wall, facing it"),
    ([2, 5.999, 1.5], [0, -1, 0], "1 mm from a wall, facing away"),
]

#: The large wall of the 1 mm case: 200 m × 100 m in the plane y = 0.
WALL_RHO = 0.5
WALL_SUN = {"altitude": 30, "azimuth": 180, "direct_normal_illuminance": E_DN}


def big_wall():
    data = {"geometry": [_rect([-100, 0, 0], [200, 0, 0], [0, 0, 100], "wall")],
            "materials": {"wall": {"type": "diffuse", "reflectance": WALL_RHO}},
            "sky": {"type": "uniform", "horizontal_illuminance": E_H, "ground_reflectance": 0.2},
            "sun": dict(WALL_SUN)}
    return scene_from_dict(data, Path.cwd(), "extremes-wall.toml")


def wall_illuminance() -> float:
    """Illuminance [lux] on the front of an unobstructed vertical wall facing the sun's
    azimuth: E_dn cos(altitude) + E_h/2 (half of a uniform sky) + ρ_g E_gh/2 (half of
    the uniform ground glow, E_gh = E_h + E_dn sin(altitude))."""
    alt = math.radians(WALL_SUN["altitude"])
    E_gh = E_H + E_DN * math.sin(alt)
    return E_DN * math.cos(alt) + E_H / 2 + 0.2 * E_gh / 2


def wall_view_factor(distance: float) -> float:
    """Fraction of the projected hemisphere that the 200 × 100 m wall fills from a point
    ``distance`` in front of its centre (x = 0, z = 50), facing it (four corner
    rectangles of :func:`_corner_factor`)."""
    return 4.0 * float(_corner_factor(np.array(100.0), np.array(50.0), distance))


def sphere_scene(r):
    """§4: a sphere of radius r touching a square plane of half-width 1000 r, both ρ = 0.7,
    under a zenith sun of 1000 lux, no sky."""
    w = 1000.0 * r
    data = {"geometry": [{"shape": "sphere", "center": [0, 0, r], "radius": r, "material": "white"},
                         {"shape": "polygon", "vertices": [[-w, -w, 0], [w, -w, 0], [w, w, 0], [-w, w, 0]],
                          "material": "white"}],
            "materials": {"white": {"type": "diffuse", "reflectance": 0.7}}, "sky": {"type": "none"},
            "sun": {"altitude": 90, "azimuth": 0, "direct_normal_illuminance": 1000}}
    return scene_from_dict(data, Path.cwd(), "extremes-sphere.toml")


def sphere_sensors(r):
    """Points on the upper half at elevations 5…85° (step 5) × azimuths 0/90/180/270,
    outward normals, and the §4 closed form E0 sin γ + ρ E0 (1 − sin γ)/2 (E0 = 1000,
    ρ = 0.7: the direct light and the first reflection from the plane)."""
    g, p = np.meshgrid(np.radians(np.arange(5.0, 86.0, 5.0)), np.radians([0.0, 90.0, 180.0, 270.0]))
    g, p = g.ravel(), p.ravel()
    N = np.column_stack([np.cos(g) * np.cos(p), np.cos(g) * np.sin(p), np.sin(g)])
    P = np.array([0.0, 0.0, r]) + r * N
    return P, N, 1000.0 * N[:, 2] + 0.7 * 1000.0 * (1.0 - N[:, 2]) / 2.0


# -- degenerate geometry ----------------------------------------------------------------------
def _obj(tris) -> str:
    lines = []
    for t in tris:
        for v in t:
            lines.append("v {:.9g} {:.9g} {:.9g}".format(*v))
    lines += [f"f {3 * i + 1} {3 * i + 2} {3 * i + 3}" for i in range(len(tris))]
    return "\n".join(lines) + "\n"


def degenerate_meshes():
    """(clean, dirty, counts): the roof-lit room with a fin, as (T, 3, 3) corners [m].
    The fin, a 6 m × 1 m panel rising at 45° into the room from the foot of the wall
    x = 0, shares the floor–wall edge, which so has three faces: a non-manifold mesh.
    ``dirty`` adds 2 zero-area triangles (three collinear corners; three equal corners)
    and 3 duplicates of the first triangle (same order, reversed, rotated)."""
    from lbl_illum.scene import rectangle_triangles

    tris = [rectangle_triangles(e["origin"], e["u"], e["v"]) for e in room_geometry()]
    fin = rectangle_triangles([0, 0, 0], [0, ROOM[1], 0], [0.7071, 0, 0.7071])
    clean = np.concatenate(tris + [fin])
    a = clean[0]
    zero = [np.array([[1, 1, 0], [2, 2, 0], [3, 3, 0.0]]), np.array([[1, 2, 1.0]] * 3)]
    dups = [a, a[::-1], a[[1, 2, 0]]]
    dirty = np.concatenate([clean, np.array(zero), np.array(dups)])
    return clean, dirty, {"zero-area": len(zero), "duplicate": len(dups)}


def mesh_scene(file: str, base_dir: Path):
    """A geometry file under the uniform sky, every face diffuse ρ = 0.5."""
    data = {"geometry": [{"file": file, "material": "wall"}],
            "materials": {"wall": {"type": "diffuse", "reflectance": 0.5}},
            "sky": {"type": "uniform", "horizontal_illuminance": E_H, "ground_reflectance": 0.2}}
    return scene_from_dict(data, base_dir, "extremes-mesh.toml")


def non_manifold_edges(tris) -> int:
    """Edges (corner pairs, after merging equal corners) shared by more than two faces."""
    corners, inverse = np.unique(np.asarray(tris, np.float64).reshape(-1, 3), axis=0, return_inverse=True)
    faces = inverse.reshape(-1, 3)
    edges = np.sort(np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]]), axis=1)
    _, counts = np.unique(edges, axis=0, return_counts=True)
    return int(np.sum(counts > 2))


def warning_count(warnings, kind) -> int:
    """Triangles of ``kind`` ("zero-area" or "duplicate") the scene's warnings report dropped."""
    import re

    total = 0
    for w in warnings:
        for m in re.finditer(r"(\d+) (zero-area|duplicate)", w):
            if m.group(2) == kind:
                total += int(m.group(1))
    return total


# -- the study ----------------------------------------------------------------------------------
def run(ctx: StudyContext) -> Report:
    plan = QUICK if ctx.quick else FULL
    report = Report("extremes", TITLE, command="")
    res = report.results
    cases: list[Case] = []
    # references 3, a 3, samples 2 + 2 × seeds + 1 (+1), bounces 2, reflectance 2 (+3), scale 3 + spheres,
    # closed box 3, sensors and sun 5, meshes 2
    ctx.plan(26 + 2 * plan.seeds + len(plan.sphere_radii) + plan.big_samples_paths + 3 * plan.cached_50
             + len(plan.memory_samples))
    t_start = time.perf_counter()

    # ---------------------------------------------------------------- group 1: settings
    room = room_scene()
    P, N = workplane()
    n = len(P)
    E_max_room = upper_bound(E_H / math.pi, max(RHO_ROOM))
    S_ref = plan.ref_samples
    refs = {}
    for B in sorted({1, 2, plan.a_small_bounces}):
        refs[B] = run_engine(ctx, f"reference, bounces {B}", room, P, N,
                             Options(accuracy=0.0, samples=S_ref, bounces=B, seed=101), E_max_room)
    refs[50] = run_engine(ctx, "reference, bounces 50", room, P, N,
                          Options(accuracy=0.0, samples=plan.ref50_samples, bounces=50, seed=101), E_max_room)
    ref_note = f"pure Monte Carlo, {S_ref} samples"
    analytic = opening_illuminance(P)
    g1 = "settings"

    opts = Options(accuracy=0.001, samples=plan.a_small_samples, bounces=plan.a_small_bounces)
    r = run_engine(ctx, "a = 0.001", room, P, N, opts, E_max_room)
    cases.append(compared(g1, "a = 0.001", describe(opts), r, refs[opts.bounces].E, ref_note))
    for a in (1.0, 10.0):
        r = run_engine(ctx, f"a = {a:g}", room, P, N, Options(accuracy=a, samples=256, bounces=2), E_max_room)
        cases.append(bounds_only(g1, f"a = {a:g}", "256 samples, 2 bounces", r, refs[2].E, ref_note,
                                 level_accuracy=[Options(accuracy=a).level_accuracy(k) for k in range(3)]))
    # samples 1 and 4: pure Monte Carlo, each sensor repeated (independent estimates), and
    # cached (a = 0.1) over several seeds
    for S in (1, 4):
        Pc, Nc = np.repeat(P, plan.copies, axis=0), np.repeat(N, plan.copies, axis=0)
        r = run_engine(ctx, f"samples {S}, a = 0", room, Pc, Nc, Options(accuracy=0.0, samples=S, bounces=2),
                       E_max_room)
        per_point = r.E.reshape(n, plan.copies).mean(axis=1)
        r_mean = Run(per_point, r.rgb, r.direct, r.stats, r.seconds, r.plausible, r.why)
        cases.append(compared(g1, f"samples = {S}, a = 0", f"2 bounces, each sensor {plan.copies}×", r_mean,
                              refs[2].E, ref_note, queries=len(Pc)))
    for S in (1, 4):
        means, records, rays, secs, ok, whys = [], 0, 0, 0.0, True, []
        for seed in range(plan.seeds):
            r = run_engine(ctx, f"samples {S}, a = 0.1, seed {seed}", room, P, N,
                           Options(accuracy=0.1, samples=S, bounces=2, seed=seed), E_max_room)
            means.append(r.E.mean())
            secs += r.seconds
            ok &= r.plausible
            whys.append(r.why)
            records += int(sum(r.stats.new_records))
            rays += int(r.stats.rays)
        errs = np.array(means) / refs[2].E.mean() - 1.0
        c = Case(g1, f"samples = {S}, a = 0.1", f"2 bounces, {plan.seeds} seeds", float(refs[2].E.mean()), ref_note,
                 float(np.mean(means)), float(errs.mean()), None, ok, records, rays, secs,
                 extra={"se": float(errs.std(ddof=1) / math.sqrt(len(errs))), "seed_errors": errs.tolist(),
                        "why": "; ".join(w for w in whys if w)})
        cases.append(c)
    # samples 65536
    m = plan.big_samples_points
    Pb, Nb = P[:m], N[:m]
    r = run_engine(ctx, "samples 65536, bounces 0", room, Pb, Nb, Options(samples=65536, bounces=0), E_max_room)
    cases.append(compared(g1, "samples = 65536", "a = 0.1, 0 bounces", r, analytic[:m], "closed form"))
    if plan.big_samples_paths:
        opts = Options(accuracy=0.0, samples=65536, bounces=1)
        r = run_engine(ctx, "samples 65536, a = 0, bounces 1", room, P, N, opts, E_max_room)
        cases.append(compared(g1, "samples = 65536", describe(opts), r, refs[1].E, ref_note))
    memory = [memory_probe(ctx, S) for S in plan.memory_samples]
    # bounces 0 and 50
    r = run_engine(ctx, "bounces 0", room, P, N, Options(samples=1024, bounces=0), E_max_room)
    cases.append(compared(g1, "bounces = 0", "a = 0.1, 1024 samples", r, analytic, "closed form"))
    r = run_engine(ctx, "bounces 50, a = 0", room, P, N, Options(accuracy=0.0, samples=256, bounces=50), E_max_room)
    cases.append(compared(g1, "bounces = 50, a = 0", "256 samples", r, refs[50].E,
                          f"pure Monte Carlo, {plan.ref50_samples} samples, 50 bounces, other seed"))

    # ---------------------------------------------------------------- group 2: reflectance
    g2 = "reflectance"
    black = room_scene(rho=(0.0, 0.0, 0.0))
    r0 = run_engine(ctx, "reflectance 0, bounces 0", black, P, N, Options(samples=1024, bounces=0), E_H)
    r8 = run_engine(ctx, "reflectance 0, bounces 8", black, P, N, Options(samples=1024, bounces=8), E_H)
    c = compared(g2, "reflectance 0", "a = 0.1, 1024 samples, 8 bounces", r8, analytic,
                 "closed form (sky through the opening)")
    c.extra.update(deeper_records=int(sum(r8.stats.records[1:])),
                   same_as_bounces_0=bool(np.array_equal(r8.rgb, r0.rgb)))
    c.plausible = c.plausible and c.extra["deeper_records"] == 0 and c.extra["same_as_bounces_0"]
    cases.append(c)

    if plan.cached_50:
        cases += cached_50_cases(ctx, room, P, N, E_max_room, refs[50], plan.ref50_samples)

    # ---------------------------------------------------------------- group 3: scale
    g3 = "scale"
    runs = {}
    for units, f in (("mm", 1000.0), ("m", 1.0), ("km", 1e-3)):
        sc = room_scene(scale=f, units=units)
        runs[units] = run_engine(ctx, f"room in {units}", sc, P, N, plan.scale_options, E_max_room)
    diff = max(float(np.max(np.abs(runs[u].E / runs["m"].E - 1.0))) for u in ("mm", "km"))
    cases.append(Case(g3, "room in mm and km", describe(plan.scale_options) + ", same seed", float(runs["m"].E.mean()),
                      "the same room in m", float(runs["km"].E.mean()), diff, SCALE_TOLERANCE,
                      all(x.plausible for x in runs.values()), int(sum(runs["km"].stats.new_records)),
                      int(runs["km"].stats.rays), sum(x.seconds for x in runs.values()),
                      extra={"mm_vs_m": float(np.max(np.abs(runs["mm"].E / runs["m"].E - 1.0))),
                             "km_vs_m": float(np.max(np.abs(runs["km"].E / runs["m"].E - 1.0)))}))
    sph = {}
    for radius in plan.sphere_radii:
        Ps, Ns, closed = sphere_sensors(radius)
        sph[radius] = run_engine(ctx, f"sphere r = {radius:g} m", sphere_scene(radius), Ps, Ns,
                                 Options(samples=plan.sphere_samples, bounces=1), upper_bound(0.0, 0.7, 1000.0))
        err = sph[radius].E / closed - 1.0
        c = Case(g3, f"sphere r = {radius:g} m", f"a = 0.1, {plan.sphere_samples} samples, 1 bounce",
                 float(closed.mean()), "§4 closed form (upper half)", float(sph[radius].E.mean()),
                 float(np.max(np.abs(err))), SPHERE_TOLERANCE, sph[radius].plausible,
                 int(sum(sph[radius].stats.new_records)), int(sph[radius].stats.rays), sph[radius].seconds,
                 extra={"mean_abs_error": float(np.mean(np.abs(err))), "kind": "largest error over the sensors"})
        cases.append(c)
    r_lo, r_hi = min(plan.sphere_radii), max(plan.sphere_radii)
    sdiff = float(np.max(np.abs(sph[r_lo].E / sph[r_hi].E - 1.0)))
    cases.append(Case(g3, f"sphere r = {r_lo:g} m vs {r_hi:g} m", "same seed", float(sph[r_hi].E.mean()),
                      f"the sphere of r = {r_hi:g} m", float(sph[r_lo].E.mean()), sdiff, SCALE_TOLERANCE,
                      True, 0, 0, 0.0))

    # ---------------------------------------------------------------- group 4: sensors and sun
    g4 = "sensors and sun"
    Pb = np.array([s[0] for s in BOX_SENSORS], float)
    Nb = np.array([s[1] for s in BOX_SENSORS], float)
    Nb /= np.linalg.norm(Nb, axis=1, keepdims=True)
    box = closed_box()
    E_max_box = upper_bound(E_H / math.pi, 0.7, E_DN)
    for label, opts in (("a = 0, 256 samples, 1 bounce", Options(accuracy=0.0, samples=256, bounces=1)),
                        (describe(plan.box_options), plan.box_options)):
        r = run_engine(ctx, f"closed box in daylight, {label}", box, Pb, Nb, opts, E_max_box)
        c = Case(g4, "closed box under sun and sky", label, 0.0, "exact: no light inside", float(r.E.max()),
                 float(r.E.max()), 0.0, r.plausible, int(sum(r.stats.new_records)), int(r.stats.rays), r.seconds,
                 absolute=True, extra={"per_sensor": {s[2]: float(e) for s, e in zip(BOX_SENSORS, r.E)},
                                       "why": r.why, "kind": "largest E over the sensors [lux]"})
        cases.append(c)
    dark = closed_box(sun=False, sky=False)
    r = run_engine(ctx, "closed box, no light", dark, Pb, Nb, plan.box_options, 0.0)
    c = Case(g4, "closed box, no light", describe(plan.box_options), 0.0, "exact", float(r.E.max()),
             float(r.E.max()), 0.0, r.plausible and r.stats.rays == 0 and sum(r.stats.records) == 0,
             int(sum(r.stats.new_records)), int(r.stats.rays), r.seconds, absolute=True,
             extra={"records": int(sum(r.stats.records)), "why": r.why})
    cases.append(c)

    rng = np.random.default_rng(7)
    k = plan.ground_points
    Pg = np.column_stack([rng.uniform(-5, 5, (k, 2)), np.zeros(k)])
    Ng = np.tile([0.0, 0.0, 1.0], (k, 1))
    cie = open_ground("cie-overcast")
    r = run_engine(ctx, "sensors on the ground, CIE overcast", cie, Pg, Ng, Options(samples=1024, bounces=2),
                   upper_bound(9.0 / 7.0 * E_H / math.pi, 0.2))
    cases.append(compared(g4, "sensor on a surface (z = 0)", "CIE overcast, a = 0.1, 1024 samples", r, E_H,
                          "exact: E_h", bias=0.002, note="stratified sampling of a smooth sky: < 0.2 %"))

    wall = big_wall()
    d = 1e-3
    r = run_engine(ctx, "1 mm from a 200 m wall", wall, np.array([[0.0, -d, 50.0]]), np.array([[0.0, 1.0, 0.0]]),
                   Options(samples=256, bounces=1), upper_bound(E_H / math.pi, WALL_RHO, E_DN))
    F_wall = wall_view_factor(d)
    expected = WALL_RHO * wall_illuminance() * F_wall
    cases.append(Case(g4, "facing a wall at 1 mm", "200 m wall, sun 30°, a = 0.1, 256 samples, 1 bounce",
                      expected, "ρ E_wall F (closed form)", float(r.E[0]), float(r.E[0] / expected - 1.0), 0.005,
                      r.plausible, int(sum(r.stats.new_records)), int(r.stats.rays), r.seconds,
                      extra={"epsilon": SELF_HIT_EPSILON * (50.0 + Integrator(wall, Options()).tracer.length_scale),
                             "view_factor": F_wall, "why": r.why}))

    for alt in (0.1, 90.0):
        sc = open_ground("uniform", {"altitude": alt, "azimuth": 135, "direct_normal_illuminance": E_DN})
        r = run_engine(ctx, f"sun at {alt:g}°", sc, Pg, Ng, Options(samples=256, bounces=2),
                       upper_bound(E_H / math.pi, 0.2, E_DN))
        if alt < 1:
            exact, centre = grazing_sun_illuminance(alt)
            direct = Run(r.direct, r.rgb, r.direct, r.stats, r.seconds, r.plausible, r.why)
            c = compared(g4, "grazing sun, 0.1°", f"horizontal sensors on the ground, {k}, direct part", direct,
                         exact, "disk cut by the horizon (closed form)", centre_cosine_model=centre)
            c.extra["sky_part_error"] = float(np.max(np.abs((r.E - r.direct) / E_H - 1.0)))
            c.plausible = c.plausible and c.extra["sky_part_error"] < 1e-9
            cases.append(c)
        else:
            expected = E_DN + E_H
            diff = float(np.max(np.abs(r.E / expected - 1.0)))
            cases.append(Case(g4, "sun at the zenith", f"horizontal sensors on the ground, {k}", expected,
                              "exact: E_dn + E_h", float(r.E.mean()), diff, 1e-9, r.plausible,
                              int(sum(r.stats.new_records)), int(r.stats.rays), r.seconds,
                              extra={"kind": "largest relative difference"}))
            Pv = Pg + [0.0, 0.0, 1.0]
            Nv = np.tile([0.0, -1.0, 0.0], (k, 1))
            rv = run_engine(ctx, "zenith sun on vertical sensors", sc, Pv, Nv, Options(samples=256, bounces=0),
                            upper_bound(E_H / math.pi, 0.2, E_DN))
            direct = Run(rv.direct, rv.rgb, rv.direct, rv.stats, rv.seconds, rv.plausible, rv.why)
            sliver = E_DN * 2.0 * sun_disk_radius() / (3.0 * math.pi)
            cases.append(compared(g4, "zenith sun, vertical sensor", f"{k} sensors 1 m up, direct part", direct,
                                  sliver, "half the disk in front: E_dn 2δ/(3π)"))

    # ---------------------------------------------------------------- group 5: degenerate input
    g5 = "degenerate geometry"
    clean, dirty, counts = degenerate_meshes()
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        (tmp / "clean.obj").write_text(_obj(clean))
        (tmp / "dirty.obj").write_text(_obj(dirty))
        scenes = {name: mesh_scene(f"{name}.obj", tmp) for name in ("clean", "dirty")}
        results = {name: run_engine(ctx, f"{name} mesh", sc, P, N, plan.mesh_options, E_max_room)
                   for name, sc in scenes.items()}
        (tmp / "nan.obj").write_text(_obj(clean).replace("v 0 0 0", "v nan 0 0", 1))
        (tmp / "flat.obj").write_text(_obj(dirty[-5:-3]))
        refusals = {}
        for name in ("nan", "flat"):
            try:
                mesh_scene(f"{name}.obj", tmp)
                refusals[name] = None
            except InputError as exc:
                refusals[name] = str(exc)
    found = {kind: warning_count(scenes["dirty"].warnings, kind) for kind in counts}
    same = bool(np.array_equal(results["dirty"].rgb, results["clean"].rgb))
    cases.append(Case(g5, "zero-area and duplicate triangles, non-manifold edge",
                      describe(plan.mesh_options), float(results["clean"].E.mean()),
                      "the clean mesh (exact: same triangles)", float(results["dirty"].E.mean()),
                      float(np.max(np.abs(results["dirty"].E - results["clean"].E))), 0.0,
                      results["dirty"].plausible and found == counts and len(scenes["dirty"].warnings) == 1,
                      int(sum(results["dirty"].stats.new_records)), int(results["dirty"].stats.rays),
                      results["dirty"].seconds, absolute=True,
                      extra={"warnings": scenes["dirty"].warnings, "counted": found, "injected": counts,
                             "non_manifold_edges": non_manifold_edges(clean), "identical": same,
                             "clean_warnings": scenes["clean"].warnings}))
    for name, what in (("nan", "a NaN corner"), ("flat", "only zero-area triangles")):
        msg = refusals[name]
        ok = msg is not None and "\n" not in msg
        cases.append(Case(g5, f"file with {what}", "loading", None, "refused with one line", None, None, None, ok,
                          extra={"message": msg}))

    # ---------------------------------------------------------------- option validation
    bad = [("samples", 0), ("samples", -4), ("bounces", -1), ("accuracy", -0.1), ("accuracy", float("nan")),
           ("accuracy", float("inf")), ("samples", 1.5), ("min_spacing", 0.0), ("seed", -1)]
    refused = []
    for key, value in bad:
        try:
            Options(**{key: value})
            refused.append((key, value, None))
        except InputError as exc:
            refused.append((key, value, str(exc)))

    # ---------------------------------------------------------------- the report
    seconds = time.perf_counter() - t_start
    order = ["settings", "reflectance", "scale", "sensors and sun", "degenerate geometry"]
    cases.sort(key=lambda c: order.index(c.group))
    write_report(report, plan, cases, refused, memory, seconds, ctx.quick)
    return report


def cached_50_cases(ctx, room, P, N, E_max_room, ref50: Run, ref_samples: int) -> list[Case]:
    """The full version's 50-bounce cache runs: the room against its pure Monte Carlo
    reference ``ref50``, and a closed box of reflectance 0.999 against the flux balance
    (cached, and pure Monte Carlo to confirm the balance)."""
    out = []
    opts = Options(samples=256, bounces=50)
    r = run_engine(ctx, "bounces 50, a = 0.1", room, P, N, opts, E_max_room)
    out.append(compared("settings", "bounces = 50", describe(opts), r, ref50.E,
                        f"pure Monte Carlo, {ref_samples} samples, 50 bounces", bias=CACHE_BIAS_50))
    box, Pq, Nq, pred, parts = lamp_box()
    E_max = upper_bound(LAMP_LUMINANCE, 0.999)
    opts = Options(accuracy=0.2, samples=64, bounces=50)
    r = run_engine(ctx, "ρ = 0.999 box, 50 bounces", box, Pq, Nq, opts, E_max)
    diff = float(r.E.mean() / pred - 1.0)
    out.append(Case("reflectance", "reflectance 0.999, closed box", describe(opts), pred,
                    "flux balance", float(r.E.mean()), diff, CACHE_BIAS_50, r.plausible, int(sum(r.stats.new_records)),
                    int(r.stats.rays), r.seconds,
                    extra={**parts, "direct_mean": float(r.direct.mean()), "min": float(r.E.min()),
                           "max": float(r.E.max()), "E_max": E_max, "why": r.why}))
    opts = Options(accuracy=0.0, samples=256, bounces=50)
    r = run_engine(ctx, "ρ = 0.999 box, 50 bounces, a = 0", box, Pq, Nq, opts, E_max)
    out.append(compared("reflectance", "reflectance 0.999, closed box", describe(opts), r, pred, "flux balance",
                        bias=LAMP_FRACTION_ALLOWANCE))
    return out


#: The ρ = 0.999 box: side 2 m, a horizontal two-sided lamp of 0.2 × 0.2 m and luminance
#: 1000 cd/m² at its centre; 6 × 6 sensors on each face, facing in.
LAMP_LUMINANCE = 1000.0
BOX_SIDE = 2.0
LAMP_SIDE = 0.2
#: The flux balance takes the lamp's share f of reflected flux from uniform radiosity;
#: f moves the 50-bounce sum by 8 %, so an error of 1/8 in f moves it 1 %.
LAMP_FRACTION_ALLOWANCE = 0.01


def lamp_box(rho=0.999, bounces=50, per_side=6):
    """(scene, P, N, predicted mean E, parts).  Flux balance: the lamp emits
    Φ = 2 π L A_l (two sides); every wall reflection returns ρ of the flux it receives,
    of which a fraction f = 2 A_l / A_w (reciprocity, uniform radiosity) falls back on the
    lamp and is absorbed.  After 0 … B reflections the walls have received
    Φ Σ_{k=0}^{B} (ρ (1 − f))^k, so their mean illuminance is that over A_w."""
    s, la = BOX_SIDE, LAMP_SIDE
    data = {"geometry": [{"shape": "box", "center": [0, 0, 0], "size": [s, s, s], "material": "wall"},
                         _rect([-la / 2, -la / 2, 0], [la, 0, 0], [0, la, 0], "lamp")],
            "materials": {"wall": {"type": "diffuse", "reflectance": rho},
                          "lamp": {"type": "light", "luminance": LAMP_LUMINANCE}}}
    scene = scene_from_dict(data, Path.cwd(), "extremes-lamp-box.toml")
    u = (np.arange(per_side) + 0.5) / per_side * s - s / 2
    U, V = [x.ravel() for x in np.meshgrid(u, u)]
    P, N = [], []
    for axis in range(3):
        for sign in (-1.0, 1.0):
            p = np.zeros((len(U), 3))
            p[:, axis] = sign * s / 2
            others = [i for i in range(3) if i != axis]
            p[:, others[0]], p[:, others[1]] = U, V
            nn = np.zeros((len(U), 3))
            nn[:, axis] = -sign
            P.append(p)
            N.append(nn)
    flux = 2.0 * math.pi * LAMP_LUMINANCE * la * la
    area = 6.0 * s * s
    f = 2.0 * la * la / area
    x = rho * (1.0 - f)
    mean = flux / area * (1.0 - x ** (bounces + 1)) / (1.0 - x)
    limit = flux / area / (1.0 - x)
    return scene, np.concatenate(P), np.concatenate(N), mean, {"flux": flux, "lamp_fraction": f,
                                                               "infinite_bounce_limit": limit,
                                                               "direct_exact": flux / area}


# -- writing ------------------------------------------------------------------------------------
def _cell_diff(c: Case) -> str:
    if c.diff is None:
        return "—"
    if c.absolute:
        return fmt(c.diff)
    text = pct(c.diff)
    se = c.extra.get("se")
    if se is not None and c.tol is None:
        text += f" ± {pct(se)}"
    return text


def _cell_tol(c: Case) -> str:
    if c.tol is None:
        return "—" if c.expected is None and c.result is None else "bounds only"
    if c.absolute:
        return fmt(c.tol) if c.tol else "0 (exact)"
    se = c.extra.get("se")
    if se is not None:
        bias = c.extra.get("bias_allowed", 0.0)
        return f"{pct(c.tol)} (4 SE{' + ' + pct(bias, 1) if bias else ''})"
    return pct(c.tol, 4) if c.tol < 1e-3 else pct(c.tol)


def write_report(report: Report, plan: Plan, cases: list[Case], refused, memory, seconds: float, quick: bool) -> None:
    res = report.results
    res["plan"] = {k: v.as_dict() if isinstance(v, Options) else v for k, v in plan.__dict__.items()}
    res["seconds"] = seconds
    res["cases"] = [{"group": c.group, "case": c.name, "settings": c.settings, "expected": c.expected,
                     "source": c.source, "result": c.result, "difference": c.diff,
                     "difference_is_absolute": c.absolute, "tolerance": c.tol, "plausible": c.plausible,
                     "passed": c.passed, "records": c.records, "rays": c.rays, "seconds": c.seconds, **c.extra}
                    for c in cases]
    res["passed"] = sum(c.passed for c in cases)
    res["failed"] = [c.name for c in cases if not c.passed]
    res["options_refused"] = [{"key": k, "value": v, "message": m} for k, v, m in refused]
    res["memory"] = memory
    by = {c.name + " | " + c.settings: c for c in cases}

    failing = "" if not res["failed"] else " (failing: " + ", ".join(res["failed"]) + ")"
    report.text(f"""
Every case below runs the engine at an extreme of a setting or of its input, and checks that it
finishes with finite, non-negative illuminance below the scene's physical upper bound, that the
record counts stay within what the placement guarantees, and that the value agrees with what it
must be: a closed form, or an independent pure Monte Carlo run (`accuracy = 0`) of the same case.
**{res['passed']} of {len(cases)} cases pass**{failing}.
This is the {'quick' if quick else 'full'} version; it took {seconds:.1f} s.
""")
    report.heading("What is checked")
    report.bullets([
        "**Plausible**: every RGB value finite and ≥ 0; illuminance ≤ E_max = max(E_dn + π L_max, "
        "E_dn/(1 − ρ_max)) (the maximum principle: no surface can outshine the brightest source when "
        "ρ < 1; without a sun E_max = π L_max, so in a room under a uniform sky of 10,000 lux no sensor "
        "may exceed 10,000 lux); records: at most one new record per query at every level, "
        "`queries[0]` = the sensors and `queries[k+1]` ≤ S_k × `new_records[k]` (S_k = M·N, the level's "
        "hemisphere rays per record).",
        "**Value**: against a closed form or a pure Monte Carlo reference. Where the difference is Monte "
        "Carlo noise, the mean over the sensors must lie within 4 standard errors (SE, from the spread of "
        "the sensor-by-sensor differences, which holds the noise of both runs) plus a stated bias "
        "allowance, 0 for unbiased estimators. Exact cases have tolerance 0.",
        "**Bounds only**: settings outside the range where the method is meant to be accurate "
        "(a ≥ 1, 1 or 4 samples with interpolation); their difference from the reference is reported, not tested.",
    ])
    report.heading("Results")
    rows = []
    for c in cases:
        rows.append([c.group, c.name, c.settings, "—" if c.expected is None else c.expected, c.source,
                     "—" if c.result is None else c.result, _cell_diff(c), _cell_tol(c),
                     "pass" if c.passed else "FAIL", c.records, c.rays, round(c.seconds, 2)])
    report.table(["group", "case", "settings", "expected [lux]", "source", "result [lux]", "difference",
                  "tolerance", "", "records", "rays", "s"], rows,
                 caption="One row per case. Expected and result are means over the case's sensors unless "
                         "stated; the difference is that of the means, relative, except for the exact cases "
                         "(absolute, lux) and the scale and sphere rows (largest relative difference at any sensor).")

    _settings_text(report, cases, plan)
    _memory_text(report, memory)
    _reflectance_text(report, cases)
    _scale_text(report, cases)
    _sensor_text(report, cases)
    _degenerate_text(report, cases)
    report.heading("Out-of-range settings")
    report.text("Each value below is refused by `Options` with a one-line `InputError` naming the key; the "
                "command line reports the same message with exit status 2 and writes nothing "
                "(`tests/test_cli.py::test_bad_option_values_are_refused` runs `--samples 0`, "
                "`--accuracy -1` and `--bounces x` through the command).")
    report.table(["key", "value", "message"], [[k, repr(v), m or "NOT REFUSED"] for k, v, m in refused])


def _find(cases, name, settings_start=""):
    for c in cases:
        if c.name == name and c.settings.startswith(settings_start):
            return c
    return None


def _settings_text(report, cases, plan):
    report.heading("Settings at their extremes")
    a_small = _find(cases, "a = 0.001")
    a1, a10 = _find(cases, "a = 1"), _find(cases, "a = 10")
    s1, s4 = _find(cases, "samples = 1, a = 0.1"), _find(cases, "samples = 4, a = 0.1")
    s1mc, s4mc = _find(cases, "samples = 1, a = 0"), _find(cases, "samples = 4, a = 0")
    big = _find(cases, "samples = 65536", "a = 0.1, 0")
    b50 = _find(cases, "bounces = 50")
    text = [
        f"The scene is a 4 × 6 × 3 m room lit through a 2 × 2 m opening in the middle of its ceiling by a "
        f"uniform sky of 10,000 lux (floor 0.2, walls 0.5, ceiling 0.7), with 12 sensors on the workplane. "
        f"Under a uniform sky the light through the opening has a closed form (the configuration factor of a "
        f"parallel rectangle), which checks `bounces = 0` and the sky part of every run.",
        f"**a = 0.001** made its own record for {fmt(a_small.records)} of "
        f"{fmt(sum(a_small.extra['queries_per_level']))} queries, so the cache becomes a branching Monte Carlo: "
        f"{fmt(a_small.rays)} rays for 12 sensors "
        f"({a_small.settings}). Its mean is "
        f"{pct(a_small.diff)} from the reference (SE {pct(a_small.extra['se'])}). Unlike `accuracy = 0`, whose "
        f"deeper levels follow one path ray per hit, a → 0 keeps the §3.4 sample series (S/2 per level), so its "
        f"cost grows as the product of the samples over the levels (records per level here: "
        f"{', '.join(fmt(x) for x in a_small.extra['records_per_level'])}, for "
        f"{', '.join(fmt(x) for x in a_small.extra['queries_per_level'])} queries). Use `accuracy = 0` for "
        f"Monte Carlo.",
        f"**a = 1 and a = 10** finish and stay within the bounds, but their values are wrong by "
        f"{pct(a1.diff)} and {pct(a10.diff)}: with the growth capped at {BOUNCE_ACCURACY_CAP:g}× the deeper "
        f"levels use a = {fmt(a1.extra['level_accuracy'][2])} and {fmt(a10.extra['level_accuracy'][2])}. Eq. 5's "
        f"ε = |P − P_i|/R_i + √(1 − N·N_i) is below a for normals 90° apart once a > 1 and for opposite normals "
        f"once a > √2, and the front test (Eq. 6) cannot reject opposite normals (N + N_i = 0), so records "
        f"on the ceiling answer queries on the floor. Nothing refuses or warns about a ≥ 1.",
        f"**1 and 4 samples**: pure Monte Carlo with each sensor repeated (independent estimates) agrees with "
        f"the reference within its noise: {pct(s1mc.diff)} (SE {pct(s1mc.extra['se'])}) at 1 sample and "
        f"{pct(s4mc.diff)} (SE {pct(s4mc.extra['se'])}) at 4. With interpolation (a = 0.1) over {plan.seeds} "
        f"seeds the mean "
        f"differs by {pct(s1.diff)} ± {pct(s1.extra['se'])} and {pct(s4.diff)} ± {pct(s4.extra['se'])} (mean ± "
        f"SE over the seeds; single seeds range from {pct(min(s1.extra['seed_errors']))} to "
        f"{pct(max(s1.extra['seed_errors']))} at 1 sample): a record from 1 ray holds either 0 or a whole "
        f"sky, and every sensor it covers inherits that. These runs are checked for bounds only.",
        f"**65536 samples** on {plan.big_samples_points} sensors with 0 bounces: {fmt(big.rays)} rays, "
        f"{pct(big.diff)} from the closed form (largest sensor {pct(big.extra['max_point_error'])}).",
    ]
    if b50 is not None:
        per = b50.extra["records_per_level"]
        text.append(f"**50 bounces, cached** (a = 0.1, 256 samples): {fmt(b50.records)} records, "
                    f"{fmt(b50.rays)} rays, {b50.seconds:.1f} s; {pct(b50.diff)} from a 50-bounce pure Monte "
                    f"Carlo reference (SE {pct(b50.extra['se'])}). A level is made whenever the sky can light "
                    f"it, whatever light it carries: records at levels 1, 10, 25 and 50: {fmt(per[1])}, "
                    f"{fmt(per[10])}, {fmt(per[25])}, {fmt(per[50])}, while the light reaching level k is at "
                    f"most ρ_max^k = 0.7^k of what enters the room ({pct(0.7 ** 10)} at k = 10). Nothing "
                    f"stops the levels whose light is negligible.")
    b50mc = _find(cases, "bounces = 50, a = 0")
    text.append(f"**50 bounces, pure Monte Carlo** ({b50mc.settings}): {fmt(b50mc.records)} records (one per "
                f"path vertex), {pct(b50mc.diff)} from the reference of another seed (SE {pct(b50mc.extra['se'])}).")
    big_mc = _find(cases, "samples = 65536", "a = 0,")
    if big_mc is not None:
        text.append(f"**65536 samples, pure Monte Carlo, 1 bounce**: {fmt(big_mc.rays)} rays, {pct(big_mc.diff)} "
                    f"from the reference (SE {pct(big_mc.extra['se'])}).")
    report.text("\n\n".join(text))


def memory_probe(ctx, samples: int) -> dict:
    """Peak memory of the roof-lit room at ``samples``, a = 0.1, 1 bounce, measured in a
    fresh process (its peak resident set, ``ru_maxrss``), with the run's rays and records."""
    import json
    import subprocess
    import sys

    code = ("import json, resource; from lbl_illum import Integrator, Options; "
            "from lbl_illum_studies import extremes as ex; P, N = ex.workplane(); "
            f"r = Integrator(ex.room_scene(), Options(samples={int(samples)}, bounces=1)).compute(P, N); "
            "print(json.dumps({'rss_mb': resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024, "
            "'rays': int(r.stats.rays), 'records': list(r.stats.new_records), 'seconds': r.stats.seconds}))")
    t0 = time.perf_counter()
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    probe = {"samples": int(samples), **json.loads(out.stdout.strip().splitlines()[-1])}
    opts = Options(samples=int(samples), bounces=1)
    probe["level1_rays"] = probe["records"][1] * rays_per_record(opts, 1)
    probe["wall_seconds"] = time.perf_counter() - t0
    ctx.step(f"memory probe, {samples} samples", None)
    return probe


def _memory_text(report, memory):
    if not memory:
        return
    report.heading("Memory and cost at large sample counts")
    last = memory[-1]
    level1 = last["records"][1] * rays_per_record(Options(samples=65536, bounces=1), 1)
    rate = last["rays"] / max(last["seconds"], 1e-9)
    machine_gb = os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES") / 1e9
    report.text(
        f"A cached run (a > 0) keeps, until a level is evaluated, the next level's queries (every diffuse hit, "
        f"68 bytes each) and, for the gradients, 32 bytes per hemisphere ray of the level; the temporary arrays "
        f"of a placement pass are bounded by tracing it in blocks of at most 2^20 rays. Measured on the "
        f"roof-lit room, a = 0.1, 1 bounce, each in a fresh process: "
        + "; ".join(f"{m['samples']} samples: {fmt(m['records'][1])} level-1 records × "
                    f"{fmt(rays_per_record(Options(samples=m['samples'], bounces=1), 1))} rays, "
                    f"{fmt(m['rays'])} rays in all, {fmt(m['seconds'])} s, peak {fmt(m['rss_mb'])} MB"
                    for m in memory)
        + f" (machine: {fmt(machine_gb)} GB). With `samples = 65536` the level-1 records get 32,768 samples "
        f"each: at least {fmt(last['records'][1])} records × 32,768 = {fmt(float(level1))} rays, about "
        f"{fmt(level1 / rate / 60)} minutes at the {fmt(rate / 1e6)} M rays/s measured here — a cost of time "
        f"that §3.4's halving of the samples per level does not prevent. The study therefore runs 65536 samples "
        f"with `bounces = 0` and with `accuracy = 0` (one path ray per hit below level 0), as in the table.")
    report.results["rays_65536_cached_lower_bound"] = level1
    report.results["machine_memory_gb"] = machine_gb


def _reflectance_text(report, cases):
    report.heading("Reflectance 0 and 0.999")
    c = _find(cases, "reflectance 0")
    text = [f"With every surface black, the hemisphere rays that hit a surface end with nothing, no deeper "
            f"level is made ({c.extra['deeper_records']} records below level 0), and the 8-bounce result is "
            f"{'bit-identical to' if c.extra['same_as_bounces_0'] else 'DIFFERENT from'} the 0-bounce one with the "
            f"same seed: the indirect light from surfaces is exactly 0. What is left, the sky through the "
            f"opening, is {pct(c.diff)} from the closed form (SE {pct(c.extra['se'])})."]
    box = _find(cases, "reflectance 0.999, closed box")
    if box is not None:
        e = box.extra
        mc = _find(cases, "reflectance 0.999, closed box", "a = 0,")
        text.append(
            f"**ρ = 0.999, 50 bounces**: a closed 2 m box lit by a 0.2 m two-sided lamp of 1000 cd/m² at its "
            f"centre (Φ = {fmt(e['flux'])} lm), 216 sensors on the walls. The flux balance gives the mean wall "
            f"illuminance after 50 reflections, {fmt(box.expected)} lux (the infinite-bounce limit is "
            f"{fmt(e['infinite_bounce_limit'])} lux; the lamp absorbs a fraction f = {fmt(e['lamp_fraction'])} "
            f"of each reflection). The cached run gives {fmt(box.result)} lux ({pct(box.diff)}), min "
            f"{fmt(e['min'])}, max {fmt(e['max'])}, all finite and below E_max = {fmt(e['E_max'])} lux. Pure "
            f"Monte Carlo of the same box gives {fmt(mc.result)} lux ({pct(mc.diff)}, SE {pct(mc.extra['se'])}), "
            f"which confirms the flux balance; the cached run's difference is the cache's own: interpolation "
            f"errors that accumulate over 50 levels, the bias the office study found over 8.")
    else:
        text.append("The ρ = 0.999 box with 50 bounces runs in the full version only; the "
                    "integrating-sphere study covers high reflectance in depth.")
    report.text("\n\n".join(text))


def _scale_text(report, cases):
    report.heading("Scale")
    c = _find(cases, "room in mm and km")
    sph = [x for x in cases if x.name.startswith("sphere r =") and "vs" not in x.name]
    pair = [x for x in cases if x.name.startswith("sphere r =") and "vs" in x.name][0]
    same = ("bit-identical illuminance to the run in metres" if c.extra["mm_vs_m"] == c.extra["km_vs_m"] == 0.0
            else f"the same illuminance as in metres to {fmt(c.extra['mm_vs_m'])} (mm) and "
                 f"{fmt(c.extra['km_vs_m'])} (km) relative")
    report.text(
        f"The roof-lit room read in millimetres and in kilometres gives, with the same seed, {same}: the "
        f"units are converted on reading, and the ray offsets scale with the coordinates and "
        f"the median edge length. The §4 sphere on a plane at radii "
        + ", ".join(f"{x.name[len('sphere r = '):]}" for x in sph)
        + f" gives the same values to {fmt(pair.diff)} between the extreme radii, and each is within "
        + ", ".join(pct(x.diff) for x in sph)
        + f" (largest sensor error) of the closed form E0 sin γ + ρ E0 (1 − sin γ)/2.")


def _sensor_text(report, cases):
    report.heading("Sensors and sun positions")
    boxes = [c for c in cases if c.name == "closed box under sun and sky"]
    wall = _find(cases, "facing a wall at 1 mm")
    graze = _find(cases, "grazing sun, 0.1°")
    zen_v = _find(cases, "zenith sun, vertical sensor")
    zen = _find(cases, "sun at the zenith")
    report.text(
        f"**Inside a closed box** under a sun of 80,000 lux and a sky of 10,000 lux, every sensor must read "
        f"exactly 0: on the floor, in the corners facing up, along the diagonal and into the wall, on the edges, "
        f"and 1 mm from a wall facing it or away from it. Largest value: "
        + " and ".join(f"{fmt(c.result)} lux ({c.settings})" for c in boxes)
        + f". In the dark box nothing is traced at all. Before this study a sensor in a floor corner saw the sun "
        f"and the sky: its ray origin, offset along its normal only, lay in the planes of both walls, and rays "
        f"slipped out between their triangles (fixed: `Tracer.sensor_origins`).\n\n"
        f"**Facing a wall at 1 mm**: the ray offset ε = 10⁻⁵ (|P|∞ + median edge) is "
        f"{fmt(wall.extra['epsilon'] * 1000)} mm beside a 200 m wall, so the sensor's rays started behind the "
        f"wall and saw the sky behind it before this study. Now the wall fills all but "
        f"{fmt(1.0 - wall.extra['view_factor'])} of the sensor's view and it reads {fmt(wall.result)} lux, "
        f"{pct(wall.diff, 3)} from ρ E_wall F. Sensors within {ON_SURFACE_FRACTION:g} ε of a surface in front "
        f"of them ({fmt(ON_SURFACE_FRACTION * wall.extra['epsilon'] * 1000)} mm here) count as lying on it, and "
        f"their rays start behind it.\n\n"
        f"**Grazing sun** (altitude 0.1°, E_dn = 80,000 lux): the 0.27° disk is cut by the horizon. The direct "
        f"part on the ground is {fmt(graze.result)} lux against {fmt(graze.expected)} lux for the part of the "
        f"disk above the horizon ({pct(graze.diff)}, SE {pct(graze.extra['se'])}); the disk centre's cosine "
        f"times the visible fraction, as the engine computed it before this study, gives "
        f"{fmt(graze.extra['centre_cosine_model'])} lux. The sky part is exact to "
        f"{fmt(graze.extra['sky_part_error'])}. The sky and the ground glow are split at the horizon, but a "
        f"sun disk below the horizon is not blocked by the glow: only modelled geometry blocks it.\n\n"
        f"**Sun at the zenith**: horizontal sensors read E_dn + E_h to {fmt(zen.diff)}; vertical ones get the "
        f"sliver of "
        f"the disk in front of them, {fmt(zen_v.result)} lux against E_dn 2δ/(3π) = {fmt(zen_v.expected)} lux.")


def _degenerate_text(report, cases):
    report.heading("Degenerate input geometry")
    c = _find(cases, "zero-area and duplicate triangles, non-manifold edge")
    e = c.extra
    nan = _find(cases, "file with a NaN corner")
    flat = _find(cases, "file with only zero-area triangles")
    report.text(
        f"The roof-lit room as an OBJ file with a fin along the foot of one wall, so that the floor–wall edge "
        f"has three faces ({plural(e['non_manifold_edges'], 'non-manifold edge')}), plus "
        f"{e['injected']['zero-area']} zero-area triangles (collinear corners, equal corners) and "
        f"{e['injected']['duplicate']} duplicates (same order, reversed, rotated). The scene reports "
        f"\"{e['warnings'][0] if e['warnings'] else 'no warning'}\": {e['counted']['zero-area']} zero-area and "
        f"{e['counted']['duplicate']} duplicates counted. After the clean-up the triangles are those of the "
        f"clean file, and the results are {'bit-identical' if e['identical'] else 'DIFFERENT'}. The non-manifold "
        f"edge draws no warning and needs none: surfaces are two-sided and the engine never uses connectivity, "
        f"and the run is finite and within the bounds.\n\n"
        f"A corner that is NaN is refused: \"{nan.extra['message']}\". A file of zero-area triangles only is "
        f"refused: \"{flat.extra['message']}\".")

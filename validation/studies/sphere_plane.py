"""The paper's §4 test: a sphere on a plane under overhead parallel light.

Ward, Rubinstein & Clear (1988), §4, checked the interpolation of the irradiance cache
(Eq. 5) on a sphere of radius 1 resting on an infinite plane, both Lambertian with
reflectance 0.7, lit by parallel light straight overhead; the illuminance on the sphere
from the direct light plus the first reflection has a closed form on the upper half and
a 1-D integral on the lower half (:mod:`sphere_plane_reference`).  They found the error
"relatively uniform over the sphere", the record density varying by orders of
magnitude, the mean error about a quarter and the maximum about twice "the estimated
error for the split sphere" (§3.2: < 1.4 a E), and the error linear in a.

This study repeats that test with the engine and with Radiance:

* the a-ladder: ``accuracy`` a ∈ {0.025 … 0.4} at 1024 samples, every record set
  answered both by the paper's Eq. 5 and by Eq. 5 over gradient-extrapolated values
  (the default; Ward & Heckbert 1992), plus ``accuracy = 0`` (a primary evaluation at
  every point: the Monte Carlo noise alone) at every 4th of the same points;
* the paper's sequential order (each query answered from the records that exist when it
  is reached, a new record only where none covers it) against the final record set and
  against the engine's wavefront placement;
* Radiance's ``rtrace -I`` on the same scene at the same ``-aa``/``-ad``/``-ab 1``, at
  its default ``-ar`` and at an ``-ar`` whose minimum record radius equals the engine's
  minimum spacing.

Illuminance is in lux, lengths in metres, angles in degrees unless stated.
"""

from __future__ import annotations

import math
import re
import subprocess
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

import numba
import numpy as np

from lbl_illum import Integrator, Options
from lbl_illum.engine import LevelRecords, RunStats, cell_counts, irradiance_gradients, limit_gradients, stratified_directions
from lbl_illum.photometry import luminance
from lbl_illum.io import radiance_programs
from lbl_illum.scene import scene_from_dict
from lbl_illum.daylight import SUN_SOLID_ANGLE

from . import sphere_plane_reference as ref
from .report import Report, StudyContext, error_summary, fmt, new_figure, pct

TITLE = "Sphere on a plane: the paper's §4 interpolation test against a closed form and Radiance"

# -- the scene -----------------------------------------------------------------------
#: Half-width [m] of the square standing in for the infinite plane (see the report:
#: the missing far plane is < 0.03 % of E at every point used; the bound falls as 1/W).
HALF_WIDTH = 5000.0
#: Elevation range of the query points [deg]: from GAMMA_MIN up to the top.  Below it the
#: illuminance falls towards 0 at the contact point and a 1024-sample evaluation's own
#: noise grows past 1 % of E (band mean; the probe run shows it in every report).
GAMMA_MIN = -50.0
#: Hemisphere samples of a primary evaluation (Eq. 2).
SAMPLES = 1024
#: The a-ladder (the paper does not list the values it used).
ACCURACIES = (0.025, 0.05, 0.1, 0.2, 0.3, 0.4)
#: The query points continue this far [deg] below GAMMA_MIN (not scored), so that points
#: near the range's lower edge have records on both sides, as on the paper's whole sphere.
GUARD = 10.0
#: Elevation bands of the tables and plots [deg].
BAND = 10.0
#: The quick version's bounds at a = 0.1, 1024 samples (asserted by the test suite).
QUICK_BOUNDS = {"mean": 0.02, "max": 0.06}
#: Radiance's sensor points sit this far [m] off the sphere along the normal, so that
#: its rays do not start exactly on the surface (effect on E: about 1e-4 relative).
RADIANCE_OFFSET = 1e-4
#: Radiance: 179 lm/W, and its RGB → luminance weights (Radiance's ``bright``).
RADIANCE_EFFICACY = 179.0
RADIANCE_RGB_WEIGHTS = (0.265, 0.670, 0.065)
#: The paper's split-sphere bound on the error of an admitted record (§3.2): 1.4 a E.
SPLIT_SPHERE_FACTOR = math.sqrt(2.0)
#: A run "interpolates" when it made records at no more than this fraction of the queries;
#: above it most answers are a record's own value and the error is Monte Carlo noise.
INTERPOLATING = 0.25


@dataclass(frozen=True)
class Plan:
    """What one version of the study computes."""

    points: int                   # query points on the band γ ≥ GAMMA_MIN of the whole sphere
    wedge: float                  # keep the points with azimuth in [0, wedge) [deg]
    mc_stride: int                # pure Monte Carlo at every mc_stride-th point
    accuracies: tuple             # the a-ladder
    sequential: tuple             # a values of the sequential-order runs
    orders: tuple                 # query orders of the sequential runs
    probe_points: int             # pure Monte Carlo points below GAMMA_MIN
    check_samples: int            # brute-force samples per elevation of the reference check
    radiance: bool                # run Radiance side by side


#: The quick version keeps the full version's point density (what decides how much
#: interpolation happens) on a quarter of the sphere, so it makes a quarter of the records.
FULL = Plan(points=10000, wedge=360.0, mc_stride=4, accuracies=ACCURACIES, sequential=(0.1, 0.2, 0.4),
            orders=("random", "rows"), probe_points=400, check_samples=400_000, radiance=True)
QUICK = Plan(points=10000, wedge=90.0, mc_stride=4, accuracies=(0.1,), sequential=(0.1,), orders=("random",),
             probe_points=100, check_samples=100_000, radiance=False)


# -- scene and points ----------------------------------------------------------------------
def scene_dict(half_width: float = HALF_WIDTH) -> dict:
    """The §4 scene as a scene-file dict: unit sphere centred (0, 0, 1) on a square plane
    of half-width ``half_width`` [m], both diffuse ρ = 0.7, sun at the zenith with
    E0 = 1000 lux, no sky, one diffuse reflection (``bounces = 1``)."""
    w = float(half_width)
    return {
        "units": "m",
        "geometry": [
            {"shape": "sphere", "center": [0, 0, 1], "radius": 1, "material": "white"},
            {"shape": "polygon", "vertices": [[-w, -w, 0], [w, -w, 0], [w, w, 0], [-w, w, 0]],
             "material": "white"},
        ],
        "materials": {"white": {"type": "diffuse", "reflectance": ref.RHO}},
        "sky": {"type": "none"},
        "sun": {"altitude": 90, "azimuth": 0, "direct_normal_illuminance": ref.E0},
        "settings": {"bounces": 1},
    }


def build_scene(half_width: float = HALF_WIDTH):
    return scene_from_dict(scene_dict(half_width), Path.cwd(), "sphere-plane")


def sphere_points(n: int, gamma_min: float = GAMMA_MIN, gamma_max: float = 90.0):
    """(points, normals): ``n`` points spread uniformly by area over the band of the
    unit sphere (centre (0, 0, 1)) between elevations ``gamma_min`` and ``gamma_max``
    [deg] (a Fibonacci spiral: heights uniform in sin γ, azimuths by the golden angle),
    with outward normals."""
    s0, s1 = math.sin(math.radians(gamma_min)), math.sin(math.radians(gamma_max))
    i = np.arange(n) + 0.5
    s = s0 + (s1 - s0) * i / n
    phi = math.pi * (3.0 - math.sqrt(5.0)) * np.arange(n)
    c = np.sqrt(np.maximum(0.0, 1.0 - s * s))
    N = np.stack([c * np.cos(phi), c * np.sin(phi), s], axis=1)
    return N + np.array([0.0, 0.0, 1.0]), N


def elevation(normals) -> np.ndarray:
    """Elevation γ [deg] of outward normals."""
    return np.degrees(np.arcsin(np.clip(np.asarray(normals)[:, 2], -1.0, 1.0)))


def band_edges(gamma_min: float = GAMMA_MIN) -> np.ndarray:
    return np.arange(gamma_min, 90.0 + 1e-9, BAND)


def band_errors(gamma, err, edges) -> dict:
    """Per elevation band: mean |err|, max |err|, bias and count."""
    idx = np.clip(np.searchsorted(edges, gamma, side="right") - 1, 0, len(edges) - 2)
    out = {"mean": [], "max": [], "bias": [], "count": []}
    for b in range(len(edges) - 1):
        e = err[idx == b]
        out["count"].append(int(len(e)))
        out["mean"].append(float(np.mean(np.abs(e))) if len(e) else None)
        out["max"].append(float(np.max(np.abs(e))) if len(e) else None)
        out["bias"].append(float(np.mean(e)) if len(e) else None)
    return out


def summary(values, reference, gamma) -> dict:
    """:func:`error_summary` plus the elevation [deg] of the largest |error|."""
    out = error_summary(values, reference)
    out["gamma_of_max"] = float(gamma[np.argmax(np.abs(np.asarray(values) / reference - 1.0))])
    return out


def band_density(gamma, edges) -> list:
    """Points per m² of sphere in each elevation band."""
    counts, _ = np.histogram(gamma, bins=edges)
    area = 2.0 * np.pi * np.diff(np.sin(np.radians(edges)))
    return (counts / area).tolist()


def span(lo: float, hi: float, percent: bool = False) -> str:
    """``lo–hi`` as the report prints a range (one value when they agree)."""
    f = (lambda v: pct(v, 1)) if percent else fmt
    return f(lo) if f(lo) == f(hi) else f"{f(lo)}–{f(hi)}"


def fit_line(x, y) -> dict:
    """Least-squares line y = intercept + slope·x and its R²."""
    x, y = np.asarray(x, float), np.asarray(y, float)
    A = np.column_stack([np.ones_like(x), x])
    (c0, c1), *_ = np.linalg.lstsq(A, y, rcond=None)
    pred = c0 + c1 * x
    ss = float(np.sum((y - y.mean()) ** 2))
    r2 = 1.0 - float(np.sum((y - pred) ** 2)) / ss if ss > 0 else 1.0
    return {"intercept": float(c0), "slope": float(c1), "r2": r2}


# -- the engine ------------------------------------------------------------------------------
def engine_run(scene, points, normals, accuracy: float, samples: int = SAMPLES, seed: int = 0) -> dict:
    """One calculation at ``accuracy``.  Its records are answered twice: by the paper's
    Eq. 5 and by Eq. 5 over gradient-extrapolated values (the placement of records does
    not depend on the interpolation rule, so both answers come from one record set)."""
    t0 = time.perf_counter()
    integ = Integrator(scene, Options(accuracy=accuracy, bounces=1, samples=samples, seed=seed))
    result = integ.compute(points, normals)
    seconds = time.perf_counter() - t0
    out = {"seconds": seconds, "stats": result.stats, "rays": int(result.stats.rays),
           "records": int(result.stats.records[0]), "direct": result.direct,
           "gradients": result.illuminance, "min_spacing": result.stats.min_spacing,
           "max_spacing": result.stats.max_spacing}
    lv = integ.cache.levels[0]
    out["record_gamma"] = elevation(lv.N[: lv.count].astype(np.float64))
    out["record_R"] = lv.R[: lv.count].astype(np.float64)
    if accuracy > 0:
        E, _, count = lv.lookup(points, normals, gradients=False)
        out["paper"] = luminance(result.direct + E)
        if np.any(count == 0):
            raise RuntimeError("a query point is not covered by the final record set")
    else:
        out["paper"] = result.illuminance
    return out


def sequential_run(scene, points, normals, accuracy: float, order: np.ndarray, spacing: tuple,
                   direct: np.ndarray, samples: int = SAMPLES, seed: int = 0) -> dict:
    """The paper's order (§3.2): the queries are taken one by one in ``order``; each is
    answered from the records that exist when it is reached (Eq. 5, and Eq. 5 over
    gradient-extrapolated values), and only a query no record covers makes a new record
    at its own position — a primary evaluation of Eq. 2 whose ``samples`` rays are
    traced in one batch (bounces = 1: their hits' value is the direct light there).
    R_i is the harmonic mean ray length (Eq. 4) clamped to ``spacing`` = (min, max) [m],
    the limits of the engine's run at the same a.  ``direct`` (n, 3) is the direct light
    at the points [lux], shared with the engine's run.

    Returns the sequential answers, the answers from the final record set (both rules),
    the record count, rays and seconds.
    """
    t0 = time.perf_counter()
    integ = Integrator(scene, Options(accuracy=accuracy, bounces=1, samples=samples, seed=seed))
    tracer, rays0 = integ.tracer, integ.tracer.rays_traced
    lo = np.minimum(scene.triangles.bounds[0], points.min(axis=0))
    hi = np.maximum(scene.triangles.bounds[1], points.max(axis=0))
    lv = LevelRecords(accuracy, 0.5 * (lo + hi), 0.5 * float(np.max(hi - lo)) * 1.01 + 1e-9, capacity=1024)
    m, n = cell_counts(samples)
    seq = {"paper": np.zeros((len(points), 3)), "gradients": np.zeros((len(points), 3))}
    # one query per lookup: numba's parallel launch would cost more than the lookup itself
    threads = numba.get_num_threads()
    numba.set_num_threads(1)
    try:
        _sequential_loop(integ, lv, points, normals, accuracy, order, (m, n), spacing, seq, seed)
    finally:
        numba.set_num_threads(threads)
    final_paper = lv.lookup(points, normals, gradients=False)[0]
    final_grad = lv.lookup(points, normals, gradients=True)[0]
    return {"sequential_paper": luminance(direct + seq["paper"]),
            "sequential_gradients": luminance(direct + seq["gradients"]),
            "final_paper": luminance(direct + final_paper), "final_gradients": luminance(direct + final_grad),
            "records": int(lv.count), "rays": int(tracer.rays_traced - rays0),
            "seconds": time.perf_counter() - t0}


def _sequential_loop(integ, lv, points, normals, accuracy, order, cells, spacing, seq, seed):
    """The loop of :func:`sequential_run`: answer or make a record, query by query."""
    m, n = cells
    S = m * n
    min_s, max_s = spacing
    tracer = integ.tracer
    for step, q in enumerate(order):
        P, N = points[q:q + 1], normals[q:q + 1]
        E, _, count = lv.lookup(P, N, gradients=False)
        if count[0] > 0:
            seq["paper"][q] = E[0]
            seq["gradients"][q] = lv.lookup(P, N, gradients=True)[0][0]
            continue
        rng = np.random.default_rng(np.random.SeedSequence([seed, 11, step]))
        dirs = stratified_directions(N, m, n, rng).reshape(-1, 3)
        origins = np.repeat(tracer.offset(P, N), S, axis=0)
        first_t, L, hits, _ = integ.trace_paths(origins, dirs, rng)
        if len(hits["ray"]):
            E_hit = integ.direct.illuminance(hits["P"], hits["Ns"], hits["Ng"], rng)
            np.add.at(L, hits["ray"], hits["weight"] * E_hit)
        Ei = np.pi / S * L.sum(axis=0)
        inv = float(np.sum(np.where(np.isfinite(first_t), 1.0 / np.maximum(first_t, 1e-300), 0.0)))
        R = float(np.clip(S / inv if inv > 0 else np.inf, min_s, max_s))
        rot, trans = irradiance_gradients(N, dirs.reshape(1, m, n, 3), L.reshape(1, m, n, 3),
                                          first_t.reshape(1, m, n))
        Gr, Gt = limit_gradients(Ei[None], rot, trans, np.array([accuracy * R]), accuracy)
        lv.add(P, N, np.array([R]), Ei[None], Gr, Gt)
        seq["paper"][q] = Ei
        seq["gradients"][q] = Ei


def query_order(points, normals, kind: str, seed: int = 0) -> np.ndarray:
    """``random``: a random permutation.  ``rows``: like an image's scanlines — rows of
    equal height (top to bottom, each about one point spacing tall), each row in order
    of azimuth."""
    n = len(points)
    if kind == "random":
        return np.random.default_rng(np.random.SeedSequence([seed, 12])).permutation(n)
    if kind == "rows":
        area = 2.0 * np.pi * (points[:, 2].max() - points[:, 2].min())
        row = np.floor(-points[:, 2] / math.sqrt(area / n)).astype(np.int64)
        phi = np.arctan2(normals[:, 1], normals[:, 0])
        return np.lexsort((phi, row))
    raise ValueError(kind)


# -- Radiance ----------------------------------------------------------------------------------
def radiance_scene(half_width: float = HALF_WIDTH) -> str:
    """The same scene in Radiance's language.  The sun is a ``source`` whose solid angle
    2π(1 − cos(angle/2)) equals the engine's 6.8e-5 sr, with radiance such that its normal
    irradiance × 179 lm/W = E0; ``plastic`` with no specular part is Lambertian."""
    half_angle = math.acos(1.0 - SUN_SOLID_ANGLE / (2.0 * math.pi))
    angle = 2.0 * math.degrees(half_angle)
    L = ref.E0 / RADIANCE_EFFICACY / SUN_SOLID_ANGLE
    w = half_width
    rho = ref.RHO
    return (f"void light sunlight\n0\n0\n3 {L:.9g} {L:.9g} {L:.9g}\n\n"
            f"sunlight source sun\n0\n0\n4 0 0 1 {angle:.9g}\n\n"
            f"void plastic white\n0\n0\n5 {rho} {rho} {rho} 0 0\n\n"
            "white sphere ball\n0\n0\n4 0 0 1 1\n\n"
            f"white polygon ground\n0\n0\n12 {-w} {-w} 0  {w} {-w} 0  {w} {w} 0  {-w} {w} 0\n")


class Radiance:
    """The scene compiled once (``oconv``), then ``rtrace -I`` runs."""

    def __init__(self, programs: dict, folder: Path, points, normals):
        self.p, self.folder = programs, folder
        (folder / "scene.rad").write_text(radiance_scene())
        with open(folder / "scene.oct", "wb") as out:
            subprocess.run([str(programs["bin"]["oconv"]), "scene.rad"], cwd=folder, env=programs["env"],
                           stdout=out, check=True)
        info = self._out(["getinfo", "-d", "scene.oct"]).split()
        self.cube_size = float(info[-1])                     # the octree cube's side [m]
        self.version = self._out(["rtrace", "-version"]).strip()
        defaults = self._out(["rtrace", "-defaults"])
        self.default_ar = int(re.search(r"-ar\s+(\d+)", defaults).group(1))
        lines = np.hstack([points + RADIANCE_OFFSET * normals, normals])
        (folder / "points.txt").write_text("\n".join(" ".join(f"{v:.10g}" for v in row) for row in lines) + "\n")

    def _out(self, args) -> str:
        return subprocess.run([str(self.p["bin"][args[0]]), *args[1:]], cwd=self.folder, env=self.p["env"],
                              capture_output=True, text=True, check=True).stdout

    def run(self, accuracy: float, ar: int | None, samples: int = SAMPLES, processes: int = 2) -> dict:
        """``rtrace -I -h -ab 1 -aa a -ad samples -as 0 [-ar ar] -n processes -af FILE``:
        illuminance [lux] at the points, records in the ambient file, wall seconds."""
        amb = self.folder / "run.amb"
        amb.unlink(missing_ok=True)
        cmd = [str(self.p["bin"]["rtrace"]), "-I", "-h", "-ab", "1", "-aa", f"{accuracy:g}", "-ad", str(samples),
               "-as", "0", "-n", str(processes)]
        if ar is not None:
            cmd += ["-ar", str(ar)]
        if accuracy > 0:
            cmd += ["-af", amb.name]
        cmd.append("scene.oct")
        t0 = time.perf_counter()
        with open(self.folder / "points.txt", "rb") as stdin:
            out = subprocess.run(cmd, cwd=self.folder, env=self.p["env"], stdin=stdin, capture_output=True,
                                 check=True).stdout
        seconds = time.perf_counter() - t0
        rgb = np.array(out.split(), dtype=np.float64).reshape(-1, 3)
        lux = RADIANCE_EFFICACY * rgb @ np.array(RADIANCE_RGB_WEIGHTS)
        records, radii = 0, np.zeros(0)
        if accuracy > 0 and amb.exists():
            text = self._out(["lookamb", "-h", "-d", amb.name])
            rows = [r.split() for r in text.splitlines() if r.strip()]
            records = len(rows)
            # lookamb -d: position, normal, u axis, level, weight, two radii, ...
            radii = np.array([[float(r[11]), float(r[12])] for r in rows]) if rows else np.zeros((0, 2))
            normals = np.array([[float(v) for v in r[3:6]] for r in rows]) if rows else np.zeros((0, 3))
        else:
            normals = np.zeros((0, 3))
        return {"illuminance": lux, "seconds": seconds, "records": records, "radii": radii,
                "record_gamma": elevation(normals) if len(normals) else np.zeros(0)}


# -- the study -----------------------------------------------------------------------------------
def run(ctx: StudyContext) -> Report:
    quick = ctx.quick
    plan = QUICK if quick else FULL
    report = Report("sphere-plane", TITLE, "")
    res = report.results
    res["settings"] = {"points_on_band": plan.points, "wedge_deg": plan.wedge, "mc_stride": plan.mc_stride,
                       "gamma_min_deg": GAMMA_MIN, "guard_deg": GUARD, "half_width_m": HALF_WIDTH,
                       "samples": SAMPLES, "accuracies": list(plan.accuracies), "bounces": 1,
                       "E0_lux": ref.E0, "reflectance": ref.RHO, "band_deg": BAND, "quick": quick}
    programs = radiance_programs() if plan.radiance else None
    n_radiance = 2 * len(plan.accuracies) if programs else 0
    ctx.plan(2 + len(plan.accuracies) + len(plan.sequential) * len(plan.orders) + n_radiance)

    scene = build_scene()
    # the points continue GUARD degrees below the range, at the same density, so that points
    # near its lower edge have records on both sides; only those in the range are scored
    low = GAMMA_MIN - GUARD
    n_all = int(round(plan.points * (1.0 - math.sin(math.radians(low))) / (1.0 - math.sin(math.radians(GAMMA_MIN)))))
    points, normals = sphere_points(n_all, low)
    azimuth = np.degrees(np.arctan2(normals[:, 1], normals[:, 0])) % 360.0
    keep = azimuth < plan.wedge
    points, normals = points[keep], normals[keep]
    gamma_all = elevation(normals)
    ev = gamma_all >= GAMMA_MIN                      # the scored points
    gamma = gamma_all[ev]
    n_queries, n_points = len(points), int(ev.sum())
    E_all = ref.illuminance(np.radians(gamma_all))
    E_ref = E_all[ev]
    edges = band_edges()
    centres = 0.5 * (edges[:-1] + edges[1:])

    def score(values):
        """Summary and per-band errors of illuminance at all queries, over the scored points."""
        v = np.asarray(values)[ev]
        return {**summary(v, E_ref, gamma), "bands": band_errors(gamma, v / E_ref - 1.0, edges)}

    # -- the reference and its checks --------------------------------------------------
    quad = ref.quadrature_error(np.radians(gamma))
    check_g = np.array([-50.0, -40.0, -30.0, -20.0, -10.0, -1.0, 0.0, 30.0, 60.0])
    check_E = ref.illuminance(np.radians(check_g))
    mc, se = ref.monte_carlo_illuminance(np.radians(check_g), plan.check_samples,
                                         np.random.default_rng(np.random.SeedSequence([0, 21])))
    z = (mc - check_E) / np.where(se > 0, se, np.inf)
    below = ref.illuminance(np.radians(-1e-9))[0]
    deficit = {w: ref.truncation_deficit(np.radians(gamma), w) / E_ref for w in (1000.0, 2000.0, HALF_WIDTH)}
    # the deficit falls as 1/W once W ≫ 1: scale from W = HALF_WIDTH, then confirm
    w_needed = HALF_WIDTH * float(deficit[HALF_WIDTH].max()) / 1e-3
    while np.max(ref.truncation_deficit(np.radians(gamma), w_needed) / E_ref) >= 1e-3:
        w_needed *= 1.01
    res["reference"] = {
        "E_at": {f"{g:g}": float(e) for g, e in zip(check_g, check_E)},
        "quadrature_max_relative_change": float(quad.max()),
        "monte_carlo_check": {"samples": plan.check_samples, "gamma_deg": check_g.tolist(),
                              "estimate": mc.tolist(), "standard_error": se.tolist(),
                              "max_abs_z": float(np.max(np.abs(z))),
                              "max_relative_difference": float(np.max(np.abs(mc / check_E - 1.0)))},
        "continuity_at_equator": {"lower_side": float(below), "closed_form": ref.RHO * ref.E0 / 2.0},
        "truncation_max_fraction": {f"{w:g}": float(d.max()) for w, d in deficit.items()},
        "truncation_worst_gamma_deg": float(gamma[np.argmax(deficit[HALF_WIDTH])]),
        "half_width_for_0.1_percent": w_needed,
        "E_min": float(E_ref.min()), "E_max": float(E_ref.max()),
    }

    # -- warm-up (untimed: numba compilation and embree start-up); the quick version's
    # seconds are not compared, so it skips this
    if not quick:
        engine_run(scene, points[:64], normals[:64], 0.1, samples=64)

    # -- noise probe below the range, and pure Monte Carlo at the points -------------------
    probe_P, probe_N = sphere_points(plan.probe_points, -80.0, GAMMA_MIN)
    probe_g = elevation(probe_N)
    probe = engine_run(scene, probe_P, probe_N, 0.0)
    ctx.step("pure Monte Carlo below the range", probe["stats"])
    probe_err = probe["gradients"] / ref.illuminance(np.radians(probe_g)) - 1.0
    probe_edges = np.arange(-80.0, GAMMA_MIN + 1e-9, BAND)
    res["probe_below_range"] = {"edges_deg": probe_edges.tolist(),
                                **band_errors(probe_g, probe_err, probe_edges),
                                "E_at_edges": ref.illuminance(np.radians(probe_edges)).tolist()}

    sub = np.flatnonzero(ev)[::plan.mc_stride]
    mc0 = engine_run(scene, points[sub], normals[sub], 0.0)
    ctx.step("pure Monte Carlo (a = 0)", mc0["stats"])
    err0 = mc0["gradients"] / E_all[sub] - 1.0
    res["monte_carlo"] = {**error_summary(mc0["gradients"], E_all[sub]), "points": len(sub),
                          "records": mc0["records"], "rays": mc0["rays"], "seconds": mc0["seconds"],
                          "bands": band_errors(gamma_all[sub], err0, edges)}

    # -- the a-ladder, each a followed by Radiance at the same a (similar machine load) -------
    ladder, rad_rows = {}, []
    rad, tmp = None, None
    if programs is not None:
        tmp = tempfile.TemporaryDirectory(prefix="lbl-illum-sphere-plane-")
        rad = Radiance(programs, Path(tmp.name), points, normals)
    try:
        for a in plan.accuracies:
            r = engine_run(scene, points, normals, a)
            ctx.step(f"a = {a:g}", r["stats"])
            ladder[a] = r
            if rad is None:
                continue
            ar_match = int(round(rad.cube_size / r["min_spacing"]))
            for label, ar in (("default", None), ("matched", ar_match)):
                q = rad.run(a, ar)
                ctx.step(f"Radiance a = {a:g}, -ar {ar or rad.default_ar}")
                rad_rows.append({"accuracy": a, "ar": ar or rad.default_ar, "ar_kind": label,
                                 "records": q["records"], "seconds": q["seconds"], **score(q["illuminance"]),
                                 "record_density": band_density(q["record_gamma"], edges),
                                 "median_radius": float(np.median(q["radii"][:, 0])) if len(q["radii"]) else None})
    finally:
        if tmp is not None:
            tmp.cleanup()

    res["ladder"] = []
    for a, r in ladder.items():
        row = {"accuracy": a, "records": r["records"], "rays": r["rays"], "seconds": r["seconds"],
               "records_per_query": r["records"] / n_queries,
               "min_spacing": r["min_spacing"], "max_spacing": r["max_spacing"]}
        for rule in ("paper", "gradients"):
            row[rule] = score(r[rule])
        dens = (np.array(band_density(r["record_gamma"], edges)) * 360.0 / plan.wedge).tolist()
        row["record_density"] = dens
        filled = [d for d in dens if d > 0]
        row["record_density_ratio"] = max(filled) / min(filled) if filled else None
        band = np.clip(np.searchsorted(edges, r["record_gamma"], side="right") - 1, 0, len(edges) - 2)
        inside = r["record_gamma"] >= GAMMA_MIN
        row["median_R"] = [float(np.median(r["record_R"][inside & (band == b)])) if np.any(inside & (band == b))
                           else None for b in range(len(edges) - 1)]
        res["ladder"].append(row)
    res["query_density"] = (np.array(band_density(gamma, edges)) * 360.0 / plan.wedge).tolist()
    spacing = (ladder[plan.accuracies[0]]["min_spacing"], ladder[plan.accuracies[0]]["max_spacing"])
    res["spacing"] = {"min": spacing[0], "max": spacing[1]}
    if rad is not None:
        ar_match = int(round(rad.cube_size / spacing[0]))
        res["radiance"] = {"version": rad.version, "cube_size": rad.cube_size, "default_ar": rad.default_ar,
                           "matched_ar": ar_match,
                           "min_radius": {"default": rad.cube_size / rad.default_ar, "matched": rad.cube_size / ar_match},
                           "max_radius": {"default": min(64 * rad.cube_size / rad.default_ar, 0.2 * rad.cube_size),
                                          "matched": min(64 * rad.cube_size / ar_match, 0.2 * rad.cube_size)},
                           "runs": rad_rows}
    else:
        res["radiance"] = None

    fits = {}
    interp_rows = [row for row in res["ladder"] if row["records_per_query"] <= INTERPOLATING]
    if len(plan.accuracies) >= 3:
        for subset, rows_ in (("all", res["ladder"]), ("interpolating", interp_rows)):
            if len(rows_) < 3:
                continue
            a_arr = np.array([row["accuracy"] for row in rows_])
            for rule in ("paper", "gradients"):
                for stat in ("mean", "max"):
                    y = np.array([row[rule][stat] for row in rows_])
                    fits[f"{subset}_{rule}_{stat}"] = {**fit_line(a_arr, y), "accuracies": a_arr.tolist()}
    res["fits"] = fits
    ratios = []
    for row in res["ladder"]:
        a = row["accuracy"]
        for rule in ("paper", "gradients"):
            ratios.append({"accuracy": a, "rule": rule,
                           "mean_over_a": row[rule]["mean"] / a, "max_over_a": row[rule]["max"] / a,
                           "mean_over_split_sphere": row[rule]["mean"] / (SPLIT_SPHERE_FACTOR * a),
                           "max_over_split_sphere": row[rule]["max"] / (SPLIT_SPHERE_FACTOR * a)})
    res["split_sphere_ratios"] = ratios

    # -- sequential order ---------------------------------------------------------------------
    res["sequential"] = []
    for a in plan.sequential:
        base = ladder[a] if a in ladder else engine_run(scene, points, normals, a)
        for kind in plan.orders:
            order = query_order(points, normals, kind)
            s = sequential_run(scene, points, normals, a, order, (base["min_spacing"], base["max_spacing"]),
                               base["direct"])
            ctx.step(f"sequential a = {a:g} ({kind})", RunStats(new_records=[s["records"]], rays=s["rays"]))
            row = {"accuracy": a, "order": kind, "records": s["records"], "rays": s["rays"],
                   "seconds": s["seconds"], "wavefront_records": base["records"],
                   "wavefront_rays": base["rays"], "wavefront_seconds": base["seconds"]}
            for key in ("sequential_paper", "sequential_gradients", "final_paper", "final_gradients"):
                row[key] = score(s[key])
            row["wavefront_paper"] = score(base["paper"])
            row["wavefront_gradients"] = score(base["gradients"])
            res["sequential"].append(row)

    res["settings"]["points"] = n_points
    res["settings"]["queries"] = n_queries
    res["findings"] = _verdicts(res)
    res["density_summary"] = _density_analysis(res)
    res["sequential_summary"] = _sequential_analysis(res["sequential"])
    if res["radiance"] is not None:
        _radiance_analysis(res, plan.accuracies)
    _write(report, res, plan, ladder, gamma, edges, centres, programs is not None, quick)
    return report


# -- the report ------------------------------------------------------------------------------------
def _write(report: Report, res: dict, plan: Plan, ladder: dict, gamma, edges, centres, have_radiance, quick):
    R = res["reference"]
    mc = res["monte_carlo"]
    report.heading("What was tested")
    report.text(
        f"Ward, Rubinstein & Clear (1988), §4: a sphere of radius 1 m resting on an infinite plane, both "
        f"Lambertian with reflectance {ref.RHO}, lit by parallel light straight overhead (E0 = {fmt(ref.E0)} lux "
        "on a surface facing it); the illuminance on the sphere from the direct light plus the first "
        "reflection (`bounces = 1`, no sky).  The scene is built in the study: the sphere primitive "
        f"(centre (0, 0, 1)) and a square plane of half-width {fmt(HALF_WIDTH)} m, sun at altitude 90° "
        "(a 6.8e-5 sr disc).  The query points are a Fibonacci spiral spread uniformly by area over the "
        f"sphere, with outward normals: {fmt(plan.points)} points scored, from elevation γ = {GAMMA_MIN:g}° to the "
        f"top, and {GUARD:g}° more below at the same density, queried but not scored, so that the points near the "
        "lower edge have records on both sides as on the paper's whole sphere"
        + (f".  The quick version keeps the points whose azimuth lies between 0° and {plan.wedge:g}° "
           f"({fmt(res['settings']['points'])} scored, {fmt(res['settings']['queries'])} queried): the same density "
           "on a quarter of the sphere, so it makes a quarter of the records" if plan.wedge < 360 else
           f" ({fmt(res['settings']['queries'])} queried)")
        + ".  γ is the angle above the horizontal through the centre (the paper measures it below, so its "
        "lower half is our γ < 0).  "
        + ("This is the **quick** version (a = 0.1 only, one sequential order, no Radiance) that the test suite "
           "runs." if quick else "This is the full version."))

    _summary(report, res, plan, quick)

    # -- reference --------------------------------------------------------------------------
    report.heading("The reference")
    report.text(
        "A point on the sphere is P = C + n, C = (0, 0, 1), n = (cos γ cos φ, cos γ sin φ, sin γ).  "
        "The plane's luminance after the light's first reflection is L = ρE0/π outside the sphere's shadow "
        "and 0 inside it; the shadow of overhead light is the vertical projection of the sphere, the unit "
        "disc D around the contact point.  A point on a convex body sees the whole half-space in front of "
        "its tangent plane and nothing behind it (the sphere cannot shade itself), so it sees the plane's "
        "half-plane H = {Q on z = 0 : (Q − P)·n > 0}.  With Φ(A) = ∫_A cos θ dω the projected solid angle "
        "of a region A seen from P:")
    report.equation(
        "E(γ) = E0·max(0, sin γ)  +  (ρE0/π)·[ Φ(H) − Φ(H ∩ D) ]\n"
        "Φ(H) = π(1 − sin γ)/2          (everything below the horizon, seen by a tilted surface)\n"
        "\n"
        "Upper half, γ ≥ 0: for Q in D, (Q − P)·n = q·n_xy − 1 − sin γ < cos γ − 1 − sin γ ≤ 0,\n"
        "  so H ∩ D is empty:   E = E0 sin γ + ρE0 (1 − sin γ)/2          (closed form)\n"
        "\n"
        "Lower half, γ < 0: H cuts D along the line x' = c = (1 + sin γ)/cos γ < 1 (x' along n's\n"
        "  azimuth), leaving a circular segment.  Its projected solid angle, by the contour form\n"
        "  of the form factor (Stokes; Sparrow 1963):\n"
        "    Φ(H ∩ D) = ½ | ∮ n·(r × dr)/|r|² |,   r = Q − P, around the segment's boundary\n"
        "  = chord term (Lambert's closed form for a straight edge: ½·angle(a,b)·n·(a×b)/|a×b|)\n"
        "  + arc term  ½ ∫_{−ψ0}^{ψ0} n·(r(ψ) × r'(ψ))/|r(ψ)|² dψ,  Q(ψ) = (cos ψ, sin ψ, 0), cos ψ0 = c\n"
        "  The arc integrand is smooth: Gauss–Legendre, nodes doubled from 32 until two estimates\n"
        "  agree to 1e-13 sr.   E = (ρE0/π)·[π(1 − sin γ)/2 − Φ(H ∩ D)]  → 0 at the contact point.")
    report.text(
        f"Accuracy of the lower-half integral: the largest last change of the quadrature, relative to E, "
        f"over the points used is {fmt(R['quadrature_max_relative_change'])} (target 1e-6).  "
        f"Continuity at the equator: the contour integral just below γ = 0 gives {fmt(R['continuity_at_equator']['lower_side'], 9)} lux, "
        f"the closed form {fmt(R['continuity_at_equator']['closed_form'], 9)} lux.  An independent brute-force check "
        f"(cosine-distributed rays from the point, counting those that reach the lit plane; "
        f"{fmt(R['monte_carlo_check']['samples'])} rays at each of {len(R['monte_carlo_check']['gamma_deg'])} elevations) "
        f"agrees within {fmt(R['monte_carlo_check']['max_abs_z'])} standard errors "
        f"(largest relative difference {pct(R['monte_carlo_check']['max_relative_difference'], 3)}).  "
        f"Over the points used E runs from {fmt(R['E_min'])} lux to {fmt(R['E_max'], 4)} lux.")
    report.table(["γ [°]"] + [k for k in R["E_at"]], [["E [lux]"] + list(R["E_at"].values())],
                 caption="Reference illuminance (direct + first reflection), E0 = 1000 lux, ρ = 0.7.")

    report.heading("How large the \"infinite\" plane must be", 3)
    tf = R["truncation_max_fraction"]
    report.text(
        "A square of half-width W misses the light of the plane beyond it.  That part is bounded by "
        "(ρE0/π)·Φ(H outside the inscribed disc of radius W), computed with the same contour integral.  "
        "For large W it is about (2ρE0/π)(1 + sin γ)cos γ / W: a tilted surface sees the distant plane "
        "right up to its horizon, so the deficit falls only as 1/W, not as 1/W².  Largest deficit over the "
        f"points, relative to E: {pct(tf['1000'], 3)} at W = 1000 m (the 2 km plane of "
        f"`examples/sphere_on_plane`), {pct(tf['2000'], 3)} at W = 2000 m, {pct(tf[f'{HALF_WIDTH:g}'], 3)} at "
        f"W = {fmt(HALF_WIDTH)} m (largest at γ = {fmt(R['truncation_worst_gamma_deg'])}°: "
        "a vertical surface sees most of the distant plane for the least light).  The 0.1 % limit needs W ≥ {fmt(R['half_width_for_0.1_percent'])} m; "
        f"this study uses W = {fmt(HALF_WIDTH)} m, a 10 km square.  The engine pays nothing for it: "
        "records far from the query points may grow in proportion to their distance (architecture.md, "
        "departure 2), and here all level-0 records lie on the sphere.  Radiance's `-ar` does feel it (below).")

    report.heading("Range of γ", 3)
    pb = res["probe_below_range"]
    probe_rows = [[f"{lo:g} to {lo + BAND:g}", pb["count"][i], pb["E_at_edges"][i], pb["mean"][i], pb["max"][i]]
                  for i, lo in enumerate(pb["edges_deg"][:-1])]
    report.text(
        "E → 0 at the contact point (γ = −90°), so relative errors there mean nothing.  Below the range "
        f"used, a probe of {fmt(plan.probe_points)} points between −80° and {GAMMA_MIN:g}°, each with its own "
        f"{SAMPLES}-sample evaluation (a = 0), shows the Monte Carlo noise alone, which no interpolation can "
        f"beat: its mean is {pct(pb['mean'][-1])} in the band just below {GAMMA_MIN:g}° and "
        f"{pct(res['monte_carlo']['bands']['mean'][0])} in the band just above, where the scored range starts and E "
        f"is {fmt(R['E_min'])} lux, {pct(R['E_min'] / (ref.RHO * ref.E0 / 2.0), 0)} of its value at the equator.")
    report.table(["γ band [°]", "points", "E at lower edge [lux]", "mean |error|", "max |error|"],
                 [[r[0], r[1], r[2], pct(r[3]), pct(r[4])] for r in probe_rows],
                 caption="Pure Monte Carlo (a = 0, 1024 samples) below the range used.")

    # -- the a-ladder ------------------------------------------------------------------------------
    report.heading("Error against a (the paper's Figure 8)")
    report.text(
        f"Every run uses {SAMPLES} samples per primary evaluation and the default spacing limits "
        f"(min {fmt(res['spacing']['min'])} m, max {fmt(res['spacing']['max'])} m, from the extent of the points).  "
        "Each record set is answered by the paper's Eq. 5 (*paper*) and by Eq. 5 over values extrapolated "
        "with each record's gradients (*gradients*, the default); where the records go does not depend on "
        "that choice, so both come from one run and share its records, rays and seconds.  Errors are "
        "relative to the reference; *mean* is the mean of |error| over the points, *max* the largest.  "
        f"Pure Monte Carlo at every {plan.mc_stride}th of the same points (a = 0, one {SAMPLES}-sample "
        f"evaluation per point, {fmt(mc['points'])} points, "
        f"{fmt(mc['records'])} records, {fmt(mc['rays'])} rays, {fmt(mc['seconds'])} s): mean {pct(mc['mean'])}, "
        f"max {pct(mc['max'])}, bias {pct(mc['bias'])} — the noise floor of a single evaluation.")
    rows = []
    for row in res["ladder"]:
        rows.append([fmt(row["accuracy"]), pct(row["paper"]["mean"]), pct(row["paper"]["max"]),
                     fmt(row["paper"]["gamma_of_max"]), pct(row["gradients"]["mean"]), pct(row["gradients"]["max"]),
                     fmt(row["gradients"]["gamma_of_max"]), pct(row["gradients"]["bias"]),
                     row["records"], fmt(row["records_per_query"]), row["rays"], fmt(row["seconds"])])
    rows.append(["0 (pure MC)", pct(mc["mean"]), pct(mc["max"]), "—", pct(mc["mean"]), pct(mc["max"]), "—",
                 pct(mc["bias"]), mc["records"], fmt(1.0), mc["rays"], fmt(mc["seconds"])])
    report.table(["a", "paper: mean", "paper: max", "at γ [°]", "gradients: mean", "gradients: max", "at γ [°]",
                  "gradients: bias", "records", "records / query", "rays", "seconds"], rows,
                 caption=f"{fmt(res['settings']['points'])} points, γ from {GAMMA_MIN:g}° to 90°; pure Monte Carlo "
                 f"at every {plan.mc_stride}th of them ({fmt(mc['points'])}).")

    fig, axes = new_figure(10, 4, ncols=2, sharey=True)
    for ax, rule in zip(axes, ("paper", "gradients")):
        for row in res["ladder"]:
            ax.plot(centres, [100 * (v or 0) for v in row[rule]["bands"]["mean"]], marker="o",
                    label=f"a = {row['accuracy']:g}")
        ax.plot(centres, [100 * (v or 0) for v in mc["bands"]["mean"]], "k--", label="a = 0 (noise floor)")
        ax.set_title(f"Eq. 5, {'as published' if rule == 'paper' else 'over gradient-extrapolated values'}")
        ax.set_xlabel("elevation γ [°]")
        ax.grid(alpha=0.3)
    axes[0].set_ylabel("mean |relative error| in 10° band [%]")
    axes[1].legend(fontsize=8)
    report.figure("error_vs_gamma", fig,
                  "Mean relative error against elevation for each a (like the paper's Figure 8).")

    # per-band table for the paper's rule
    band_rows = []
    for i, c in enumerate(centres):
        band_rows.append([f"{edges[i]:g} to {edges[i + 1]:g}", int(mc["bands"]["count"][i]),
                          pct(mc["bands"]["mean"][i])]
                         + [pct(row["paper"]["bands"]["mean"][i]) for row in res["ladder"]]
                         + [pct(row["gradients"]["bands"]["mean"][i]) for row in res["ladder"]])
    report.table(["γ band [°]", "points", "a = 0"] + [f"paper {row['accuracy']:g}" for row in res["ladder"]]
                 + [f"gradients {row['accuracy']:g}" for row in res["ladder"]], band_rows,
                 caption="Mean |relative error| per elevation band.")

    report.heading("Records against γ", 3)
    qd = res["query_density"]
    dens_rows = []
    for i in range(len(centres)):
        dens_rows.append([f"{edges[i]:g} to {edges[i + 1]:g}", qd[i]] + [row["record_density"][i] for row in res["ladder"]]
                         + [row["median_R"][i] for row in res["ladder"] if row["accuracy"] == 0.1])
    report.table(["γ band [°]", "points / m²"] + [f"records / m², a = {row['accuracy']:g}" for row in res["ladder"]]
                 + ["median R_i [m], a = 0.1" for row in res["ladder"] if row["accuracy"] == 0.1],
                 dens_rows, caption="Density of the query points and of the level-0 records on the sphere, and the "
                 "records' radius R_i (Eq. 4, clamped).")
    fig, ax = new_figure(6.4, 4)
    for row in res["ladder"]:
        ax.semilogy(centres, [d if d > 0 else np.nan for d in row["record_density"]], marker="o",
                    label=f"a = {row['accuracy']:g}")
    ax.semilogy(centres, qd, "k--", label="query points")
    ax.set_xlabel("elevation γ [°]")
    ax.set_ylabel("records per m² of sphere")
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=8)
    report.figure("record_density", fig, "Record density against elevation; the dashed line is the density "
                  "of the query points, the most records a run can make.")
    interp = [row for row in res["ladder"] if row["records_per_query"] <= INTERPOLATING]
    saturated = [row for row in res["ladder"] if row["records_per_query"] > INTERPOLATING]
    ratio_text = ", ".join(f"{fmt(row['record_density_ratio'])} at a = {row['accuracy']:g}" for row in interp)
    r01 = next((row for row in res["ladder"] if row["accuracy"] == 0.1), None)
    R_known = [v for v in (r01["median_R"] if r01 else []) if v is not None]
    orders = res["density_summary"]["orders_of_magnitude"]
    clamp_ratio = res["density_summary"]["largest_ratio_the_spacing_limits_allow"]
    report.text(
        "Records crowd where the plane is close (small harmonic mean distance R_i, Eq. 4: "
        + (f"the median R_i at a = 0.1 runs from {fmt(min(R_known))} m to {fmt(max(R_known))} m over the bands) "
           if R_known else ") ")
        + "and spread out on the upper half, whose rays mostly escape.  On a unit sphere Eq. 5 limits a record "
        "to |Δx| < a/(1/R_i + 1/√2) (the normal turns by |Δx| radians), so the density goes as (1/R_i + 1/√2)²; "
        f"with R_i between the spacing limits {fmt(res['spacing']['min'])} m and {fmt(res['spacing']['max'])} m it "
        f"can vary by a factor of {fmt(clamp_ratio)} at most.  "
        + (f"Densest band over sparsest band, for the runs that interpolate (records at ≤ {pct(INTERPOLATING, 0)} "
           f"of the queries): {ratio_text}.  " if interp else "")
        + ("The paper's \"orders of magnitude\" "
           + ("held here" if orders else "did not hold here: it comes from the region near the contact point, "
              "where R_i → 0, which this range of γ leaves out, and R_i cannot fall below the minimum spacing "
              f"({fmt(res['spacing']['min'])} m; architecture.md, departure 3)")
           + ".  ")
        + "The density cannot exceed that of the query points"
        + (f": at a = {', '.join(format(row['accuracy'], 'g') for row in saturated)} "
           f"records were made at more than {pct(INTERPOLATING, 0)} of the queries "
           f"({', '.join(pct(row['records_per_query'], 0) for row in saturated)}), so most answers there are a "
           "record's own value and the error is the Monte Carlo noise floor, not interpolation."
           if saturated else "; no run came close to that."))

    # -- linearity and the split-sphere estimate ------------------------------------------------------
    report.heading("Error against a, and the split-sphere estimate")
    report.text(
        "§3.2 bounds the change of E in the split sphere by Eq. 3b, ε ≤ E·(4/π·|Δx|/R + |Δξ|).  Eq. 5 admits a "
        "record when |Δx|/R + √(1 − N·N_i) < a, and since |Δξ| ≈ √2·√(1 − N·N_i) and 4/π < √2, an admitted "
        "record's split-sphere error is below √2·a ≈ 1.4a — the paper's \"the error is less than 1.4aE\".  "
        "That 1.4a is the estimate used here; ratios to a itself (the reading \"mean ≈ a/4, max ≈ 2a\") are "
        "given too.  The measured errors include the Monte Carlo noise of the records (floor: the a = 0 run).")
    ratio_rows = [[fmt(r["accuracy"]), r["rule"], fmt(r["mean_over_split_sphere"]), fmt(r["max_over_split_sphere"]),
                   fmt(r["mean_over_a"]), fmt(r["max_over_a"])] for r in res["split_sphere_ratios"]]
    report.table(["a", "rule", "mean / 1.4a", "max / 1.4a", "mean / a", "max / a"], ratio_rows,
                 caption="Measured error over the split-sphere estimate (paper: mean ≈ 0.25, max ≈ 2 of the estimate).")
    if res["fits"]:
        fit_rows = [[k.split("_")[0], k.split("_")[1], k.split("_")[2], ", ".join(f"{a:g}" for a in f["accuracies"]),
                     pct(f["intercept"]), fmt(f["slope"]), fmt(f["r2"])] for k, f in res["fits"].items()]
        report.table(["runs", "rule", "statistic", "a", "intercept", "slope (per unit a)", "R²"], fit_rows,
                     caption="Least-squares lines error = intercept + slope·a, over the whole ladder and over the "
                     f"runs that interpolate (records at ≤ {pct(INTERPOLATING, 0)} of the queries).")
        fig, axes = new_figure(10, 4, ncols=2)
        a_arr = np.array([row["accuracy"] for row in res["ladder"]])
        xs = np.linspace(0, a_arr.max(), 50)
        for ax, stat in zip(axes, ("mean", "max")):
            for rule, style in (("paper", "o"), ("gradients", "s")):
                y = [100 * row[rule][stat] for row in res["ladder"]]
                f = res["fits"].get(f"interpolating_{rule}_{stat}") or res["fits"][f"all_{rule}_{stat}"]
                line = ax.plot(a_arr, y, style, label=f"{rule}")[0]
                fx = np.linspace(min(f["accuracies"]), max(f["accuracies"]), 20)
                ax.plot(fx, 100 * (f["intercept"] + f["slope"] * fx), "-", color=line.get_color(), alpha=0.6)
            paper = 0.25 if stat == "mean" else 2.0
            ax.plot(xs, 100 * paper * SPLIT_SPHERE_FACTOR * xs, "k:", label=f"paper: {paper:g} × 1.4a")
            ax.plot(xs, 100 * paper * xs, "k--", alpha=0.5, label=f"{paper:g} × a")
            ax.axhline(100 * mc[stat], color="grey", lw=0.8, label="a = 0 (noise floor)")
            ax.set_xlabel("a")
            ax.set_ylabel(f"{stat} |relative error| [%]")
            ax.grid(alpha=0.3)
            ax.legend(fontsize=8)
        report.figure("error_vs_a", fig, "Mean and max relative error against a, with the lines fitted to the "
                      "runs that interpolate, and the paper's statements.")
    _findings(report, res)

    # -- sequential order -------------------------------------------------------------------------------
    report.heading("The paper's sequential order against the final record set")
    report.text(
        "The engine places each level's records in coarse-to-fine batches and answers every query from the "
        "complete record set (architecture.md, departure 1).  The paper answered each query when it was "
        "reached, from the records made so far, and made a record only at a query no record covered.  The "
        "study runs that order with the engine's own pieces (`Integrator.trace_paths`, "
        "`stratified_directions`, the direct light at the hits, `LevelRecords.add`/`lookup`, the same "
        "spacing limits), one record's hemisphere per batch, and answers the queries twice: when they are "
        "reached (*sequential*) and again from the final record set (*final*).  Orders: *random* (a random "
        "permutation) and *rows* (like an image's scanlines: rows of equal height top to bottom, each by "
        "azimuth).  *Wavefront* is the engine's run at the same a.")
    seq_rows = []
    for r in res["sequential"]:
        for rule in ("paper", "gradients"):
            seq_rows.append([fmt(r["accuracy"]), r["order"], rule,
                             pct(r[f"sequential_{rule}"]["mean"]), pct(r[f"sequential_{rule}"]["max"]),
                             pct(r[f"final_{rule}"]["mean"]), pct(r[f"final_{rule}"]["max"]),
                             pct(r[f"wavefront_{rule}"]["mean"]), pct(r[f"wavefront_{rule}"]["max"]),
                             r["records"], r["wavefront_records"]])
    report.table(["a", "order", "rule", "sequential: mean", "sequential: max", "final: mean", "final: max",
                  "wavefront: mean", "wavefront: max", "records (sequential)", "records (wavefront)"], seq_rows,
                 caption="Relative error of the sequential answers, of the same records answered at the end, "
                 "and of the engine's wavefront run.")
    summ = res.get("sequential_summary")
    if summ:
        parts = []
        for rule in ("paper", "gradients"):
            gain, wave = summ[rule]["sequential_over_final"], summ[rule]["final_over_wavefront"]
            label = "the paper's Eq. 5" if rule == "paper" else "gradients"
            parts.append(f"with {label}, answering each "
                         f"query when it is reached gives {span(*gain)} times the mean error of "
                         f"answering it from the final records, and the sequential records answered at the end give "
                         f"{span(*wave)} times the mean error of the wavefront run")
        text = "; ".join(parts)
        report.text(
            f"The wavefront placement made {span(*summ['extra_records'], percent=True)} more records than the "
            "sequential one: records placed together in a batch cannot take each other into account.  "
            + text[0].upper() + text[1:] + ".")

    # -- Radiance ----------------------------------------------------------------------------------------
    report.heading("Side by side with Radiance")
    if not have_radiance:
        why = ("the quick version skips it" if quick
               else "the `pyradiance` package (an optional extra: `pip install lbl-illum[radiance]`) is not "
               "installed, so this part was not run")
        report.text(f"Radiance was not run: {why}.")
        return
    _radiance_section(report, res, plan)


def _summary(report: Report, res: dict, plan: Plan, quick: bool) -> None:
    """The findings in brief, each with its numbers (details in the sections below)."""
    R, mc = res["reference"], res["monte_carlo"]
    row = next((r for r in res["ladder"] if r["accuracy"] == 0.1), res["ladder"][0])
    word = lambda ok: "held" if ok else "did not hold"   # noqa: E731
    items = [
        f"**Reference**: closed form on the upper half, contour integral on the lower half converged to "
        f"{fmt(R['quadrature_max_relative_change'])} of E; the {fmt(2 * HALF_WIDTH / 1000)} km square plane misses at most "
        f"{pct(R['truncation_max_fraction'][f'{HALF_WIDTH:g}'], 3)} of E.",
        f"**At a = {row['accuracy']:g}, {SAMPLES} samples**: mean {pct(row['gradients']['mean'])}, max "
        f"{pct(row['gradients']['max'])} with the default interpolation (gradients); mean {pct(row['paper']['mean'])}, "
        f"max {pct(row['paper']['max'])} with the paper's Eq. 5; {fmt(row['records'])} records for "
        f"{fmt(res['settings']['queries'])} queries.  Pure Monte Carlo (a = 0) at every {plan.mc_stride}th point: mean {pct(mc['mean'])}, "
        f"max {pct(mc['max'])}, bias {pct(mc['bias'])}.",
    ]
    F = res["findings"]
    if not quick and F["paper"]["interpolating_accuracies"]:
        p, g = F["paper"], F["gradients"]
        items.append(
            f"**The paper's findings** (Eq. 5 as published; runs that interpolate, a = "
            f"{_listing(p['interpolating_accuracies'])}): error linear in a — mean {word(p['linear_mean'])}, max "
            f"{word(p['linear_max'])}; mean ≈ ¼ of the split-sphere estimate 1.4a {word(p['1.4a']['mean_about_quarter'])} "
            f"(measured {span(*p['1.4a']['mean_ratio'])} × 1.4a, so the mean error is smaller than the paper found); "
            f"max ≈ 2 × 1.4a {word(p['1.4a']['max_about_twice'])} ({span(*p['1.4a']['max_ratio'])} × 1.4a, i.e. "
            f"{span(*p['a']['max_ratio'])} × a); error uniform over the sphere {word(p['uniform'])} (worst band "
            f"{span(*p['band_ratio'])} × the median band); record density varying by orders of magnitude "
            f"{word(res['density_summary']['orders_of_magnitude'])} "
            f"(densest over sparsest band ≤ {fmt(max(v or 0 for v in res['density_summary']['densest_over_sparsest'].values()))}).  "
            f"With gradients the errors are lower: mean {span(*g['a']['mean_ratio'])} × a, max "
            f"{span(*g['a']['max_ratio'])} × a.")
    seq = res.get("sequential_summary")
    if seq:
        items.append(
            f"**Sequential order**: the engine's batches made {span(*seq['extra_records'], percent=True)} more records "
            "than the paper's one-query-at-a-time order; answering each query when it is reached, as the paper did, "
            f"had {span(*seq['paper']['sequential_over_final'])} times the mean error (Eq. 5) of answering it from the "
            "final record set, as the engine does.")
    rad = res.get("radiance")
    if rad:
        S = rad["summary"]
        bias = S["default_lower_half_bias"]
        a0, a1 = min(bias), max(bias)
        items.append(
            f"**Radiance** ({rad['version']}): at its default `-ar {rad['default_ar']}` the "
            f"{fmt(2 * HALF_WIDTH / 1000)} km plane makes every record's radius at least "
            f"{fmt(rad['min_radius']['default'])} m, and its mean signed error on the lower half is {pct(bias[a0])} at "
            f"a = {a0:g} to {pct(bias[a1])} at a = {a1:g}; at `-ar {fmt(rad['matched_ar'])}` "
            f"(the same minimum spacing as ours) our mean error is lower at a = {_listing(S['ours_lower_mean_at_equal_a'])} "
            f"and Radiance is faster at a = {_listing(S['radiance_faster_at_equal_a'])}; at equal time our mean error is "
            f"lower at a = {_listing(S['ours_lower_mean_at_equal_time'])} of "
            f"{_listing(S['equal_time_compared'])}.")
    report.heading("Findings in brief")
    report.bullets(items)


def _density_analysis(res: dict) -> dict:
    """Record density over the bands: densest over sparsest band for the runs that
    interpolate, the median R_i range at a = 0.1, and the largest density ratio the spacing
    limits allow on a unit sphere, ((1/R_min + 1/√2) / (1/R_max + 1/√2))² (Eq. 5)."""
    interp = [row for row in res["ladder"] if row["records_per_query"] <= INTERPOLATING]
    saturated = [row for row in res["ladder"] if row["records_per_query"] > INTERPOLATING]
    r01 = next((row for row in res["ladder"] if row["accuracy"] == 0.1), None)
    R_known = [v for v in (r01["median_R"] if r01 else []) if v is not None]
    lo_s, hi_s = res["spacing"]["min"], res["spacing"]["max"]
    return {"interpolating": [row["accuracy"] for row in interp],
            "saturated": [row["accuracy"] for row in saturated],
            "densest_over_sparsest": {row["accuracy"]: row["record_density_ratio"] for row in interp},
            "orders_of_magnitude": any((row["record_density_ratio"] or 0) >= 100 for row in interp),
            "median_R_range_at_0.1": [min(R_known), max(R_known)] if R_known else None,
            "largest_ratio_the_spacing_limits_allow":
                ((1.0 / lo_s + 1.0 / math.sqrt(2.0)) / (1.0 / hi_s + 1.0 / math.sqrt(2.0))) ** 2}


def _sequential_analysis(rows: list) -> dict | None:
    """Ranges over the sequential runs: extra records of the wavefront placement, and the
    mean-error ratios sequential/final and final/wavefront per interpolation rule."""
    if not rows:
        return None
    extra = [r["wavefront_records"] / r["records"] - 1.0 for r in rows]
    summ = {"extra_records": [min(extra), max(extra)]}
    for rule in ("paper", "gradients"):
        gain = [r[f"sequential_{rule}"]["mean"] / r[f"final_{rule}"]["mean"] for r in rows]
        wave = [r[f"final_{rule}"]["mean"] / r[f"wavefront_{rule}"]["mean"] for r in rows]
        summ[rule] = {"sequential_over_final": [min(gain), max(gain)], "final_over_wavefront": [min(wave), max(wave)]}
    return summ


def _verdicts(res: dict) -> dict:
    """What held of the paper's §4 findings, per interpolation rule, over the runs that
    interpolate (records at ≤ INTERPOLATING of the queries).  Criteria: "linear" is a fitted
    line with R² ≥ 0.9 and a positive slope; "about a quarter" is 0.125–0.5 of the estimate
    and "about twice" 1–4 times it, at every such run, for the estimate 1.4a (§3.2) and for
    a itself; "uniform" is no 10° band's mean error above twice the median band's."""
    interp = [row for row in res["ladder"] if row["records_per_query"] <= INTERPOLATING]
    held = {}
    for rule in ("paper", "gradients"):
        verdict = {"interpolating_accuracies": [row["accuracy"] for row in interp]}
        for stat in ("mean", "max"):
            f = res["fits"].get(f"interpolating_{rule}_{stat}")
            verdict[f"linear_{stat}"] = bool(f) and f["r2"] >= 0.9 and f["slope"] > 0
        for name, factor in (("1.4a", SPLIT_SPHERE_FACTOR), ("a", 1.0)):
            mean_r = [row[rule]["mean"] / (factor * row["accuracy"]) for row in interp]
            max_r = [row[rule]["max"] / (factor * row["accuracy"]) for row in interp]
            verdict[name] = {"mean_ratio": [min(mean_r), max(mean_r)] if mean_r else None,
                             "max_ratio": [min(max_r), max(max_r)] if max_r else None,
                             "mean_about_quarter": bool(mean_r) and all(0.125 <= r <= 0.5 for r in mean_r),
                             "max_about_twice": bool(max_r) and all(1.0 <= r <= 4.0 for r in max_r)}
        ratios = []
        for row in interp:
            bands = [v for v in row[rule]["bands"]["mean"] if v is not None]
            ratios.append(max(bands) / float(np.median(bands)))
        verdict["band_ratio"] = [min(ratios), max(ratios)] if ratios else None
        verdict["uniform"] = bool(ratios) and all(r <= 2.0 for r in ratios)
        held[rule] = verdict
    return held


def _findings(report: Report, res: dict) -> None:
    """Plain statements of what held of the paper's findings (criteria: :func:`_verdicts`)."""
    ladder = res["ladder"]
    bounds = (f"Bounds the test suite asserts on the quick version (a = 0.1): mean ≤ {pct(QUICK_BOUNDS['mean'], 0)} "
              f"and max ≤ {pct(QUICK_BOUNDS['max'], 0)} with the default interpolation; mean ≤ "
              f"{pct(QUICK_BOUNDS['mean'], 0)} and max ≤ 2 × 1.4a = {pct(2 * SPLIT_SPHERE_FACTOR * 0.1, 0)} with the "
              "paper's Eq. 5.")
    if len(ladder) < 3:
        a = ladder[0]["accuracy"]
        g, p = ladder[0]["gradients"], ladder[0]["paper"]
        report.text(
            f"At a = {a:g}: mean {pct(p['mean'])} and max {pct(p['max'])} (paper's rule), mean {pct(g['mean'])} and "
            f"max {pct(g['max'])} (gradients), against the paper's ≈ {pct(0.25 * SPLIT_SPHERE_FACTOR * a)} and "
            f"≈ {pct(2 * SPLIT_SPHERE_FACTOR * a)} (a quarter and twice 1.4a).  " + bounds)
        return
    held = res["findings"]
    lines = []
    word = lambda ok: "**held**" if ok else "**did not hold**"   # noqa: E731
    for rule in ("paper", "gradients"):
        verdict = held[rule]
        f_mean = res["fits"].get(f"interpolating_{rule}_mean")
        f_max = res["fits"].get(f"interpolating_{rule}_max")
        if f_mean:
            fit_text = (f"mean error = {pct(f_mean['intercept'])} + {fmt(f_mean['slope'])}·a (R² = {fmt(f_mean['r2'])}), "
                        f"linear: {word(verdict['linear_mean'])}; max error = {pct(f_max['intercept'])} + "
                        f"{fmt(f_max['slope'])}·a (R² = {fmt(f_max['r2'])}), linear: {word(verdict['linear_max'])}.  ")
        else:
            fit_text = "fewer than three runs interpolate, no line fitted.  "
        v14, v1 = verdict["1.4a"], verdict["a"]
        lines.append(
            f"**{rule}** (runs that interpolate: a = "
            f"{', '.join(f'{r:g}' for r in verdict['interpolating_accuracies']) or 'none'}): {fit_text}"
            + (f"Against the estimate 1.4a: mean {span(*v14['mean_ratio'])} × 1.4a, \"about one fourth\" "
               f"{word(v14['mean_about_quarter'])}; max {span(*v14['max_ratio'])} × 1.4a, \"about twice\" "
               f"{word(v14['max_about_twice'])}.  Against a itself: mean {span(*v1['mean_ratio'])} × a "
               f"({word(v1['mean_about_quarter'])}), max {span(*v1['max_ratio'])} × a "
               f"({word(v1['max_about_twice'])}).  Error uniform over the sphere (worst 10° band's mean over the "
               f"median band's: {span(*verdict['band_ratio'])}): {word(verdict['uniform'])}."
               if verdict["interpolating_accuracies"] else ""))
    report.bullets(lines)
    mc = res["monte_carlo"]
    report.text(
        "Criteria: a line fitted to the runs that interpolate (records at no more than "
        f"{pct(INTERPOLATING, 0)} of the queries) with R² ≥ 0.9 and a positive slope; \"about one fourth\" = "
        "0.125–0.5 and \"about twice\" = 1–4 times the estimate at every such run; \"uniform\" = no band's mean "
        "error above twice the median band's at every such run.  The smaller a values make a "
        "record at most queries, so their errors sit on the Monte Carlo floor (a = 0: mean "
        f"{pct(mc['mean'])}, max {pct(mc['max'])}) and say nothing about interpolation.  " + bounds)


def _radiance_section(report: Report, res: dict, plan: Plan) -> None:
    rad = res["radiance"]
    ours = {row["accuracy"]: row for row in res["ladder"]}
    report.text(
        f"{rad['version']}, from the `pyradiance` wheel.  The same scene in Radiance's language (sun: a "
        "`source` of the same solid angle, radiance set so its normal irradiance × 179 lm/W = E0; sphere: "
        "`sphere`; plane: one `polygon`; both `plastic 0.7 0.7 0.7 0 0`), evaluated by "
        f"`rtrace -I -h -ab 1 -aa a -ad {SAMPLES} -as 0 -n 2 -af FILE` at the same points, each moved "
        f"{RADIANCE_OFFSET:g} m off the surface along its normal.  Illuminance = 179 × (0.265 R + 0.670 G + "
        "0.065 B); records = the lines of `lookamb -d FILE`; seconds = wall time of `rtrace` (both programs "
        "use 2 processes or threads; ours includes building the ray-tracing scene).  `rtrace` does not "
        "report its ray count.")
    report.text(
        "Radiance's interpolation is no longer the 1988 one: a record's two radii come from the Hessian of "
        "its samples' luminance (Schwarzhaupt, Jensen & Jarosz 2012), limited by its gradient, and are then "
        "clamped between minarad = (octree cube size)/`-ar` and maxarad = min(64·minarad, 0.2·cube size); "
        "a record serves a point within a·(its radii) and whose normal differs by less than 10° + a "
        "radians.  The octree cube is the scene's: here "
        f"{fmt(rad['cube_size'])} m, so the default `-ar {rad['default_ar']}` gives minarad = "
        f"{fmt(rad['min_radius']['default'])} m — every record is larger than the whole 1 m sphere, and only "
        f"the normal test limits it.  `-ar {fmt(rad['matched_ar'])}` makes minarad = "
        f"{fmt(rad['min_radius']['matched'])} m, equal to our minimum spacing, with maxarad = "
        f"{fmt(rad['max_radius']['matched'])} m (ours: {fmt(res['spacing']['max'])} m).")
    rows = []
    for a in plan.accuracies:
        o = ours[a]
        for rule in ("gradients", "paper"):
            rows.append([f"lbl_illum ({rule})", fmt(a), "—", pct(o[rule]["mean"]), pct(o[rule]["max"]),
                         fmt(o[rule]["gamma_of_max"]), pct(o[rule]["bias"]), o["records"], fmt(o["seconds"])])
        for r in rad["runs"]:
            if r["accuracy"] == a:
                rows.append([f"Radiance, -ar {r['ar_kind']}", fmt(a), fmt(r["ar"]), pct(r["mean"]), pct(r["max"]),
                             fmt(r["gamma_of_max"]), pct(r["bias"]), r["records"], fmt(r["seconds"])])
    report.table(["program", "a", "-ar", "mean |error|", "max |error|", "max at γ [°]", "bias", "records", "seconds"],
                 rows, caption="Equal a: the same points, reference and -aa/-ad/-ab.")

    eq_rows = []
    for e in rad["equal_time"]:
        run, best = e["run"], e["best_other_within_time"]
        eq_rows.append([run["program"], fmt(run["accuracy"]), fmt(run["seconds"]), pct(run["mean"]), pct(run["max"]),
                        best["program"] if best else "—", fmt(best["accuracy"]) if best else "—",
                        fmt(best["seconds"]) if best else "—", pct(best["mean"]) if best else "—",
                        pct(best["max"]) if best else "—"])
    report.table(["run", "a", "seconds", "mean", "max", "other program's best run in no more time", "its a",
                  "its seconds", "its mean", "its max"], eq_rows,
                 caption="Equal time: for each run, the run of the other program (Radiance with the matched -ar) "
                 "with the lowest mean error among those that took no longer; — where none did.")
    fig, axes = new_figure(10, 4, ncols=2)
    for ax, stat in zip(axes, ("mean", "max")):
        ax.loglog([ours[a]["seconds"] for a in plan.accuracies],
                  [100 * ours[a]["gradients"][stat] for a in plan.accuracies], "o-", label="lbl_illum, gradients")
        ax.loglog([ours[a]["seconds"] for a in plan.accuracies],
                  [100 * ours[a]["paper"][stat] for a in plan.accuracies], "o--", label="lbl_illum, paper")
        for kind, style in (("matched", "s-"), ("default", "^-")):
            runs = [r for r in rad["runs"] if r["ar_kind"] == kind]
            ax.loglog([r["seconds"] for r in runs], [100 * r[stat] for r in runs], style,
                      label=f"Radiance, -ar {runs[0]['ar']}")
        ax.set_xlabel("seconds")
        ax.set_ylabel(f"{stat} |relative error| [%]")
        ax.grid(alpha=0.3, which="both")
        ax.legend(fontsize=8)
    report.figure("radiance_error_vs_time", fig, "Error against time, each point one a of the ladder.")
    _radiance_findings(report, res, plan)


def _radiance_analysis(res: dict, accuracies) -> None:
    """Equal-a and equal-time comparisons with Radiance (into ``res["radiance"]``).  Equal
    time: for each run of one program, the run of the other (Radiance at the matched -ar)
    with the lowest mean error among those that took no longer."""
    rad = res["radiance"]
    ours = {row["accuracy"]: row for row in res["ladder"]}
    by = {(r["ar_kind"], r["accuracy"]): r for r in rad["runs"]}
    eq = []
    mine = [{"program": "lbl_illum (gradients)", "accuracy": a, "seconds": ours[a]["seconds"],
             "mean": ours[a]["gradients"]["mean"], "max": ours[a]["gradients"]["max"]} for a in accuracies]
    theirs = [{"program": f"Radiance, -ar {r['ar_kind']}", "accuracy": r["accuracy"], "seconds": r["seconds"],
               "mean": r["mean"], "max": r["max"]} for r in rad["runs"] if r["ar_kind"] == "matched"]
    for side, other in ((mine, theirs), (theirs, mine)):
        for run in side:
            within = [o for o in other if o["seconds"] <= run["seconds"]]
            eq.append({"run": run, "best_other_within_time": min(within, key=lambda o: o["mean"]) if within else None})
    rad["equal_time"] = eq
    lower = [i for i, e in enumerate(band_edges()[:-1]) if e < 0]
    per_record_ours = [ours[a]["seconds"] / ours[a]["records"] for a in accuracies]
    per_record_rad = [by[("matched", a)]["seconds"] / max(by[("matched", a)]["records"], 1) for a in accuracies]
    ours_side = [e for e in eq if e["run"]["program"].startswith("lbl_illum")]
    compared = [e for e in ours_side if e["best_other_within_time"] is not None]
    rad["summary"] = {
        "default_lower_half_bias": {a: float(np.mean([by[("default", a)]["bands"]["bias"][i] for i in lower]))
                                    for a in accuracies},
        "ours_lower_mean_at_equal_a": [a for a in accuracies if ours[a]["gradients"]["mean"] < by[("matched", a)]["mean"]],
        "ours_lower_max_at_equal_a": [a for a in accuracies if ours[a]["gradients"]["max"] < by[("matched", a)]["max"]],
        "radiance_faster_at_equal_a": [a for a in accuracies if ours[a]["seconds"] > by[("matched", a)]["seconds"]],
        "radiance_fewer_records_at_equal_a": [a for a in accuracies
                                              if by[("matched", a)]["records"] < ours[a]["records"]],
        "seconds_per_record_ours": per_record_ours, "seconds_per_record_radiance": per_record_rad,
        "seconds_per_record_ratio": [o / r for o, r in zip(per_record_ours, per_record_rad)],
        "our_runs": len(ours_side), "equal_time_compared": [e["run"]["accuracy"] for e in compared],
        "ours_lower_mean_at_equal_time": [e["run"]["accuracy"] for e in compared
                                          if e["run"]["mean"] < e["best_other_within_time"]["mean"]],
        "ours_lower_max_at_equal_time": [e["run"]["accuracy"] for e in compared
                                         if e["run"]["max"] < e["best_other_within_time"]["max"]],
    }


def _listing(values) -> str:
    return ", ".join(f"{a:g}" for a in values) or "none"


def _radiance_findings(report: Report, res: dict, plan: Plan) -> None:
    """Where each program is better, from the numbers of the two tables."""
    rad = res["radiance"]
    S = rad["summary"]
    d_bias_low = S["default_lower_half_bias"]
    lower_mean_ours, lower_max_ours = S["ours_lower_mean_at_equal_a"], S["ours_lower_max_at_equal_a"]
    faster, fewer_records = S["radiance_faster_at_equal_a"], S["radiance_fewer_records_at_equal_a"]
    per_record_ours, per_record_rad = S["seconds_per_record_ours"], S["seconds_per_record_radiance"]
    cost_ratio = S["seconds_per_record_ratio"]
    ours_better_time, ours_better_time_max = S["ours_lower_mean_at_equal_time"], S["ours_lower_max_at_equal_time"]
    listing = _listing
    more_records = [a for a in plan.accuracies if a not in fewer_records]
    report.bullets([
        "**Radiance's default -ar on a large plane.**  Its records are clamped to a radius of at least "
        f"{fmt(rad['min_radius']['default'])} m on a 1 m sphere, so one record reaches across the lower half, where "
        "the light changes fastest; only the normal test (10° + a) limits it.  Its mean signed error over the "
        "lower-half bands is " + ", ".join(f"{pct(v)} at a = {a:g}" for a, v in d_bias_low.items()) + ".  The engine "
        "has no such trap: its spacing limits come from the extent of the query points, not the scene.",
        f"**Equal a, matched -ar.**  Our mean error is lower at a = {listing(lower_mean_ours)}, our max error at "
        f"a = {listing(lower_max_ours)}.  Radiance makes fewer records at a = {listing(fewer_records)} and more at "
        f"a = {listing(more_records)}.  Its normal test admits up to 10° + a radians, Eq. 5 about √2·a radians for a "
        "record with a large R_i "
        f"(at a = 0.1: {fmt(math.degrees(0.1) + 10.0)}° against {fmt(math.degrees(math.sqrt(2.0) * 0.1))}°); the two "
        f"agree at a = {fmt(math.radians(10.0) / (math.sqrt(2.0) - 1.0))}, so at small a Radiance's records "
        "cover more of the sphere, and at large a its Hessian radii, not the normal test, set their size.  "
        f"Radiance is faster at a = {listing(faster)}.",
        f"**Cost per record** (seconds over records, same {SAMPLES} hemisphere rays): ours "
        f"{span(min(per_record_ours), max(per_record_ours))} s, Radiance's "
        f"{span(min(per_record_rad), max(per_record_rad))} s; ours is {span(min(cost_ratio), max(cost_ratio))} times "
        "Radiance's.",
        f"**Equal time.**  Of our {S['our_runs']} runs, {len(S['equal_time_compared'])} took at least as long as "
        "some Radiance run; "
        f"against Radiance's best run in no more time our mean error is lower at a = {listing(ours_better_time)} "
        f"and our max error at a = {listing(ours_better_time_max)}.",
    ])
    report.text(
        "Seconds were measured in the same study run on a shared 2-core machine; the ratios between the programs "
        "are what the tables can support, not the absolute times.")

"""Integrating sphere: closed-form interreflection over many bounces, up to ρ = 0.99,
and a closed box of reflectance 0.999 checked by flux balance.

**Scene.**  A closed hollow sphere of radius R with a Lambertian inner wall of
reflectance ρ, and at its centre a small sphere of radius r and uniform luminance L
(a ``light`` surface: it emits, and absorbs whatever reaches it).

**Direct light.**  A sphere of uniform luminance L seen from distance R subtends a cone
of half-angle α with sin α = r/R.  On a wall point facing the centre the cone is
centred on the normal, so (the view factor from a differential area to a sphere;
Modest, *Radiative Heat Transfer*, 3rd ed., 2013, ch. 4)

    E_0 = L ∫_cone cos θ dω = π L sin²α = π L (r/R)²   [lux].

The engine's emitter is an icosphere of 81,920 facets; its illuminance at each sensor
is computed here exactly by Lambert's contour integral over the facets that face the
sensor, E = L/2 Σ_edges γ_i (n · ĝ_i), ĝ_i the unit normal of the plane through the
sensor and edge i, γ_i the angle the edge subtends (Hottel & Sarofim, *Radiative
Transfer*, 1967; Baum, Rushmeier & Winget, "Improving radiosity solutions through the
use of analytically determined form-factors", SIGGRAPH 1989).

**Interreflection.**  The wall's exitance is uniform by symmetry.  A wall point sees
only the wall and the emitter; the view factor from it to the concentric emitter is
f = sin²α = (r/R)², so of the light a wall point reflects, the fraction f is absorbed
by the emitter and 1 − f lands on the wall, uniformly (the integrating-sphere property:
a uniform Lambertian wall of exitance M irradiates every wall point with M · (1 − f)).
Each bounce therefore multiplies the wall illuminance by q = ρ (1 − f):

    E_k = E_0 q^k,    E(N) = Σ_{k=0..N} E_k = E_0 (1 − q^{N+1}) / (1 − q),
    E_∞ = E_0 / (1 − q),    truncation  1 − E(N)/E_∞ = q^{N+1}.

``bounces = N`` in the engine is exactly E(N): level k's records hold the indirect
irradiance after N − k further bounces, V_k = E_0 Σ_{j=1..N−k} q^j.

**Ambient.**  At the bounce limit a hit contributes ρ/π · ``ambient`` (docs/design.md §3,
the paper's §3.4), so the deepest level holds q · A and the answer is
E(N) + q^{N+1} A: ``ambient = E_∞`` gives E_∞ at any N, and a guess A gives the bias
q^{N+1} (A − E_∞).

**Closed box (flux balance).**  A cube of side 2h with every wall of reflectance ρ and
the same small spherical emitter at its centre.  The emitter's flux Φ = π L A_e all
lands on the walls (area A_w), so the mean direct illuminance is Ē_0 = Φ / A_w.  Of
the flux Φ_j arriving on the walls at bounce j, ρ Φ_j is reflected and the fraction f_j
of it (the exitance-weighted mean view factor to the emitter) is absorbed by the
emitter; the rest arrives again:

    Φ_{j+1} = ρ (1 − f_j) Φ_j,    Ē(N) = Ē_0 Σ_{j=0..N} Π_{i<j} ρ (1 − f_i).

f_0 follows from the direct distribution, f_0 = ∫ E_d² dA / (π L Φ); the later f_j
come from the exitance distribution of each bounce, computed here by a Nyström
iteration of the radiosity equation on Gauss–Legendre points (independent of the
engine); for uniform exitance f = A_e / A_w.  The mean over the walls is taken from
the engine's sensors on 6 × 6 Gauss–Legendre points per wall.

**Noise.**  The direct step gives a light surface in full view its closed form
(emitters.py: the true sphere, π L sin²α cos θ_c), and nothing stands between the wall
and the emitter, so the direct light at the sensors and at every hemisphere-ray hit has
no noise at all.  The records' noise is that of their hemisphere rays alone: about
(r/R)² of them end on the emitter, which absorbs.  (Before, 16 shadow rays uniform over
the emitter's area left σ_1 ≈ 1.46 per ray, 40 % at the worst sensor.)

**Measured** (``run``): the mean over the wall sensors for a ladder of bounce counts
per ρ; every diffuse level of the deepest run against V_k; rays and records per level
(the §3.4 series) with bounce scaling on and off; ``ambient`` at the bounce limit; at
ρ = 0.99 the spread over seeds, with R_i held fixed and in pure Monte Carlo; the box at
two accuracies and in pure Monte Carlo.  ``QUICK`` is the reduced set the test suite
runs, with the bounds stated below.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from lbl_illum import Integrator, Options
from lbl_illum.scene import scene_from_dict, sphere_triangles
from lbl_illum.options import BOUNCE_ACCURACY_CAP, BOUNCE_ACCURACY_FACTOR, MIN_DEEP_SAMPLES
from lbl_illum.photometry import luminance

from .report import Report, StudyContext, fmt, new_figure, pct

TITLE = "Integrating sphere: closed-form interreflection over many bounces"

#: Sphere radius R [m], emitter radius r [m], emitter luminance L [cd/m²].
WALL_RADIUS = 1.0
LAMP_RADIUS = 0.1
LAMP_LUMINANCE = 1000.0
#: Half side h [m] and wall reflectance of the closed box.
BOX_HALF = 1.5
BOX_REFLECTANCE = 0.999
#: Bounds the quick version asserts (tests/studies/test_integrating_sphere.py); the
#: report states them and whether they held.
#: ρ = 0.9 after 46 bounces (truncation q^47 = 0.44 %): sensor mean within 2 % of E_∞.
CONVERGED_RHO, CONVERGED_BOUNCES, CONVERGED_BOUND = 0.9, 46, 0.02
#: ρ = 0.9 after k = 1, 2, 3 bounces: mean indirect part within 4 % of E_0 Σ_{j=1..k} q^j
#: (the direct step's noise through 128 sensors × 256 rays is σ ≈ 0.8 %).
PER_BOUNCE_BOUND = 0.04
#: ambient = E_∞ at the bounce limit: sensor mean within 2 % of E_∞.
AMBIENT_BOUND = 0.02
#: Every level's mean record value within 5 % of V_k (the direct light at its hits is exact).
LEVEL_BOUND = 0.05
#: Direct step at every sensor within this of π L (r/d)², d the sensor's distance from the centre.
DIRECT_BOUND = 1e-6
#: Closed box ρ = 0.999, 50 bounces, pure Monte Carlo: wall mean within 2 % of the flux balance.
BOX_MC_BOUND = 0.02
#: Gauss–Legendre points per side of each box wall (6 × 6: the direct illuminance's
#: wall mean is integrated to 1.2e-4 by them).
BOX_GAUSS = 6


@dataclass
class Plan:
    """What one version of the study runs."""

    sensors: int                 # sensors on the sphere wall
    accuracy: float              # a of the sphere runs
    samples: int                 # first-level samples of the sphere runs
    ladders: dict                # ρ -> bounce counts run at the sensors
    contour_sensors: int         # sensors whose exact E_0 is integrated over the facets
    ambient_rho: float
    ambient_bounces: int
    ambient_factors: tuple       # ambient = factor · E_∞
    bias_rho: float | None           # sphere runs repeated over seeds and variants ...
    bias_bounces: int                # ... at this many bounces
    bias_runs: tuple                 # (label, option overrides, seeds); {} = the ladder's settings
    scaling_rho: float | None        # sphere run with bounce_scaling off
    scaling_bounces: int
    box_runs: tuple              # (label, accuracy, samples, bounce_scaling, bounce counts)
    box_nystrom: int             # Gauss points per side of a wall in the Nyström reference


QUICK = Plan(
    sensors=128, accuracy=0.2, samples=256,
    ladders={0.9: (1, 2, 3, 46)},
    contour_sensors=8,
    ambient_rho=0.9, ambient_bounces=3, ambient_factors=(1.0,),
    bias_rho=None, bias_bounces=0, bias_runs=(),
    scaling_rho=None, scaling_bounces=0,
    box_runs=(("pure Monte Carlo (a = 0)", 0.0, 32, True, (50,)),),
    box_nystrom=12,
)

FULL = Plan(
    sensors=128, accuracy=0.2, samples=256,
    ladders={0.2: (1, 2, 8), 0.5: (1, 4, 16), 0.8: (1, 4, 8, 16, 32),
             0.9: (1, 2, 3, 46), 0.95: (1, 8, 32, 110), 0.99: (1, 4, 32, 100, 300)},
    contour_sensors=64,
    ambient_rho=0.99, ambient_bounces=4, ambient_factors=(1.0, 0.5, 2.0),
    bias_rho=0.99, bias_bounces=100,
    bias_runs=(("cache (the ladder's settings)", {}, (0, 1, 2)),
               ("cache, R_i fixed at 1 m (min = max spacing)", {"min_spacing": 1.0, "max_spacing": 1.0}, (0, 1, 2)),
               ("pure Monte Carlo (a = 0)", {"accuracy": 0.0}, (0,))),
    scaling_rho=0.8, scaling_bounces=8,
    box_runs=(("a = 0.1 (default)", 0.1, 256, True, (1, 5, 50)),
              ("a = 0.2", 0.2, 256, True, (1, 5, 50)),
              ("pure Monte Carlo (a = 0)", 0.0, 256, True, (5, 50))),
    box_nystrom=20,
)


# -- scenes and sensors ------------------------------------------------------------------
def sphere_scene(reflectance: float):
    """The integrating sphere: wall of radius R (reflectance ρ), emitter of radius r at the centre."""
    data = {"units": "m",
            "geometry": [{"shape": "sphere", "center": [0, 0, 0], "radius": WALL_RADIUS, "material": "wall"},
                         {"shape": "sphere", "center": [0, 0, 0], "radius": LAMP_RADIUS, "material": "lamp"}],
            "materials": {"wall": {"type": "diffuse", "reflectance": reflectance},
                          "lamp": {"type": "light", "luminance": LAMP_LUMINANCE}},
            "sky": {"type": "none"}}
    return scene_from_dict(data, Path("."), "integrating-sphere")


def box_scene(reflectance: float):
    """The closed cube of side 2h (reflectance ρ) with the same emitter at its centre."""
    data = {"units": "m",
            "geometry": [{"shape": "box", "center": [0, 0, 0], "size": [2 * BOX_HALF] * 3, "material": "wall"},
                         {"shape": "sphere", "center": [0, 0, 0], "radius": LAMP_RADIUS, "material": "lamp"}],
            "materials": {"wall": {"type": "diffuse", "reflectance": reflectance},
                          "lamp": {"type": "light", "luminance": LAMP_LUMINANCE}},
            "sky": {"type": "none"}}
    return scene_from_dict(data, Path("."), "closed-box")


def wall_sensors(n: int):
    """n points spread evenly over the sphere wall (Fibonacci lattice), normals to the centre."""
    i = np.arange(n) + 0.5
    z = 1.0 - 2.0 * i / n
    phi = np.pi * (1.0 + 5.0 ** 0.5) * i
    s = np.sqrt(1.0 - z * z)
    u = np.column_stack([s * np.cos(phi), s * np.sin(phi), z])
    return WALL_RADIUS * u, -u


def box_sensors(n: int):
    """Gauss–Legendre n × n points on each inner wall of the cube, inward normals, and
    their quadrature weights for the mean over all six walls (weights sum to 1)."""
    g, w = np.polynomial.legendre.leggauss(n)
    X, Y = np.meshgrid(g * BOX_HALF, g * BOX_HALF)
    W = (np.outer(w, w) / 4.0).ravel() / 6.0
    pts, nrm, wts = [], [], []
    for axis in range(3):
        others = [c for c in range(3) if c != axis]
        for sign in (-1.0, 1.0):
            p = np.zeros((X.size, 3))
            p[:, others[0]], p[:, others[1]], p[:, axis] = X.ravel(), Y.ravel(), sign * BOX_HALF
            nv = np.zeros((X.size, 3))
            nv[:, axis] = -sign
            pts.append(p), nrm.append(nv), wts.append(W)
    return np.concatenate(pts), np.concatenate(nrm), np.concatenate(wts)


# -- exact values ------------------------------------------------------------------------
def polygon_illuminance(points, normals, triangles, L):
    """Exact illuminance [lux] at ``points`` from Lambertian triangles of luminance L
    [cd/m²] that face them (Lambert's contour integral, E = L/2 Σ γ_i n·ĝ_i), for a
    convex emitter wholly above each point's horizon (so no facet hides another)."""
    out = np.empty(len(points))
    outward = np.cross(triangles[:, 1] - triangles[:, 0], triangles[:, 2] - triangles[:, 0])
    for i, (p, n) in enumerate(zip(points, normals)):
        rel = triangles - p
        rel = rel[np.einsum("ij,ij->i", outward, rel[:, 0]) < 0.0]         # facets facing p
        u = rel / np.linalg.norm(rel, axis=2, keepdims=True)
        total = np.zeros(len(rel))
        for a in range(3):
            b = (a + 1) % 3
            c = np.cross(u[:, a], u[:, b])
            cn = np.linalg.norm(c, axis=1)
            gamma = np.arctan2(cn, np.einsum("ij,ij->i", u[:, a], u[:, b]))
            total += gamma * (c @ n) / cn
        out[i] = 0.5 * L * np.abs(total).sum()
    return out


def partial_sum(E0: float, q: float, N: int) -> float:
    """E(N) = E_0 Σ_{k=0..N} q^k."""
    return E0 * (1.0 - q ** (N + 1)) / (1.0 - q)


def box_reference(reflectance: float, n_gauss: int, bounces: int) -> dict:
    """Flux-balance mean wall illuminance of the closed box after 0 … ``bounces``
    bounces, with the absorbed fractions f_j from a Nyström iteration of the radiosity
    equation on ``n_gauss``² Gauss–Legendre points per wall (emitter's shadow on the
    wall-to-wall exchange neglected; it changes f_j by a fraction of f itself).

    Returns Ē_0, the f_j, Ē(N) for every N and the infinite limit [lux].
    """
    tri = sphere_triangles([0, 0, 0], LAMP_RADIUS)
    A_e = 0.5 * np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1).sum()
    deficit = 1.0 - A_e / (4.0 * np.pi * LAMP_RADIUS ** 2)      # mean projected area = A/4 (Cauchy)
    A_w = 6.0 * (2.0 * BOX_HALF) ** 2
    Phi = np.pi * LAMP_LUMINANCE * A_e
    P, N, W = box_sensors(n_gauss)
    d2 = np.einsum("ij,ij->i", P, P)
    cos_x = BOX_HALF / np.sqrt(d2)
    # direct illuminance of the (tessellated) sphere, and each point's view factor to it
    Ed = np.pi * LAMP_LUMINANCE * LAMP_RADIUS ** 2 * (1.0 - deficit) * cos_x / d2
    Fe = Ed / (np.pi * LAMP_LUMINANCE)
    # wall-to-wall view-factor kernel (gathering): K_ij = cos θ_i cos θ_j / (π d²) · w_j A_w,
    # rows scaled so each point's hemisphere holds 1 − F_e (the quadrature misses part
    # of the adjacent walls right next to the edges)
    PP = P @ P.T
    dist2 = d2[:, None] + d2[None, :] - 2.0 * PP
    NP = N @ P.T                                    # NP[i, j] = N_i · P_j
    cx = NP - np.diag(NP)[:, None]                  # N_i · (P_j − P_i)
    cy = NP.T - np.diag(NP)[None, :]                # −N_j · (P_j − P_i) = N_j · P_i − N_j · P_j
    np.fill_diagonal(dist2, 1.0)
    K = np.where((cx > 1e-12) & (cy > 1e-12), cx * cy / (np.pi * dist2 * dist2), 0.0) * (W * A_w)[None, :]
    row = K.sum(axis=1)
    K *= ((1.0 - Fe) / row)[:, None]
    E = Ed.copy()
    f = []
    for _ in range(bounces + 60):
        M = reflectance * E
        f.append(float((W @ (M * Fe)) / (W @ M)))
        E = K @ M
    Eb = Phi / A_w
    terms = np.cumprod(np.concatenate([[1.0], reflectance * (1.0 - np.array(f[:bounces]))]))
    f_inf = f[-1]
    total = Eb * terms.sum()
    tail = Eb * terms[-1] * reflectance * (1.0 - f[bounces]) / (1.0 - reflectance * (1.0 - f_inf))
    return {"E0": Eb, "A_e": A_e, "A_w": A_w, "Phi": Phi, "f": f[:max(bounces, 3)], "f_inf": f_inf,
            "f_uniform": A_e / A_w, "partial": Eb * np.cumsum(terms), "infinite": total + tail,
            "kernel_row_error_median": float(np.median(np.abs(row / (1.0 - Fe) - 1.0))),
            "kernel_row_error_max": float(np.max(np.abs(row / (1.0 - Fe) - 1.0)))}


# -- engine runs -------------------------------------------------------------------------
def run_engine(scene, points, normals, options):
    """One calculation; returns the integrator (for its cache) and the result."""
    integ = Integrator(scene, options)
    result = integ.compute(points, normals)
    return integ, result


def level_profile(integ, options, E0, q):
    """Per level k of a sphere run with N bounces: records, a_k, S_k, hemisphere rays,
    the mean record value against V_k = E_0 Σ_{j=1..N−k} q^j, the correlation between
    the records' R_i and values, and the bound :data:`LEVEL_BOUND`."""
    N = options.bounces
    rows = []
    for k, lv in enumerate(integ.cache.levels):
        if lv.count == 0:
            continue
        values = luminance(lv.E[: lv.count])
        mean = float(values.mean())
        exact = partial_sum(E0, q, N - k) - E0
        radii = lv.R[: lv.count].astype(np.float64)
        corr = float(np.corrcoef(radii, values)[0, 1]) if lv.count > 2 and radii.std() > 0 else None
        rows.append({"level": k, "remaining": N - k, "records": int(lv.count), "accuracy": lv.accuracy,
                     "samples": options.level_samples(k), "hemisphere_rays": int(lv.count) * options.level_samples(k),
                     "mean": mean, "exact": exact, "error": mean / exact - 1.0, "corr_R_E": corr,
                     "bound": LEVEL_BOUND})
    return rows


def run(ctx: StudyContext) -> Report:
    plan = QUICK if ctx.quick else FULL
    rep = Report("integrating-sphere", TITLE, "")
    res = rep.results
    t_study = time.perf_counter()
    f = (LAMP_RADIUS / WALL_RADIUS) ** 2
    E0_ideal = np.pi * LAMP_LUMINANCE * f
    points, normals = wall_sensors(plan.sensors)
    ambient_new = [x for x in plan.ambient_factors if x != 0.0]
    n_runs = (sum(len(v) for v in plan.ladders.values()) + len(ambient_new)
              + sum(len(b[2]) - (not b[1] and 0 in b[2] and plan.bias_bounces in plan.ladders.get(plan.bias_rho, ()))
                    for b in plan.bias_runs)
              + (1 if plan.scaling_rho else 0)
              + sum(len(b[4]) for b in plan.box_runs))
    ctx.plan(n_runs)
    scenes: dict = {}

    def scene_for(rho):
        if rho not in scenes:
            scenes[rho] = sphere_scene(rho)
        return scenes[rho]

    # -- emitter: exact E_0 of the tessellated sphere --------------------------------
    lamp = sphere_triangles([0, 0, 0], LAMP_RADIUS)
    pick = np.linspace(0, plan.sensors - 1, plan.contour_sensors).round().astype(int)
    E0_tess = polygon_illuminance(points[pick], normals[pick], lamp, LAMP_LUMINANCE)
    E0 = float(E0_tess.mean())
    f_tess = E0 / (np.pi * LAMP_LUMINANCE)        # view factor wall → emitter = E_0 / (π L)
    res["scene"] = {"wall_radius_m": WALL_RADIUS, "lamp_radius_m": LAMP_RADIUS,
                    "lamp_luminance_cd_m2": LAMP_LUMINANCE, "sensors": plan.sensors,
                    "accuracy": plan.accuracy, "samples": plan.samples}
    res["emitter"] = {"E0_ideal_lux": E0_ideal, "E0_facets_lux": E0,
                      "facet_deficit": E0 / E0_ideal - 1.0,
                      "facet_spread": float((E0_tess.max() - E0_tess.min()) / E0),
                      "f_ideal": f, "f_facets": f_tess, "contour_sensors": plan.contour_sensors,
                      "area_deficit": float(1.0 - 0.5 * np.linalg.norm(np.cross(lamp[:, 1] - lamp[:, 0],
                                                                                 lamp[:, 2] - lamp[:, 0]), axis=1).sum()
                                            / (4.0 * np.pi * LAMP_RADIUS ** 2))}
    base = Options(accuracy=plan.accuracy, samples=plan.samples, bounces=0)

    # -- bounce ladders per ρ ----------------------------------------------------------
    ladder_rows, final_rows, profiles, kept = [], [], {}, {}
    res["ladders"] = {}
    for rho, counts in plan.ladders.items():
        q = rho * (1.0 - f_tess)
        E_inf = E0 / (1.0 - q)
        runs = []
        for N in counts:
            opt = base.replace(bounces=N)
            integ, r = run_engine(scene_for(rho), points, normals, opt)
            ctx.step(f"sphere ρ={rho}: {N} bounces", r.stats)
            total, ind = luminance(r.rgb), luminance(r.indirect)
            if "direct" not in res:
                # the direct step at the sensors (its random stream is the same in every run)
                direct = luminance(r.direct)
                exact = np.pi * LAMP_LUMINANCE * LAMP_RADIUS ** 2 / np.sum(points ** 2, axis=1)
                res["direct"] = {"mean_lux": float(direct.mean()), "error_of_mean": float(direct.mean() / E0 - 1.0),
                                 "sensor_spread": float(direct.std() / E0),
                                 "max_sensor_error": float(np.abs(direct / exact - 1.0).max()),
                                 "finite": bool(np.isfinite(direct).all())}
            item = {"bounces": N, "mean": float(total.mean()), "indirect": float(ind.mean()),
                    "rays": int(r.stats.rays), "seconds": r.stats.seconds,
                    "records": int(sum(r.stats.new_records)), "finite": bool(np.isfinite(total).all())}
            runs.append(item)
            kept[(rho, N)] = (item, level_profile(integ, opt, E0, q))
            if N == max(counts):
                profiles[rho] = kept[(rho, N)][1]
            del integ
        # N = 0 is the direct step alone, the same for every ρ
        runs.insert(0, {"bounces": 0, "mean": res["direct"]["mean_lux"], "indirect": 0.0, "rays": None,
                        "seconds": None, "records": 0, "finite": res["direct"]["finite"]})
        for run_ in runs:
            N = run_["bounces"]
            exact = partial_sum(E0, q, N)
            run_["exact"] = exact
            run_["error"] = run_["mean"] / exact - 1.0
            run_["error_vs_infinite"] = run_["mean"] / E_inf - 1.0
            run_["truncation"] = q ** (N + 1)
            run_["indirect_error"] = run_["indirect"] / (exact - E0) - 1.0 if N > 0 else None
            ladder_rows.append([f"{rho:g}", N, run_["mean"], exact, pct(run_["error"]),
                                pct(run_["indirect_error"]) if N else "—", pct(run_["error_vs_infinite"]),
                                run_["rays"], run_["records"], run_["seconds"]])
        last = runs[-1]
        res["ladders"][f"{rho:g}"] = {"q": q, "E_inf": E_inf, "runs": runs,
                                      "profile": profiles[rho]}
        n_conv = int(np.ceil(np.log(0.01) / np.log(q))) - 1           # smallest N with q^(N+1) ≤ 1 %
        res["ladders"][f"{rho:g}"]["bounces_for_1_percent"] = n_conv
        final_rows.append([f"{rho:g}", f"{q:.4f}", E_inf, n_conv, last["bounces"], f"{last['truncation']:.1e}",
                           last["mean"], pct(last["error"]), pct(last["indirect_error"]),
                           pct(last["error_vs_infinite"]), last["rays"], last["seconds"]])

    # -- ambient at the bounce limit -----------------------------------------------------
    rho = plan.ambient_rho
    q = rho * (1.0 - f_tess)
    E_inf = E0 / (1.0 - q)
    Nb = plan.ambient_bounces
    amb_rows, res["ambient"] = [], []
    for factor in (0.0,) + tuple(ambient_new):
        A = factor * E_inf
        if factor == 0.0 and (rho, Nb) in kept:
            mean, rays, seconds = kept[(rho, Nb)][0]["mean"], kept[(rho, Nb)][0]["rays"], kept[(rho, Nb)][0]["seconds"]
        else:
            if factor == 0.0:
                ctx.plan(1)
            _, r = run_engine(scene_for(rho), points, normals, base.replace(bounces=Nb, ambient=A))
            ctx.step(f"sphere ρ={rho}: ambient {factor:g}·E_∞", r.stats)
            mean, rays, seconds = float(luminance(r.rgb).mean()), int(r.stats.rays), r.stats.seconds
        expected = partial_sum(E0, q, Nb) + q ** (Nb + 1) * A
        item = {"factor": factor, "ambient_lux": A, "mean": mean, "expected": expected,
                "error_vs_expected": mean / expected - 1.0, "error_vs_infinite": mean / E_inf - 1.0,
                "predicted_bias": (expected - E_inf) / E_inf, "rays": rays, "seconds": seconds}
        res["ambient"].append(item)
        amb_rows.append([f"{factor:g} · E_∞", A, mean, expected, pct(item["error_vs_expected"]),
                         pct(item["predicted_bias"]), pct(item["error_vs_infinite"]), seconds])
    res["ambient_setup"] = {"rho": rho, "q": q, "bounces": Nb, "E_inf": E_inf}

    # -- another accuracy, and bounce scaling off -------------------------------------
    if plan.bias_rho:
        # the same many-bounce case over seeds, with R_i held fixed, and without the cache
        rho, N = plan.bias_rho, plan.bias_bounces
        q = rho * (1.0 - f_tess)
        exact = partial_sum(E0, q, N)
        res["bias"] = {"rho": rho, "bounces": N, "groups": []}
        for label, overrides, seeds in plan.bias_runs:
            group = {"label": label, "overrides": dict(overrides), "runs": []}
            for seed in seeds:
                if not overrides and seed == 0 and (rho, N) in kept:
                    item = kept[(rho, N)][0]
                    ind, rays, seconds = item["indirect"], item["rays"], item["seconds"]
                else:
                    _, r = run_engine(scene_for(rho), points, normals, base.replace(bounces=N, seed=seed, **overrides))
                    ctx.step(f"sphere ρ={rho}: {label}, seed {seed}", r.stats)
                    ind, rays, seconds = float(luminance(r.indirect).mean()), int(r.stats.rays), r.stats.seconds
                group["runs"].append({"seed": seed, "indirect": ind, "indirect_error": ind / (exact - E0) - 1.0,
                                      "rays": rays, "seconds": seconds})
            errs = np.array([x["indirect_error"] for x in group["runs"]])
            group["mean_error"] = float(errs.mean())
            group["standard_error"] = float(errs.std(ddof=1) / np.sqrt(len(errs))) if len(errs) > 1 else None
            res["bias"]["groups"].append(group)
    if plan.scaling_rho:
        rho, N = plan.scaling_rho, plan.scaling_bounces
        q = rho * (1.0 - f_tess)
        exact = partial_sum(E0, q, N)
        on, prof_on = kept[(rho, N)]
        res["scaling"] = {"on": {"mean": on["mean"], "exact": exact, "error": on["mean"] / exact - 1.0,
                                 "indirect_error": on["indirect"] / (exact - E0) - 1.0, "rays": on["rays"],
                                 "seconds": on["seconds"], "records": on["records"], "profile": prof_on}}
        opt = base.replace(bounces=N, bounce_scaling=False)
        integ, r = run_engine(scene_for(rho), points, normals, opt)
        ctx.step(f"sphere ρ={rho}: {N} bounces, bounce scaling off", r.stats)
        mean = float(luminance(r.rgb).mean())
        res["scaling"]["off"] = {
            "mean": mean, "exact": exact, "error": mean / exact - 1.0,
            "indirect_error": float(luminance(r.indirect).mean()) / (exact - E0) - 1.0,
            "rays": int(r.stats.rays), "seconds": r.stats.seconds,
            "records": int(sum(r.stats.new_records)), "profile": level_profile(integ, opt, E0, q)}
        del integ
        res["scaling_setup"] = {"rho": rho, "bounces": N}
    scenes.clear()

    # -- the closed box at ρ = 0.999 ------------------------------------------------------
    bp, bn, bw = box_sensors(BOX_GAUSS)
    max_b = max(max(b[4]) for b in plan.box_runs)
    ref = box_reference(BOX_REFLECTANCE, plan.box_nystrom, max_b)
    coarse = box_reference(BOX_REFLECTANCE, plan.box_nystrom // 2, max_b)
    # exact direct illuminance at the sensors (a fully visible sphere acts as a point of
    # intensity L π r² (1 − deficit)), integrated by the sensors' Gauss–Legendre weights
    d2 = np.einsum("ij,ij->i", bp, bp)
    deficit = 1.0 - ref["A_e"] / (4.0 * np.pi * LAMP_RADIUS ** 2)
    Ed_sensors = np.pi * LAMP_LUMINANCE * LAMP_RADIUS ** 2 * (1.0 - deficit) * (BOX_HALF / np.sqrt(d2)) / d2
    ref["quadrature_direct"] = float(bw @ Ed_sensors) / ref["E0"] - 1.0
    ref["nystrom_change"] = float(abs(coarse["partial"][max_b] / ref["partial"][max_b] - 1.0))
    ref["nystrom_coarse"] = plan.box_nystrom // 2
    res["box"] = {"reference": {k: ref[k] for k in ("E0", "A_e", "A_w", "Phi", "f", "f_inf", "f_uniform",
                                                     "infinite", "quadrature_direct", "kernel_row_error_median",
                                                     "kernel_row_error_max", "nystrom_change", "nystrom_coarse")},
                  "runs": []}
    box_rows = []
    bscene = box_scene(BOX_REFLECTANCE)
    for label, a, S, scaling, counts in plan.box_runs:
        for N in counts:
            opt = Options(accuracy=a, samples=S, bounces=N, bounce_scaling=scaling)
            _, r = run_engine(bscene, bp, bn, opt)
            ctx.step(f"box ρ={BOX_REFLECTANCE}: {label}, {N} bounces", r.stats)
            total = luminance(r.rgb)
            mean = float(bw @ total)
            exact = float(ref["partial"][N])
            ind = float(bw @ luminance(r.indirect))
            item = {"label": label, "accuracy": a, "samples": S, "bounce_scaling": scaling, "bounces": N,
                    "mean": mean, "exact": exact, "error": mean / exact - 1.0,
                    "indirect_error": ind / (exact - ref["E0"]) - 1.0 if N else None,
                    "finite": bool(np.isfinite(total).all()), "min_sensor": float(total.min()),
                    "max_sensor": float(total.max()),
                    "rays": int(r.stats.rays), "seconds": r.stats.seconds,
                    "records": int(sum(r.stats.new_records))}
            res["box"]["runs"].append(item)
            box_rows.append([label, N, mean, exact, pct(item["error"]), pct(item["indirect_error"]),
                             item["rays"], item["records"], item["seconds"]])
    res["study_seconds"] = time.perf_counter() - t_study

    _write(rep, plan, ctx, ladder_rows, final_rows, profiles, amb_rows, box_rows, ref)
    return rep


# -- the report -----------------------------------------------------------------------
def _write(rep, plan, ctx, ladder_rows, final_rows, profiles, amb_rows, box_rows, ref):
    res = rep.results
    em = res["emitter"]
    E0 = em["E0_facets_lux"]
    version = "quick (reduced)" if ctx.quick else "full"
    rep.text(f"""
This is the **{version}** version.  A closed hollow sphere of radius R = {fmt(WALL_RADIUS)} m with a
Lambertian inner wall of reflectance ρ holds at its centre a spherical `light` surface of radius
r = {fmt(LAMP_RADIUS)} m and luminance L = {fmt(LAMP_LUMINANCE)} cd/m².  Every wall point receives
the same light, so the illuminance after any number of bounces has a closed form.  The study runs
ρ = {", ".join(f"{r:g}" for r in plan.ladders)} with increasing bounce counts, compares each result
with the exact value, follows every diffuse level of the deepest runs, shows the `ambient` option
at the bounce limit, and checks a closed box of reflectance {BOX_REFLECTANCE:g} after 50 bounces
against a flux balance.  {plan.sensors} sensors lie on the wall (a Fibonacci lattice), facing the
centre.  Unless stated otherwise the sphere runs use accuracy a = {fmt(plan.accuracy)},
{plan.samples} first-level samples and §3.4 bounce scaling (a × {BOUNCE_ACCURACY_FACTOR:g} per level up to
{BOUNCE_ACCURACY_CAP:g}a, samples halved per level down to {MIN_DEEP_SAMPLES}).
""")
    rep.heading("Exact solution")
    rep.equation(f"""
Direct:      E_0 = π L sin²α = π L (r/R)²                     (sphere of uniform luminance, sin α = r/R)
View factor from a wall point to the emitter:  f = sin²α = (r/R)² = {fmt(em['f_ideal'])}
Uniform wall exitance M irradiates every wall point with M (1 − f)   (integrating-sphere property)
Each bounce: E_k = q E_(k-1),  q = ρ (1 − f)
After N bounces:      E(N) = E_0 (1 − q^(N+1)) / (1 − q)
Infinite bounces:     E_∞  = E_0 / (1 − q)
Truncation:           1 − E(N)/E_∞ = q^(N+1)
Level k of an N-bounce run holds  V_k = E_0 Σ_(j=1..N−k) q^j  (N − k bounces still to come)
Ambient A at the bounce limit:  E(N) + q^(N+1) A   (A = E_∞ gives E_∞ exactly)
""")
    rep.text(f"""
The engine's emitter is an icosphere of 81,920 flat facets.  Its illuminance at
{em['contour_sensors']} sensors, integrated exactly over the facets by Lambert's contour integral,
is {fmt(em['E0_facets_lux'], 6)} lx against π L (r/R)² = {fmt(em['E0_ideal_lux'], 6)} lx: the facets
give {pct(em['facet_deficit'], 4)} (the tessellation's area is {em['area_deficit']:.2e} below the sphere's), the same at every sensor
to {fmt(em['facet_spread'], 2)}.  The reference values below use the facets' E_0 and f = E_0/(πL) =
{fmt(em['f_facets'], 6)}; the difference from the ideal sphere is far below every error reported.
""")
    d = res["direct"]
    rep.heading("Direct light at the sensors")
    rep.text(f"""
With 0 bounces the result is the direct step alone: the emitter is in full view of every sensor, so
it is the closed form of the true sphere, π L (r/d)² (emitters.py), with no shadow ray's noise.  Worst
sensor against it: {fmt(d['max_sensor_error'], 2)}; mean over the {plan.sensors} sensors {fmt(d['mean_lux'])} lx,
{pct(d['error_of_mean'])} from the facets' E_0 (the facets lie inside the sphere by 7e-5 of its radius).
The direct light at every hemisphere-ray hit is exact in the same way, so the records' noise is that of
their hemisphere rays alone.
""")

    rep.heading("Convergence with the number of bounces")
    rep.table(["ρ", "q", "E_∞ [lx]", "N for q^(N+1) ≤ 1 %", "bounces N", "q^(N+1)", "mean E [lx]", "error vs E(N)",
               "indirect error", "error vs E_∞", "rays", "seconds"], final_rows,
              caption="Deepest run per reflectance: mean over the sensors against the exact E(N) and E_∞.")
    rep.table(["ρ", "N", "mean E [lx]", "exact E(N) [lx]", "error", "indirect error", "error vs E_∞",
               "rays", "records", "seconds"], ladder_rows,
              caption="Every run.  'indirect error' compares the interreflected part with E(N) − E_0.")
    fig, (ax1, ax2) = new_figure(11, 4.2, ncols=2)
    colors = {}
    for rho, item in res["ladders"].items():
        runs = item["runs"]
        N = np.array([x["bounces"] for x in runs])
        err = np.array([abs(x["error_vs_infinite"]) for x in runs])
        line, = ax1.semilogy(N, np.maximum(err, 1e-5), "o", label=f"ρ = {rho}")
        colors[rho] = line.get_color()
        n_fine = np.arange(0, N.max() + 1)
        ax1.semilogy(n_fine, item["q"] ** (n_fine + 1), "-", color=line.get_color(), lw=0.8)
        ax2.plot(N[1:], 100 * np.array([x["error"] for x in runs[1:]]), "o-", color=line.get_color(),
                 label=f"ρ = {rho}, total")
        ax2.plot(N[1:], 100 * np.array([x["indirect_error"] for x in runs[1:]]), "s--", mfc="none",
                 color=line.get_color(), lw=0.8, label=f"ρ = {rho}, interreflected part")
    n_max = max(max(x["bounces"] for x in item["runs"]) for item in res["ladders"].values())
    _bounce_axis(ax1, n_max, "bounces N")
    ax1.set_ylabel("|1 − mean E / E_∞|")
    ax1.set_ylim(1e-5, 1.5)
    ax1.set_title("distance from the infinite-bounce value\n(lines: truncation q^(N+1))")
    ax1.legend(fontsize=8)
    ax2.axhline(0, color="k", lw=0.6)
    _bounce_axis(ax2, n_max, "bounces N")
    ax2.set_ylabel("mean E / E(N) − 1 [%]")
    ax2.set_title("error against the exact E(N)")
    ax2.legend(fontsize=7, ncol=2)
    rep.figure("convergence", fig, "Left: distance of the computed mean from E_∞ (markers) and the "
               "truncation q^(N+1) (lines). Right: error against the exact value for the same N, of the total "
               "(solid) and of the interreflected part E(N) − E_0 (dashed).")

    rep.heading("Every diffuse level of the deepest runs")
    rep.text("""
Level k of an N-bounce run holds the indirect irradiance that N − k further bounces bring, so the
mean record value of each level is checked against V_k = E_0 Σ_(j=1..N−k) q^j: one run gives the
error for every number of remaining bounces.  The records of a level interpolate one another, so this
tests the values the level above reads.
""")
    fig, ax = new_figure(6.4, 4.0)
    prof_rows = []
    for rho, rows in profiles.items():
        rem = np.array([x["remaining"] for x in rows])
        err = np.array([x["error"] for x in rows])
        ax.plot(rem, 100 * err, ".-", lw=0.8, ms=3, color=colors.get(f"{rho:g}"), label=f"ρ = {rho:g}")
        e = np.abs(err)
        deep = [x for x in rows if x["level"] >= 4]
        prof_rows.append([f"{rho:g}", rows[0]["remaining"], len(rows), pct(float(np.mean(err))),
                          pct(float(np.max(e))), pct(rows[0]["error"]),
                          int(np.mean([x["records"] for x in deep])) if deep else "—",
                          int(sum(x["hemisphere_rays"] for x in rows))])
    ax.axhline(0, color="k", lw=0.6)
    _bounce_axis(ax, max(x["remaining"] for rows in profiles.values() for x in rows), "bounces still to come (N − k)")
    ax.set_ylabel("mean record value / V_k − 1 [%]")
    ax.legend(fontsize=8)
    rep.figure("levels", fig, "Mean record value of every level of the deepest run per reflectance, "
               "against the exact V_k.")
    rep.table(["ρ", "N", "levels", "mean signed error", "largest error", "level 0 error",
               "records per level (k ≥ 4)", "hemisphere rays"], prof_rows,
              caption="Per-level record means of the deepest runs.")
    res["profile_summary"] = {r[0]: {"bounces": r[1], "levels": r[2]} for r in prof_rows}

    # rays per level: the §3.4 series
    rho_deep = max(profiles)
    rows = profiles[rho_deep]
    show = [x for x in rows if x["level"] < 7 or x["level"] in (rows[-1]["level"], rows[len(rows) // 2]["level"])]
    rep.heading("Rays per level: the §3.4 series")
    series_rows = [[x["level"], fmt(x["accuracy"]), x["samples"], x["records"], x["hemisphere_rays"]] for x in show]
    hemi = sum(x["hemisphere_rays"] for x in rows)
    rep.text(f"""
Per level of the ρ = {rho_deep:g} run with N = {rows[0]['remaining']} bounces: a grows by
{BOUNCE_ACCURACY_FACTOR:g} per level up to {fmt(BOUNCE_ACCURACY_CAP * plan.accuracy)} and the samples halve down
to the floor of {MIN_DEEP_SAMPLES}.  Below the floor the rays
per level stop shrinking, so the cost grows in proportion to N: {fmt(hemi)} hemisphere rays in all,
{fmt(hemi / max(1, len(rows)))} per level on average.  The level count, not the series, sets the cost of
a many-bounce run.
""")
    rep.table(["level", "a", "samples", "records", "hemisphere rays"], series_rows,
              caption=f"§3.4 series of the ρ = {rho_deep:g}, N = {rows[0]['remaining']} run (first levels, "
                      "a middle one and the last).")

    if "scaling" in res:
        sc = res["scaling"]
        su = res["scaling_setup"]
        rep.heading("With and without bounce scaling")
        rep.table(["bounce scaling", "mean E [lx]", "exact E(N) [lx]", "error", "indirect error", "rays",
                   "records", "seconds"],
                  [[k, v["mean"], v["exact"], pct(v["error"]), pct(v["indirect_error"]), v["rays"], v["records"],
                    v["seconds"]] for k, v in sc.items()],
                  caption=f"ρ = {su['rho']:g}, N = {su['bounces']}, a = {fmt(plan.accuracy)}, "
                          f"{plan.samples} samples.")
        fig, ax = new_figure(6.4, 3.8)
        for k, v in sc.items():
            lv = [x["level"] for x in v["profile"]]
            ax.semilogy(lv, [x["hemisphere_rays"] for x in v["profile"]], "o-", ms=3, label=f"scaling {k}")
        ax.set_xlabel("level k")
        ax.set_ylabel("hemisphere rays of the level")
        ax.legend(fontsize=8)
        rep.figure("rays_per_level", fig, f"Hemisphere rays per level, ρ = {su['rho']:g}, N = {su['bounces']}.")
        ratio = sc["off"]["rays"] / sc["on"]["rays"]
        res["scaling_ray_ratio"] = ratio
        rep.text(f"""
Without scaling every level keeps a = {fmt(plan.accuracy)} and {plan.samples} samples: {fmt(ratio, 3)} times
the rays ({fmt(sc['off']['rays'])} against {fmt(sc['on']['rays'])}) and
{fmt(sc['off']['seconds'] / sc['on']['seconds'], 3)} times the seconds; the interreflected part is off by
{pct(sc['off']['indirect_error'])} against {pct(sc['on']['indirect_error'])} with scaling (the total
includes the same direct step in both).
Every wall point of the sphere receives the same light, so the growth of a brings no interpolation
bias here; the box below shows where it does.
""")
    if "bias" in res:
        _bias_section(rep, plan)

    su = res["ambient_setup"]
    rep.heading("The ambient value at the bounce limit")
    rep.text(f"""
ρ = {su['rho']:g} needs many bounces: q = {su['q']:.4f}, so the truncation after N bounces is q^(N+1).
The paper substitutes a constant ambient value at the bounce limit ("this value can be zero").  With N = {su['bounces']}
and `ambient` = A, the exact result is E({su['bounces']}) + q^({su['bounces'] + 1}) A; A = E_∞ =
{fmt(su['E_inf'])} lx gives E_∞ itself, and a wrong guess is off by q^(N+1) (A − E_∞).
""")
    rep.table(["ambient", "A [lx]", "mean E [lx]", "expected [lx]", "error vs expected", "predicted bias vs E_∞",
               "error vs E_∞", "seconds"], amb_rows,
              caption=f"ρ = {su['rho']:g}, N = {su['bounces']} bounces with an ambient value.")

    bx = res["box"]
    rf = bx["reference"]
    rep.heading(f"Closed box, reflectance {BOX_REFLECTANCE:g}")
    rep.text(f"""
A cube of side {fmt(2 * BOX_HALF)} m, all six walls of reflectance {BOX_REFLECTANCE:g}, with the same
emitter at its centre.  The mean wall illuminance follows from the flux balance (module docstring):
Ē_0 = Φ/A_w = {fmt(rf['E0'])} lx; the fraction of the reflected flux absorbed by the emitter is
f_0 = {fmt(rf['f'][0], 4)} for the first reflection, f_1 = {fmt(rf['f'][1], 4)}, f_2 = {fmt(rf['f'][2], 4)},
tending to {fmt(rf['f_inf'], 4)} (uniform exitance would give A_e/A_w = {fmt(rf['f_uniform'], 4)}).  The
infinite-bounce mean is {fmt(rf['infinite'])} lx; after 50 bounces the partial sum is
{fmt(float(ref['partial'][min(50, len(ref['partial']) - 1)]))} lx, so 50 bounces are far from convergence at
this reflectance and the check is against the partial sum.  The engine's mean is the Gauss–Legendre
mean over {6 * BOX_GAUSS ** 2} sensors ({BOX_GAUSS} × {BOX_GAUSS} per wall; for the exact direct
illuminance this quadrature is off by {rf['quadrature_direct']:.1e}).  The f_j come from a Nyström
iteration on {plan.box_nystrom} × {plan.box_nystrom} Gauss–Legendre points per wall; each point's row of
view factors is scaled to hold 1 − F_e (by {pct(rf['kernel_row_error_median'], 2)} at the median point; the
points next to an edge, where the kernel of the adjacent wall peaks between the quadrature points, by up
to {pct(rf['kernel_row_error_max'], 0)}); with half as many points per side ({rf['nystrom_coarse']}) the
{max(max(b[4]) for b in plan.box_runs)}-bounce partial sum changes by {rf['nystrom_change']:.1e}.
""")
    rep.table(["run", "N", "mean E [lx]", "flux balance [lx]", "error", "indirect error", "rays", "records",
               "seconds"], box_rows, caption="Closed box: wall mean against the flux-balance partial sum.")
    if len(box_rows) > 2:
        fig, ax = new_figure(6.4, 4.0)
        labels = sorted({x["label"] for x in bx["runs"]}, key=lambda s: [x["label"] for x in bx["runs"]].index(s))
        for label in labels:
            items = [x for x in bx["runs"] if x["label"] == label]
            ax.plot([x["bounces"] for x in items], [100 * x["error"] for x in items], "o-", ms=4, label=label)
        ax.axhline(0, color="k", lw=0.6)
        _bounce_axis(ax, max(x["bounces"] for x in bx["runs"]), "bounces N")
        ax.set_ylabel("wall mean / flux balance − 1 [%]")
        ax.legend(fontsize=8)
        rep.figure("box", fig, f"Closed box, ρ = {BOX_REFLECTANCE:g}: error of the wall mean against the "
                               "flux-balance partial sum.")

    _findings(rep, plan, ctx)


def _bias_section(rep, plan):
    """ρ = 0.99 over seeds: the cache, the cache with R_i fixed, and pure Monte Carlo."""
    res = rep.results
    bias = res["bias"]
    rho, N = bias["rho"], bias["bounces"]
    q = res["ladders"][f"{rho:g}"]["q"]
    j = np.arange(1, N + 1)
    amp = float((j * q ** j).sum() / (q ** j).sum())       # d ln V / d ln(per-bounce factor)
    bias["amplification"] = amp
    groups = {g["label"]: g for g in bias["groups"]}
    cache = bias["groups"][0]
    bias["per_bounce"] = cache["mean_error"] / amp
    S = MIN_DEEP_SAMPLES
    dsum = 1.0 / (WALL_RADIUS - LAMP_RADIUS) - 1.0 / (2.0 * WALL_RADIUS)
    bias["radius_drop"] = dsum / (S / WALL_RADIUS + dsum)
    deep = [x["corr_R_E"] for x in res["ladders"][f"{rho:g}"]["profile"]
            if x["level"] >= 4 and x["corr_R_E"] is not None]
    bias["corr_R_E_deep_levels"] = float(np.mean(deep)) if deep else None
    rows = []
    for g in bias["groups"]:
        for x in g["runs"]:
            rows.append([g["label"], x["seed"], pct(x["indirect_error"]), x["rays"], x["seconds"]])
    fixed, mc = bias["groups"][1], bias["groups"][2]
    c_mean, c_se = cache["mean_error"], cache["standard_error"] or 0.0
    separated = (c_mean > 2.0 * c_se and abs(fixed["mean_error"]) < 0.5 * c_mean
                 and abs(mc["mean_error"]) < 0.5 * c_mean)
    bias["attributed_to_R"] = bool(separated)
    verdict = ("The cache's error is more than twice its standard error; with R_i held fixed and in pure "
               "Monte Carlo it is less than half as large, so it comes from R_i." if separated else
               "These runs do not separate the variants beyond their noise; the mechanism below is the one "
               "the geometry suggests, not a measured attribution.")
    rep.heading(f"A bias at ρ = {rho:g}: the record radius and the emitter")
    rep.table(["run", "seed", "indirect error vs E(N) − E_0", "rays", "seconds"], rows,
              caption=f"ρ = {rho:g}, N = {N} bounces, repeated with other random seeds and variants.")
    summary = "; ".join(f"{g['label']}: {pct(g['mean_error'])}"
                        + (f" ± {pct(g['standard_error'])}" if g["standard_error"] is not None else "")
                        for g in bias["groups"])
    rep.text(f"""
Mean indirect error over the seeds (± standard error): {summary}.  At ρ = {rho:g} a relative error b
in what each bounce passes on becomes about {fmt(amp)} b in E({N}) (the mean bounce order of the partial
sum, Σ j q^j / Σ q^j), so the cache's mean corresponds to b = {fmt(bias['per_bounce'], 2)} per bounce.
{verdict}  A hemisphere ray that hits the emitter stops at R − r = {fmt(WALL_RADIUS - LAMP_RADIUS)} m, where a ray
near the normal would otherwise reach the wall {fmt(2 * WALL_RADIUS)} m away; it brings no light and
it raises Σ 1/t of Eq. 4.  With the {S} rays per record of the deeper levels (§3.4's floor), one such
ray lowers the record's value by 1/{S} = {pct(1 / S, 1)} and its R_i by about {pct(bias['radius_drop'], 1)}
(Σ 1/t ≈ {S}/R grows by 1/(R − r) − 1/(2R)), so the records that saw the
emitter are darker and have smaller domains and weights in Eq. 5; the interpolated values lean to the
brighter records.  Over the records of the levels k ≥ 4 of the N = {res['ladders'][f'{rho:g}']['runs'][-1]['bounces']}
run, the correlation between R_i and E_i is {fmt(bias['corr_R_E_deep_levels'], 2)} on average.  At
ρ ≤ 0.8 the amplification is ≤ {fmt(0.8 * 0.99 / (1 - 0.8 * 0.99), 2)} and the same b gives below
{pct(bias['per_bounce'] * 0.8 * 0.99 / (1 - 0.8 * 0.99), 2)}, under the noise of the ladder above.
""")


def _bounce_axis(ax, largest: int, label: str) -> None:
    """A bounce-count x axis: linear from 0 to 1, logarithmic beyond, ticks at 0, 1, 2, 4, 8, …"""
    ax.set_xscale("symlog", linthresh=1, linscale=0.4)
    ticks = [0] + [2 ** i for i in range(0, 12) if 2 ** i <= max(1, largest)]
    ax.set_xticks(ticks)
    ax.set_xticklabels([str(t) for t in ticks])
    from matplotlib.ticker import NullLocator

    ax.xaxis.set_minor_locator(NullLocator())
    ax.set_xlim(-0.3, largest * 1.15 + 0.5)
    ax.set_xlabel(label)


def checks(res: dict) -> list[dict]:
    """The bounds the quick version asserts, evaluated on a study's results:
    (name, measured value, bound, held) for each."""
    out = []

    def add(name, value, bound):
        out.append({"check": name, "value": float(value), "bound": float(bound), "held": bool(value <= bound)})

    add("direct step, worst sensor: |E / (π L (r/d)²) − 1|", res["direct"]["max_sensor_error"], DIRECT_BOUND)
    runs = {x["bounces"]: x for x in res["ladders"].get(f"{CONVERGED_RHO:g}", {}).get("runs", [])}
    if CONVERGED_BOUNCES in runs:
        add(f"ρ = {CONVERGED_RHO:g}, {CONVERGED_BOUNCES} bounces: |mean / E_∞ − 1|",
            abs(runs[CONVERGED_BOUNCES]["error_vs_infinite"]), CONVERGED_BOUND)
    for k in (1, 2, 3):
        if k in runs:
            add(f"ρ = {CONVERGED_RHO:g}, {k} bounce{'s' if k > 1 else ''}: |indirect / (E(k) − E_0) − 1|",
                abs(runs[k]["indirect_error"]), PER_BOUNCE_BOUND)
    for item in res["ambient"]:
        if item["factor"] == 1.0:
            add(f"ρ = {res['ambient_setup']['rho']:g}, {res['ambient_setup']['bounces']} bounces, ambient = E_∞: "
                "|mean / E_∞ − 1|", abs(item["error_vs_infinite"]), AMBIENT_BOUND)
    for rho, item in res["ladders"].items():
        worst = max(abs(x["error"]) / x["bound"] for x in item["profile"])
        add(f"ρ = {rho}, every level of the {item['runs'][-1]['bounces']}-bounce run: "
            "max |record mean / V_k − 1| / bound_k", worst, 1.0)
    for item in res["box"]["runs"]:
        if item["accuracy"] == 0.0 and item["bounces"] == 50:
            add(f"box ρ = {BOX_REFLECTANCE:g}, 50 bounces, pure Monte Carlo: |wall mean / flux balance − 1|",
                abs(item["error"]), BOX_MC_BOUND)
    add("values that are NaN or infinite", 0 if res["all_finite"] else 1, 0)
    return out


def _findings(rep, plan, ctx):
    """The conclusions, stated with the numbers measured above."""
    res = rep.results
    rep.heading("Findings")
    items = []
    finals = {rho: item["runs"][-1] for rho, item in res["ladders"].items()}
    worst = max(abs(v["error"]) for v in finals.values())
    worst_ind = max(abs(v["indirect_error"]) for v in finals.values())
    worst_inf = max(abs(v["error_vs_infinite"]) for v in finals.values())
    res["worst_final_error"] = worst
    res["worst_final_indirect_error"] = worst_ind
    res["worst_final_error_vs_infinite"] = worst_inf
    rhos = ", ".join(res["ladders"])
    items.append(f"Integrating sphere, deepest run for each ρ in {{{rhos}}}: the interreflected part is within "
                 f"{pct(worst_ind)} of the exact E(N) − E_0, and the total within {pct(worst)} of E(N).  The total "
                 f"includes the direct step, the same in every run: {pct(res['direct']['error_of_mean'])} from the "
                 f"facets' E_0 over these sensors (the closed form of the true sphere), "
                 f"weighing E_0/E(N) in the total.  Against E_∞ the deepest runs are within {pct(worst_inf)}.")
    conv = ", ".join(f"ρ = {rho}: {item['bounces_for_1_percent']}" for rho, item in res["ladders"].items())
    items.append(f"Where it converges: the computed means follow the truncation q^(N+1) (figure 1), so the "
                 f"bounces needed for a truncation of 1 % or less are {conv}.  The default of 8 bounces leaves "
                 f"q^9 = " + ", ".join(f"{100 * item['q'] ** 9:.2g} % (ρ = {rho})" for rho, item in res["ladders"].items())
                 + " of E_∞ uncomputed.")
    finite = all(all(x.get("finite", True) for x in item["runs"]) for item in res["ladders"].values())
    res["all_finite"] = finite and all(x["finite"] for x in res["box"]["runs"])
    deepest = max(max(x["bounces"] for x in item["runs"]) for item in res["ladders"].values())
    longest = max(res["ladders"].values(), key=lambda i: len(i["profile"]))["profile"]
    floor_rays = int(np.mean([x["hemisphere_rays"] for x in longest if x["level"] >= 4] or [0]))
    res["hemisphere_rays_per_deep_level"] = floor_rays
    items.append(f"No value was NaN or infinite in any run, up to {deepest} bounces, and every level's mean record "
                 f"value stayed within its noise bound (checks below).  The cost per level reaches a floor of "
                 f"about {fmt(floor_rays)} hemisphere rays once the samples reach {MIN_DEEP_SAMPLES}, so the cost of a run grows "
                 f"in proportion to N.")
    if "scaling" in res:
        sc = res["scaling"]
        su = res["scaling_setup"]
        items.append(f"Bounce scaling off (ρ = {su['rho']:g}, N = {su['bounces']}): "
                     f"{fmt(res['scaling_ray_ratio'], 3)} times the rays and "
                     f"{fmt(sc['off']['seconds'] / sc['on']['seconds'], 3)} times the seconds; the interreflected "
                     f"part is off by {pct(sc['off']['indirect_error'])} against {pct(sc['on']['indirect_error'])} "
                     f"with scaling.")
    amb = res["ambient"]
    exact_amb = [x for x in amb if x["factor"] == 1.0][0]
    items.append(f"Ambient: with A = E_∞, {res['ambient_setup']['bounces']} bounces at ρ = "
                 f"{res['ambient_setup']['rho']:g} give {pct(exact_amb['error_vs_infinite'])} from E_∞; "
                 f"without it {pct(amb[0]['error_vs_infinite'])}."
                 + (f"  A wrong guess moves the result by the predicted q^(N+1)(A − E_∞): every ambient run is "
                    f"within {pct(max(abs(x['error_vs_expected']) for x in amb))} of E(N) + q^(N+1) A."
                    if any(x["factor"] not in (0.0, 1.0) for x in amb) else ""))
    if "bias" in res:
        bias = res["bias"]
        items.append(f"Bias at ρ = {bias['rho']:g}: the cache's interreflected part is "
                     f"{pct(bias['groups'][0]['mean_error'])} high on average over "
                     f"{len(bias['groups'][0]['runs'])} seeds ({bias['bounces']} bounces), "
                     f"{pct(bias['groups'][1]['mean_error'])} with R_i held fixed and "
                     f"{pct(bias['groups'][2]['mean_error'])} in pure Monte Carlo: about "
                     f"{fmt(bias['per_bounce'], 2)} per bounce, multiplied by the mean bounce order "
                     f"({fmt(bias['amplification'])}).")
    items.append(f"Noise: the direct light is the emitter's closed form at every sensor (worst "
                 f"{fmt(res['direct']['max_sensor_error'], 2)} from π L (r/d)²) and at every hemisphere-ray hit; "
                 f"what noise is left is the hemisphere rays'.")
    box_runs = res["box"]["runs"]
    for label in dict.fromkeys(x["label"] for x in box_runs):
        items_l = [x for x in box_runs if x["label"] == label]
        text = "; ".join(f"{x['bounces']} bounce{'s' if x['bounces'] != 1 else ''} {pct(x['error'])}"
                         for x in items_l)
        items.append(f"Closed box ρ = {BOX_REFLECTANCE:g}, {label}: wall mean against the flux balance: {text}.")
    rep.bullets(items)
    res["checks"] = checks(res)
    rep.heading("Bounds asserted by the test suite", 3)
    rep.text(f"""
`tests/studies/test_integrating_sphere.py` runs the quick version and asserts these bounds.  The level
bound_k is {pct(LEVEL_BOUND, 0)}: the deepest levels hold few records, each of few hemisphere rays.
""")
    rep.table(["check", "measured", "bound", "held"],
              [[c["check"], fmt(c["value"], 3), fmt(c["bound"], 3), c["held"]] for c in res["checks"]])
    if not ctx.quick:
        by = {(x["label"], x["bounces"]): x for x in res["box"]["runs"]}
        d01, d02 = by.get(("a = 0.1 (default)", 50)), by.get(("a = 0.2", 50))
        mc = by.get(("pure Monte Carlo (a = 0)", 50))
        sc = res.get("scaling", {})
        on_ind = pct(sc["on"]["indirect_error"]) if sc else "—"
        off_ind = pct(sc["off"]["indirect_error"]) if sc else "—"
        rep.heading("What bounds the error", 3)
        rep.text(f"""
In the sphere the light is the same at every wall point, so interpolation cannot go wrong by the shape
of the light; the errors there are the noise of the hemisphere rays, the truncation q^(N+1), and at ρ = 0.99 the small bias of the record radius (previous section).  The
accuracy growth of §3.4 (a up to twice the first level's) has no shape of the light to miss there: with
bounce scaling on and off the interreflected part is off by {on_ind} and {off_ind}.

In the closed box the light falls off towards the edges of each wall.  There the cache's error grows
with a and with the number of bounces: after 50 bounces {pct(d01['error']) if d01 else '—'} at a = 0.1
(deep levels 0.2) and {pct(d02['error']) if d02 else '—'} at a = 0.2 (deep levels 0.4), against
{pct(mc['error']) if mc else '—'} for pure Monte Carlo, which does not interpolate.  Each deeper level
adds its interpolation error to the light the level above receives, and at ρ = 0.999 nearly all of the
light is many bounces deep, so this is the case where the accuracy growth of §3.4 matters.  It is not a
blow-up: the error grows by the sum of small per-level errors, and every value is finite.
""")

"""The paper's Figure 5: blocks on a table, cached against pure Monte Carlo at equal rays.

Ward, Rubinstein & Clear (1988), §3.3 and Figure 5: "three colored, textured blocks on
a table illuminated by a low-angle light source" (5a), "the placement of indirect
illuminance values", crowding "around inside corners ... and outside corners" and
"more densely populated" between and around the blocks than in the background (5b),
and "a pure Monte Carlo computation that used as many rays as the calculation of
Figure 5a", whose "speckling results from inadequate integration of the indirect
contributions at each pixel" (5c).

**Scene.**  A closed 6 × 6 × 3 m room (walls ρ = 0.6), a 2.0 × 1.2 × 0.75 m table
(ρ = 0.5) and three blocks on it (red, green, blue; untextured).  The only source is a
0.6 × 0.6 m light panel on the west wall whose centre is 14.7° above the table top
seen from the table's centre: a low-angle light with long shadows.  No sky.  The camera
looks down on the table from the south-east.

**What is measured.**

1. The image with the cache (:func:`lbl_illum.engine.render_image`, one jittered sample
   per pixel) and its rays R.
2. Pure Monte Carlo (``accuracy = 0``: every pixel's hit gets its own Eq. 2
   hemisphere of S rays, deeper bounces one path ray each) with S chosen so that its
   rays equal R: the ray count is linear in S, fitted from two short runs (S = 2 and 8),
   and the run's actual rays are reported.
3. Noise in flat regions.  Each method is rendered twice with different seeds; on
   pixels whose 3 × 3 neighbourhood sees one plane with one material and the same
   direct light (within 2 %, from 64 shadow rays at the pixel centres), the pixel
   standard deviation is σ = std(L₁ − L₂)/√2, stated relative to the mean luminance
   there.  The cached image's error is mostly smooth (a record's error is shared by
   its whole domain), so this *pixel* noise is what the eye sees as speckle, not the
   cache's total error.
4. Where the level-0 records are: drawn on the image at their positions with their
   valid domain a·R_i, and counted per 1,000 diffuse hits near the blocks (within
   ``NEAR`` of a block) and elsewhere on the table top.
"""

from __future__ import annotations

import math
import time
from pathlib import Path

import numpy as np

from lbl_illum import Options
from lbl_illum.io import preview_pixels
from lbl_illum.engine import Integrator, image_options, render_image
from lbl_illum.photometry import luminance
from lbl_illum.scene import View, scene_from_dict

from .report import Report, StudyContext, fmt, new_figure, pct

TITLE = "The paper's Figure 5: blocks on a table, cached against pure Monte Carlo at equal rays"

ROOM = {"center": [0, 0, 1.5], "size": [6, 6, 3]}
TABLE = {"center": [0, 0, 0.375], "size": [2.0, 1.2, 0.75]}
TABLE_TOP = 0.75
#: (name, centre, size [m], reflectance RGB)
BLOCKS = (("red", (-0.5, 0.1, TABLE_TOP + 0.15), (0.3, 0.3, 0.3), (0.7, 0.15, 0.1)),
          ("green", (0.05, -0.15, TABLE_TOP + 0.1), (0.25, 0.4, 0.2), (0.15, 0.6, 0.2)),
          ("blue", (0.5, 0.25, TABLE_TOP + 0.2), (0.2, 0.2, 0.4), (0.15, 0.2, 0.7)))
#: The light panel on the west wall: centre, size [m] and luminance [cd/m²].
LIGHT_CENTER, LIGHT_SIZE, LIGHT_LUMINANCE = (-2.99, 0.0, 1.5), 0.6, 50000.0
VIEW = View("v", (1.8, -2.2, 1.9), (-1.8, 2.2, -1.1), (0, 0, 1), 50.0, 37.5)
#: "Near a block": within this distance [m] of a block's box.
NEAR = 0.25
#: Direct light within this fraction across a 3 × 3 neighbourhood counts as flat.
FLAT_DIRECT = 0.02

QUICK = {"width": 96, "height": 72, "options": {"accuracy": 0.15, "samples": 128, "bounces": 2}}
FULL = {"width": 320, "height": 240, "options": {"accuracy": 0.1, "samples": 512, "bounces": 3}}


def scene():
    """The room, table, blocks and light as a scene."""
    geometry = [{"shape": "box", **ROOM, "material": "room"},
                {"shape": "box", **TABLE, "material": "table"}]
    materials = {"room": {"type": "diffuse", "reflectance": 0.6},
                 "table": {"type": "diffuse", "reflectance": 0.5},
                 "lamp": {"type": "light", "luminance": LIGHT_LUMINANCE}}
    for name, center, size, rho in BLOCKS:
        geometry.append({"shape": "box", "center": list(center), "size": list(size), "material": name})
        materials[name] = {"type": "diffuse", "reflectance": list(rho)}
    half = LIGHT_SIZE / 2
    x, y, z = LIGHT_CENTER
    geometry.append({"shape": "rectangle", "origin": [x, y - half, z - half], "u": [0, LIGHT_SIZE, 0],
                     "v": [0, 0, LIGHT_SIZE], "material": "lamp"})
    return scene_from_dict({"units": "m", "geometry": geometry, "materials": materials, "sky": {"type": "none"}},
                           Path("."), "figure5")


def light_elevation() -> float:
    """Elevation [°] of the light's centre seen from the table top's centre."""
    x, y, z = LIGHT_CENTER
    return math.degrees(math.atan2(z - TABLE_TOP, math.hypot(x, y)))


# -- measurements ---------------------------------------------------------------------
def _block_distance(P: np.ndarray) -> np.ndarray:
    """(n,) distance [m] from points to the nearest block's box."""
    out = np.full(len(P), np.inf)
    for _, center, size, _ in BLOCKS:
        d = np.maximum(np.abs(P - np.asarray(center)) - 0.5 * np.asarray(size), 0.0)
        out = np.minimum(out, np.linalg.norm(d, axis=1))
    return out


def flat_mask(sc, width: int, height: int) -> tuple[np.ndarray, dict]:
    """Pixels whose 3 × 3 neighbourhood sees one plane of one material under the same
    direct light (pixel-centre rays; direct light from 64 shadow rays)."""
    integ = Integrator(sc, Options(accuracy=0.0, samples=1, bounces=0))
    x, y = VIEW.pixel_coordinates(width, height)
    o, d, _ = VIEW.image_rays(x, y)
    hits = integ.tracer.intersect(o, d)
    ok = hits.hit
    idx = np.flatnonzero(ok)
    P, Ng, Ns = integ.tracer.surface(o, d, hits, idx)
    mat = np.full(len(o), -1)
    mat[idx] = sc.triangles.material[hits.prim[idx]]
    normal = np.zeros((len(o), 3))
    normal[idx] = Ns
    plane = np.full(len(o), np.nan)
    plane[idx] = np.einsum("ij,ij->i", P, Ns)
    direct = np.zeros(len(o))
    direct[idx] = luminance(integ.direct.illuminance(P, Ns, Ng, np.random.default_rng(5), light_samples=64))
    diffuse = np.isin(mat, [i for i, m in enumerate(sc.materials) if m.kind == "diffuse"])
    shape = (height, width)
    mat, plane, direct, diffuse = (a.reshape(shape) for a in (mat, plane, direct, diffuse))
    normal = normal.reshape(height, width, 3)
    mask = diffuse.copy()
    mask[0, :] = mask[-1, :] = mask[:, 0] = mask[:, -1] = False
    c = (slice(1, -1), slice(1, -1))
    inner = mask[c]
    scale = max(float(direct.max()), 1e-300)
    for di in (-1, 0, 1):
        for dj in (-1, 0, 1):
            s = (slice(1 + di, height - 1 + di), slice(1 + dj, width - 1 + dj))
            inner &= mat[s] == mat[c]
            inner &= np.abs(plane[s] - plane[c]) < 1e-6
            inner &= np.einsum("ijk,ijk->ij", normal[s], normal[c]) > 1 - 1e-9
            inner &= np.abs(direct[s] - direct[c]) <= FLAT_DIRECT * np.maximum(direct[c], 1e-3 * scale)
    mask[c] = inner
    names = np.array([m.name for m in sc.materials] + ["none"])
    return mask, {"material": names[mat], "direct": direct}


def pixel_noise(a: np.ndarray, b: np.ndarray, mask: np.ndarray) -> dict:
    """σ = std(a − b)/√2 over ``mask`` and the mean luminance there."""
    la, lb = luminance(a.astype(np.float64)), luminance(b.astype(np.float64))
    diff = (la - lb)[mask]
    mean = float(0.5 * (la[mask].mean() + lb[mask].mean()))
    sigma = float(diff.std() / math.sqrt(2.0))
    return {"sigma": sigma, "mean": mean, "relative": sigma / mean if mean > 0 else float("nan"),
            "pixels": int(mask.sum())}


def project(points: np.ndarray, width: int, height: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Pixel (column, row) of points seen in the perspective ``VIEW`` and their depth [m]
    along the view direction (the inverse of ``View.image_rays`` for ``-vtv``)."""
    d, r, u = VIEW.unit_direction, VIEW.right, VIEW.image_up
    sh, sv = 2 * math.tan(math.radians(VIEW.horizontal) / 2), 2 * math.tan(math.radians(VIEW.vertical) / 2)
    v = points - np.asarray(VIEW.position)
    depth = v @ d
    X = (v @ r) / depth / sh
    Y = (v @ u) / depth / sv
    return (X + 0.5) * width, (0.5 - Y) * height, depth


def record_distribution(cache, level0_hits: np.ndarray) -> dict:
    """Level-0 records per 1,000 diffuse hits on the table top near the blocks and elsewhere."""
    lv = cache.levels[0]
    P = lv.P[:lv.count]
    N = lv.N[:lv.count]
    on_top = (np.abs(P[:, 2] - TABLE_TOP) < 1e-6) & (N[:, 2] > 0.99)
    hits_top = np.abs(level0_hits[:, 2] - TABLE_TOP) < 1e-6
    out = {}
    for name, rec_sel, hit_sel in (
            ("near", on_top & (_block_distance(P) < NEAR), hits_top & (_block_distance(level0_hits) < NEAR)),
            ("far", on_top & (_block_distance(P) >= NEAR), hits_top & (_block_distance(level0_hits) >= NEAR))):
        records, hits = int(rec_sel.sum()), int(hit_sel.sum())
        out[name] = {"records": records, "hits": hits,
                     "per_1000_hits": 1000.0 * records / hits if hits else float("nan"),
                     "median_R": float(np.median(lv.R[:lv.count][rec_sel])) if records else float("nan")}
    return out


# -- the study --------------------------------------------------------------------------
def _render(sc, opts, plan, seed, cache=None):
    t0 = time.perf_counter()
    result = render_image(sc, VIEW, plan["width"], plan["height"], opts.replace(seed=seed), cache=cache)
    result.stats.seconds = time.perf_counter() - t0
    return result


def _mc_samples(sc, base: Options, plan, target_rays: int, ctx: StudyContext) -> tuple[int, dict]:
    """Pure Monte Carlo hemisphere samples whose render traces about ``target_rays``."""
    rays = {}
    for S in (2, 8):
        res = _render(sc, base.replace(accuracy=0.0, samples=S), plan, seed=100 + S)
        rays[S] = res.stats.rays
        ctx.step(f"Monte Carlo calibration S = {S}", res.stats)
    slope = (rays[8] - rays[2]) / 6.0
    offset = rays[2] - 2 * slope
    S = max(1, int(round((target_rays - offset) / slope)))
    return S, {"rays_at_2": rays[2], "rays_at_8": rays[8], "rays_per_sample": slope, "rays_fixed": offset}


def run(ctx: StudyContext) -> Report:
    plan = QUICK if ctx.quick else FULL
    base = image_options(Options(**plan["options"]))
    sc = scene()
    report = Report("figure5", TITLE, "")
    res = report.results
    res["settings"] = {"width": plan["width"], "height": plan["height"], **plan["options"],
                       "view": VIEW.options(), "light_elevation_deg": light_elevation()}
    ctx.plan(7)

    cached = [_render(sc, base, plan, seed) for seed in (0, 1)]
    for seed, r in enumerate(cached):
        ctx.step(f"cached, seed {seed}", r.stats)
    target = cached[0].stats.rays
    S, calibration = _mc_samples(sc, base, plan, target, ctx)
    mc_opts = base.replace(accuracy=0.0, samples=S)
    mc = [_render(sc, mc_opts, plan, seed) for seed in (0, 1)]
    for seed, r in enumerate(mc):
        ctx.step(f"Monte Carlo, seed {seed}", r.stats)
    mask, info = flat_mask(sc, plan["width"], plan["height"])
    ctx.step("flat regions")

    noise_cached = pixel_noise(cached[0].rgb, cached[1].rgb, mask)
    noise_mc = pixel_noise(mc[0].rgb, mc[1].rgb, mask)
    per_material = {}
    for name in ("table", "room"):
        sel = mask & (info["material"] == name)
        if sel.sum() >= 20:
            per_material[name] = {"cached": pixel_noise(cached[0].rgb, cached[1].rgb, sel),
                                  "monte_carlo": pixel_noise(mc[0].rgb, mc[1].rgb, sel)}
    # level-0 hits of the cached image: the pixel-centre hits stand in for them
    x, y = VIEW.pixel_coordinates(plan["width"], plan["height"])
    o, d, _ = VIEW.image_rays(x, y)
    integ = Integrator(sc, base)
    hits = integ.tracer.intersect(o, d)
    P_hits, _, _ = integ.tracer.surface(o, d, hits)
    distribution = record_distribution(cached[0].cache, P_hits)

    def run_doc(r):
        s = r.stats
        return {"rays": s.rays, "records": s.records, "records_made": s.records_made,
                "diffuse_hits": s.diffuse_hits, "seconds": s.seconds,
                "mean_luminance": float(r.luminance.mean())}

    res["cached"] = [run_doc(r) for r in cached]
    res["monte_carlo"] = {"samples": S, "calibration": calibration, "runs": [run_doc(r) for r in mc]}
    res["noise"] = {"cached": noise_cached, "monte_carlo": noise_mc,
                    "ratio_sigma": noise_mc["sigma"] / noise_cached["sigma"] if noise_cached["sigma"] > 0 else None,
                    "per_material": per_material, "flat_pixels": int(mask.sum()),
                    "flat_fraction": float(mask.mean())}
    res["records"] = distribution
    ray_ratio = mc[0].stats.rays / cached[0].stats.rays
    res["ray_ratio"] = ray_ratio
    # equal time instead of equal rays, estimated with σ ∝ 1/√S
    time_ratio = cached[0].stats.seconds / mc[0].stats.seconds
    res["time_ratio"] = time_ratio
    res["monte_carlo_equal_time_relative_sigma"] = noise_mc["relative"] / math.sqrt(time_ratio)
    # the paper's claims, as checks
    res["checks"] = {
        "equal rays within 10 %": abs(ray_ratio - 1.0) < 0.10,
        "Monte Carlo pixel noise at least 2x the cached": (noise_mc["sigma"] >= 2.0 * noise_cached["sigma"]),
        "records denser near the blocks": distribution["near"]["per_1000_hits"] > distribution["far"]["per_1000_hits"],
    }

    _write(report, res, plan, cached, mc, mask, S)
    return report


def _write(report: Report, res: dict, plan: dict, cached, mc, mask, S) -> None:
    s = res["settings"]
    nc, nm = res["noise"]["cached"], res["noise"]["monte_carlo"]
    report.text(f"""
The paper's Figure 5 shows blocks on a table lit by a low-angle light (5a), where the
cache placed its values (5b), and a pure Monte Carlo image made with as many rays
(5c), whose speckle "results from inadequate integration of the indirect contributions
at each pixel".  This study renders the same kind of scene with `lbl_illum.engine.render`
and measures both claims: the pixel noise in flat regions at equal rays, and where the
records go.

Scene: a closed 6 × 6 × 3 m room (ρ = 0.6), a table (ρ = 0.5) with three coloured
blocks, and a 0.6 m light panel on the west wall {fmt(s['light_elevation_deg'])}° above
the table top; no sky.  Image {s['width']} × {s['height']}, one jittered sample per pixel,
view `{s['view']}`.  Cache settings: a = {fmt(s['accuracy'])}, {s['samples']} samples,
{s['bounces']} bounces (the §3.4 series below the first level).
""")
    report.heading("Images")
    fig, axes = new_figure(13.0, 3.6, ncols=3)
    exposure = 0.18 / math.exp(float(np.mean(np.log(np.maximum(cached[0].luminance[cached[0].luminance > 0], 1e-9)))))
    white = exposure * float(np.percentile(cached[0].luminance, 99.5))
    for ax, r, title in ((axes[0], cached[0], "a: with the cache"),
                         (axes[1], mc[0], f"c: pure Monte Carlo, S = {S}, equal rays")):
        ax.imshow(preview_pixels(r.rgb, exposure=exposure, white=white))
        ax.set_title(title)
        ax.set_axis_off()
    ax = axes[2]
    ax.imshow(preview_pixels(cached[0].rgb, exposure=exposure, white=white) // 3 + 170)
    lv = cached[0].cache.levels[0]
    P = lv.P[:lv.count]
    col, row, depth = project(P, plan["width"], plan["height"])
    radius = lv.accuracy * lv.R[:lv.count] / depth / (2 * math.tan(math.radians(VIEW.horizontal) / 2)) * plan["width"]
    from matplotlib.collections import EllipseCollection

    ax.add_collection(EllipseCollection(2 * radius, 2 * radius, 0.0, units="xy", offsets=np.column_stack([col, row]),
                                        offset_transform=ax.transData, facecolors="none", edgecolors="tab:red",
                                        linewidths=0.4))
    ax.plot(col, row, ".", ms=1.0, color="black")
    ax.set_xlim(0, plan["width"])
    ax.set_ylim(plan["height"], 0)
    ax.set_title(f"b: {lv.count:,} level-0 records, circles a·R_i")
    ax.set_axis_off()
    report.figure("images", fig, "a: the cached image; c: pure Monte Carlo with the same number of rays; b: the "
                  "level-0 records at their positions with their valid domain a·R_i (drawn on the image plane).")

    report.heading("Noise at equal rays")
    rows = []
    for label, runs, noise in (("cache", res["cached"], nc), (f"pure Monte Carlo, S = {S}", res["monte_carlo"]["runs"], nm)):
        rows.append([label, runs[0]["rays"], sum(runs[0]["records"]), runs[0]["seconds"], noise["mean"], noise["sigma"],
                     pct(noise["relative"], 1)])
    report.table(["method", "rays", "records (all levels)", "seconds", "mean L in flat regions [cd/m²]",
                  "pixel σ [cd/m²]", "σ / mean"], rows,
                 caption=f"Pixel noise over {res['noise']['flat_pixels']:,} flat-region pixels "
                         f"({pct(res['noise']['flat_fraction'], 0)} of the image), from two seeds per method.")
    pm = res["noise"]["per_material"]
    if pm:
        report.table(["surface", "cache σ / mean", "Monte Carlo σ / mean"],
                     [[name, pct(v["cached"]["relative"], 1), pct(v["monte_carlo"]["relative"], 1)]
                      for name, v in pm.items()])
    cal = res["monte_carlo"]["calibration"]
    report.text(f"""
Pure Monte Carlo's samples were chosen for equal rays: a render traces
{fmt(cal['rays_fixed'])} + {fmt(cal['rays_per_sample'])} · S rays (fitted from S = 2 and 8), so
S = {S} gives {fmt(res['monte_carlo']['runs'][0]['rays'])} rays against the cache's
{fmt(res['cached'][0]['rays'])} (ratio {fmt(res['ray_ratio'])}).  At equal rays the Monte Carlo
pixel noise is {fmt(res['noise']['ratio_sigma'])} times the cached image's.  Direct light is
computed the same way in both (16 shadow rays per hit), so the difference is the indirect
part: the cache integrates each record's hemisphere with {s['samples']} rays and shares it
among the pixels of its domain, where Monte Carlo gives each pixel {S}.

A Monte Carlo ray costs less than a cached one (no placement and no lookups): the
cached image took {fmt(res['time_ratio'])} times as long.  At equal *time*, with the pixel
noise falling as 1/√S, Monte Carlo would reach about
{pct(res['monte_carlo_equal_time_relative_sigma'], 1)} (an estimate), still
{fmt(res['monte_carlo_equal_time_relative_sigma'] / nc['relative'])} times the cached image's
{pct(nc['relative'], 1)}.
""")
    report.heading("Where the records go")
    dist = res["records"]
    report.table(["table top", "level-0 records", "diffuse hits (pixel centres)", "records per 1,000 hits",
                  "median R_i [m]"],
                 [[f"within {NEAR} m of a block", dist["near"]["records"], dist["near"]["hits"],
                   dist["near"]["per_1000_hits"], dist["near"]["median_R"]],
                  [f"farther than {NEAR} m", dist["far"]["records"], dist["far"]["hits"],
                   dist["far"]["per_1000_hits"], dist["far"]["median_R"]]])
    report.text("""
As in the paper's Figure 5b, the records crowd where surfaces are in close visual
contact — along the blocks' bases and in the gaps between them — because the harmonic
mean distance R_i of Eq. 4 is small there, while the open table top and the room's
walls are covered by a few large records.
""")
    report.heading("Checks")
    report.bullets([f"{name}: {'yes' if ok else 'NO'}" for name, ok in res["checks"].items()])

"""Study: window portals in a deep side-lit room, at equal time (the paper's §5).

Ward, Rubinstein & Clear (1988), §5: large sources such as windows belong in the indirect
calculation, where they should be sampled well.  A window seen from the back of a deep
room subtends a small solid angle, so the hemisphere rays of a record there (and of
the records on the walls and ceiling whose light reaches the back) rarely find it;
portal sampling draws directions through the window's area and combines them with the
hemisphere rays by multiple importance sampling (``lbl_illum.engine.portal_sampling``).

The room is 4 m wide, 12 m deep and 3 m high, with one 3 × 1.5 m window in the south
wall (sill 1 m), floor ρ 0.2, walls 0.5, ceiling 0.7, an outside ground of 0.2, under a
CIE overcast sky of 10,000 lux.  Nine workplane sensors (0.8 m) lie 0.5–2.5 m from the
back wall.  Two windows are compared:

* **glazed**: Fresnel glass of normal transmittance 0.7, ``portal = false`` against
  ``portal = true``;
* **unglazed**: an empty opening, without and with a ``[[portals]]`` polygon over it.

Every run is compared with a converged reference of the same window: pure Monte Carlo
(``accuracy = 0``, one path per hemisphere ray below the first level, 8 bounces) with
many samples and independent seeds, whose standard error is stated.  The settings are
the four presets and pure Monte Carlo at four sample counts, each with and without the
portal, each over several seeds; the error of a run is |E/E_ref − 1| per sensor, its mean
over sensors and seeds.  "Equal time" compares a portal run with the run without portal
interpolated (log–log, within the same family of settings) at the same seconds.
"""

from __future__ import annotations

import math
import time

import numpy as np

from lbl_illum import Options, compute_illuminance
from lbl_illum.options import PRESETS
from lbl_illum.scene import scene_from_dict

from .report import Report, StudyContext, fmt, new_figure, pct

TITLE = "Window portals in a deep side-lit room, at equal time"

WIDTH, DEPTH, HEIGHT = 4.0, 12.0, 3.0                # [m] interior
WINDOW = (0.5, 3.5, 1.0, 2.5)                         # [m] x0, x1, sill z0, head z1 in the wall y = 0
SKY = {"type": "cie-overcast", "horizontal_illuminance": 10000.0}
REFLECTANCE = {"floor": 0.2, "wall": 0.5, "ceiling": 0.7, "ground": 0.2}
GLASS_TAU = 0.7
BACK_X = (1.0, 2.0, 3.0)                              # [m] the sensors near the back wall
BACK_Y = (9.5, 10.5, 11.5)
WORKPLANE_Z = 0.8

FULL = {"ref_samples": 65536, "ref_seeds": 16, "seeds": 4, "presets": tuple(PRESETS),
        "mc_samples": (256, 1024, 4096, 16384)}
QUICK = {"ref_samples": 4096, "ref_seeds": 2, "seeds": 1, "presets": ("medium",), "mc_samples": (256,)}


def _rect(origin, u, v, material):
    return {"shape": "rectangle", "origin": list(origin), "u": list(u), "v": list(v), "material": material}


def deep_room(window: str = "glazed", portal: bool = True):
    """The deep room as a scene (built from the tables a scene file would hold).

    window : ``"glazed"`` (Fresnel glass, ``portal`` on the material) or ``"opening"``
    (an empty hole; ``portal`` adds a ``[[portals]]`` polygon over it, and without it the
    engine is told not to look for openings in the geometry)."""
    x0, x1, z0, z1 = WINDOW
    geometry = [
        _rect([0, 0, 0], [WIDTH, 0, 0], [0, DEPTH, 0], "floor"),
        _rect([0, 0, HEIGHT], [WIDTH, 0, 0], [0, DEPTH, 0], "ceiling"),
        _rect([0, DEPTH, 0], [WIDTH, 0, 0], [0, 0, HEIGHT], "wall"),
        _rect([0, 0, 0], [0, DEPTH, 0], [0, 0, HEIGHT], "wall"),
        _rect([WIDTH, 0, 0], [0, DEPTH, 0], [0, 0, HEIGHT], "wall"),
        _rect([0, 0, 0], [WIDTH, 0, 0], [0, 0, z0], "wall"),                 # south wall around the window
        _rect([0, 0, z1], [WIDTH, 0, 0], [0, 0, HEIGHT - z1], "wall"),
        _rect([0, 0, z0], [x0, 0, 0], [0, 0, z1 - z0], "wall"),
        _rect([x1, 0, z0], [WIDTH - x1, 0, 0], [0, 0, z1 - z0], "wall"),
        {"shape": "polygon", "material": "ground",                           # outside, south of the room
         "vertices": [[-50, -50, 0], [50 + WIDTH, -50, 0], [50 + WIDTH, -1e-3, 0], [-50, -1e-3, 0]]},
    ]
    materials = {name: {"type": "diffuse", "reflectance": rho} for name, rho in REFLECTANCE.items()}
    data = {"geometry": geometry, "materials": materials, "sky": dict(SKY)}
    opening = [[x0, 0, z0], [x1, 0, z0], [x1, 0, z1], [x0, 0, z1]]
    if window == "glazed":
        geometry.append({"shape": "polygon", "material": "glazing", "vertices": opening})
        materials["glazing"] = {"type": "glass", "transmittance": GLASS_TAU, "portal": bool(portal)}
    elif window == "opening":
        if portal:
            data["portals"] = [{"name": "window", "vertices": opening}]
        else:                   # without any portal, also none found in the geometry
            data["find_openings"] = False
    else:
        raise ValueError(f"window must be 'glazed' or 'opening', got {window!r}")
    return scene_from_dict(data, ".", f"deep-room ({window})")


def back_points():
    """The nine workplane sensors near the back wall, facing up: (points, normals) [m]."""
    x, y = np.meshgrid(BACK_X, BACK_Y)
    points = np.column_stack([x.ravel(), y.ravel(), np.full(x.size, WORKPLANE_Z)])
    return points, np.tile([0.0, 0.0, 1.0], (len(points), 1))


def reference(ctx, window, samples, seeds):
    """Pure Monte Carlo with portals: mean, relative standard error per sensor, rays, seconds."""
    scene = deep_room(window, True)
    P, N = back_points()
    runs, rays, t0 = [], 0, time.perf_counter()
    for seed in range(seeds):
        r = compute_illuminance(scene, P, N, Options(accuracy=0, samples=samples, bounces=8, point_samples=0,
                                                     seed=1000 + seed))
        ctx.step(f"{window} reference, seed {seed}", r.stats)
        runs.append(r.illuminance)
        rays += r.stats.rays
    runs = np.array(runs)
    mean = runs.mean(axis=0)
    rse = runs.std(axis=0, ddof=1) / math.sqrt(seeds) / mean if seeds > 1 else np.full(len(mean), np.nan)
    return {"illuminance": mean, "rse": rse, "rays": rays, "seconds": time.perf_counter() - t0}


def measure(ctx, window, portal, family, label, options, seeds, ref):
    """Runs of one setting over ``seeds`` seeds: mean seconds and rays, error against ``ref``."""
    scene = deep_room(window, portal)
    P, N = back_points()
    errors, secs, rays = [], [], []
    for seed in range(seeds):
        opts = Options(**{**options, "seed": seed})
        t0 = time.perf_counter()
        r = compute_illuminance(scene, P, N, opts)
        secs.append(time.perf_counter() - t0)
        rays.append(r.stats.rays)
        ctx.step(f"{window} {label} portal={portal} seed {seed}", r.stats)
        errors.append(r.illuminance / ref - 1.0)
    err = np.array(errors)
    return {"window": window, "portal": portal, "family": family, "label": label, "options": options,
            "seconds": float(np.mean(secs)), "rays": float(np.mean(rays)),
            "mean_error": float(np.mean(np.abs(err))), "max_error": float(np.max(np.abs(err))),
            "bias": float(np.mean(err)), "rms_error": float(np.sqrt(np.mean(err * err)))}


def equal_time(runs):
    """For each portal run, the error of the runs without portal of its family interpolated
    log–log at its seconds (None outside their range): ``{label: (error_without, ratio)}``."""
    out = {}
    for on in (r for r in runs if r["portal"]):
        off = sorted((r for r in runs if not r["portal"] and r["family"] == on["family"]
                      and r["window"] == on["window"]), key=lambda r: r["seconds"])
        if len(off) < 2:
            continue
        t = np.log([r["seconds"] for r in off])
        e = np.log([r["mean_error"] for r in off])
        x = math.log(on["seconds"])
        if x < t[0] or x > t[-1]:
            out[on["label"]] = (None, None)
            continue
        interp = float(np.exp(np.interp(x, t, e)))
        out[on["label"]] = (interp, interp / on["mean_error"])
    return out


def run(ctx: StudyContext) -> Report:
    plan = QUICK if ctx.quick else FULL
    settings = [("preset", f"preset {name}", dict(PRESETS[name])) for name in plan["presets"]]
    settings += [("pure Monte Carlo", f"accuracy 0, {s} samples",
                  {"accuracy": 0.0, "samples": s, "bounces": 8, "point_samples": 0}) for s in plan["mc_samples"]]
    windows = ("glazed", "opening")
    ctx.plan(len(windows) * (plan["ref_seeds"] + 2 * len(settings) * plan["seeds"]) + 1)
    P, N = back_points()
    compute_illuminance(deep_room("glazed", True), P[:2], N[:2], Options(samples=16, bounces=1))   # compile
    ctx.step("warm-up")

    refs, runs = {}, []
    for window in windows:
        refs[window] = reference(ctx, window, plan["ref_samples"], plan["ref_seeds"])
        for family, label, options in settings:
            for portal in (False, True):
                runs.append(measure(ctx, window, portal, family, label, options, plan["seeds"],
                                    refs[window]["illuminance"]))

    rep = Report("deep-room", TITLE, "")
    res = rep.results
    res["scene"] = {"size": [WIDTH, DEPTH, HEIGHT], "window": list(WINDOW), "reflectance": REFLECTANCE,
                    "glass_transmittance": GLASS_TAU, "sky": SKY, "points": P.tolist()}
    res["reference"] = {w: {"method": "pure Monte Carlo, accuracy 0, 8 bounces, portals",
                            "samples": plan["ref_samples"], "seeds": plan["ref_seeds"],
                            "illuminance": r["illuminance"], "relative_standard_error": r["rse"],
                            "rse_mean": float(np.nanmean(r["rse"])) if plan["ref_seeds"] > 1 else None,
                            "rse_max": float(np.nanmax(r["rse"])) if plan["ref_seeds"] > 1 else None,
                            "rays": r["rays"], "seconds": r["seconds"]} for w, r in refs.items()}
    res["seeds"] = plan["seeds"]
    res["runs"] = runs
    res["equal_time"] = {}
    per_window = {}
    for window in windows:
        sub = equal_time([r for r in runs if r["window"] == window])
        per_window[window] = sub
        for label, (without, ratio) in sub.items():
            res["equal_time"][f"{window}: {label}"] = {"error_without_portal": without, "ratio": ratio}
    pairs = {}
    for window in windows:
        for family, label, _ in settings:
            off = next(r for r in runs if r["window"] == window and r["label"] == label and not r["portal"])
            on = next(r for r in runs if r["window"] == window and r["label"] == label and r["portal"])
            pairs[(window, label)] = (off, on)
    res["same_settings"] = {f"{w}: {label}": {"error_ratio": off["mean_error"] / on["mean_error"],
                                               "time_ratio": on["seconds"] / off["seconds"]}
                            for (w, label), (off, on) in pairs.items()}

    rep.text(f"""
The paper's §5 puts large sources, windows among them, in the indirect calculation and asks
that they be sampled well.  This study measures what sampling the window's area (portals)
buys where it should matter most: at the back of a deep side-lit room, where the window is
small as seen from the sensors and from most of the surfaces that light them.

Room {WIDTH:g} × {DEPTH:g} × {HEIGHT:g} m (x east, y north, z up), one window {WINDOW[1] - WINDOW[0]:g} ×
{WINDOW[3] - WINDOW[2]:g} m in the south wall (sill {WINDOW[2]:g} m), reflectances floor {REFLECTANCE['floor']:g},
walls {REFLECTANCE['wall']:g}, ceiling {REFLECTANCE['ceiling']:g}, outside ground {REFLECTANCE['ground']:g}; CIE
overcast sky of {SKY['horizontal_illuminance']:,.0f} lux.  {len(P)} sensors at {WORKPLANE_Z:g} m, x ∈ {BACK_X},
y ∈ {BACK_Y} m (0.5–2.5 m from the back wall).  Window **glazed**: Fresnel glass, τ_n = {GLASS_TAU:g},
`portal = false` against `portal = true`.  Window **unglazed**: an empty opening without and with a
`[[portals]]` polygon over it.""")
    rep.heading("The references")
    rows = []
    for w, r in refs.items():
        rse = res["reference"][w]
        rows.append([w, f"{plan['ref_samples']:,}", plan["ref_seeds"], fmt(float(r["illuminance"].min())),
                     fmt(float(r["illuminance"].max())), pct(rse["rse_mean"]), pct(rse["rse_max"]),
                     f"{r['rays']:,}", fmt(r["seconds"])])
    rep.table(["window", "samples", "seeds", "E min [lux]", "E max [lux]", "standard error, mean", "max",
               "rays", "seconds"], rows,
              caption="Pure Monte Carlo (accuracy 0, 8 bounces, one path per hemisphere ray below the first level, "
                      "with portals); standard error = seed spread / √seeds, relative, per sensor.")
    rep.text("""Errors below the reference's standard error are not resolved.  Portal sampling is unbiased
(tests/test_portals.py checks it against an integral over the opening), so the reference may use it.""")

    rep.heading("Error and time, with and without portals")
    for window in windows:
        rows = []
        for family, label, _ in settings:
            off, on = pairs[(window, label)]
            rows.append([label, fmt(off["seconds"]), fmt(on["seconds"]), pct(off["mean_error"]),
                         pct(on["mean_error"]), pct(off["max_error"]), pct(on["max_error"]), pct(off["bias"]),
                         pct(on["bias"])])
        rep.table(["settings", "s, without", "s, with", "mean error, without", "with", "max error, without",
                   "with", "bias, without", "with"], rows,
                  caption=f"Window {window}: mean over {plan['seeds']} seed(s) of the wall time (2 cores shared) "
                          f"and of |E/E_ref − 1| over the {len(P)} sensors.")
        lines = []
        for label, (without, ratio) in per_window[window].items():
            on = next(r for r in runs if r["window"] == window and r["label"] == label and r["portal"])
            if ratio is None:
                lines.append(f"{label} with portal ({fmt(on['seconds'])} s, {pct(on['mean_error'])}): outside the "
                             "time range of the runs without portal")
            else:
                lines.append(f"{label} with portal: {pct(on['mean_error'])} in {fmt(on['seconds'])} s; without "
                             f"portal at the same time {pct(without)} (×{ratio:.1f})")
        if lines:
            rep.text(f"At equal time (window {window}; runs without portal interpolated log–log within "
                     "the same family):")
            rep.bullets(lines)
        best_off = min((r for r in runs if r["window"] == window and not r["portal"]), key=lambda r: r["mean_error"])
        better = sorted((r for r in runs if r["window"] == window and r["portal"]
                         and r["mean_error"] < best_off["mean_error"]), key=lambda r: r["seconds"])
        if better:
            res.setdefault("fastest_better", {})[window] = {"without": best_off["label"], "with": better[0]["label"]}
            rep.text(f"The most accurate run without portal ({best_off['label']}, {pct(best_off['mean_error'])} in "
                     f"{fmt(best_off['seconds'])} s) is beaten by {better[0]['label']} with portal "
                     f"({pct(better[0]['mean_error'])} in {fmt(better[0]['seconds'])} s).")

    fig, axes = new_figure(11, 4.2, ncols=2)
    for ax, window in zip(np.atleast_1d(axes), windows):
        for portal, colour in ((False, "C3"), (True, "C0")):
            for family, marker in (("preset", "o"), ("pure Monte Carlo", "s")):
                sel = sorted((r for r in runs if r["window"] == window and r["portal"] == portal
                              and r["family"] == family), key=lambda r: r["seconds"])
                if sel:
                    ax.plot([r["seconds"] for r in sel], [100 * r["mean_error"] for r in sel], marker=marker,
                            color=colour, ls="-" if family == "preset" else "--",
                            label=f"{family}, {'with' if portal else 'without'} portal")
        rse = res["reference"][window]["rse_mean"]
        if rse:
            ax.axhline(100 * rse, color="grey", ls=":", lw=0.8, label="reference standard error")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("wall time [s]")
        ax.set_ylabel("mean relative error [%]")
        ax.set_title(f"window {window}")
        ax.legend(fontsize=7)
    rep.figure("error_time", fig, "Mean relative error at the nine back sensors against wall time, with and "
                                  "without portals (presets: solid; pure Monte Carlo: dashed).")

    rep.heading("Decision")
    glazed = [v["error_ratio"] for k, v in res["same_settings"].items() if k.startswith("glazed")]
    opening = [v["error_ratio"] for k, v in res["same_settings"].items() if k.startswith("opening")]
    times = [v["time_ratio"] for v in res["same_settings"].values()]
    families = {}
    for key, value in res["equal_time"].items():
        if value["ratio"] is not None:
            family = "preset" if key.split(": ", 1)[1].startswith("preset") else "pure Monte Carlo"
            families.setdefault(family, []).append(value["ratio"])
    preset_bias = {p: [r["bias"] for r in runs if r["family"] == "preset" and r["portal"] == p] for p in (False, True)}
    pays = bool(np.median(glazed) > 1.0 and all(np.median(v) >= 1.0 for v in families.values()))
    res["decision"] = {"glazed_error_ratio_median": float(np.median(glazed)),
                       "opening_error_ratio_median": float(np.median(opening)),
                       "time_ratio_median": float(np.median(times)),
                       "equal_time_ratio_median": {f: float(np.median(v)) for f, v in families.items()},
                       "preset_bias_without": [min(preset_bias[False]), max(preset_bias[False])],
                       "preset_bias_with": [min(preset_bias[True]), max(preset_bias[True])],
                       "portals_pay": pays}
    text = (f"With the same settings, portals divide the mean error at the back sensors by a median "
            f"×{np.median(glazed):.1f} (glazed) and ×{np.median(opening):.1f} (unglazed opening), at a median "
            f"time ratio of {np.median(times):.2f}.")
    for family, values in families.items():
        text += (f"  At equal time ({family}), the error without portals is a median ×{np.median(values):.1f} the "
                 "error with them.")
    rep.text(text)
    rep.text(f"""Mean signed error of the presets at the back sensors: {pct(min(preset_bias[False]))} to
{pct(max(preset_bias[False]))} without portals, {pct(min(preset_bias[True]))} to {pct(max(preset_bias[True]))} with
them.""")
    if max(preset_bias[False]) < -0.05:
        rep.text("""Without portals every preset is biased low, and the slower presets do not remove it: the records of
the reflection levels, at 64–128 samples, rarely see the window, and those that do get small radii (the light
they know changes fast), so the interpolated light is mostly that of records that missed it.  With portals
what remains is the interpolation error of the cache, which falls with the accuracy a.  Pure Monte Carlo gains
less: its deeper levels are one-ray paths, which do not draw portal samples, and the sensors see the window
directly under a small solid angle.""")
    if pays:
        rep.text("""Portals pay here, so glass is a portal unless its material says `portal = false`
(`lbl_illum.scene.materials.DEFAULT_GLASS_PORTAL`).  An unglazed opening has no surface to mark: it
needs a `[[portals]]` entry (docs/windows.md).""")
    else:
        rep.text("""Portals do not pay here at equal time: `lbl_illum.scene.materials.DEFAULT_GLASS_PORTAL` should be
reconsidered.""")
    return rep

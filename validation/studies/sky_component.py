"""Study: the sky component through unglazed openings, against an independent integral.

The sky component of the daylight factor (CIE Publication 16, 1970) is the
illuminance that a point receives straight from the sky through an opening, divided by
the unobstructed horizontal illuminance E_h of the same sky.  In a room whose interior
surfaces are black (reflectance 0) under a sky with a black ground (ρ_g = 0), that is all
the light there is, so the tool's illuminance at default settings can be checked
against a direct integral of the sky's luminance over the opening:

    E(P) = ∫_Ω L(ω) (n_P · ω) dω = ∫_A L(ω(x)) (n_P · ω) (−n_A · ω) / |x − P|² dA(x)     (1)

with ω(x) = (x − P)/|x − P| the unit direction from the sensor P (normal n_P) to the point
x of the opening A (normal n_A, facing the room) [Ward, Rubinstein & Clear 1988, Eq. 1
restricted to the sky seen through A].  Every direction through the opening reaches the
sky: the rooms are convex and the openings are holes in zero-thickness walls, so nothing
but the opening's edges bounds what a floor point sees.

The integral over A is a Gauss–Legendre product rule in the opening's two edge
directions (Abramowitz & Stegun 1964, 25.4.29), NODES × NODES nodes, with the sky's
luminance function (``Sky.luminance``, evaluated on the nodes' directions) as the only
code shared with the tool: the integration is independent of the tool's hemisphere and
portal sampling.  Its own error is stated: the rule is compared with one of half the
nodes in each direction.  The sky's E_h, which both sides divide by, is checked with an
independent midpoint rule in altitude and azimuth.

Rooms (x east, y north, z up, metres; every surface reflectance 0):

* **roof**: 8 × 8 × 3 m, a square opening of side 1 m or 4 m in the middle of the ceiling,
  with a ``[[portals]]`` polygon over it (docs/windows.md);
* **façade**: 6 m wide, 8 m deep, 3 m high, one 2 × 1.5 m opening in the south wall (sill
  1 m) with a ``[[portals]]`` polygon over it.

Sensors lie on the floor, facing up: under the middle of the opening, 5 cm inside and
outside its edges' vertical projection, under its corners, well outside the projection and
near the walls.  Skies: the 15 CIE standard general skies (ISO 15469:2004) with the sun at
altitude 40°, azimuth 210° (south-south-west; it shapes the sky and adds no direct light),
and the traditional CIE overcast sky (Moon & Spencer 1942), each of E_h = 10,000 lux.  The
tool runs at the scene defaults (:func:`lbl_illum.options.scene_defaults`, the ``high``
preset), with one seed per run.  The project's criterion is |SC_tool / SC_ref − 1| ≤ 5 %
at every sensor.

References: CIE Publication 16 (1970), *Daylight*; ISO 15469:2004 / CIE S 011/E:2003,
*Spatial distribution of daylight — CIE standard general sky*; P. Moon, D. E. Spencer,
"Illumination from a non-uniform sky", Illuminating Engineering 37, 707–726 (1942);
M. Abramowitz, I. A. Stegun, *Handbook of Mathematical Functions* (1964), 25.4.29.
"""

from __future__ import annotations

import dataclasses
import math
import time

import numpy as np

from lbl_illum import compute_illuminance
from lbl_illum.options import DEFAULT_PRESET, scene_defaults
from lbl_illum.scene import scene_from_dict

from .report import Report, StudyContext, fmt, new_figure, pct

TITLE = "Sky component through roof and façade openings, against an independent integral"

E_H = 10000.0                                        # [lux] every sky's unobstructed horizontal illuminance
SUN = (40.0, 210.0)                                  # [°] altitude, azimuth of the sun that shapes the skies
ROOF_ROOM = (8.0, 8.0, 3.0)                          # [m] width (x), depth (y), height (z)
ROOF_SIDES = (1.0, 4.0)                              # [m] sides of the square roof openings
FACADE_ROOM = (6.0, 8.0, 3.0)                        # [m]
FACADE_WINDOW = (2.0, 4.0, 1.0, 2.5)                 # [m] x0, x1, sill z0, head z1 in the wall y = 0
EDGE = 0.05                                          # [m] sensors this far inside and outside an edge
TOLERANCE = 0.05                                     # the project's criterion: at every sensor
NODES = 256                                          # Gauss–Legendre nodes per edge direction of the reference
SKIES = ["cie-overcast", *range(1, 16)]              # "cie-overcast" or a CIE general type 1…15

#: ``seeds``: further seeds (1…seeds) of the seed study, on SEED_SKY
FULL = {"skies": SKIES, "openings": ("roof 1 m", "roof 4 m", "façade"), "points": "all", "without_portal": True,
        "seeds": 16}
QUICK = {"skies": ["cie-overcast", 12], "openings": ("roof 1 m", "façade"), "points": "few", "without_portal": False,
         "seeds": 0}
SEED_SKY = 12                                        # the CIE standard clear sky: the most peaked common type


# -- the rooms -----------------------------------------------------------------------
def _rect(origin, u, v):
    return {"shape": "rectangle", "origin": [float(c) for c in origin], "u": [float(c) for c in u],
            "v": [float(c) for c in v], "material": "black"}


def sky_table(sky) -> dict:
    """The ``[sky]`` table of ``sky`` ("cie-overcast" or a CIE general type 1…15), black ground."""
    if sky == "cie-overcast":
        return {"type": "cie-overcast", "horizontal_illuminance": E_H, "ground_reflectance": 0.0}
    return {"type": "cie-general", "sky_type": int(sky), "horizontal_illuminance": E_H, "ground_reflectance": 0.0}


def sky_label(sky) -> str:
    return "CIE overcast (traditional)" if sky == "cie-overcast" else f"CIE general type {sky}"


def opening(kind: str):
    """The opening of room ``kind`` as a rectangle: (origin, u, v) [m], its edges u and v."""
    if kind == "façade":
        x0, x1, z0, z1 = FACADE_WINDOW
        return np.array([x0, 0.0, z0]), np.array([x1 - x0, 0.0, 0.0]), np.array([0.0, 0.0, z1 - z0])
    side = float(kind.split()[1])
    w, d, h = ROOF_ROOM
    return np.array([(w - side) / 2, (d - side) / 2, h]), np.array([side, 0.0, 0.0]), np.array([0.0, side, 0.0])


def room(kind: str, sky, portal: bool = True):
    """The black room with opening ``kind`` ("roof 1 m", "roof 4 m", "façade") under ``sky``,
    with a ``[[portals]]`` polygon over the opening unless ``portal`` is False."""
    o, u, v = opening(kind)
    if kind == "façade":
        w, d, h = FACADE_ROOM
        x0, x1, z0, z1 = FACADE_WINDOW
        geometry = [_rect([0, 0, 0], [w, 0, 0], [0, d, 0]), _rect([0, 0, h], [w, 0, 0], [0, d, 0]),
                    _rect([0, d, 0], [w, 0, 0], [0, 0, h]), _rect([0, 0, 0], [0, d, 0], [0, 0, h]),
                    _rect([w, 0, 0], [0, d, 0], [0, 0, h]),
                    _rect([0, 0, 0], [w, 0, 0], [0, 0, z0]), _rect([0, 0, z1], [w, 0, 0], [0, 0, h - z1]),
                    _rect([0, 0, z0], [x0, 0, 0], [0, 0, z1 - z0]),
                    _rect([x1, 0, z0], [w - x1, 0, 0], [0, 0, z1 - z0])]
    else:
        w, d, h = ROOF_ROOM
        (x0, y0), (x1, y1) = o[:2], (o + u + v)[:2]
        geometry = [_rect([0, 0, 0], [w, 0, 0], [0, d, 0]),
                    _rect([0, 0, 0], [w, 0, 0], [0, 0, h]), _rect([0, d, 0], [w, 0, 0], [0, 0, h]),
                    _rect([0, 0, 0], [0, d, 0], [0, 0, h]), _rect([w, 0, 0], [0, d, 0], [0, 0, h]),
                    _rect([0, 0, h], [w, 0, 0], [0, y0, 0]), _rect([0, y1, h], [w, 0, 0], [0, d - y1, 0]),
                    _rect([0, y0, h], [x0, 0, 0], [0, y1 - y0, 0]),
                    _rect([x1, y0, h], [w - x1, 0, 0], [0, y1 - y0, 0])]
    data = {"geometry": geometry, "materials": {"black": {"type": "diffuse", "reflectance": 0.0}},
            "sky": sky_table(sky)}
    if sky != "cie-overcast":
        data["sun"] = {"altitude": SUN[0], "azimuth": SUN[1], "direct_normal_illuminance": 0.0}
    if portal:
        data["portals"] = [{"name": kind, "vertices": [list(o), list(o + u), list(o + u + v), list(o + v)]}]
    return scene_from_dict(data, ".", f"sky-component ({kind}, {sky_label(sky)})")


def sensors(kind: str, few: bool = False):
    """Floor sensors of room ``kind``: (points [m], normals, labels).  ``few``: a subset
    (the middle, both sides of an edge, a corner, far outside) for the quick version."""
    if kind == "façade":
        w, d, _ = FACADE_ROOM
        x0, x1, _, _ = FACADE_WINDOW
        xm = (x0 + x1) / 2
        rows = [((xm, 0.05), "under the sill, 5 cm from the wall"), ((xm, 0.5), "middle, 0.5 m in"),
                ((xm, 1.5), "middle, 1.5 m in"), ((xm, 3.0), "middle, 3 m in"), ((xm, 5.0), "middle, 5 m in"),
                ((xm, d - 0.2), "middle, at the back wall"),
                ((x0 + EDGE, 1.0), "5 cm inside the west jamb's plane, 1 m in"),
                ((x0 - EDGE, 1.0), "5 cm outside the west jamb's plane, 1 m in"),
                ((x1 + EDGE, 0.3), "5 cm outside the east jamb's plane, 0.3 m in"),
                ((0.3, 0.3), "south-west corner of the room"), ((w - 0.3, 2.0), "near the east wall, 2 m in"),
                ((0.3, d - 0.3), "north-west corner of the room"), ((w - 0.3, d - 0.3), "north-east corner")]
        if few:
            rows = [rows[i] for i in (0, 2, 7, 9, 12)]
    else:
        w, d, _ = ROOF_ROOM
        half = float(kind.split()[1]) / 2
        cx, cy = w / 2, d / 2
        far = min(w, d) / 2 - 0.1
        rows = [((0, 0), "under the middle"),
                ((half - EDGE, 0), "5 cm inside the east edge"), ((half + EDGE, 0), "5 cm outside the east edge"),
                ((0, half - EDGE), "5 cm inside the north edge"), ((0, half + EDGE), "5 cm outside the north edge"),
                ((-half + EDGE, 0), "5 cm inside the west edge"), ((-half - EDGE, 0), "5 cm outside the west edge"),
                ((0, -half - EDGE), "5 cm outside the south edge"),
                ((half, half), "under the north-east corner"),
                ((-half - EDGE, -half - EDGE), "5 cm outside the south-west corner, diagonally"),
                ((half + 1.0, 0), "1 m outside the east edge"), ((0, half + 1.0), "1 m outside the north edge"),
                ((0, far), "near the north wall"), ((0, -far), "near the south wall"),
                ((-far, far), "north-west corner of the room"), ((far, -far), "south-east corner of the room")]
        rows = [((cx + dx, cy + dy), label) for (dx, dy), label in rows if max(abs(dx), abs(dy)) <= far]
        if few:
            rows = [rows[i] for i in (0, 1, 2, 9, 12)]
    P = np.array([[x, y, 0.0] for (x, y), _ in rows])
    return P, np.tile([0.0, 0.0, 1.0], (len(P), 1)), [label for _, label in rows]


# -- the independent integral ----------------------------------------------------------
def gauss_legendre_rectangle(origin, u, v, n: int):
    """Nodes (n², 3) [m] and weights (n²,) [m²] of the n × n Gauss–Legendre product rule on
    the parallelogram origin + s u + t v, 0 ≤ s, t ≤ 1 (weights sum to its area |u × v|)."""
    x, w = np.polynomial.legendre.leggauss(n)
    s, ws = (x + 1.0) / 2.0, w / 2.0
    S, T = np.meshgrid(s, s, indexing="ij")
    nodes = np.asarray(origin) + S.reshape(-1, 1) * np.asarray(u) + T.reshape(-1, 1) * np.asarray(v)
    weights = np.outer(ws, ws).ravel() * float(np.linalg.norm(np.cross(u, v)))
    return nodes, weights


def opening_illuminance(sky, points, normals, origin, u, v, n: int = NODES) -> np.ndarray:
    """Eq. (1): illuminance [lux] at each of (m, 3) ``points`` facing ``normals`` from the
    sky seen through the rectangular opening origin + s u + t v, by the n × n
    Gauss–Legendre rule over its area.  Only ``sky.luminance`` is the tool's."""
    nodes, weights = gauss_legendre_rectangle(origin, u, v, n)
    n_a = np.cross(u, v)
    n_a = n_a / np.linalg.norm(n_a)
    out = np.empty(len(points))
    for i, (p, nrm) in enumerate(zip(np.asarray(points, float), np.asarray(normals, float))):
        d = nodes - p
        r2 = np.einsum("ij,ij->i", d, d)
        w = d / np.sqrt(r2)[:, None]
        cos_p = np.clip(w @ nrm, 0.0, None)
        cos_a = np.abs(w @ n_a)
        lum = sky.luminance(w)[:, 1]                   # grey sky: every channel is the luminance
        out[i] = float(np.sum(weights * lum * cos_p * cos_a / r2))
    return out


def horizontal_illuminance(sky, n_alt: int = 900, n_az: int = 1440) -> float:
    """E_h [lux] of ``sky`` by the midpoint rule in altitude γ and azimuth:
    ∫₀^{2π} ∫₀^{π/2} L(γ, α) sin γ cos γ dγ dα (a rule independent of the tool's)."""
    g = (np.arange(n_alt) + 0.5) * (math.pi / 2) / n_alt
    a = (np.arange(n_az) + 0.5) * 2 * math.pi / n_az
    G, A = np.meshgrid(g, a, indexing="ij")
    dirs = np.column_stack([(np.cos(G) * np.sin(A)).ravel(), (np.cos(G) * np.cos(A)).ravel(), np.sin(G).ravel()])
    lum = sky.luminance(dirs)[:, 1].reshape(G.shape)
    return float(np.sum(lum * np.sin(G) * np.cos(G)) * (math.pi / 2 / n_alt) * (2 * math.pi / n_az))


# -- the study --------------------------------------------------------------------------
def measure(ctx, kind: str, sky, few: bool, without_portal: bool) -> dict:
    """One room and sky: the tool at the scene defaults against Eq. (1); with
    ``without_portal`` also the same room without its ``[[portals]]`` polygon."""
    scene = room(kind, sky)
    P, N, labels = sensors(kind, few)
    t0 = time.perf_counter()
    result = compute_illuminance(scene, P, N)
    seconds = time.perf_counter() - t0
    ctx.step(f"{kind}, {sky_label(sky)}", result.stats)
    plain = None
    if without_portal:
        t0 = time.perf_counter()
        plain = compute_illuminance(room(kind, sky, portal=False), P, N)
        plain_seconds = time.perf_counter() - t0
        ctx.step(f"{kind}, {sky_label(sky)}, without portal", plain.stats)
    o, u, v = opening(kind)
    ref = opening_illuminance(scene.sky, P, N, o, u, v, NODES)
    coarse = opening_illuminance(scene.sky, P, N, o, u, v, NODES // 2)
    e_h = scene.sky.horizontal_illuminance
    sc, sc_ref = result.illuminance / e_h, ref / e_h
    err = sc / sc_ref - 1.0
    extra = {}
    if plain is not None:
        err_plain = plain.illuminance / ref - 1.0
        extra = {"without_portal": {"error": err_plain, "max_error": float(np.max(np.abs(err_plain))),
                                    "mean_error": float(np.mean(np.abs(err_plain))), "seconds": plain_seconds}}
    return {"opening": kind, "sky": sky if sky == "cie-overcast" else int(sky), "label": sky_label(sky),
            "sensors": labels, "points": P, "sc": sc, "sc_reference": sc_ref, "error": err,
            "max_error": float(np.max(np.abs(err))), "mean_error": float(np.mean(np.abs(err))),
            "bias": float(np.mean(err)), "worst_sensor": labels[int(np.argmax(np.abs(err)))],
            "quadrature_error": float(np.max(np.abs(coarse / ref - 1.0))), "seconds": seconds,
            "rays": int(result.stats.rays), "e_h": e_h,
            "e_h_midpoint": horizontal_illuminance(scene.sky), **extra}


def seed_spread(ctx, kind: str, seeds: int, few: bool) -> dict:
    """The tool at the scene defaults with seeds 1…``seeds`` under :data:`SEED_SKY`: the
    relative error at every sensor and seed, against Eq. (1)."""
    scene = room(kind, SEED_SKY)
    P, N, labels = sensors(kind, few)
    o, u, v = opening(kind)
    ref = opening_illuminance(scene.sky, P, N, o, u, v, NODES)
    errors = []
    for seed in range(1, seeds + 1):
        result = compute_illuminance(scene, P, N, dataclasses.replace(scene.options, seed=seed))
        ctx.step(f"{kind}, seed {seed}", result.stats)
        errors.append(result.illuminance / ref - 1.0)
    err = np.array(errors)
    worst = np.unravel_index(int(np.argmax(np.abs(err))), err.shape)
    return {"seeds": seeds, "error": err, "max_error": float(np.max(np.abs(err))),
            "rms_error": float(np.sqrt(np.mean(err * err))), "bias": float(np.mean(err)),
            "sensor_rms": np.sqrt(np.mean(err * err, axis=0)), "worst_sensor": labels[worst[1]],
            "worst_seed": int(worst[0]) + 1}


def run(ctx: StudyContext) -> Report:
    plan = QUICK if ctx.quick else FULL
    few = plan["points"] == "few"
    ctx.plan(len(plan["skies"]) * len(plan["openings"]) * (2 if plan["without_portal"] else 1)
             + plan["seeds"] * len(plan["openings"]) + 1)
    P, N, _ = sensors("roof 1 m", True)
    compute_illuminance(room("roof 1 m", "cie-overcast"), P[:1], N[:1])       # compile
    ctx.step("warm-up")
    runs = [measure(ctx, kind, sky, few, plan["without_portal"]) for kind in plan["openings"] for sky in plan["skies"]]
    seeds = {kind: seed_spread(ctx, kind, plan["seeds"], few) for kind in plan["openings"]} if plan["seeds"] else {}

    options = scene_defaults()
    rep = Report("sky-component", TITLE, "")
    res = rep.results
    res["settings"] = {"preset": DEFAULT_PRESET, **{k: getattr(options, k) for k in
                       ("accuracy", "samples", "bounces", "point_samples", "interpolation", "seed")}}
    res["scene"] = {"roof_room": ROOF_ROOM, "roof_sides": ROOF_SIDES, "facade_room": FACADE_ROOM,
                    "facade_window": FACADE_WINDOW, "sun_altitude": SUN[0], "sun_azimuth": SUN[1],
                    "horizontal_illuminance": E_H, "reflectance": 0.0, "ground_reflectance": 0.0}
    res["reference"] = {"rule": "Gauss-Legendre product over the opening", "nodes": NODES,
                        "quadrature_error_max": max(r["quadrature_error"] for r in runs),
                        "e_h_midpoint_error_max": max(abs(r["e_h_midpoint"] / r["e_h"] - 1) for r in runs)}
    res["runs"] = runs
    worst = max(runs, key=lambda r: r["max_error"])
    res["max_error"] = worst["max_error"]
    res["mean_error"] = float(np.mean([r["mean_error"] for r in runs]))
    res["passed"] = bool(all(r["max_error"] <= TOLERANCE for r in runs))
    res["worst"] = {"opening": worst["opening"], "sky": worst["sky"], "sensor": worst["worst_sensor"]}
    res["per_opening"] = {k: {"max_error": max(r["max_error"] for r in runs if r["opening"] == k),
                              "mean_error": float(np.mean([r["mean_error"] for r in runs if r["opening"] == k])),
                              "seconds": float(np.mean([r["seconds"] for r in runs if r["opening"] == k]))}
                          for k in plan["openings"]}

    rep.text(f"""
The sky component SC = E / E_h is the part of the daylight factor that comes straight from the
sky through an opening.  In a room with black interior surfaces (reflectance 0) under a sky with
a black ground it is all the light there is, so the tool can be checked against a direct
integral of the sky's luminance over the opening, point by point.  The project asks for agreement
within {pct(TOLERANCE, 0)} at every sensor, sensors near the opening's edges included, at the
default settings (the `{DEFAULT_PRESET}` preset) with a `[[portals]]` polygon over the opening.""")
    rep.heading("Rooms, skies and sensors")
    w, d, h = ROOF_ROOM
    fw, fd, fh = FACADE_ROOM
    x0, x1, z0, z1 = FACADE_WINDOW
    rep.bullets([
        f"**roof 1 m**, **roof 4 m**: an {w:g} × {d:g} × {h:g} m room (x east, y north, z up) with a square opening "
        f"of side 1 m or 4 m in the middle of its ceiling;",
        f"**façade**: a {fw:g} m wide, {fd:g} m deep, {fh:g} m high room with a {x1 - x0:g} × {z1 - z0:g} m opening "
        f"in its south wall (sill {z0:g} m, x {x0:g}–{x1:g} m);",
        "every surface black (reflectance 0), walls of zero thickness, no glazing, a `[[portals]]` polygon over "
        "each opening in its plane;",
        f"skies: the traditional CIE overcast sky and the 15 CIE standard general skies (ISO 15469), each of "
        f"E_h = {E_H:,.0f} lux, ground reflectance 0; the general skies are shaped by a sun at altitude "
        f"{SUN[0]:g}°, azimuth {SUN[1]:g}° (clockwise from north; a `[sun]` table with "
        "`direct_normal_illuminance = 0`, so it adds no direct light);",
        "sensors on the floor (z = 0), facing up: under the middle of the opening, 5 cm inside and 5 cm outside "
        "its edges (for the façade: the planes of its jambs), under a corner, 1 m outside, near the walls and "
        "in the room's corners; every sensor and its SC are in results.json.",
        f"tool: `compute_illuminance` with the scene defaults (preset `{DEFAULT_PRESET}`: accuracy "
        f"{options.accuracy:g}, {options.samples} samples, {options.bounces} bounces, {options.point_samples} point "
        f"samples, interpolation `{options.interpolation}`), seed {options.seed}."])
    rep.heading("The reference")
    rep.equation("""
E(P) = ∫_A L(ω(x)) (n_P · ω) (−n_A · ω) / |x − P|² dA(x),    ω(x) = (x − P) / |x − P|
SC(P) = E(P) / E_h""")
    rep.text(f"""The integral runs over the opening's area A (normal n_A facing the room) by a
{NODES} × {NODES} Gauss–Legendre product rule.  The sky's luminance L along each node's direction is
`Sky.luminance`, the only code the reference shares with the tool; the tool instead samples the
hemisphere and the portal polygon and traces rays through the room.  Against the rule with
{NODES // 2} × {NODES // 2} nodes the reference changes by at most {fmt(res['reference']['quadrature_error_max'])}
(relative) at any sensor: the integrand is smooth over the opening except at the cusp of a
circumsolar peak.  E_h, which both sides divide by, is the sky's own (its luminance is scaled to
it); an independent midpoint rule in altitude and azimuth (900 × 1440 nodes) gives it within
{fmt(res['reference']['e_h_midpoint_error_max'])} (relative).""")

    rep.heading("Results")
    for kind in plan["openings"]:
        sub = [r for r in runs if r["opening"] == kind]
        rows = [[r["label"], fmt(float(np.min(r["sc_reference"])) * 100), fmt(float(np.max(r["sc_reference"])) * 100),
                 pct(r["max_error"]), pct(r["mean_error"]), pct(r["bias"]), r["worst_sensor"], fmt(r["seconds"])]
                for r in sub]
        rep.table(["sky", "SC_ref min [%]", "SC_ref max [%]", "largest deviation", "mean deviation", "mean signed",
                   "where the largest is", "seconds"], rows,
                  caption=f"Opening **{kind}**, {len(sub[0]['sensors'])} floor sensors: SC of the reference (range), "
                          "and the tool's relative error SC/SC_ref − 1 (largest and mean absolute value, mean "
                          "signed value, where the largest is).")
    verdict = "meets" if res["passed"] else "does not meet"
    rep.text(f"""Over {len(runs)} room–sky pairs the largest deviation is {pct(res['max_error'])}
({worst['label']}, {worst['opening']}, sensor {worst['worst_sensor']!s}) and the mean of the mean
deviations {pct(res['mean_error'])}: the tool {verdict} the {pct(TOLERANCE, 0)} criterion at every
sensor.""")
    res["note_seed"] = ("every run above uses seed 0, so all skies are sampled along the same directions and "
                        "their deviations are correlated")
    if seeds:
        res["seeds"] = seeds
        rows = [[kind, d["seeds"], pct(d["max_error"]), pct(d["rms_error"]), pct(d["bias"]), d["worst_sensor"]]
                for kind, d in seeds.items()]
        same = all(len({r["worst_sensor"] for r in runs if r["opening"] == k}) == 1 for k in plan["openings"])
        where = " (the largest is at the same sensor for every sky of an opening)" if same else ""
        rep.text(f"""Every run above uses the default seed 0, so every sky is sampled along the same
directions and the deviations are correlated across skies{where}: they are one draw of the tool's
noise, not {len(runs)} independent ones.  The table below draws {plan['seeds']} more (seeds
1–{plan['seeds']}) under CIE general type {SEED_SKY}.""")
        rep.table(["opening", "seeds", "largest deviation", "RMS deviation", "mean signed", "where the largest is"],
                  rows, caption=f"CIE general sky type {SEED_SKY}, scene defaults with seeds 1–{plan['seeds']}: "
                                "relative error over every sensor and seed.")
        res["passed_seeds"] = bool(all(d["max_error"] <= TOLERANCE for d in seeds.values()))
    if plan["without_portal"]:
        rows = []
        for kind in plan["openings"]:
            sub = [r for r in runs if r["opening"] == kind]
            on = max(r["max_error"] for r in sub)
            off = max(r["without_portal"]["max_error"] for r in sub)
            mean_on = float(np.mean([r["mean_error"] for r in sub]))
            mean_off = float(np.mean([r["without_portal"]["mean_error"] for r in sub]))
            t_on = float(np.mean([r["seconds"] for r in sub]))
            t_off = float(np.mean([r["without_portal"]["seconds"] for r in sub]))
            res["per_opening"][kind].update(max_error_without_portal=off, mean_error_without_portal=mean_off,
                                            seconds_without_portal=t_off)
            rows.append([kind, pct(on), pct(off), pct(mean_on), pct(mean_off), fmt(t_on), fmt(t_off)])
        rep.table(["opening", "largest deviation, with portal", "without", "mean deviation, with", "without",
                   "seconds, with", "without"], rows,
                  caption="The same rooms without the `[[portals]]` polygon (for comparison; the criterion "
                          "applies to the defaults with portals): largest and mean deviation over every sky and "
                          "sensor, mean wall time of a run.")
        rep.text("""Without the polygon the sensors find the opening only through their cosine-distributed
hemisphere rays; the few of them that pass through a small or distant opening carry its whole
sky component, so the noise grows where the opening subtends a small solid angle.""")

    fig, axes = new_figure(11, 3.8, ncols=len(plan["openings"]), sharey=True)
    axes = np.atleast_1d(axes)
    for ax, kind in zip(axes, plan["openings"]):
        sub = [r for r in runs if r["opening"] == kind]
        for j, r in enumerate(sub):
            ax.plot(np.full(len(r["error"]), j), 100 * r["error"], "o", ms=3, color="C0", alpha=0.6)
        ax.axhline(100 * TOLERANCE, color="C3", lw=0.8, ls="--")
        ax.axhline(-100 * TOLERANCE, color="C3", lw=0.8, ls="--")
        ax.axhline(0, color="grey", lw=0.5)
        ax.set_xticks(range(len(sub)))
        ax.set_xticklabels(["ov" if r["sky"] == "cie-overcast" else str(r["sky"]) for r in sub], fontsize=7)
        ax.set_xlabel("sky")
        ax.set_title(f"opening {kind}")
    axes[0].set_ylabel("SC / SC_ref − 1 [%]")
    rep.figure("errors", fig, "Relative error of the tool's sky component at every floor sensor, per sky (ov: "
                              "the traditional CIE overcast sky; 1–15: the CIE general types) and opening; dashed: "
                              f"the ±{pct(TOLERANCE, 0)} criterion.")
    return rep

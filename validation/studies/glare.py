"""Study: the glare figures of 180° fisheye images (``lbl-illum glare``) against Radiance's
evalglare, a source evaluated by hand, and the illuminance computed at the eye.

Four checks, each of a different part of the calculation:

* **Pixel solid angles.**  Each pixel's ω and projected ω_⊥ = ∫ cos θ dω are contour
  integrals over its edges (docs/glare.md), each edge shared by two pixels, so the whole
  image sums to 2π and π up to round-off, for ``-vta`` and ``-vth`` at every resolution.
  The pixels whose centre looks into the hemisphere (the ones evaluated, as in evalglare)
  hold a little less: what is measured is that share, beside evalglare's own pixel solid
  angles (the spherical quadrilateral of a pixel's corners, zero for a ``-vth`` pixel with
  a corner outside the circle).
* **A source evaluated by hand.**  A synthetic image: a uniform background of luminance
  L_b and one disc of luminance L_s and angular radius γ at a known angle σ from the line
  of sight and τ from the image's up direction.  By hand: ω_s = 2π (1 − cos γ),
  E_v = π L_b + (L_s − L_b) π sin² γ cos σ (the projected solid angle of a cap),
  the position index by Guth's formula above the line of sight and Iwata's below it,
  DGP, DGI and UGR by their formulas.  The image holds the disc as whole pixels, so ω_s
  and E_v differ from the hand values by the disc's outline, measured.
* **The bundled office against evalglare.**  Fisheyes of `examples/office` rendered by
  ``lbl-illum render`` and written as Radiance HDR files with their ``VIEW=`` line, read
  by ``lbl-illum glare`` and by the evalglare of the pyradiance wheel (``-d -C l+``: the
  low-light correction on, as ours; without ``-C l+`` for the uncorrected DGP): the
  overcast sky with the window in view (evalglare's default threshold of 2000 cd/m²,
  and 5 × the average luminance, ``-b 5``), the clear sky with the sun hidden above the
  window but sun patches in view, the same as a ``-vth`` fisheye, and the clear sky with
  the sun seen through the window.
* **E_v against the illuminance at the eye.**  ``compute_illuminance`` at the eye with the
  normal along the view direction (as ``lbl-illum illuminance`` with the one line
  ``x y z dx dy dz``), with the ``high`` preset (``draft`` in the quick version), against
  the image's E_v: this checks the integration of the image (solid angles, cosine, the
  hemisphere's edge) and the renderer's agreement with the point calculation.  The sun's
  disk (6.8e-5 sr) covers about one pixel of a 400-pixel fisheye, and the image carries its
  light in proportion to the share of each pixel's jittered samples that meet it: with the
  sun in view, E_v is checked without the sun's disk (the sources at or above the peak
  luminance, against the illuminance at the eye less its direct sunlight), and the disk's
  own share is reported beside it.

Criteria (the project's): DGP within 0.02 of evalglare on every image, E_v within 2 % of the
illuminance at the eye (without the sun's disk where it is seen); the solid angles summing to 2π and π within 1e-9; the hand-evaluated
DGP within 0.01 and E_v and ω_s within the discretisation of the disc (2 %).
"""

from __future__ import annotations

import math
import os
import shutil
import subprocess
import tempfile
import time
from pathlib import Path

import numpy as np

from lbl_illum import Options, compute_illuminance, load_scene
from lbl_illum.errors import plural
from lbl_illum.engine import Integrator, image_options, render_image
from lbl_illum.glare import (DGP_CONSTANTS, EVALGLARE_DGP_CONSTANTS, PEAK_LUMINANCE, evaluate_glare,
                             fisheye_geometry, glare_from_image, low_light_factor)
from lbl_illum.photometry import luminance
from lbl_illum.io import radiance_programs, write_image
from lbl_illum.scene import view_from_string

from . import repository_root
from .report import Report, StudyContext, fmt, new_figure, pct

TITLE = ("Glare: DGP, vertical illuminance and glare sources of 180° fisheyes against evalglare, "
         "a source evaluated by hand and the illuminance at the eye")

DGP_BOUND = 0.02                # |DGP − evalglare's| on every image (the project's target)
EV_EYE_BOUND = 0.02             # |E_v(image) / E(eye) − 1| (the project's target)
SUM_BOUND = 1e-9                # |Σ ω − 2π|, |Σ ω_⊥ − π| over every pixel
HAND_DGP_BOUND = 0.01           # |DGP(image) − DGP(hand)| of the synthetic source
HAND_SHAPE_BOUND = 0.02         # |ω_s / ω_s(hand) − 1| and |E_v / E_v(hand) − 1|: the disc's outline

#: (name, view type, σ [°], τ [°], γ [°], L_b, L_s [cd/m²])
SYNTHETIC = (("above the line of sight", "a", 30.0, 45.0, 5.0, 100.0, 20000.0),
             ("below the line of sight", "a", 25.0, 150.0, 4.0, 150.0, 30000.0),
             ("above, hemispherical fisheye", "h", 30.0, 45.0, 5.0, 100.0, 20000.0))
#: Office images: name, scene file, eye [m], view direction, view type, glare options,
#: evalglare options for them, pixel samples (full, quick).
OFFICE = (
    ("overcast, window in view", "scene.toml", (2.0, 4.0, 1.2), (0.0, -1.0, 0.0), "a", {}, [], (1, 1)),
    ("overcast, window in view, 5 x average", "scene.toml", (2.0, 4.0, 1.2), (0.0, -1.0, 0.0), "a",
     {"factor": 5.0}, ["-b", "5"], (1, 1)),
    ("clear sky, sun hidden above the window", "office_clear_sky.toml", (2.0, 4.0, 1.2), (0.0, -1.0, 0.0), "a", {},
     [], (1, 1)),
    ("clear sky, sun hidden, hemispherical fisheye", "office_clear_sky.toml", (2.0, 4.0, 1.2), (0.0, -1.0, 0.0), "h",
     {}, [], (1, 1)),
    ("clear sky, sun in view through the window", "office_clear_sky.toml", (2.0, 1.5, 1.2), (0.0, -1.0, 0.0), "a", {},
     [], (16, 1)),
)
#: image side [pixels] and render preset: full, quick
#: image side [pixels], render preset, the sides of the solid-angle table, the synthetic
#: images' side, the preset of the illuminance at the eye: full, quick
FULL = {"side": 400, "preset": "low", "sizes": (64, 128, 256, 512, 1024), "synthetic": 400, "eye_preset": "high"}
QUICK = {"side": 100, "preset": "draft", "sizes": (64, 128, 256), "synthetic": 400, "eye_preset": "draft"}


def unavailable() -> str | None:
    """Why the study cannot run here (it renders the bundled office), or None."""
    if repository_root() is None:
        return "needs the examples/ folder of a source checkout (examples/office)"
    return None


# -- evalglare ---------------------------------------------------------------------------------------------
def evalglare_program() -> tuple[Path, dict] | None:
    """(evalglare, environment): the pyradiance wheel's, else on the PATH; None without it."""
    programs = radiance_programs()
    if programs is not None and programs.get("root") is not None:
        path = Path(programs["root"]) / "bin" / "evalglare"
        if path.is_file():
            return path, programs["env"]
    found = shutil.which("evalglare")
    return (Path(found), dict(os.environ)) if found else None


def run_evalglare(program, image: Path, options=()) -> dict:
    """evalglare ``-d`` on ``image``: its summary figures by name and its sources (L_s,
    ω_s, position index, E_s, direction), and the seconds it took."""
    path, env = program
    t = time.perf_counter()
    run = subprocess.run([str(path), "-d", *options, str(image)], capture_output=True, text=True, env=env,
                         check=True)
    seconds = time.perf_counter() - t
    lines = run.stdout.splitlines()
    head = next(i for i, line in enumerate(lines) if "No pixels" in line)
    count = int(lines[head].split()[0])
    sources = []
    for line in lines[head + 1:head + 1 + count]:
        v = [float(x) for x in line.split()]
        sources.append({"pixels": int(v[1]), "luminance": v[4], "solid_angle": v[5], "position_index": v[6],
                        "direction": v[13:16], "illuminance": v[16]})
    names, values = next(line for line in lines if line.startswith("dgp,")).split(":", 1)
    figures = dict(zip(names.split(","), (float(x) for x in values.split())))
    return {**figures, "sources": sources, "seconds": seconds, "options": list(options)}


# -- hand evaluation ---------------------------------------------------------------------------------------
def guth(sigma: float, tau: float) -> float:
    """Guth's position index at σ, τ [°] above the line of sight, at most 16 (IES handbook form)."""
    p = math.exp((35.2 - 0.31889 * tau - 1.22 * math.exp(-2 * tau / 9)) / 1000 * sigma
                 + (21 + 0.26667 * tau - 0.002963 * tau * tau) / 100000 * sigma * sigma)
    return min(p, 16.0)


def iwata(sigma: float, tau: float) -> float:
    """Iwata & Osterhaus's position index below the line of sight (evalglare 3.02's coordinates)."""
    beta = math.degrees(math.atan(math.tan(math.radians(sigma)) * math.sqrt(1 + 0.3225 * math.cos(math.radians(tau)) ** 2)))
    return min(math.exp(6.49 / 1000 * beta + 21 / 100000 * beta * beta), 16.0)


def hand_figures(sigma, tau, gamma, lb, ls, constants=DGP_CONSTANTS) -> dict:
    """The synthetic image's figures by hand (module text)."""
    s, g = math.radians(sigma), math.radians(gamma)
    omega = 2 * math.pi * (1 - math.cos(g))
    e_source = ls * math.pi * math.sin(g) ** 2 * math.cos(s)
    ev = math.pi * lb + (ls - lb) * math.pi * math.sin(g) ** 2 * math.cos(s)
    p = guth(sigma, tau) if tau <= 90.0 else iwata(sigma, tau)
    c1, c2, c3 = constants
    dgp = min(c1 * ev + c2 * math.log10(1 + ls ** 2 * omega / (ev ** 1.87 * p ** 2)) + c3, 1.0)
    background = (ev - e_source) / math.pi
    dgi = 10 * math.log10(0.478 * ls ** 1.6 * (omega / p ** 2) ** 0.8 / (background + 0.07 * math.sqrt(omega) * ls))
    ugr = 8 * math.log10(0.25 / background * ls ** 2 * omega / p ** 2)
    return {"omega": omega, "ev": ev, "position_index": p, "dgp_uncorrected": dgp,
            "dgp": dgp * low_light_factor(ev), "background_luminance": background, "dgi": dgi, "ugr": ugr}


def synthetic_image(view_type: str, side: int, sigma, tau, gamma, lb, ls):
    """(view, luminance (side, side)): the background and the disc's pixels (centres within γ)."""
    view = view_from_string(f"-vt{view_type} -vp 0 0 1.2 -vd 0 1 0 -vu 0 0 1 -vh 180 -vv 180")
    geometry = fisheye_geometry(view, side, side)
    s, t = math.radians(sigma), math.radians(tau)
    centre = (math.cos(s) * view.unit_direction
              + math.sin(s) * (math.sin(t) * view.right + math.cos(t) * view.image_up))
    L = np.full((side, side), lb)
    L[geometry.directions @ centre >= math.cos(math.radians(gamma))] = ls
    return view, L, geometry


# -- the study ---------------------------------------------------------------------------------------------
def run(ctx: StudyContext) -> Report:
    quick = ctx.quick
    cfg = QUICK if quick else FULL
    rep = Report("glare", TITLE, "")
    res = rep.results
    program = evalglare_program()
    ctx.plan(len(cfg["sizes"]) + len(SYNTHETIC) + len(OFFICE) + 2)
    res["evalglare"] = None if program is None else str(program[0].name)
    res["solid_angles"] = _solid_angles(ctx, cfg)
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        res["synthetic"] = _synthetic(ctx, cfg, folder, program)
        res["office"], images = _office(ctx, cfg, folder, program)
        figure = _figure(images)
    res["settings"] = {"side": cfg["side"], "preset": cfg["preset"], "eye_preset": cfg["eye_preset"],
                       "synthetic_side": cfg["synthetic"]}
    res["checks"] = checks(res)
    _write(rep, res, figure)
    return rep


def _solid_angles(ctx, cfg) -> list[dict]:
    rows = []
    for side in cfg["sizes"]:
        for kind in ("a", "h"):
            view = view_from_string(f"-vt{kind} -vd 0 1 0 -vh 180 -vv 180")
            t = time.perf_counter()
            exact = fisheye_geometry(view, side, side)
            seconds = time.perf_counter() - t
            corners = fisheye_geometry(view, side, side, method="corners")
            omega_all, projected_all = exact.square_solid_angle.sum(), exact.square_projected.sum()
            rows.append({"type": kind, "side": side, "seconds": seconds,
                         "all_omega_error": omega_all - 2 * math.pi, "all_projected_error": projected_all - math.pi,
                         "valid_omega_share": exact.solid_angle.sum() / (2 * math.pi) - 1,
                         "valid_projected_share": exact.projected.sum() / math.pi - 1,
                         "corners_omega_share": corners.solid_angle.sum() / (2 * math.pi) - 1,
                         "corners_projected_share": corners.projected.sum() / math.pi - 1})
        ctx.step(f"solid angles {side}")
    return rows


def _synthetic(ctx, cfg, folder: Path, program) -> list[dict]:
    out = []
    side = cfg["synthetic"]
    for name, kind, sigma, tau, gamma, lb, ls in SYNTHETIC:
        view, L, geometry = synthetic_image(kind, side, sigma, tau, gamma, lb, ls)
        ours = evaluate_glare(L, view, geometry=geometry)
        hand = hand_figures(sigma, tau, gamma, lb, ls)
        row = {"name": name, "type": kind, "sigma": sigma, "tau": tau, "gamma": gamma, "lb": lb, "ls": ls,
               "side": side, "hand": hand, "ours": _ours(ours)}
        if program is not None:
            path = folder / f"synthetic-{len(out)}.hdr"
            write_image(path, np.repeat(L[..., None], 3, axis=-1), view=view)
            row["evalglare"] = run_evalglare(program, path, ["-C", "l+"])
            row["hand_evalglare_constants"] = hand_figures(sigma, tau, gamma, lb, ls, EVALGLARE_DGP_CONSTANTS)
        out.append(row)
        ctx.step(f"synthetic: {name}")
    return out


def _ours(result) -> dict:
    """The figures of one of our results that the report compares."""
    s = result.sources
    return {"dgp": result.dgp, "dgp_uncorrected": result.dgp_uncorrected, "ev": result.ev,
            "ev_sources": result.ev_sources, "background_luminance": result.background_luminance,
            "average_luminance": result.average_luminance, "dgi": result.dgi, "ugr": result.ugr,
            "threshold": result.threshold, "sources": len(s), "en17037": result.en17037,
            "source_list": [{"luminance": x.luminance, "solid_angle": x.solid_angle, "position_index": x.position_index,
                             "illuminance": x.illuminance, "pixels": x.pixels, "direction": list(x.direction),
                             "sigma": x.sigma, "tau": x.tau} for x in s]}


def _office(ctx, cfg, folder: Path, program) -> tuple[list[dict], list]:
    root = repository_root() / "examples" / "office"
    side, out, images = cfg["side"], [], []
    scenes, integrators = {}, {}
    for name, file, eye, direction, kind, options, eg_options, samples in OFFICE:
        if file not in scenes:
            scenes[file] = load_scene(root / file)
            integrators[file] = Integrator(scenes[file], image_options(Options().with_preset(cfg["preset"])))
        scene = scenes[file]
        view = view_from_string(f"-vt{kind} -vp {eye[0]:g} {eye[1]:g} {eye[2]:g} "
                                f"-vd {direction[0]:g} {direction[1]:g} {direction[2]:g} -vu 0 0 1 -vh 180 -vv 180")
        spp = samples[1] if ctx.quick else samples[0]
        path = folder / f"office-{len(out)}.hdr"
        key = (file, eye, direction, kind)
        done = next((o for o in out if o["key"] == key), None)
        t = time.perf_counter()
        if done is None:
            image = render_image(scene, view, side, side, pixel_samples=spp, integrator=integrators[file])
            ctx.step(f"render: {name}", image.stats)
            write_image(path, image.rgb, view=view)
            render_seconds = time.perf_counter() - t
        else:
            path, render_seconds = Path(done["image"]), 0.0
        t = time.perf_counter()
        ours = glare_from_image(path, **options)
        our_seconds = time.perf_counter() - t
        row = {"name": name, "key": key, "image": str(path), "scene": file, "eye": list(eye), "direction": list(direction),
               "type": kind, "pixel_samples": spp, "render_seconds": render_seconds, "glare_seconds": our_seconds,
               "ours": _ours(ours),
               "options": {k: v for k, v in options.items()}}
        if program is not None:
            row["evalglare"] = run_evalglare(program, path, ["-C", "l+", *eg_options])
            row["evalglare_uncorrected"] = run_evalglare(program, path, list(eg_options))
        out.append(row)
        if done is None:
            images.append((name, ours, path))
    # the illuminance at every eye, one run per scene
    for file in scenes:
        rows = [r for r in out if r["scene"] == file]
        eyes = np.array([r["eye"] for r in rows])
        normals = np.array([r["direction"] for r in rows])
        t = time.perf_counter()
        result = compute_illuminance(scenes[file], eyes, normals, Options().with_preset(cfg["eye_preset"]))
        ctx.step(f"illuminance at the eyes: {file}", result.stats)
        seconds = time.perf_counter() - t
        for r, e, direct in zip(rows, result.illuminance, luminance(result.direct)):
            r["eye_illuminance"], r["eye_direct"] = float(e), float(direct)
            r["eye_seconds"] = seconds / len(rows)
            r["ev_error"] = r["ours"]["ev"] / float(e) - 1.0
            # the sun's disk seen: the sources at or above the peak luminance (module text)
            sun = sum(x["illuminance"] for x in r["ours"]["source_list"] if x["luminance"] >= PEAK_LUMINANCE)
            r["ev_sun"] = sun
            if sun > 0.0 and direct > 0.0:
                r["ev_error_without_sun"] = (r["ours"]["ev"] - sun) / (float(e) - float(direct)) - 1.0
                r["sun_error"] = sun / float(direct) - 1.0
    for r in out:               # what found the image again: not a result
        r.pop("key")
        r.pop("image")
    return out, images


def _figure(images):
    """The office images in false colour (log luminance) with their glare sources outlined."""
    if not images:
        return None
    fig, axes = new_figure(3.2 * len(images), 3.6, ncols=len(images), squeeze=False)
    from lbl_illum.io import read_image

    for ax, (name, result, path) in zip(axes[0], images):
        L = read_image(path).luminance
        valid = fisheye_geometry(result.view, result.width, result.height).valid
        shown = np.where(valid, np.log10(np.maximum(L, 1e-2)), np.nan)     # behind the eye: blank
        ax.imshow(shown, cmap="magma", vmin=0, vmax=5)
        for s in result.sources:
            ax.plot([s.column], [s.row], "c+", ms=10, mew=1.5)
        ax.set_title(f"{name}\nDGP {result.dgp:.3f}, Ev {result.ev:,.0f} lux", fontsize=7)
        ax.set_xticks([])
        ax.set_yticks([])
    return fig


def checks(res: dict) -> list[dict]:
    """The bounds the quick version asserts: (check, value, bound, held)."""
    out = []

    def add(name, value, bound):
        out.append({"check": name, "value": float(value), "bound": float(bound), "held": bool(value <= bound)})

    sa = res["solid_angles"]
    add("every pixel: max |Σ ω − 2π|, |Σ ω_⊥ − π| [sr]",
        max(max(abs(r["all_omega_error"]), abs(r["all_projected_error"])) for r in sa), SUM_BOUND)
    for r in res["synthetic"]:
        h, o = r["hand"], r["ours"]
        add(f"synthetic, {r['name']}: |DGP − hand|", abs(o["dgp"] - h["dgp"]), HAND_DGP_BOUND)
        add(f"synthetic, {r['name']}: |E_v/hand − 1|, |ω_s/hand − 1|",
            max(abs(o["ev"] / h["ev"] - 1), abs(o["source_list"][0]["solid_angle"] / h["omega"] - 1)), HAND_SHAPE_BOUND)
        if "evalglare" in r:
            add(f"synthetic, {r['name']}: |DGP − evalglare|", abs(o["dgp"] - r["evalglare"]["dgp"]), DGP_BOUND)
    for r in res["office"]:
        if "evalglare" in r:
            add(f"office, {r['name']}: |DGP − evalglare|", abs(r["ours"]["dgp"] - r["evalglare"]["dgp"]), DGP_BOUND)
        if "ev_error_without_sun" in r:
            add(f"office, {r['name']}: |E_v / E(eye) − 1| without the sun's disk", abs(r["ev_error_without_sun"]),
                EV_EYE_BOUND)
        else:
            add(f"office, {r['name']}: |E_v / E(eye) − 1|", abs(r["ev_error"]), EV_EYE_BOUND)
    return out


def _write(rep: Report, res: dict, figure) -> None:
    rep.intro(__doc__)
    program = res["evalglare"]
    settings = res["settings"]
    rep.text(f"Images of {settings['side']} × {settings['side']} pixels rendered with the `{settings['preset']}` preset; "
             f"the illuminance at the eye with the `{settings['eye_preset']}` preset; the synthetic images "
             f"{settings['synthetic_side']} × {settings['synthetic_side']} pixels. "
             + (f"evalglare: the `{program}` of the pyradiance wheel (3.06)." if program else
                "evalglare is not installed here: its columns are empty."))

    rep.heading("Pixel solid angles")
    rep.table(["view", "pixels", "Σ ω − 2π, every pixel", "Σ ω_⊥ − π, every pixel", "valid pixels: Σ ω / 2π − 1",
               "Σ ω_⊥ / π − 1", "evalglare's corners: Σ ω / 2π − 1", "Σ ω cos θ / π − 1", "seconds"],
              [[f"-vt{r['type']}", f"{r['side']}²", f"{r['all_omega_error']:.1e}", f"{r['all_projected_error']:.1e}",
                pct(r["valid_omega_share"], 3), pct(r["valid_projected_share"], 4), pct(r["corners_omega_share"], 3),
                pct(r["corners_projected_share"], 4), f"{r['seconds']:.2f}"] for r in res["solid_angles"]])
    rep.text("Σ ω_⊥ / π − 1 is the share of a uniform hemisphere's E_v = πL that the valid pixels miss: "
             "the parts in front of the eye of the rim pixels whose centres look behind it (`-vta`) or fall "
             "outside the circle (`-vth`, where the solid angle per pixel grows as 1/cos θ towards the rim). "
             "evalglare's quadrilaterals count a `-vta` rim pixel whole, and give a `-vth` pixel with a corner "
             "outside the circle nothing.")

    rep.heading("A source evaluated by hand")
    rows = []
    for r in res["synthetic"]:
        h, o = r["hand"], r["ours"]
        src = o["source_list"][0] if o["source_list"] else {}
        eg = r.get("evalglare")
        eg_src = eg["sources"][0] if eg and eg["sources"] else {}
        rows.append([f"{r['name']} (-vt{r['type']}; σ {r['sigma']:g}°, τ {r['tau']:g}°, γ {r['gamma']:g}°)",
                     "hand", fmt(h["omega"], 4), fmt(h["position_index"], 4), fmt(h["ev"], 4), fmt(h["dgp"], 4),
                     fmt(h["dgi"], 3), fmt(h["ugr"], 3)])
        rows.append(["", "ours", fmt(src.get("solid_angle"), 4), fmt(src.get("position_index"), 4), fmt(o["ev"], 4),
                     fmt(o["dgp"], 4), fmt(o["dgi"], 3), fmt(o["ugr"], 3)])
        if eg:
            rows.append(["", "evalglare", fmt(eg_src.get("solid_angle"), 4), fmt(eg_src.get("position_index"), 4),
                         fmt(eg["E_v"], 4), fmt(eg["dgp"], 4), fmt(eg["dgi"], 3), fmt(eg["ugr"], 3)])
    rep.table(["image", "", "ω_s [sr]", "P", "E_v [lux]", "DGP", "DGI", "UGR"], rows)
    rep.text("The hand values are those of the continuous disc; the image holds the pixels whose centres lie "
             "within γ, so ω_s and E_v differ by its outline. evalglare's position index is taken at the pixel "
             "holding the source's centre (its coordinates truncated), ours at the centre itself; its DGP "
             "constants are 0.092 and 0.159 for the published 0.0918 and 0.16.")

    rep.heading("The office against evalglare and the illuminance at the eye")
    rows = []
    for r in res["office"]:
        o, eg = r["ours"], r.get("evalglare")
        egu = r.get("evalglare_uncorrected")
        rows.append([r["name"], f"-vt{r['type']}, {r['pixel_samples']} spp",
                     f"{o['sources']} / {len(eg['sources']) if eg else '—'}",
                     f"{fmt(o['ev'], 4)} / {fmt(eg['E_v'], 4) if eg else '—'}", fmt(r["eye_illuminance"], 4),
                     pct(r["ev_error"]) + (f" ({pct(r['ev_error_without_sun'])} without the sun)"
                                           if "ev_error_without_sun" in r else ""),
                     f"{o['dgp']:.4f} / {eg['dgp']:.4f}" if eg else f"{o['dgp']:.4f}",
                     f"{o['dgp'] - eg['dgp']:+.4f}" if eg else "—",
                     f"{o['dgp_uncorrected']:.4f} / {egu['dgp']:.4f}" if egu else f"{o['dgp_uncorrected']:.4f}",
                     f"{fmt(o['dgi'], 3)} / {fmt(eg['dgi'], 3)}" if eg else fmt(o["dgi"], 3),
                     f"{fmt(o['ugr'], 3)} / {fmt(eg['ugr'], 3)}" if eg else fmt(o["ugr"], 3)])
    rep.table(["image", "view", "sources ours / evalglare", "E_v ours / evalglare [lux]", "E at the eye [lux]",
               "E_v / E(eye) − 1", "DGP ours / evalglare", "Δ DGP", "DGP without low-light correction",
               "DGI", "UGR"], rows)
    sun = [r for r in res["office"] if "sun in view" in r["name"]]
    for r in sun:
        src = r["ours"]["source_list"][0] if r["ours"]["source_list"] else None
        if src:
            rep.text(f"With the sun in view ({plural(r['pixel_samples'], 'sample')} per pixel), its disk is a "
                     f"source of {plural(src['pixels'], 'pixel')} bringing {fmt(src['illuminance'], 4)} lux against "
                     f"{fmt(r['eye_direct'], 4)} lux of direct sunlight at the eye "
                     f"({pct(src['illuminance'] / r['eye_direct'] - 1)}): the pixels carry the sun in proportion to "
                     "the share of their jittered samples that meet its disk (one sample, at the pixel's centre, "
                     "gives the whole pixel the sun's luminance or none of it). The DGP is 1, its upper bound, in "
                     f"both programs: the sun's {fmt(r['eye_direct'], 3)} lux at the eye alone make 5.87e-5 E_v > 1.")
    rep.text("E_v at the eye is `compute_illuminance` at the eye with the normal along the view direction (the "
             f"sensor's own hemisphere samples, `{settings['eye_preset']}` preset); the image's E_v comes from its "
             "pixels, whose light the renderer takes from the irradiance cache at their surfaces.")
    if figure is not None:
        rep.figure("office", figure, "The office fisheyes (log₁₀ luminance, 1 to 10⁵ cd/m²; the hemisphere in "
                   "front of the eye) with the centres of their glare sources (+).")

    rep.heading("Where we differ from evalglare", 3)
    rep.bullets([
        "Pixel solid angles: exact integrals of each pixel's square in front of the eye, against the spherical "
        "quadrilateral of its corners' directions (table above).",
        "Grouping: single-linkage clusters within the search angle; evalglare's two scans merge a source into a "
        "larger one within reach, and keep two of equal solid angle apart.",
        "Position index at the source's centre, evalglare at the pixel its truncated coordinates name; τ from the "
        "image's up direction (−vu made normal to −vd), evalglare from −vu itself (the same for level views).",
        "DGP constants as published (0.0918, 0.16), evalglare 0.092 and 0.159; the low-light correction on by "
        "default (evalglare: `-C l+`).",
        "No sources: DGI and UGR are none, evalglare prints 0."])
    rep.heading("Bounds asserted by the test suite", 3)
    rep.table(["check", "measured", "bound", "held"],
              [[c["check"], fmt(c["value"], 3), fmt(c["bound"], 3), str(c["held"])] for c in res["checks"]])

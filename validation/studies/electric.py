"""Study: electric light against closed forms (CIE 171:2006 test cases), a translucent
skylight, daylight and electric light together, and an office of IES downlights against
Radiance.

CIE 171:2006, *Test cases to assess the accuracy of lighting computer programs*, gives
cases whose answers follow from the physics alone.  The ones for electric light, as
built here (x east, y north, z up, metres; the luminaire files are written by the study
from analytic distributions, so every reference is computed without the tool):

* **5.2, point source.**  A luminaire of an asymmetric type C distribution I(γ, C) 2.5 m
  above the floor of a room whose surfaces are black: E = I(γ, C) cos θ / d² at every
  floor sensor (the inverse-square law with Lambert's cosine).
* **5.3, area source.**  A 1.2 × 0.6 m Lambertian light surface of luminance L 2 m above
  the floor of the black room: E = π L F, F the configuration factor of a parallel
  rectangle by superposition of corner rectangles (Howell's catalogue, B-3).
* **5.4, flux conservation.**  An isotropic source of I = 1000 cd (Φ = 4π I) at the
  centre of a closed 4 × 4 × 3 m room, the walls black: the flux arriving on the six
  faces, ∑ E dA by Gauss–Legendre quadrature over each face, is Φ.
* **5.8, internal reflected component.**  The same room with every surface of
  reflectance ρ: every unit of flux that arrives is absorbed (1 − ρ) and re-emitted ρ,
  all onto the room's own faces, so after N bounces the arriving flux is
  Φ (1 − ρ^{N+1})/(1 − ρ) and its mean over the area S is E = Φ (1 − ρ^{N+1}) / (S (1 − ρ))
  — the CIE formula Φ/(S (1 − ρ)) as N grows (here N = 12: ρ^13 < 2e-4 at ρ = 0.5).

And three more:

* **Translucent skylight.**  A 2 × 2 m opening in the flat roof of the black room,
  covered by a translucent sheet (ρ 0.2, τ 0.5) under a uniform sky of E_h: its top sees
  the sky alone (E_h), its underside sends τ E_h/π, so a floor sensor gets τ E_h F, F the
  configuration factor of the opening (as in 5.3).  The sheet, with sky behind it, is
  sampled as a portal (docs/windows.md).
* **Daylight and electric light together**: a side-lit room under a CIE overcast sky with
  two luminaires: the run with both against the sum of the runs with each (superposition;
  the difference is the runs' noise).
* **Office of IES downlights against Radiance** (when Radiance is installed): a 6 × 8 × 3 m
  office with walls 0.5, ceiling 0.7, floor 0.2 and six downlights, on a 0.8 m workplane
  grid; our run at the default preset against ``rtrace`` on the export (``-ab 8 -aa 0.05
  -ad 2048``; the quick version ``-aa 0.15 -ad 512``), and each against the other's noise.

Criteria: 5.2, 5.3 and the skylight every sensor within 1 % (2 % for the skylight, the
the project's target); 5.4 and 5.8 the flux within 1 %; superposition within 3 % in the mean;
the office within 3 % in the mean of the two programs.
"""

from __future__ import annotations

import math
import subprocess
import tempfile
import time
from pathlib import Path

import numpy as np

from lbl_illum import Options, compute_illuminance
from lbl_illum.photometry import luminance
from lbl_illum.io import export_radiance, illuminance_from_rtrace, radiance_programs
from lbl_illum.scene import scene_from_dict

from .report import Report, StudyContext, fmt, pct

TITLE = "Electric light: CIE 171 point, area, flux and interreflection cases, a translucent skylight, and IES downlights against Radiance"

ROOM = (4.0, 4.0, 3.0)                  # [m] x, y, z of the closed test room, corner at the origin
I_ISO = 1000.0                          # [cd] the isotropic source of 5.4 and 5.8
PANEL_L = 1000.0                        # [cd/m²] the area source of 5.3
RHO_58 = 0.5
BOUNCES_58 = 12
SHEET = (0.2, 0.5)                      # ρ, τ of the skylight
E_H = 10000.0
#: Samples of each floor sensor in the skylight case, evaluated on its own as the presets
#: do (the sheet sampled as a portal): what is measured is the transmission, not the
#: interpolation between sensors 0.25 m apart (at accuracy 0.15 that alone reads up to
#: 2.3 % on the full grid, whatever the samples)
SKYLIGHT_SAMPLES = 4096
#: rtrace's settings for the office: full, and quick (the test suite's)
RTRACE_FULL = ["-ab", "8", "-aa", "0.05", "-ad", "2048", "-as", "1024", "-lw", "1e-5"]
RTRACE_QUICK = ["-ab", "8", "-aa", "0.15", "-ad", "512", "-as", "256", "-lw", "1e-4"]
GAUSS = 6                               # Gauss–Legendre nodes per side of each face (5.4, 5.8)
#: bounds the quick version asserts (tests/studies/test_electric.py)
POINT_BOUND, AREA_BOUND, FLUX_BOUND, SKYLIGHT_BOUND, SUM_BOUND, OFFICE_BOUND = 0.01, 0.01, 0.01, 0.02, 0.03, 0.03


def asymmetric(gamma, c):
    """The 5.2 luminaire's intensity [cd] (γ from the nadir, C from C0, degrees)."""
    g, cc = np.radians(gamma), np.radians(c)
    return 1000.0 * (1.1 + np.cos(g)) * (1.0 + 0.5 * np.cos(cc) + 0.3 * np.sin(2 * cc)) / 2.1


def downlight(gamma, c):
    """The office's downlight [cd]: a cos^1.5 beam below the horizontal, nothing above."""
    return 1500.0 * np.clip(np.cos(np.radians(gamma)), 0.0, None) ** 1.5 + 0.0 * c


def ies_file(path: Path, fn, horizontal, vertical) -> Path:
    """Write an IES LM-63-2002 file of ``fn(γ, C)`` [cd] on the given angles."""
    H, V = np.meshgrid(horizontal, vertical, indexing="ij")
    lines = ["IESNA:LM-63-2002", "[TEST] lbl_illum electric-light study", "TILT=NONE",
             f"1 -1 1 {len(vertical)} {len(horizontal)} 1 2 0 0 0", "1 1 40",
             " ".join(f"{x:g}" for x in vertical), " ".join(f"{x:g}" for x in horizontal)]
    lines += [" ".join(f"{x:.8g}" for x in row) for row in fn(V, H)]
    path.write_text("\n".join(lines) + "\n")
    return path


def _corner(a, b, c):
    A, B = a / c, b / c
    sa, sb = np.sqrt(1 + A * A), np.sqrt(1 + B * B)
    return (A / sa * np.arctan(B / sa) + B / sb * np.arctan(A / sb)) / (2 * np.pi)


def rectangle_factor(points, x0, x1, y0, y1, h):
    """Configuration factor from upward sensors to the parallel rectangle [x0, x1] × [y0, y1]
    at height h (Howell B-3 by superposition)."""
    x, y, z = points.T
    c = h - z
    return (_corner(x1 - x, y1 - y, c) - _corner(x0 - x, y1 - y, c) - _corner(x1 - x, y0 - y, c)
            + _corner(x0 - x, y0 - y, c))


def _box(material, size=ROOM, roof_hole=None):
    """The room's six faces as rectangles (inward normals do not matter: surfaces are
    two-sided); ``roof_hole`` (x0, x1, y0, y1) leaves an opening in the roof."""
    X, Y, Z = size
    faces = [([0, 0, 0], [X, 0, 0], [0, Y, 0]), ([0, 0, 0], [X, 0, 0], [0, 0, Z]), ([0, Y, 0], [X, 0, 0], [0, 0, Z]),
             ([0, 0, 0], [0, Y, 0], [0, 0, Z]), ([X, 0, 0], [0, Y, 0], [0, 0, Z])]
    out = [{"shape": "rectangle", "origin": o, "u": u, "v": v, "material": material} for o, u, v in faces]
    if roof_hole is None:
        out.append({"shape": "rectangle", "origin": [0, 0, Z], "u": [X, 0, 0], "v": [0, Y, 0], "material": material})
    else:
        x0, x1, y0, y1 = roof_hole
        for o, u, v in (([0, 0, Z], [x0, 0, 0], [0, Y, 0]), ([x1, 0, Z], [X - x1, 0, 0], [0, Y, 0]),
                        ([x0, 0, Z], [x1 - x0, 0, 0], [0, y0, 0]), ([x0, y1, Z], [x1 - x0, 0, 0], [0, Y - y1, 0])):
            out.append({"shape": "rectangle", "origin": o, "u": u, "v": v, "material": material})
    return out


def _scene(folder, geometry, materials, sky=None, luminaires=()):
    data = {"units": "m", "geometry": geometry, "materials": materials, "sky": sky or {"type": "none"},
            "luminaires": list(luminaires)}
    return scene_from_dict(data, folder, "electric.toml")


def _floor(n, z=0.0):
    g = (np.arange(n) + 0.5) / n
    X, Y = np.meshgrid(g * ROOM[0], g * ROOM[1])
    return np.column_stack([X.ravel(), Y.ravel(), np.full(X.size, z)]), np.tile([0, 0, 1.0], (X.size, 1))


def face_quadrature(n):
    """Gauss–Legendre n × n points on each of the room's six faces, inward normals, and the
    area weights (they sum to the room's surface S)."""
    g, w = np.polynomial.legendre.leggauss(n)
    u, wu = (g + 1) / 2, w / 2
    X, Y, Z = ROOM
    pts, nrm, wts = [], [], []
    for axis, extent in ((0, X), (1, Y), (2, Z)):
        others = [a for a in range(3) if a != axis]
        A, B = np.meshgrid(u * ROOM[others[0]], u * ROOM[others[1]], indexing="ij")
        W = np.outer(wu, wu).ravel() * ROOM[others[0]] * ROOM[others[1]]
        for side, sign in ((0.0, 1.0), (extent, -1.0)):
            p = np.zeros((A.size, 3))
            p[:, others[0]], p[:, others[1]], p[:, axis] = A.ravel(), B.ravel(), side
            nn = np.zeros((A.size, 3))
            nn[:, axis] = sign
            pts.append(p)
            nrm.append(nn)
            wts.append(W)
    return np.vstack(pts), np.vstack(nrm), np.concatenate(wts)


def _errors(E, ref):
    e = np.abs(E / ref - 1)
    return {"mean_error": float(e.mean()), "max_error": float(e.max()), "bias": float(np.mean(E / ref - 1))}


def run(ctx: StudyContext) -> Report:
    quick = ctx.quick
    rep = Report("electric", TITLE, "")
    res = rep.results
    programs = radiance_programs()
    ctx.plan(8 + (0 if programs is None else 1))
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        ies_file(folder / "asym.ies", asymmetric, np.arange(0, 360.1, 5), np.arange(0, 180.1, 2.5))
        ies_file(folder / "iso.ies", lambda g, c: I_ISO + 0 * g, np.array([0.0]), np.array([0.0, 180.0]))
        ies_file(folder / "down.ies", downlight, np.array([0.0]), np.arange(0, 90.1, 5))
        black = {"black": {"type": "diffuse", "reflectance": 0.0}}
        direct = Options(bounces=0)
        n = 8 if quick else 16
        P, N = _floor(n)

        # 5.2 point source
        pos = np.array([1.6, 2.3, 2.5])
        scene = _scene(folder, _box("black"), black, luminaires=[{"file": "asym.ies", "position": pos.tolist(),
                                                                   "rotation": 30.0}])
        t = time.perf_counter()
        r = compute_illuminance(scene, P, N, direct)
        ctx.step("5.2 point source", r.stats)
        w = P - pos
        d = np.linalg.norm(w, axis=1)
        e = w / d[:, None]
        a = math.radians(30.0)
        local = e @ np.array([[math.cos(a), -math.sin(a), 0], [math.sin(a), math.cos(a), 0], [0, 0, 1.0]])
        gamma = np.degrees(np.arccos(-local[:, 2]))
        c = np.degrees(np.arctan2(local[:, 1], local[:, 0])) % 360
        ref = asymmetric(gamma, c) * (-e[:, 2]) / d ** 2
        res["point_source"] = {**_errors(r.illuminance, ref), "sensors": len(P), "seconds": time.perf_counter() - t}

        # 5.3 area source
        panel = {"shape": "rectangle", "origin": [1.4, 1.7, 2.0], "u": [1.2, 0, 0], "v": [0, 0.6, 0], "material": "lamp"}
        scene = _scene(folder, _box("black") + [panel], {**black, "lamp": {"type": "light", "luminance": PANEL_L}})
        t = time.perf_counter()
        r = compute_illuminance(scene, P, N, direct)
        ctx.step("5.3 area source", r.stats)
        ref = math.pi * PANEL_L * rectangle_factor(P, 1.4, 2.6, 1.7, 2.3, 2.0)
        res["area_source"] = {**_errors(r.illuminance, ref), "sensors": len(P), "seconds": time.perf_counter() - t}

        # 5.4 and 5.8: flux in the closed room
        Q, QN, QW = face_quadrature(GAUSS)
        S = 2 * (ROOM[0] * ROOM[1] + ROOM[0] * ROOM[2] + ROOM[1] * ROOM[2])
        centre = [ROOM[0] / 2, ROOM[1] / 2, ROOM[2] / 2]
        phi = 4 * math.pi * I_ISO
        scene = _scene(folder, _box("black"), black, luminaires=[{"file": "iso.ies", "position": centre}])
        r = compute_illuminance(scene, Q, QN, direct)
        ctx.step("5.4 flux conservation", r.stats)
        arrived = float(np.sum(r.illuminance * QW))
        res["flux_conservation"] = {"flux_lm": phi, "arrived_lm": arrived, "error": arrived / phi - 1,
                                    "area_m2": float(QW.sum()), "points": len(Q)}
        grey = {"grey": {"type": "diffuse", "reflectance": RHO_58}}
        scene = _scene(folder, _box("grey"), grey, luminaires=[{"file": "iso.ies", "position": centre}])
        opts = Options(bounces=BOUNCES_58, accuracy=0.2 if quick else 0.1, samples=128 if quick else 512)
        t = time.perf_counter()
        r = compute_illuminance(scene, Q, QN, opts)
        ctx.step("5.8 internal reflected component", r.stats)
        mean = float(np.sum(r.illuminance * QW) / S)
        exact = phi * (1 - RHO_58 ** (BOUNCES_58 + 1)) / (S * (1 - RHO_58))
        res["reflected_component"] = {"rho": RHO_58, "bounces": BOUNCES_58, "mean_lux": mean, "exact_lux": exact,
                                      "cie_lux": phi / (S * (1 - RHO_58)), "error": mean / exact - 1,
                                      "indirect_mean_lux": float(np.sum(luminance(r.indirect) * QW) / S),
                                      "seconds": time.perf_counter() - t, "records": int(sum(r.stats.new_records))}

        # translucent skylight
        hole = (1.0, 3.0, 1.0, 3.0)
        sheet = {"shape": "rectangle", "origin": [1.0, 1.0, ROOM[2]], "u": [2, 0, 0], "v": [0, 2, 0], "material": "sheet"}
        mats = {**black, "sheet": {"type": "translucent", "reflectance": SHEET[0], "transmittance": SHEET[1]}}
        scene = _scene(folder, _box("black", roof_hole=hole) + [sheet], mats,
                       sky={"type": "uniform", "horizontal_illuminance": E_H})
        t = time.perf_counter()
        r = compute_illuminance(scene, P, N, Options(bounces=2, accuracy=0.15, samples=256,
                                                     point_samples=SKYLIGHT_SAMPLES))
        ctx.step("translucent skylight", r.stats)
        ref = SHEET[1] * E_H * rectangle_factor(P, *hole, ROOM[2])
        res["skylight"] = {**_errors(r.illuminance, ref), "sensors": len(P), "seconds": time.perf_counter() - t}

        # daylight and electric light together
        window_wall = [g for g in _box("wall") if not (g["origin"] == [0, 0, 0] and g["u"] == [ROOM[0], 0, 0]
                                                       and g["v"] == [0, 0, ROOM[2]])]
        sill = [{"shape": "rectangle", "origin": [0, 0, 0], "u": [ROOM[0], 0, 0], "v": [0, 0, 0.9], "material": "wall"},
                {"shape": "rectangle", "origin": [0, 0, 2.2], "u": [ROOM[0], 0, 0], "v": [0, 0, 0.8], "material": "wall"},
                {"shape": "rectangle", "origin": [0, 0, 0.9], "u": [0.8, 0, 0], "v": [0, 0, 1.3], "material": "wall"},
                {"shape": "rectangle", "origin": [3.2, 0, 0.9], "u": [0.8, 0, 0], "v": [0, 0, 1.3], "material": "wall"},
                {"shape": "rectangle", "origin": [0.8, 0, 0.9], "u": [2.4, 0, 0], "v": [0, 0, 1.3], "material": "pane"}]
        mats = {"wall": {"type": "diffuse", "reflectance": 0.5}, "pane": {"type": "glass", "transmittance": 0.8}}
        lums = [{"file": "down.ies", "position": [1.3, 2.5, 2.95]}, {"file": "down.ies", "position": [2.7, 2.5, 2.95]}]
        sky = {"type": "cie-overcast", "horizontal_illuminance": E_H}
        W, WN = _floor(6 if quick else 10, 0.8)
        opts = Options(bounces=4, accuracy=0.15, samples=256 if quick else 512)
        runs = {}
        for label, s, ls in (("daylight", sky, ()), ("electric", None, lums), ("both", sky, lums)):
            scene = _scene(folder, window_wall + sill, mats, sky=s, luminaires=ls)
            rr = compute_illuminance(scene, W, WN, opts)
            ctx.step(f"together: {label}", rr.stats)
            runs[label] = rr.illuminance
        total = runs["daylight"] + runs["electric"]
        res["together"] = {**_errors(runs["both"], total), "sensors": len(W),
                           "daylight_mean_lux": float(runs["daylight"].mean()),
                           "electric_mean_lux": float(runs["electric"].mean())}

        # office of downlights against Radiance
        if programs is not None:
            res["office"] = _office(ctx, folder, quick, programs)
    res["checks"] = checks(res)
    _write(rep, res, programs)
    return rep


def _office(ctx, folder, quick, programs):
    X, Y, Z = 6.0, 8.0, 3.0
    geo = [{"shape": "rectangle", "origin": [0, 0, 0], "u": [X, 0, 0], "v": [0, Y, 0], "material": "floor"},
           {"shape": "rectangle", "origin": [0, 0, Z], "u": [X, 0, 0], "v": [0, Y, 0], "material": "ceiling"}]
    for o, u in (([0, 0, 0], [X, 0, 0]), ([0, Y, 0], [X, 0, 0]), ([0, 0, 0], [0, Y, 0]), ([X, 0, 0], [0, Y, 0])):
        geo.append({"shape": "rectangle", "origin": o, "u": u, "v": [0, 0, Z], "material": "wall"})
    mats = {"floor": {"type": "diffuse", "reflectance": 0.2}, "ceiling": {"type": "diffuse", "reflectance": 0.7},
            "wall": {"type": "diffuse", "reflectance": 0.5}}
    lums = [{"file": "down.ies", "position": [x, y, Z - 0.01], "name": f"D{i + 1}"}
            for i, (x, y) in enumerate((x, y) for x in (1.5, 4.5) for y in (1.5, 4.0, 6.5))]
    scene = scene_from_dict({"units": "m", "geometry": geo, "materials": mats, "luminaires": lums}, folder, "office.toml")
    g = np.arange(0.5, X, 1.0 if quick else 0.5)
    h = np.arange(0.5, Y, 1.0 if quick else 0.5)
    GX, GY = np.meshgrid(g, h)
    P = np.column_stack([GX.ravel(), GY.ravel(), np.full(GX.size, 0.8)])
    N = np.tile([0, 0, 1.0], (len(P), 1))
    t = time.perf_counter()
    ours = compute_illuminance(scene, P, N).illuminance
    t_ours = time.perf_counter() - t
    ex = export_radiance(scene, folder / "rad", P, N)
    env = programs["env"]
    with open(ex.directory / ex.octree, "wb") as octree:
        subprocess.run([str(programs["bin"]["oconv"]), *ex.scene_files], cwd=ex.directory, env=env, stdout=octree,
                       stderr=subprocess.DEVNULL, check=True)
    settings = RTRACE_QUICK if quick else RTRACE_FULL
    cmd = ex.rtrace_command(settings)
    cmd[0] = str(programs["bin"]["rtrace"])
    t = time.perf_counter()
    run = subprocess.run(cmd, cwd=ex.directory, env=env, input=(ex.directory / ex.points).read_text(),
                         capture_output=True, text=True, check=True)
    t_rad = time.perf_counter() - t
    theirs = illuminance_from_rtrace(run.stdout)
    ctx.step("office of downlights: ours and rtrace")
    return {**_errors(ours, theirs), "sensors": len(P), "ours_mean_lux": float(ours.mean()),
            "radiance_mean_lux": float(theirs.mean()), "ours_seconds": t_ours, "radiance_seconds": t_rad,
            "mean_difference": float(ours.mean() / theirs.mean() - 1), "luminaires": len(lums),
            "rtrace": " ".join(settings)}


def checks(res: dict) -> list[dict]:
    """The bounds the quick version asserts: (check, value, bound, held)."""
    out = []

    def add(name, value, bound):
        out.append({"check": name, "value": float(value), "bound": float(bound), "held": bool(value <= bound)})

    add("5.2 point source: worst sensor |E/E_ref − 1|", res["point_source"]["max_error"], POINT_BOUND)
    add("5.3 area source: worst sensor", res["area_source"]["max_error"], AREA_BOUND)
    add("5.4 flux conservation: |arrived/Φ − 1|", abs(res["flux_conservation"]["error"]), FLUX_BOUND)
    add("5.8 internal reflected component: |mean/exact − 1|", abs(res["reflected_component"]["error"]), FLUX_BOUND)
    add("translucent skylight: worst sensor", res["skylight"]["max_error"], SKYLIGHT_BOUND)
    add("daylight + electric: mean |both/(daylight + electric) − 1|", res["together"]["mean_error"], SUM_BOUND)
    if "office" in res:
        add("office of downlights: |mean ours / mean rtrace − 1|", abs(res["office"]["mean_difference"]), OFFICE_BOUND)
    return out


def _describe(rep: Report, text: str) -> None:
    """The module text as paragraphs and bullet lists (items start with ``* ``)."""
    for block in text.strip().split("\n\n"):
        lines = block.strip().splitlines()
        if lines and lines[0].startswith("* "):
            items, item = [], []
            for line in lines:
                if line.startswith("* ") and item:
                    items.append(" ".join(item))
                    item = []
                item.append(line.strip().removeprefix("* "))
            items.append(" ".join(item))
            rep.bullets(items)
        else:
            rep.text(block)


def _write(rep: Report, res: dict, programs) -> None:
    _describe(rep, __doc__.split("\n\n", 1)[1].split("Criteria:")[0])
    rep.heading("Results")
    ps, ar, fc, rc, sk, tg = (res[k] for k in ("point_source", "area_source", "flux_conservation",
                                               "reflected_component", "skylight", "together"))
    rows = [["5.2 point source", str(ps["sensors"]), pct(ps["mean_error"], 4), pct(ps["max_error"], 4)],
            ["5.3 area source", str(ar["sensors"]), pct(ar["mean_error"], 4), pct(ar["max_error"], 4)],
            ["translucent skylight", str(sk["sensors"]), pct(sk["mean_error"]), pct(sk["max_error"])],
            ["daylight + electric against the sum", str(tg["sensors"]), pct(tg["mean_error"]), pct(tg["max_error"])]]
    rep.table(["case", "sensors", "mean error", "worst sensor"], rows)
    rep.bullets([
        f"5.4: {fmt(fc['arrived_lm'])} lm arrive on the {fmt(fc['area_m2'])} m² of faces of the "
        f"{fmt(fc['flux_lm'])} lm the source emits ({pct(fc['error'], 4)}; {fc['points']} Gauss points).",
        f"5.8: ρ = {rc['rho']:g}, {rc['bounces']} bounces: mean {fmt(rc['mean_lux'])} lx against "
        f"Φ (1 − ρ^{rc['bounces'] + 1})/(S (1 − ρ)) = {fmt(rc['exact_lux'])} lx ({pct(rc['error'])}); the CIE "
        f"formula Φ/(S(1 − ρ)) = {fmt(rc['cie_lux'])} lx; {rc['records']:,} records, {rc['seconds']:.1f} s.",
        f"Together: daylight {fmt(tg['daylight_mean_lux'])} lx and electric {fmt(tg['electric_mean_lux'])} lx "
        "in the mean over the sensors."])
    if "office" in res:
        of = res["office"]
        rep.text(f"""
Office of {of['luminaires']} downlights, {of['sensors']} sensors: ours (default preset) {fmt(of['ours_mean_lux'])} lx
in the mean, `rtrace {of['rtrace']}` {fmt(of['radiance_mean_lux'])} lx ({pct(of['mean_difference'])});
per sensor {pct(of['mean_error'])} mean and {pct(of['max_error'])} worst difference (the noise of both).
Seconds of the calculation: ours {of['ours_seconds']:.1f}, rtrace {of['radiance_seconds']:.1f}.""")
    elif programs is None:
        rep.text("Radiance is not installed here: the office against rtrace was not run.")
    rep.heading("Bounds asserted by the test suite", 3)
    rep.table(["check", "measured", "bound", "held"],
              [[c["check"], fmt(c["value"], 3), fmt(c["bound"], 3), str(c["held"])] for c in res["checks"]])

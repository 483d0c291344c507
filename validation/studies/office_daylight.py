"""Study: the office example's daylight factor against Radiance, and what ``gensky``'s
horizon blend changes.

The tool (``compute_illuminance`` at the scene defaults, the ``high`` preset) and
Radiance 6's ``rtrace -I`` compute the illuminance at the 77 workplane sensors of
``examples/office`` on the same scene: the Radiance scene is the tool's own export
(:func:`lbl_illum.io.radiance.export_radiance`), in which the sky is our sky model written in
Radiance's ``.cal`` language (``lbl_sky.cal``), the glass the Radiance material with the same
optics, and the sun a ``light`` source of the same solid angle and normal illuminance.  Two
skies (the project's criteria):

* **overcast**: ``examples/office/scene.toml``, the traditional CIE overcast sky of
  E_h = 10,000 lux, ground reflectance 0.2, glazing ``model = "constant"`` (τ 0.6; exported
  as a ``BRTDfunc`` with constant coefficients); DF = 100 E / E_h [%];
* **clear with sun**: ``examples/office/office_clear_sky.toml``, the CIE standard clear sky
  (type 12) of 12,000 lux with the sun of Berkeley, California at 12:00 local standard time
  on 21 December 2024 (direct normal 70,000 lux), Fresnel glazing (exported as Radiance's
  ``glass``).

Radiance runs as pure Monte Carlo path tracing: ``-aa 0`` (no irradiance cache, so no
interpolation bias), ``-ad`` stratified hemisphere samples at the sensor, one ray per
bounce below it (``ambcomp.c``, ``samp_hemi``: n × n divisions with n = √(ad · weight),
at least 1 when ``-aa`` is 0), ``-ab 9``
(Radiance counts the sky seen from the sensor as a bounce: our 8 bounces), ``-lw 1e-5``
with Russian roulette below it (``-lr -10``, the default: unbiased), ``-dj 1`` (shadow
rays jittered over the sun's disk, as ours are).  Every sensor is traced ``repeats`` times
(:data:`FULL`, :data:`QUICK`), in two ``rtrace`` processes of one thread each
(:func:`rtrace_repeats`); the mean over the repeats is the reference and their spread
/ √repeats its standard error.  rtrace seeds its random numbers from the clock, so two
runs of the study differ within these errors.  The project's criterion: mean over the sensors of
|E_tool / E_Radiance − 1| ≤ 3 %.

**gensky.**  Radiance's own CIE overcast sky, ``gensky -c -B E_h/179 -g ρ_g`` (same zenith
luminance 9 E_h / (7π) and ground luminance ρ_g E_h / π as ours), is ``skybright.cal``:

    L = [w L_sky(D_z) + L_ground / w] / (w + 1/w),    w = (D_z + 1.01)^10

which blends sky and ground in a band around the horizon (D_z the direction's z
component): at the horizon the sky is 24 % darker than the CIE formula and the ground
just below it brighter.  Ours, like the CIE definition, switches at D_z = 0.  The study runs
Radiance once more with the gensky sky in place of ``lbl_sky.cal`` and reports the
difference in DF at the sensors, and the blended sky's own unobstructed E_h (by a midpoint
rule over the hemisphere), which is no longer the E_h that gensky was given.

References: G. J. Ward, "The RADIANCE lighting simulation and rendering system", SIGGRAPH
1994; Radiance 6 manual pages rtrace(1), gensky(1), and ``skybright.cal``;
ISO 15469:2004 / CIE S 011/E:2003; P. Moon, D. E. Spencer, Illuminating Engineering 37,
707–726 (1942).
"""

from __future__ import annotations

import dataclasses
import math
import shutil
import subprocess
import tempfile
import time
from pathlib import Path

import numpy as np

from lbl_illum import compute_illuminance, load_scene, read_points
from lbl_illum.errors import InputError
from lbl_illum.options import DEFAULT_PRESET, PRESET_MEASURED
from lbl_illum.photometry import luminance
from lbl_illum.io import export_radiance, illuminance_from_rtrace, radiance_programs, to_radiance

from . import repository_root
from .report import Report, StudyContext, error_summary, fmt, new_figure, pct

TITLE = "Office daylight factor against Radiance, and gensky's horizon blend"

TOLERANCE = 0.03                                    # the project's criterion: mean relative error
CASES = {"overcast": "scene.toml", "clear": "office_clear_sky.toml"}
#: the rtrace options besides -ad (pure Monte Carlo; see the module docstring)
RTRACE = ["-ab", "9", "-aa", "0", "-as", "0", "-lw", "1e-5", "-dj", "1"]
#: sensors of the quick version: the middle column of the grid, 0.5–5.5 m from the window
QUICK_POINTS = (3, 17, 31, 45, 59, 73)

#: ``mc_samples``, ``mc_seeds``: our pure Monte Carlo at the sensors nearest the window (overcast)
FULL = {"points": None, "ad": 16384, "repeats": 6, "mc_samples": 65536, "mc_seeds": 4}
QUICK = {"points": QUICK_POINTS, "ad": 4096, "repeats": 4, "mc_samples": 16384, "mc_seeds": 2}


def unavailable() -> str | None:
    """Why the study cannot run here (no Radiance or no source checkout), or None."""
    programs = radiance_programs()
    if programs is None:
        return "needs Radiance's oconv and rtrace (pip install pyradiance)"
    if gensky_program(programs) is None:
        return "needs Radiance's gensky (pip install pyradiance)"
    if repository_root() is None:
        return "needs the examples/ folder of a source checkout (examples/office)"
    return None


def gensky_program(programs) -> Path | None:
    """``gensky`` beside the other Radiance programs, or on the PATH."""
    if programs.get("root") is not None and (programs["root"] / "bin" / "gensky").is_file():
        return programs["root"] / "bin" / "gensky"
    found = shutil.which("gensky")
    return Path(found) if found else None


# -- Radiance ----------------------------------------------------------------------------
def gensky_overcast(programs, horizontal_illuminance: float, ground_reflectance: float) -> tuple[str, dict]:
    """``(sky file text, parameters)``: ``gensky -c -B E_h/179 -g ρ_g`` with the glows that
    make it a sky and a ground (as in Radiance's manual), and gensky's zenith and ground
    luminance [cd/m²] read back from its ``skyfunc`` arguments."""
    cmd = [str(gensky_program(programs)), "-ang", "45", "0", "-c", "-B", f"{to_radiance(horizontal_illuminance):.6g}",
           "-g", f"{ground_reflectance:g}"]
    run = subprocess.run(cmd, env=programs["env"], capture_output=True, text=True, check=True)
    words = run.stdout.split("skyfunc", 1)[1].split()
    # void brightfunc skyfunc / 2 skybr skybright.cal / 0 / 3 A1 A2 A3
    a = [float(w) for w in words[words.index("skybright.cal") + 3:][:3]]
    glows = ("\nskyfunc glow sky_glow\n0\n0\n4 1 1 1 0\n\nsky_glow source sky\n0\n0\n4 0 0 1 180\n\n"
             "skyfunc glow ground_glow\n0\n0\n4 1 1 1 0\n\nground_glow source ground\n0\n0\n4 0 0 -1 180\n")
    return run.stdout + glows, {"command": " ".join(["gensky", *cmd[1:]]), "zenith_luminance": 179.0 * a[1],
                                "ground_luminance": 179.0 * a[2]}


def gensky_luminance(dz, zenith_luminance: float, ground_luminance: float) -> np.ndarray:
    """``skybright.cal``'s CIE overcast sky [cd/m²] along directions of z component ``dz``:
    wmean((D_z+1.01)^10, L_z (1 + 2 D_z)/3, (D_z+1.01)^−10, L_ground)."""
    dz = np.asarray(dz, dtype=np.float64)
    w = (dz + 1.01) ** 10
    sky = zenith_luminance * (1.0 + 2.0 * dz) / 3.0
    return (w * sky + ground_luminance / w) / (w + 1.0 / w)


def hemisphere_illuminance(luminance_of_dz, n: int = 200000) -> float:
    """∫ L(D_z) D_z dω over the upper hemisphere [lux] for an azimuthally uniform L:
    2π ∫₀¹ L(μ) μ dμ by the midpoint rule in μ = D_z."""
    mu = (np.arange(n) + 0.5) / n
    return float(2.0 * math.pi * np.sum(luminance_of_dz(mu) * mu) / n)


def rtrace_repeats(programs, directory: Path, octree: str, points_text: str, options, repeats: int) -> np.ndarray:
    """(repeats, n) illuminance [lux]: the n sensors of ``points_text`` traced ``repeats``
    times, split over two single-threaded ``rtrace -I`` processes run side by side.  With
    ``-u+`` (its default) rtrace seeds its random numbers from the clock in seconds
    (``srandom(time(0))``, rtmain.c), so the second process starts 1.1 s after the first;
    within a process every line draws new numbers.  (``rtrace -n 2`` would not do: its
    forked children share one seed and repeat each other's samples.)"""
    lines = points_text.strip().splitlines()
    n = len(lines)
    first = (repeats + 1) // 2
    jobs = []
    for reps in (first, repeats - first):
        if reps == 0:
            continue
        if jobs:
            time.sleep(1.1)
        files = [tempfile.TemporaryFile("w+") for _ in range(3)]
        files[0].write("\n".join(lines * reps) + "\n")
        files[0].seek(0)
        cmd = [str(programs["bin"]["rtrace"]), "-I", "-h", "-u+", "-n", "1", *options, octree]
        proc = subprocess.Popen(cmd, cwd=directory, env=programs["env"], stdin=files[0], stdout=files[1],
                                stderr=files[2], text=True)
        jobs.append((proc, files, reps))
    runs = []
    for proc, files, reps in jobs:
        proc.wait()
        stdout, stderr = [(f.seek(0), f.read())[1] for f in files[1:]]
        for f in files:
            f.close()
        if proc.returncode != 0:
            raise RuntimeError(f"rtrace failed: {(stderr.strip().splitlines() or ['?'])[-1]}")
        runs.append(illuminance_from_rtrace(stdout).reshape(reps, n))
    return np.concatenate(runs)


def radiance(ctx, programs, folder: Path, octree_files: list[str], octree: str, points_text: str, ad: int,
             repeats: int, label: str) -> dict:
    """oconv ``octree_files`` into ``octree`` and trace the sensors; mean, standard error, seconds."""
    with open(folder / octree, "wb") as fh:
        subprocess.run([str(programs["bin"]["oconv"]), *octree_files], cwd=folder, env=programs["env"], stdout=fh,
                       stderr=subprocess.PIPE, check=True)
    options = [*RTRACE, "-ad", str(ad)]
    t0 = time.perf_counter()
    runs = rtrace_repeats(programs, folder, octree, points_text, options, repeats)
    seconds = time.perf_counter() - t0
    ctx.step(f"Radiance, {label}")
    mean = runs.mean(axis=0)
    se = runs.std(axis=0, ddof=1) / math.sqrt(repeats) if repeats > 1 else np.full(len(mean), np.nan)
    return {"illuminance": mean, "standard_error": se, "relative_standard_error": se / mean,
            "options": ["rtrace", "-I", "-h", "-u+", "-n", "1", *options, octree], "repeats": repeats,
            "samples_per_sensor": ad * repeats, "seconds": seconds}


# -- the study ---------------------------------------------------------------------------
def pure_monte_carlo(ctx, scene, P, N, rad: dict, samples: int, seeds: int) -> dict:
    """Our own converged answer at the sensors nearest the window (the row of smallest y),
    where Radiance's standard error is smallest: pure Monte Carlo (accuracy 0, no point
    samples, ``samples`` hemisphere samples, the scene's bounces), mean over ``seeds``
    seeds, against Radiance and against the run at the scene defaults."""
    row = np.flatnonzero(np.isclose(P[:, 1], P[:, 1].min()))
    opts = dataclasses.replace(scene.options, accuracy=0.0, samples=samples, point_samples=0)
    runs = []
    for seed in range(seeds):
        r = compute_illuminance(scene, P[row], N[row], dataclasses.replace(opts, seed=1000 + seed))
        ctx.step(f"lbl_illum pure Monte Carlo, seed {seed}", r.stats)
        runs.append(r.illuminance)
    runs = np.array(runs)
    mean = runs.mean(axis=0)
    se = runs.std(axis=0, ddof=1) / math.sqrt(seeds) / mean
    E_rad = rad["illuminance"][row]
    return {"sensors": row, "samples": samples, "seeds": seeds, "illuminance": mean, "relative_standard_error": se,
            "against_radiance": error_summary(mean, E_rad),
            "combined_standard_error": np.hypot(se, rad["relative_standard_error"][row])}


def run(ctx: StudyContext) -> Report:
    why = unavailable()
    if why is not None:
        raise InputError(f"office-daylight: {why}; the study is skipped")
    programs = radiance_programs()
    plan = QUICK if ctx.quick else FULL
    office = repository_root() / "examples" / "office"
    ctx.plan(2 * len(CASES) + 2 + plan["mc_seeds"])

    rep = Report("office-daylight", TITLE, "")
    res = rep.results
    res["rtrace"] = {"options": RTRACE, "ad": plan["ad"], "repeats": plan["repeats"]}
    res["cases"] = {}
    with tempfile.TemporaryDirectory(prefix="office-daylight-") as tmp:
        for case, file in CASES.items():
            scene = load_scene(office / file)
            P, N = read_points(office / "grid.pts", scene.unit_scale)
            if plan["points"] is not None:
                P, N = P[list(plan["points"])], N[list(plan["points"])]
            t0 = time.perf_counter()
            ours = compute_illuminance(scene, P, N)
            seconds = time.perf_counter() - t0
            ctx.step(f"lbl_illum, {case}", ours.stats)
            ex = export_radiance(scene, Path(tmp) / case, P, N)
            folder = ex.directory
            env_programs = radiance_programs(folder)
            text = (folder / ex.points).read_text()
            rad = radiance(ctx, env_programs, folder, ex.scene_files, ex.octree, text, plan["ad"], plan["repeats"],
                           case)
            e_h = scene.sky.horizontal_illuminance
            E = ours.illuminance
            entry = {"scene": f"examples/office/{file}", "sky": scene.sky.label, "horizontal_illuminance": e_h,
                     "glass": [m.model for m in scene.materials if m.kind == "glass"],
                     "sun": None if scene.sun is None else {"altitude": scene.sun.altitude,
                                                            "azimuth": scene.sun.azimuth,
                                                            "direct_normal_illuminance":
                                                                scene.sun.direct_normal_illuminance},
                     "points": P, "ours": E, "ours_direct": luminance(ours.direct),
                     "ours_seconds": seconds, "ours_rays": int(ours.stats.rays),
                     "options": {k: getattr(scene.options, k) for k in
                                 ("accuracy", "samples", "bounces", "point_samples", "interpolation", "seed")},
                     "radiance": rad, "error": error_summary(E, rad["illuminance"]),
                     "relative_error": E / rad["illuminance"] - 1.0,
                     "radiance_rse_mean": float(np.nanmean(rad["relative_standard_error"]))}
            entry["passed"] = bool(entry["error"]["mean"] <= TOLERANCE)
            if case == "overcast":
                entry["pure_monte_carlo"] = pure_monte_carlo(ctx, scene, P, N, rad, plan["mc_samples"],
                                                             plan["mc_seeds"])
                sky_text, gensky = gensky_overcast(programs, e_h, scene.sky.ground_reflectance)
                (folder / "gensky.rad").write_text(sky_text)
                files = [f if f != "sky.rad" else "gensky.rad" for f in ex.scene_files]
                gen = radiance(ctx, env_programs, folder, files, "gensky.oct", text, plan["ad"], plan["repeats"],
                               "gensky overcast")
                L_z, L_g = gensky["zenith_luminance"], gensky["ground_luminance"]
                blended_e_h = hemisphere_illuminance(lambda mu: gensky_luminance(mu, L_z, L_g))
                ours_e_h = hemisphere_illuminance(lambda mu: L_z * (1.0 + 2.0 * mu) / 3.0)
                diff = gen["illuminance"] / rad["illuminance"] - 1.0
                se = np.hypot(gen["relative_standard_error"], rad["relative_standard_error"])
                rows = np.unique(np.round(P[:, 1], 6))
                entry["gensky"] = {**gensky, "radiance": gen, "difference": diff,
                                   "difference_by_row": {f"{yy:g}": float(np.mean(diff[np.isclose(P[:, 1], yy)]))
                                                         for yy in rows},
                                   "difference_summary": error_summary(gen["illuminance"], rad["illuminance"]),
                                   "difference_standard_error_mean": float(np.mean(se)),
                                   "ours_against_gensky": error_summary(E, gen["illuminance"]),
                                   "zenith_luminance_ours": scene.sky.zenith_luminance,
                                   "ground_luminance_ours": scene.sky.ground_luminance,
                                   "horizontal_illuminance_blended": blended_e_h,
                                   "horizontal_illuminance_unblended": ours_e_h}
            res["cases"][case] = entry
    ctx.step("report")
    _write(rep, res, plan, len(res["cases"]["overcast"]["points"]))
    return rep


def _write(rep: Report, res: dict, plan: dict, n: int) -> None:
    over, clear = res["cases"]["overcast"], res["cases"]["clear"]
    opts = over["options"]
    rep.text(f"""
The project asks that the daylight factor (DF) on the office example agree with Radiance's
`rtrace -I` on the exported scene within {pct(TOLERANCE, 0)} mean relative error, and the same
for a CIE clear sky with sun; and that the difference made by Radiance's own `gensky` sky, which
blends sky and ground near the horizon, be measured.  The exported sky is ours, written in
Radiance's `.cal` language (docs/radiance-export.md), so the two programs see the same sky,
glass and sun, and differ only in how they trace and sum the light.""")
    rep.heading("Set-up")
    rep.bullets([
        f"Scene: `examples/office` (4 × 6 × 3 m room, one 3 × 1.5 m south window, reflectances floor 0.2, walls "
        f"0.5, ceiling 0.8, outside ground 0.2), {n} workplane sensors at 0.8 m"
        + (" (the full grid.pts)." if plan["points"] is None else " (the middle column of grid.pts)."),
        f"**overcast**: `{over['scene']}`, {over['sky']}, glass model `{over['glass'][0]}` (exported as a "
        "`BRTDfunc` with constant coefficients).",
        f"**clear**: `{clear['scene']}`, CIE standard clear sky (general type 12), E_h "
        f"{clear['horizontal_illuminance']:,.0f} lux; sun at altitude {clear['sun']['altitude']:.2f}°, azimuth "
        f"{clear['sun']['azimuth']:.2f}° (Berkeley, 2024-12-21 12:00 UTC−8), direct normal "
        f"{clear['sun']['direct_normal_illuminance']:,.0f} lux; glass model `{clear['glass'][0]}` (exported as "
        "Radiance's `glass`).",
        f"lbl_illum: `compute_illuminance` at the scene defaults (preset `{DEFAULT_PRESET}`: accuracy "
        f"{opts['accuracy']:g}, {opts['samples']} samples, {opts['bounces']} bounces, {opts['point_samples']} "
        f"point samples, interpolation `{opts['interpolation']}`, seed {opts['seed']}).",
        f"Radiance 6 (pyradiance): `{' '.join(over['radiance']['options'])}`, each sensor traced "
        f"{plan['repeats']} times ({plan['ad'] * plan['repeats']:,} hemisphere samples a sensor); the mean is the "
        "reference, the spread of the repeats / √repeats its standard error.  Pure Monte Carlo: no irradiance "
        "cache, so no interpolation error; Russian roulette (`-lr -10`) below the weight `-lw`, so no "
        "truncation bias; `-dj 1` samples the sun's disk."])

    rep.heading("The tool against Radiance")
    rows = []
    for case, c in res["cases"].items():
        e = c["error"]
        rows.append([case, pct(e["mean"]), pct(e["bias"]), pct(e["max"]), pct(c["radiance_rse_mean"]),
                     fmt(c["ours_seconds"]), fmt(c["radiance"]["seconds"]), "yes" if c["passed"] else "no"])
    rep.table(["sky", "mean relative error", "mean signed", "largest", "Radiance standard error (mean)",
               "lbl_illum s", "Radiance s", f"within {pct(TOLERANCE, 0)}"], rows,
              caption="Relative error E_lbl/E_Radiance − 1 over the sensors.  Wall times on the shared 2-core "
                      "machine: lbl_illum with its threads, Radiance as two single-threaded processes.")
    e = over["error"]
    rep.text(f"""**Overcast.** DF ranges from {fmt(100 * float(over['radiance']['illuminance'].min()) /
over['horizontal_illuminance'])} % at the back to {fmt(100 * float(over['radiance']['illuminance'].max()) /
over['horizontal_illuminance'])} % near the window (Radiance).  Mean relative error {pct(e['mean'])}, mean signed
{pct(e['bias'])}, largest {pct(e['max'])}; Radiance's own standard error is {pct(over['radiance_rse_mean'])} on
average, so part of the difference is its noise.""")
    mc = over["pure_monte_carlo"]
    row = mc["sensors"]
    preset_row = error_summary(over["ours"][row], over["radiance"]["illuminance"][row])
    mc["preset_against_radiance"] = preset_row
    agree = mc["against_radiance"]["max"] <= 0.005
    mc["agree_within_half_percent"] = bool(agree)
    verdict = (f"The converged answers of the two programs agree within {pct(mc['against_radiance']['max'])} here; "
               "what the defaults add is their own error (interpolation and the noise of their samples), which the "
               f"office-tradeoff study measured at {pct(PRESET_MEASURED[DEFAULT_PRESET][1])} mean against a "
               "converged reference." if agree else
               f"The converged answers of the two programs differ by up to {pct(mc['against_radiance']['max'])} "
               "here.")
    rep.text(f"""Where Radiance's standard error is smallest, at the {len(row)} sensor{'s' if len(row) > 1 else ''}
nearest the window
(y = {over['points'][row[0], 1]:g} m; {pct(float(np.mean(over['radiance']['relative_standard_error'][row])))} on
average), our own pure Monte Carlo (accuracy 0, {mc['samples']:,} hemisphere samples, {mc['seeds']} seeds;
standard error {pct(float(np.mean(mc['relative_standard_error'])))}) differs from Radiance by
{pct(mc['against_radiance']['bias'])} on average, largest {pct(mc['against_radiance']['max'])} (the two
standard errors combined: {pct(float(np.mean(mc['combined_standard_error'])))}); the run at the defaults
differs there by {pct(preset_row['bias'])} on average, largest {pct(preset_row['max'])}.  {verdict}""")
    e = clear["error"]
    sunlit = int(np.sum(clear["ours_direct"] > 1000.0))
    rep.text(f"""**Clear sky with sun.** {sunlit} of the {n} sensors lie in the sun patch (direct sun above
1,000 lux); illuminance from {fmt(float(clear['radiance']['illuminance'].min()))} to
{fmt(float(clear['radiance']['illuminance'].max()))} lux (Radiance).  Mean relative error {pct(e['mean'])},
mean signed {pct(e['bias'])}, largest {pct(e['max'])} (Radiance standard error {pct(clear['radiance_rse_mean'])}
on average).""")

    g = over["gensky"]
    d = g["difference_summary"]
    rep.heading("gensky's sky against ours")
    rep.text(f"""`{g['command']}` gives the zenith luminance {fmt(g['zenith_luminance'], 5)} cd/m² (ours
{fmt(g['zenith_luminance_ours'], 5)}) and the ground luminance {fmt(g['ground_luminance'], 5)} cd/m² (ours
{fmt(g['ground_luminance_ours'], 5)}; gensky prints 4 digits): the same sky away from the horizon.  Its
`skybright.cal` blends sky and ground near the horizon, D_z being the direction's z component:""")
    rep.equation("""
L = [w L_sky(D_z) + L_ground / w] / (w + 1/w),   w = (D_z + 1.01)^10,   L_sky = L_z (1 + 2 D_z) / 3""")
    rep.text(f"""Ours switches from sky to ground at D_z = 0, as the CIE definition does.  The blended sky's
unobstructed horizontal illuminance is {fmt(g['horizontal_illuminance_blended'], 5)} lux,
{pct(1 - g['horizontal_illuminance_blended'] / g['horizontal_illuminance_unblended'])} below the
{fmt(g['horizontal_illuminance_unblended'], 5)} lux of the unblended sky of the same zenith luminance (midpoint
rule over the hemisphere).""")
    rep.table(["", "mean signed", "mean absolute", "largest absolute", "standard error of a difference (mean)"],
              [["Radiance, gensky sky against Radiance, our sky", pct(d["bias"]), pct(d["mean"]), pct(d["max"]),
                pct(g["difference_standard_error_mean"])],
               ["lbl_illum against Radiance with the gensky sky", pct(g["ours_against_gensky"]["bias"]),
                pct(g["ours_against_gensky"]["mean"]), pct(g["ours_against_gensky"]["max"]), "—"]],
              caption="DF with the gensky sky against DF with ours (both divided by the same E_h = "
                      f"{over['horizontal_illuminance']:,.0f} lux).")
    by_row = g["difference_by_row"]
    (first_y, first), (last_y, last) = list(by_row.items())[0], list(by_row.items())[-1]
    rows = [[f"{float(k):g}", pct(v)] for k, v in by_row.items()]
    rep.table(["sensor row, distance from the window wall [m]", "mean DF difference, gensky sky against ours"],
              rows, caption="The difference by row of sensors (Radiance against Radiance).")
    L_z, L_g = g["zenith_luminance"], g["ground_luminance"]
    darker = {deg: float(gensky_luminance(math.sin(math.radians(deg)), L_z, L_g)
                         / (L_z * (1 + 2 * math.sin(math.radians(deg))) / 3) - 1) for deg in (0, 5, 10, 15)}
    g["darker_at_altitude"] = {str(k): v for k, v in darker.items()}
    rep.text(f"""The blend darkens the sky near the horizon (by {pct(-darker[0], 0)} at the horizon,
{pct(-darker[5], 0)} at 5°, {pct(-darker[10], 0)} at 10°, {pct(-darker[15], 1)} at 15°) and brightens the
ground glow just below it.  A sensor at 0.8 m sees the window
(sill 0.9 m, head 2.4 m) from 11° to 73° above the horizon at 0.5 m from the wall, but only from
1° to 16° at 5.5 m, so the deep sensors see mostly that band; the room's surfaces near the window
see it too, and pass it on to every sensor.  Over the sensors, DF with gensky's sky is
{pct(d['bias'])} on average; the row means run from {pct(first)} at {float(first_y):g} m from the window to
{pct(last)} at {float(last_y):g} m.
The blend stands for the haze at the horizon that neither formula models; the CIE overcast sky is
defined without it, and so is ours.  A study that compares with Radiance results made with
`gensky` should expect lbl_illum to be that much higher.""")

    y = over["points"][:, 1]
    fig, axes = new_figure(11, 4.0, ncols=2)
    ax = axes[0]
    middle = np.isclose(over["points"][:, 0], 2.0)
    order = np.argsort(y[middle])
    e_h = over["horizontal_illuminance"]
    for values, se, label, style in ((over["ours"], None, "lbl_illum", "o-"),
                                     (over["radiance"]["illuminance"], over["radiance"]["standard_error"],
                                      "Radiance, our sky", "s--"),
                                     (g["radiance"]["illuminance"], g["radiance"]["standard_error"],
                                      "Radiance, gensky sky", "^:")):
        v = 100 * values[middle][order] / e_h
        ax.errorbar(y[middle][order], v, yerr=None if se is None else 200 * se[middle][order] / e_h, fmt=style,
                    ms=4, capsize=2, label=label)
    ax.set_yscale("log")
    ax.set_xlabel("distance from the window wall y [m] (sensors at x = 2 m)")
    ax.set_ylabel("daylight factor [%]")
    ax.set_title("overcast sky")
    ax.legend(fontsize=8)
    ax = axes[1]
    for case, marker in (("overcast", "o"), ("clear", "s")):
        c = res["cases"][case]
        ax.errorbar(c["points"][:, 1] + (0.04 if case == "clear" else 0.0), 100 * c["relative_error"],
                    yerr=200 * c["radiance"]["relative_standard_error"], fmt=marker, ms=3, capsize=1.5,
                    alpha=0.7, label=f"{case}: lbl_illum / Radiance − 1")
    se = np.hypot(g["radiance"]["relative_standard_error"], over["radiance"]["relative_standard_error"])
    ax.errorbar(y - 0.04, 100 * g["difference"], yerr=200 * se, fmt="^", ms=3, capsize=1.5, alpha=0.7, color="C3",
                label="overcast: Radiance gensky sky / Radiance our sky − 1")
    ax.axhline(0, color="grey", lw=0.6)
    ax.set_xlabel("distance from the window wall y [m]")
    ax.set_ylabel("relative difference [%]")
    ax.set_title("every sensor (bars: 2 standard errors of Radiance's mean)")
    ax.legend(fontsize=7)
    rep.figure("office_daylight", fig, "Left: DF along the middle of the room under the overcast sky. Right: the "
                                       "relative difference at every sensor, against the distance from the window.")

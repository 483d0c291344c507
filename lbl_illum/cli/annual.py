"""``lbl-illum annual``: a year of daylight at a sensor grid from the cache's daylight
coefficients, and the annual metrics of IES LM-83, LEED v4.1 and EN 17037.

The command's side of :mod:`lbl_illum.engine.annual` (the light) and
:mod:`lbl_illum.workplane.annual` (the metrics): its arguments, the checks made before
any work, the files of OUTDIR (each written whole or not at all) and the one line it
prints.  See docs/annual.md.
"""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path

from ..errors import InputError
from .shared import (add_cluster_arguments, check_cluster_arguments, cluster_note, finite, open_study_cluster,
                     run_options)

__all__ = ["add_annual_arguments", "annual_command", "ANNUAL_PRESET", "OUTPUT_FILES", "PLOT_FILES"]

#: The preset of an annual run unless ``--preset`` names another: the metrics count hours
#: above thresholds, where draft's 0.6 % mean error on the office example changes nothing.
ANNUAL_PRESET = "draft"
#: What OUTDIR receives (the plots only with matplotlib, unless --no-plots).
OUTPUT_FILES = ("illuminance.npy", "direct_sun.npy", "points.csv", "summary.json")
#: With --views: per view and hour, the DGP and the vertical illuminance; the figures.
GLARE_FILES = ("glare_dgp.npy", "glare_ev.npy", "glare.json")
PLOT_FILES = ("da.png", "sda.png", "ase.png", "day_hour.png")
#: Rows of the year the metrics are defined on.
YEAR_ROWS = 8760
#: What closed shades let through, as a factor on the glazing's transmittance.
DEFAULT_SHADE_TRANSMITTANCE = 0.05


def add_annual_arguments(parser) -> None:
    """Arguments of ``lbl-illum annual`` (the quality options are added by the caller)."""
    parser.add_argument("scene", help="scene file (.toml); its [sky] and [sun] are set aside")
    parser.add_argument("--points", required=True, metavar="PTS", help="sensor points (.pts, optional area name "
                        "column: areas get their own figures), or a Honeybee model (.hbjson: its sensor grids are "
                        "the areas, and OUTDIR/results/ gets Honeybee's annual layout)")
    parser.add_argument("--weather", required=True, metavar="FILE", help="weather file of a year, 8760 rows: "
                        "EnergyPlus .epw or Radiance/DAYSIM .wea")
    parser.add_argument("-o", "--output", required=True, metavar="OUTDIR",
                        help=f"folder for {', '.join(OUTPUT_FILES)} and the plots (created if missing)")
    parser.add_argument("--weather-values", choices=("irradiance", "illuminance"), default="irradiance",
                        help="what sets each hour's brightness: the direct and diffuse irradiance through the Perez "
                             "efficacies, as gendaymtx (default), or an EPW's own illuminance columns")
    parser.add_argument("--sky-subdivision", type=int, choices=(1, 2, 4), default=1, metavar="MF",
                        help="sky patches: 1 = Tregenza 145 + ground (default), 2 or 4 = Reinhart (577, 2305)")
    parser.add_argument("--ground-reflectance", type=finite(0.0, 1.0), metavar="R",
                        help="reflectance of the ground glow below the horizon (default: the scene's [sky] value, "
                             "else 0.2)")
    o = parser.add_argument_group("occupancy and metrics")
    o.add_argument("--schedule", metavar="FILE", help="occupancy, one value 0..1 per row of the year (default: "
                   "IES LM-83, 8:00-18:00 every day)")
    o.add_argument("--dst", choices=("us", "eu"), help="with the LM-83 hours: clocks one hour ahead in summer "
                   "(US or EU rule, the weather file's year)")
    o.add_argument("--threshold", type=finite(0.0, above=True), default=300.0, metavar="LUX",
                   help="daylight autonomy threshold (default 300, LM-83's sDA300/50%%)")
    o.add_argument("--healthcare", action="store_true", help="LEED v4.1 points of the Healthcare column")
    o.add_argument("--area", metavar="NAME", help="the area whose mean the day x hour map shows (default: all points)")
    o.add_argument("--no-plots", action="store_true", help="no PNG plots (they need matplotlib)")
    o.add_argument("--ill", action="store_true",
                   help="with --points MODEL.hbjson: also Honeybee's text results, results/GRID.ill (sensors x "
                        "sun-up hours, about 8 bytes a value), which honeybee-radiance's annual post-processing reads")
    v = parser.add_argument_group("annual glare", "At the eyes of named views ([views.NAME] in the scene file; a "
                                  "180 degree field along each view's direction): the vertical illuminance of every "
                                  "hour, the simplified DGP, and the DGP with the sun and the sky patches above the "
                                  "threshold seen through the glazing as sources; glare autonomy, the share of "
                                  "occupied hours per DGP class and the EN 17037 class (docs/glare.md).")
    v.add_argument("--views", nargs="+", metavar="NAME", help="the views whose glare to compute, or 'all'")
    v.add_argument("--glare-threshold", type=finite(0.0, above=True), default=2000.0, metavar="L",
                   help="luminance [cd/m2] from which a sky patch seen through the glazing is a glare source "
                        "(default 2000, evalglare's)")
    s = parser.add_argument_group("operable shades (IES LM-83 2.2.6)", "Each group's shades close, hour by hour, when "
                                  "more than 2 %% of the points would get 1000 lux or more of direct sun; sDA is taken "
                                  "with the shades so operated, ASE with them open.  Each group costs one more "
                                  "calculation of the coefficients.")
    s.add_argument("--shade", action="append", metavar="GROUP=MATERIAL[,MATERIAL...]",
                   help="a window group: its name and the glass materials of the scene its shades cover (repeat for "
                        "several groups)")
    s.add_argument("--shade-transmittance", type=finite(0.0, 1.0), default=DEFAULT_SHADE_TRANSMITTANCE, metavar="F",
                   help=f"closed shades let through F times the glazing's light (default {DEFAULT_SHADE_TRANSMITTANCE:g})")
    add_cluster_arguments(parser)
    parser.add_argument("-q", "--quiet", action="store_true", help="no progress display and no summary line")


def _check(args) -> None:
    """Everything that can be refused before any work."""
    out = Path(args.output)
    if out.exists() and not out.is_dir():
        raise InputError(f"-o {args.output}: is a file; give a folder")
    if not out.exists() and not out.resolve().parent.is_dir():
        raise InputError(f"-o {args.output}: folder {out.parent} does not exist")
    if args.dst and args.schedule:
        raise InputError("--dst goes with the LM-83 hours, not with --schedule (give the schedule in clock time)")
    if args.ill and Path(args.points).suffix.lower() != ".hbjson":
        raise InputError("--ill writes Honeybee's results of a model's sensor grids: give --points MODEL.hbjson")
    _shade_groups(args)
    check_cluster_arguments(args)


def _shade_groups(args) -> dict[str, list[str]]:
    """The ``--shade`` groups: name -> materials, refused in one line when malformed."""
    groups = {}
    for text in args.shade or ():
        name, eq, materials = text.partition("=")
        names = [m.strip() for m in materials.split(",") if m.strip()]
        if not eq or not name.strip() or not names:
            raise InputError(f"--shade {text}: expected GROUP=MATERIAL[,MATERIAL...]")
        if name.strip() in groups:
            raise InputError(f"--shade {text}: the group '{name.strip()}' is given twice")
        groups[name.strip()] = names
    return groups

def _plots_wanted(args) -> bool:
    """Whether to draw the plots: asked for and matplotlib at hand (said once if not)."""
    if args.no_plots:
        return False
    from ..optional import available

    if available("matplotlib"):
        return True
    if not args.quiet:
        print("lbl-illum: note: matplotlib is not installed: no plots (pip install matplotlib, or --no-plots)",
              file=sys.stderr)
    return False


def annual_command(args) -> int:
    """``lbl-illum annual``: compute, write OUTDIR, print one line; 0.  With ``--workers`` or
    ``--scheduler`` the coefficients and the direct sun are computed on a cluster
    (:mod:`lbl_illum.distributed.annual`)."""
    _check(args)
    cluster = open_study_cluster(args)
    try:
        return _annual(args, cluster)
    finally:
        if cluster is not None:
            cluster.close()


def _annual(args, cluster) -> int:
    """:func:`annual_command` once the arguments are checked and the cluster (or None) is open."""
    import numpy as np

    from ..daylight.skymatrix import sky_matrix
    from ..daylight.weather import read_weather
    from ..engine.annual import annual_light
    from ..io.files import atomic_write_npy, atomic_write_text
    from ..io.points import read_points
    from ..scene.scenefile import load_scene
    from ..workplane import annual as metrics
    from ..workplane.metrics import readable
    from .progress import ProgressBar, compile_notice

    t0 = time.perf_counter()
    plots = _plots_wanted(args)
    scene = load_scene(args.scene)
    points, normals, areas = read_points(args.points, scene.unit_scale, with_areas=True)
    views = _views(scene, args)
    if args.area is not None and args.area not in set(areas.tolist()):
        raise InputError(f"--area {args.area}: no point of {Path(args.points).name} is in that area")
    weather = read_weather(args.weather)
    if len(weather) != YEAR_ROWS:
        raise InputError(f"{Path(args.weather).name}: {len(weather)} rows; the annual metrics need the {YEAR_ROWS} "
                         "hours of a 365-day year")
    if args.schedule:
        occupancy = metrics.read_schedule(args.schedule)
    else:
        occupancy = metrics.lm83_occupancy(dst=args.dst, year=weather.year if args.dst else None)
    rho_g = args.ground_reflectance if args.ground_reflectance is not None else scene.sky.ground_reflectance
    try:
        matrix = sky_matrix(weather, mf=args.sky_subdivision, sun="separate", values=args.weather_values,
                            ground_reflectance=rho_g)
    except ValueError as exc:
        raise InputError(f"{Path(args.weather).name}: {exc}") from None
    if not (matrix.daylight & (occupancy > 0)).any():
        raise InputError(f"{Path(args.weather).name}: no occupied hour has daylight (the sun up at latitude "
                         f"{weather.site.latitude:g} and light in the file)")
    if not args.preset:
        args.preset = ANNUAL_PRESET
    options = run_options(scene, args)
    from ..engine.annual import shaded_scene

    shades = {}
    for name, materials in _shade_groups(args).items():
        try:
            shades[name] = shaded_scene(scene, materials, args.shade_transmittance)
        except ValueError as exc:
            raise InputError(f"--shade {name}: {exc}") from None
    if not args.quiet:
        print(f"lbl-illum: note: the year's skies replace the scene's [sky] and [sun]; quality preset "
              f"'{args.preset}'", file=sys.stderr)
        for warning in scene.warnings:
            print(f"lbl-illum: warning: {warning}", file=sys.stderr)
    lent = getattr(args, "progress", None)       # a batch's display (lbl_illum.cli.batch)
    bar = lent if lent is not None else ProgressBar(enabled=not args.quiet)
    solver, costs = _solver(args, cluster, bar)
    groups = []
    n = len(points)
    eyes = np.array([v.position for v in views.values()], np.float64).reshape(-1, 3)       # metres
    looks = np.array([v.unit_direction for v in views.values()]).reshape(-1, 3)
    sensors, facing = np.vstack([points, eyes]), np.vstack([normals, looks])
    try:
        with compile_notice(enabled=not args.quiet, bar=bar):
            light = annual_light(scene, sensors, facing, weather, options, ground_reflectance=rho_g, progress=bar,
                                 matrix=matrix, solve=solver())
            for name, closed in shades.items():
                bar.describe(f"shades of {name} closed")
                year = annual_light(closed, points, normals, weather, options, ground_reflectance=rho_g,
                                    progress=bar, matrix=matrix,
                                    solve=solver((_shade_groups(args)[name], args.shade_transmittance)))
                groups.append(metrics.WindowGroup(name, year.illuminance, year.direct_sun))
            glare = _glare(views, eyes, light, matrix, args, n, bar) if views else {}
    finally:
        if lent is None:
            bar.close()
    daylight_hours = metrics.en17037_daylight_hours(
        diffuse_horizontal=np.where(matrix.daylight, matrix.diffuse_horizontal_illuminance, np.nan))
    E_grid, D_grid = light.illuminance[:n], light.direct_sun[:n]
    result = metrics.annual_metrics(E_grid, occupancy, direct_sun=D_grid, groups=groups or None,
                                    areas=areas, daylight_hours=daylight_hours, threshold=args.threshold,
                                    healthcare=args.healthcare)
    summary = metrics.annual_summary(result)
    stats = light.stats
    summary = {"command": "annual", "scene": str(args.scene), "points_file": str(args.points),
               "weather": str(args.weather), "weather_values": args.weather_values,
               "sky_subdivision": args.sky_subdivision, "ground_reflectance": rho_g,
               "settings": options.as_dict(), "records": stats.records, "rays": stats.rays,
               "shade_groups": {name: materials for name, materials in _shade_groups(args).items()},
               "shade_transmittance": args.shade_transmittance if shades else None,
               "bytes_per_record": light.record_bytes, "sun_positions": int(len(light.sun_directions)),
               "seconds": None, **summary}
    if costs:
        summary["cluster"] = {"chunk_size": args.chunk_size, "round_chunks": args.round_chunks,
                              "runs": [c.as_dict() for c in costs]}

    out = Path(args.output)
    out.mkdir(exist_ok=True)
    arrays = [("illuminance.npy", E_grid), ("direct_sun.npy", D_grid)]
    if glare:
        arrays += [("glare_dgp.npy", np.array([g.dgp for g in glare.values()], np.float32)),
                   ("glare_ev.npy", np.array([g.ev for g in glare.values()], np.float32))]
    if result.shades is not None:
        arrays.append(("illuminance_shades_operated.npy", result.shades.illuminance))
    for name, array in arrays:
        atomic_write_npy(out / name, array)
    metrics.write_point_table(out / "points.csv", points / scene.unit_scale, result)
    if Path(args.points).suffix.lower() == ".hbjson":       # Honeybee's annual layout, for Ladybug's tools
        from ..io.honeybee_results import write_annual_folder
        from ..scene.honeybee import read_grids

        write_annual_folder(out / "results", read_grids(args.points), E_grid, D_grid, matrix.sun_altitude > 0.0,
                            ill=args.ill)
    if glare:
        doc = {"views": {name: {"position": list(views[name].position), "direction": list(views[name].direction),
                                **g.summary(occupancy)} for name, g in glare.items()},
               "threshold": args.glare_threshold, "order": list(glare),
               "method": "DGP (Wienold & Christoffersen 2006, low-light corrected) with the sun and the sky patches "
                         "seen through the glazing above the threshold as sources; DGPs = 6.22e-5 Ev + 0.184"}
        atomic_write_text(out / "glare.json", json.dumps(doc, indent=2) + "\n")
        summary["glare"] = {name: {"glare_autonomy": v["dgp"]["glare_autonomy"], "en17037": v["dgp"]["en17037"]}
                            for name, v in doc["views"].items()}
    if plots:
        _plots(out, scene, points, areas, E_grid, result, args, occupancy)
    seconds = time.perf_counter() - t0
    summary["seconds"] = seconds
    atomic_write_text(out / "summary.json", json.dumps(summary, indent=2) + "\n")
    if not args.quiet:
        o = summary["overall"]
        ase = f", ASE {o['ase']:.0f} %" if "ase" in o else ""
        views_text = "".join(f", glare autonomy {name} {g['glare_autonomy']:.0f} %"
                             for name, g in summary.get("glare", {}).items())
        print(f"lbl-illum: a year at {len(points)} points ({int(result.open.occupied_hours)} occupied hours): "
              f"sDA{args.threshold:g} {o['sda']:.0f} %{ase}{views_text}, mean DA {readable(o['da'])} %, "
              f"UDI 100-3000 {readable(o['udi']['useful'])} %, LEED {summary['leed']['points']} points; "
              f"records per level {stats.records}, {stats.rays:,} rays, {seconds:.1f} s"
              f"{cluster_note(cluster, costs[0] if costs else None)} -> {out}", file=sys.stderr)
    return 0


def _solver(args, cluster, bar):
    """``(solver, costs)``: ``solver(shades=None)`` gives the ``solve`` of
    :func:`~lbl_illum.engine.annual.annual_light` on the cluster (None without one); the
    runs' costs gather in ``costs``."""
    costs = []
    if cluster is None:
        return (lambda shades=None: None), costs
    from ..distributed.annual import annual_solver
    from ..distributed.plan import CHUNK_POINTS, ROUND_CHUNKS, Decomposition

    plan = Decomposition(args.chunk_size or CHUNK_POINTS, args.round_chunks or ROUND_CHUNKS)
    path = str(Path(args.scene).resolve())
    return (lambda shades=None: annual_solver(cluster, path, plan, bar, shades, costs)), costs


def _views(scene, args) -> dict:
    """The ``--views`` of the scene, by name ('all': every one), refused when unknown."""
    if not args.views:
        return {}
    names = list(scene.views) if args.views == ["all"] else list(dict.fromkeys(args.views))
    if not names:
        raise InputError(f"--views all: {Path(args.scene).name} has no [views.NAME] table")
    missing = [n for n in names if n not in scene.views]
    if missing:
        known = ", ".join(scene.views) or "none"
        raise InputError(f"--views {missing[0]}: no [views.{missing[0]}] in {Path(args.scene).name} (its views: {known})")
    return {n: scene.views[n] for n in names}


def _glare(views, eyes, light, matrix, args, n, bar) -> dict:
    """Each view's :class:`~lbl_illum.glare.annual.AnnualGlare` from the sensors at its eye."""
    from ..glare.annual import annual_glare, patch_visibility

    bar.describe("sky patches seen from the views")
    out = {}
    for i, (name, view) in enumerate(views.items()):
        vis = patch_visibility(light.context.direct, light.context.tracer, eyes[i], view, matrix.patches)
        out[name] = annual_glare(light.illuminance[n + i], matrix.luminance, matrix.sun_direction,
                                 matrix.direct_normal_illuminance, light.direct_sun[n + i], view, vis,
                                 threshold=args.glare_threshold)
    return out


def _plots(out: Path, scene, points, areas, illuminance, result, args, occupancy) -> None:
    """The plans of DA, sDA and ASE hours and the day x hour map of the mean illuminance."""
    import numpy as np

    from ..viz import annual_plots
    from ..workplane.grid import plan_outline

    walls, glazing = plan_outline(scene, float(np.median(points[:, 2])))
    xy = points / scene.unit_scale
    where = dict(areas=areas, outline=walls, windows=glazing)
    name = Path(args.scene).name
    t = f"{args.threshold:g}"
    annual_plots.da_plan(out / "da.png", xy, result.open.da, threshold=args.threshold,
                         title=f"Daylight autonomy DA{t} [%], {name}", **where)
    annual_plots.sda_plan(out / "sda.png", xy, result.lm83.da, threshold=args.threshold,
                          title=f"sDA{t}/50%: points with DA{t} >= 50 %, {name}", **where)
    if result.ase_hours is not None:
        annual_plots.ase_plan(out / "ase.png", xy, result.ase_hours, title=f"Direct sun >= 1000 lux [h], {name}",
                              **where)
    annual_plots.day_hour_plot(out / "day_hour.png", illuminance, areas=areas, area=args.area,
                               occupancy=occupancy,
                               title=f"Mean illuminance [lux], {args.area or 'all points'}, {name}")

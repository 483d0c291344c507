"""Command line: ``lbl-illum illuminance``, ``daylight-factor``, ``grid``, ``view``, ``glare``,
``validate`` and ``export radiance``.

The command line only parses arguments and calls the library.  Bad input ends with
one line on standard error naming the file, line or key, exit status 2 and no
output file written.
"""

from __future__ import annotations

import argparse
import json
import sys
import textwrap
import time
from pathlib import Path

from .._version import __version__
from ..errors import InputError
from ..optional import check as check_optional
from .shared import (add_cluster_arguments, check_cluster_arguments, check_output_file, cluster_compute, cluster_note,
                     finite as _finite, open_study_cluster, run_options, whole as _whole)
from .progress import ProgressBar, compile_notice
from ..options import DEFAULT_PRESET, INTERPOLATIONS, PRESETS, Options, preset_table
from ..scene.scenefile import MAX_BOUNCES
from ..viz.plots import PLAN_SCALES

__all__ = ["main"]

QUALITY_HELP = """\
quality options (also settable under [settings] in the scene file; the command line wins):
  accuracy  the paper's a: smaller = more records, more accurate, slower (0 = pure Monte Carlo)
  bounces   diffuse reflections followed (Radiance's -ab is bounces + 1 for daylight)
  samples   hemisphere rays of a first-level primary evaluation (Radiance's -ad)
"""


_ProgressBar = ProgressBar


_number = _finite()


class _Parser(argparse.ArgumentParser):
    def error(self, message):  # one line, exit 2, like every other input error
        raise InputError(f"{self.prog}: {message}")


def _studies():
    """The validation studies: the installed package ``lbl_illum_studies``, or, in a
    source checkout used without installing, ``validation/studies`` beside the package."""
    try:
        import lbl_illum_studies
    except ImportError:
        import importlib.util

        init = Path(__file__).resolve().parents[2] / "validation" / "studies" / "__init__.py"
        if not init.is_file():
            raise InputError("lbl-illum: the validation studies are not installed (pip install lbl_illum)") from None
        spec = importlib.util.spec_from_file_location("lbl_illum_studies", init,
                                                      submodule_search_locations=[str(init.parent)])
        lbl_illum_studies = importlib.util.module_from_spec(spec)
        sys.modules["lbl_illum_studies"] = lbl_illum_studies
        spec.loader.exec_module(lbl_illum_studies)
    return lbl_illum_studies


def _add_quality_options(p, preset: str = DEFAULT_PRESET, text: str | None = None) -> None:
    """The quality options shared by the commands that compute; the defaults shown are what
    a run uses when neither the command line nor the scene's ``[settings]`` sets an option:
    ``preset``'s values (:data:`~lbl_illum.options.DEFAULT_PRESET` unless the command has
    its own, ``annual``'s), read from :data:`~lbl_illum.options.PRESETS` (the others from
    :class:`~lbl_illum.options.Options`)."""
    d = Options().with_preset(preset)
    q = p.add_argument_group("quality", textwrap.fill(text or (
        "An option not given here comes from the scene's [settings], else from the "
        f"'{preset}' preset: its values are the defaults shown."), 88))
    q.add_argument("--preset", choices=tuple(PRESETS), metavar="NAME",
                   help=f"quality preset: {', '.join(PRESETS)} (see below; options given here win over it; "
                        f"default {preset})")
    q.add_argument("--accuracy", type=_finite(0.0), metavar="A",
                   help=f"the paper's a (default {d.accuracy:g}; 0 = no interpolation)")
    q.add_argument("--bounces", type=_whole(0, MAX_BOUNCES), metavar="N",
                   help=f"diffuse reflections followed (default {d.bounces})")
    q.add_argument("--samples", type=_whole(1), metavar="N",
                   help=f"hemisphere samples of a first-level primary evaluation of the cache (default {d.samples})")
    q.add_argument("--point-samples", type=_whole(0), metavar="N",
                   help="evaluate every point on its own with N hemisphere samples; the cache starts at the "
                        f"first reflection (default {d.point_samples or 'off'}; 0 = off)")
    q.add_argument("--ambient", type=_finite(0.0), metavar="E",
                   help=f"illuminance [lux] at the bounce limit (default {d.ambient:g})")
    q.add_argument("--min-spacing", type=_finite(0.0, above=True), metavar="D",
                   help="lower clamp on record R_i [scene units]")
    q.add_argument("--max-spacing", type=_finite(0.0, above=True), metavar="D",
                   help="upper clamp on record R_i [scene units]")
    q.add_argument("--no-bounce-scaling", action="store_true",
                   help="keep a and samples the same at every level (§3.4 scaling off)")
    q.add_argument("--seed", type=_whole(0), metavar="S", help=f"random seed (default {d.seed})")
    q.add_argument("--interpolation", choices=INTERPOLATIONS,
                   help="paper: Eq. 5 as published; gradients: over values extrapolated by each record's "
                        "irradiance gradients (Ward & Heckbert 1992); hessian: that with elliptical record "
                        "domains from the irradiance Hessian and leak checks (Schwarzhaupt et al. 2012) "
                        f"(default {d.interpolation})")


def _add_file_options(p) -> None:
    """Cache and statistics files, shared by ``illuminance`` and ``daylight-factor``."""
    from .cache import add_cache_file_arguments

    add_cache_file_arguments(p.add_argument_group("files"))


def _add_report_options(p, thresholds: str, unit: str) -> None:
    """Summary thresholds, plan and 3-D view, shared by ``illuminance`` and ``daylight-factor``."""
    g = p.add_argument_group("summary and pictures", textwrap.fill(
        "Every run prints its overall figures (mean, min, max, U0 = min/mean, min/max and the share of points at "
        "or above each threshold); --summary writes them, overall and per named area, as JSON.", 88))
    unit = unit.replace("%", "%%")
    g.add_argument("--summary", metavar="FILE", help="write the summary figures as JSON (default: none)")
    g.add_argument("--thresholds", nargs="+", type=_number, metavar="T",
                   help=f"thresholds [{unit}] for the shares of points at or above them (default {thresholds})")
    g.add_argument("--plot", metavar="PLAN", help="false-colour plan of the grid (.png, .pdf or .svg; matplotlib)")
    g.add_argument("--plot-title", metavar="TEXT", help="the plan's title (default: the quantity and the scene file)")
    g.add_argument("--plot-scale", choices=PLAN_SCALES, default=PLAN_SCALES[0],
                   help="the plan's colour scale (default linear; log for sunlit rooms)")
    g.add_argument("--plot-range", nargs=2, type=_number, metavar=("MIN", "MAX"),
                   help="the plan's colour range (default: the values'), for sheets compared side by side")
    g.add_argument("--view3d", metavar="SHOT", help="3-D view of the room with the points coloured, written off "
                   "screen (.png; pyvista)")


#: The commands, in the order ``--help`` lists them.
COMMANDS = ("illuminance", "daylight-factor", "grid", "view", "render", "glare", "annual", "validate", "export",
            "batch", "cache")


def _build_parser(only: str | None = None) -> argparse.ArgumentParser:
    """The command line's parser; with ``only`` (a name of :data:`COMMANDS`) only that
    command's sub-parser is built and only its modules imported (the others' argument
    definitions import render, glare, annual, batch and the validation studies: 0.07 s of
    every run), for a command line that names it."""
    parser = _Parser(prog="lbl-illum", description="Illuminance in daylit rooms by the irradiance cache of "
                     "Ward, Rubinstein & Clear (1988).")
    parser.add_argument("--version", action="version", version=f"lbl-illum {__version__}")
    subparsers = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)

    def wanted(name: str) -> bool:
        return only is None or only == name

    class _Commands:
        """``add_parser`` of the sub-parsers for the wanted commands; a parser of its own,
        attached to nothing, for the others."""

        @staticmethod
        def add_parser(name, **kwargs):
            return subparsers.add_parser(name, **kwargs) if wanted(name) else _Parser(prog=name)

    sub = _Commands()
    p = sub.add_parser("illuminance", help="illuminance at sensor points",
                       description="Compute the illuminance [lux] at the sensor points of a .pts file "
                       "(x y z nx ny nz per line, scene units): direct light plus diffuse "
                       "interreflection through the irradiance cache.",
                       epilog=QUALITY_HELP + preset_table(), formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("scene", help="scene file (.toml)")
    p.add_argument("--points", required=True, metavar="PTS", help="sensor points (.pts)")
    p.add_argument("-o", "--output", required=True, metavar="OUT",
                   help=".csv (x,y,z,nx,ny,nz,illuminance,direct,indirect) or .txt (one value per line)")
    _add_quality_options(p)
    _add_file_options(p)
    add_cluster_arguments(p)
    _add_report_options(p, "300 500", "lux")
    p.add_argument("-q", "--quiet", action="store_true", help="no progress bar and no summary line")

    d = sub.add_parser("daylight-factor", help="daylight factor at sensor points (CIE overcast sky)",
                       description=textwrap.fill(
                           "Compute the daylight factor DF = 100 E / E_h [%] at the sensor points under a CIE "
                           "overcast sky that replaces the scene's sky and sun.  E_h, the illuminance on an "
                           "unobstructed horizontal plane, is integrated from the sky model, not assumed.", 88),
                       epilog=QUALITY_HELP + preset_table(), formatter_class=argparse.RawDescriptionHelpFormatter)
    d.add_argument("scene", help="scene file (.toml)")
    d.add_argument("--points", required=True, metavar="PTS", help="sensor points (.pts, optional area name column)")
    d.add_argument("-o", "--output", required=True, metavar="OUT",
                   help=".csv (x,y,z,nx,ny,nz,daylight_factor,illuminance,direct,indirect) or .txt (DF per line)")
    d.add_argument("--sky-illuminance", type=_finite(0.0, above=True), default=10000.0, metavar="E",
                   help="horizontal illuminance of the overcast sky [lux] (default 10000; DF does not depend on it)")
    d.add_argument("--ground-reflectance", type=_finite(0.0, 1.0), metavar="R",
                   help="reflectance of the ground below the horizon (default: the scene's [sky] value, else 0.2)")
    _add_quality_options(d)
    _add_file_options(d)
    add_cluster_arguments(d)
    _add_report_options(d, "2", "%")
    d.add_argument("-q", "--quiet", action="store_true", help="no progress bar and no summary line")

    g = sub.add_parser("grid", help="workplane sensor points over the floor or named surfaces",
                       description="Write sensor points at a height above the floor (the lowest horizontal "
                       "surfaces with a ceiling or roof above them) or above the horizontal triangles of the named "
                       "materials, normals up, on a lattice centred in each area with the EN 12464-1 spacing "
                       "p = 0.2 x 5^log10(d) (d the longer side of the area less the margin, p <= 10 m).  Points "
                       "inside columns and within the margin of walls are left out.  Lengths in the scene's units.",
                       epilog="See docs/workplane.md for the rules.")
    g.add_argument("scene", help="scene file (.toml)")
    g.add_argument("-o", "--output", required=True, metavar="PTS", help="sensor points to write (.pts)")
    g.add_argument("--height", type=_number, metavar="H", help="height above the surface (default 0.8 m)")
    g.add_argument("--spacing", type=_finite(0.0, above=True), metavar="S",
                   help="largest spacing (default: EN 12464-1 rule)")
    g.add_argument("--margin", type=_finite(0.0), metavar="M", help="band along edges and walls without points "
                   "(default 0.5 m)")
    g.add_argument("--surface", action="append", metavar="MATERIAL", help="lay the grid on this material's "
                   "horizontal triangles, as an area of that name (repeat for several areas)")
    g.add_argument("--align", choices=("auto", "scene"), default="auto",
                   help="grid axes: each area's outline direction (auto, default) or the scene's x and y")
    g.add_argument("--no-names", action="store_true", help="six columns only (no area name column)")
    g.add_argument("--plot", metavar="PLAN", help="plan of the points and the room (.png, .pdf or .svg)")
    g.add_argument("-q", "--quiet", action="store_true", help="no summary line")

    w = sub.add_parser("view", help="3-D view of a scene, its results and its cache records",
                       description="Show the scene in 3-D (pyvista) with sensor points coloured by result and "
                       "the records of an irradiance cache file drawn as discs of radius a x R_i (their valid "
                       "domains; ellipses for elliptical domains), coloured by level, as the paper's Figure 5b: "
                       "in a window, or off screen into a PNG file with --screenshot.  Ceilings above the points "
                       "(or, without points, above mid-height) are left out with the records on them, and the "
                       "surfaces drawn semi-transparent.")
    w.add_argument("scene", help="scene file (.toml)")
    w.add_argument("--results", metavar="FILE", help="results .csv of illuminance or daylight-factor (coloured "
                   "by daylight_factor, else illuminance) or a .pts file (points only)")
    w.add_argument("--cache", metavar="FILE", help="draw the records of this cache file (any lbl_illum cache "
                   "file: it need not match the scene's settings)")
    w.add_argument("--levels", metavar="K[,K...]", help="with --cache: draw only these diffuse levels "
                   "(0 = the records at the points or pixels themselves; default all)")
    w.add_argument("--screenshot", metavar="PNG", help="write the view to this .png file instead of a window")
    w.add_argument("-q", "--quiet", action="store_true", help="no summary line")

    r = sub.add_parser("render", help="luminance image of a view (cd/m2) through the irradiance cache",
                       description="Render the luminance image of a Radiance view (cd/m2) through the "
                       "irradiance cache: .exr, .hdr (Radiance RGBE with VIEW= and EXPOSURE= headers) or .tif, "
                       "with an optional tone-mapped preview and false-colour image; see docs/rendering.md.  "
                       "Give the view as --view=\"-vtv -vp ...\" (with '=': it starts with a dash).",
                       epilog=QUALITY_HELP + preset_table(), formatter_class=argparse.RawDescriptionHelpFormatter)
    if wanted("render"):
        from .render import add_render_arguments
        add_render_arguments(r)
    _add_quality_options(r)

    if wanted("glare"):
        from .glare import add_glare_arguments
        add_glare_arguments(subparsers.add_parser(
            "glare", help="glare of a 180 degree fisheye image: DGP, Ev, sources, DGI, UGR",
            description="Glare figures of a 180 degree fisheye luminance image (-vta or -vth, with its VIEW= line) "
            "as Radiance's evalglare computes them: vertical illuminance, glare sources, position index, DGP "
            "(low-light corrected), DGI, UGR and the EN 17037 class; see docs/glare.md."))

    from .annual import ANNUAL_PRESET
    a = sub.add_parser("annual", help="a year of daylight at sensor points: DA, sDA, ASE, UDI, LEED, EN 17037",
                       description=textwrap.fill(
                           "Compute the illuminance at the sensor points for every hour of a weather file (8760 "
                           "rows, .epw or .wea) from daylight coefficients carried by the irradiance cache's "
                           "records, with the direct sun traced hour by hour, and the annual metrics of IES LM-83 "
                           "(sDA, ASE), UDI, LEED v4.1 and EN 17037.  Writes OUTDIR/illuminance.npy and "
                           "direct_sun.npy (float32, points x 8760, lux), points.csv, summary.json and PNG plans; "
                           "see docs/annual.md.", 88),
                       epilog=QUALITY_HELP + preset_table(), formatter_class=argparse.RawDescriptionHelpFormatter)
    if wanted("annual"):
        from .annual import add_annual_arguments
        add_annual_arguments(a)
    _add_quality_options(a, ANNUAL_PRESET, text=(
        f"The preset (default '{ANNUAL_PRESET}') replaces the quality keys of the scene's [settings]; an option given "
        "here wins over both.  The defaults shown are the preset's."))

    try:
        STUDIES = _studies().STUDIES if wanted("validate") else {}
    except InputError:        # said when the command is used
        STUDIES = {}
    v = sub.add_parser("validate", help="run a validation study and write its report",
                       description="Run a validation study against analytic or converged reference values "
                       "and write DIR/NAME/report.md, report.html, PNG plots and results.json (every number "
                       "in the report).", epilog=_STUDY_HELP, formatter_class=argparse.RawDescriptionHelpFormatter)
    v.add_argument("study", choices=[*STUDIES, "all"], metavar="NAME", help="a study, or all")
    v.add_argument("--report", default="lbl-illum-reports", metavar="DIR",
                   help="folder of the reports (default lbl-illum-reports; the repository's own are in "
                        "docs/validation)")
    v.add_argument("--force", action="store_true", help="replace reports already in DIR (default: refuse)")
    v.add_argument("--quick", action="store_true", help="the reduced version (seconds, as the test suite runs it)")
    v.add_argument("-q", "--quiet", action="store_true", help="no progress bar and no summary line")

    e = sub.add_parser("export", help="write the scene in another program's format",
                       description="Write the scene in another program's format.")
    formats = e.add_subparsers(dest="format", metavar="FORMAT", parser_class=_Parser)
    x = formats.add_parser("radiance", help="an equivalent Radiance scene (oconv/rtrace)",
                           description="Write an equivalent Radiance scene into DIR: materials.rad, sky.rad "
                           "(with lbl_sky.cal), geometry.rad (large scenes: a mesh compiled by obj2mesh), the "
                           "sensor points as points.pts, and README.txt with the oconv and rtrace commands that "
                           "reproduce a run.  Lengths in metres; radiance = luminance / 179 per channel.",
                           epilog="See docs/radiance-export.md for the conversions and the known differences.")
    x.add_argument("scene", help="scene file (.toml)")
    x.add_argument("dir", metavar="DIR", help="output folder (created; must be empty unless --force)")
    x.add_argument("--points", metavar="PTS", help="sensor points (.pts, scene units), copied to DIR/points.pts in metres")
    x.add_argument("--force", action="store_true", help="write into an existing non-empty DIR, replacing files "
                   "of the same names")
    x.add_argument("--glass", choices=("auto", "glass", "brtdfunc"), default="auto",
                   help="auto (default): each pane as its model says — Fresnel single panes as Radiance's glass, "
                        "double panes and constant panes as BRTDfunc; or every pane as glass, or as BRTDfunc")
    x.add_argument("-q", "--quiet", action="store_true", help="no progress bar and no summary line")
    if wanted("batch"):
        from .batch import add_batch_arguments
        add_batch_arguments(sub.add_parser(
            "batch", help="many studies (scenes, variants, grids, views, weather files) on one cluster",
            description=textwrap.fill(
                "Run the studies of a batch file (TOML: [defaults] and [[study]] tables, each a run of illuminance, "
                "daylight-factor, render or annual with that command's options; a scene may be a glob of variants) "
                "one after the other on one cluster, with one progress display and one summary table.  Every "
                "study is checked before any runs.  See docs/distributed.md.", 88)))

    from .cache import add_cache_commands

    add_cache_commands(sub)
    return parser


_STUDY_HELP = """\
studies:
  sphere-plane        the paper's §4: sphere on a plane against a closed form; Radiance side by side
  integrating-sphere  closed-form interreflection to many bounces, reflectance up to 0.99
  office-tradeoff     seconds against error on examples/office; the --preset ladder
  extremes            every knob at its extremes: finite, plausible, checked values
  scene-requires      records and rays go only where the queries need them
  figure5             the paper's Figure 5: blocks on a table, cache against pure Monte Carlo at equal rays
  deep-room           window portals and unglazed openings on a deep room, with and without portals
  sky-component       sky component through roof and façade openings against an independent integral, 16 skies
  office-daylight     office DF against Radiance rtrace (overcast; clear sky with sun) and gensky's horizon blend
  corpus              every preset on daylit interiors modelled by others, whole commands against references
  electric            CIE 171 point, area, flux and interreflection cases, a translucent skylight, IES downlights
  glare               DGP, Ev and glare sources of fisheye images against evalglare, a hand-evaluated case and Ev at the eye
  annual              a year through the cache's daylight coefficients against point-in-time runs and Radiance's two-phase
"""


class RunError(Exception):
    """A failure that is not bad input (e.g. no OpenGL for a 3-D view): one line, exit 1."""


def _check_run_files(args) -> None:
    """Refuse every bad output path before any work, so bad input leaves no file behind."""
    from ..viz.plots import check_plot_path
    from ..io.points import check_output_path

    if _grid_folder(args):
        out = Path(args.output)
        if out.exists() and not out.is_dir():
            raise InputError(f"{args.output}: is a file; a Honeybee model's results go into a folder of .res files")
        if not out.resolve().parent.is_dir():
            raise InputError(f"{args.output}: folder {out.parent} does not exist")
    else:
        check_output_path(args.output)
    if args.rebuild_cache and not args.cache:
        raise InputError("--rebuild-cache: give the cache file with --cache FILE")
    for extra in (args.stats, args.cache, args.summary):
        check_output_file(extra)
    if args.plot:
        check_plot_path(args.plot)
    elif args.plot_title is not None or args.plot_range is not None or args.plot_scale != "linear":
        raise InputError("--plot-title, --plot-scale and --plot-range go with --plot PLAN")
    if args.plot_range is not None and not args.plot_range[0] < args.plot_range[1]:
        raise InputError(f"--plot-range: MIN must be below MAX, got {args.plot_range[0]:g} {args.plot_range[1]:g}")
    if args.plot_range is not None and args.plot_scale == "log" and args.plot_range[0] <= 0.0:
        raise InputError(f"--plot-range: a log scale needs MIN above 0, got {args.plot_range[0]:g}")
    if args.view3d:
        from ..viz.view3d import check_view_path

        check_view_path(args.view3d)
    if args.thresholds is not None and not args.thresholds:
        raise InputError("--thresholds: give at least one value")
    check_cluster_arguments(args)


def _grid_folder(args) -> bool:
    """Points from a Honeybee model and an output without a suffix: a folder of one ``.res``
    per sensor grid and ``grids_info.json``, as Ladybug Tools reads them."""
    return Path(args.points).suffix.lower() == ".hbjson" and Path(args.output).suffix == ""


def _write_values(args, scene, points, normals, result, values, areas, **extra) -> None:
    """The results file, or a Honeybee model's folder of ``.res`` files (:func:`_grid_folder`)."""
    from ..photometry import luminance
    from ..io.points import write_results

    if _grid_folder(args):
        from ..io.honeybee_results import write_res_folder
        from ..scene.honeybee import read_grids

        write_res_folder(args.output, read_grids(args.points), values)
        return
    write_results(args.output, points / scene.unit_scale, normals, result.illuminance,
                  luminance(result.direct), luminance(result.indirect), areas=areas, **extra)


def _compute(scene, args, points, normals, cluster=None, recipe=None):
    """Run the integrator with the options, cache file and progress bar of ``args``:
    (result, integrator, options, costs).  With a ``cluster`` (:func:`open_study_cluster`)
    the run goes by rounds of chunks on it (``recipe``: how its workers make the scene;
    ``costs`` the rounds' costs, else None)."""
    from ..engine.integrator import Integrator

    options = run_options(scene, args)
    if not args.quiet:
        for warning in scene.warnings:
            print(f"lbl-illum: warning: {warning}", file=sys.stderr)
    integ = Integrator(scene, options)
    if not args.quiet:
        for note in integ.portal_notes():
            print(f"lbl-illum: note: {note}", file=sys.stderr)
    lent = getattr(args, "progress", None)       # a batch's display (lbl_illum.cli.batch)
    bar = lent if lent is not None else _ProgressBar(enabled=not args.quiet)
    integ.progress = bar
    costs = None
    try:
        if cluster is not None:
            with compile_notice(enabled=not args.quiet, bar=bar):
                result, costs = cluster_compute(cluster, integ, recipe, points, normals, args, bar)
            return result, integ, options, costs
        if args.cache:
            from ..io.cachefile import attach_cache_file
            attach_cache_file(integ, args.cache, rebuild=args.rebuild_cache)
        with compile_notice(enabled=not args.quiet, bar=bar):
            result = integ.compute(points, normals)       # writes the cache file too
    finally:
        if lent is None:
            bar.close()
    return result, integ, options, costs


def _write_stats(args, scene, result, options, seconds, values: dict, costs=None) -> None:
    """``--stats``: what the run did and its effective settings, as JSON."""
    from ..io.files import atomic_write_text

    stats = result.stats
    doc = {
        "points": len(result.rgb),
        "records": stats.records,
        "new_records": stats.new_records,
        "primary_evaluations": stats.primary_evaluations,
        "cache_hits": stats.cache_hits,
        "queries": stats.queries,
        "rays": stats.rays,
        "seconds": seconds,
        "compute_seconds": stats.seconds,
        **{key: {"mean": float(v.mean()), "min": float(v.min()), "max": float(v.max())} for key, v in values.items()},
        "settings": {**options.as_dict(),
                     "min_spacing": stats.min_spacing / scene.unit_scale,
                     "max_spacing": stats.max_spacing / scene.unit_scale,
                     "units": scene.units},
    }
    if costs is not None:
        doc["cluster"] = {"chunk_size": args.chunk_size, "round_chunks": args.round_chunks, **costs.as_dict()}
    atomic_write_text(args.stats, json.dumps(doc, indent=2) + "\n")


def _report(args, scene, points, values, areas, quantity: str, unit: str, thresholds, extra: dict) -> dict:
    """Write the summary JSON, the plan and the 3-D view of a run; return the summary.

    points : (n, 3) [m];  values : (n,) in ``unit``;  areas : (n,) names.
    """
    import numpy as np

    from ..io.files import atomic_write_text
    from ..workplane.metrics import grid_summary, summary_line

    doc = grid_summary(values, thresholds, areas, quantity=quantity.lower().replace(" ", "_"), unit=unit)
    doc = {"command": args.command, "scene": str(args.scene), "points_file": str(args.points),
           "output": str(args.output), **extra, **doc}
    if args.summary:
        atomic_write_text(args.summary, json.dumps(doc, indent=2) + "\n")
    if args.plot:
        from ..workplane.grid import plan_outline
        from ..viz.plots import plan_plot

        walls, glazing = plan_outline(scene, float(np.median(points[:, 2])))
        plan_plot(args.plot, points, values, areas=areas, outline=walls, windows=glazing, quantity=quantity,
                  unit=unit, thresholds=thresholds, summary=summary_line(doc), scale=args.plot_scale,
                  title=args.plot_title or f"{quantity} [{unit}], {Path(args.scene).name}",
                  value_range=tuple(args.plot_range) if args.plot_range is not None else None)
    if args.view3d:
        _view3d(scene, points, values, areas, f"{quantity} [{unit}]", args.view3d,
                title=f"{Path(args.scene).name}: {quantity.lower()}")
    return doc


def _view3d(scene, points, values, areas, label, screenshot, title=None) -> None:
    """Render the room with its points off screen into ``screenshot``; a failure of VTK is a
    :class:`RunError` (exit 1), not bad input."""
    from ..viz import view3d

    layers = [view3d.GeometryLayer(scene)]
    if points is not None:
        layers.append(view3d.PointLayer(points, values, label=label, areas=areas))
    try:
        view3d.render(scene, layers, points=points, screenshot=screenshot, title=title)
    except InputError:
        raise
    except Exception as exc:  # VTK reports a missing OpenGL as anything from RuntimeError up
        reason = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        raise RunError(f"{screenshot}: the 3-D view failed ({reason})") from None


def _start_compiling() -> None:
    """On a first run, start compiling half the engine's kernels in a second process
    before the scene is read (:func:`lbl_illum.engine.compiled.start_first_run`): the
    scene's first parse then overlaps it."""
    from ..engine.compiled import start_first_run

    start_first_run()


def _run_illuminance(args) -> int:
    t0 = time.perf_counter()
    from ..workplane.metrics import readable, summary_line
    from ..scene.scenefile import load_scene
    from ..io.points import read_points

    _check_run_files(args)
    cluster = open_study_cluster(args)
    if cluster is None:
        _start_compiling()
    try:
        scene = load_scene(args.scene)
        points, normals, areas = read_points(args.points, scene.unit_scale, with_areas=True)
        recipe = _recipe(args.scene) if cluster is not None else None
        result, integ, options, costs = _compute(scene, args, points, normals, cluster, recipe)
    finally:
        if cluster is not None:
            cluster.close()
    stats = result.stats
    E = result.illuminance
    _write_values(args, scene, points, normals, result, E, areas)
    thresholds = args.thresholds if args.thresholds is not None else [300.0, 500.0]
    doc = _report(args, scene, points, E, areas, "Illuminance", "lux", thresholds, {})
    seconds = time.perf_counter() - t0
    if args.stats:
        _write_stats(args, scene, result, options, seconds, {"illuminance": E}, costs)
    if not args.quiet:
        print(f"lbl-illum: illuminance at {len(points)} points (mean {readable(E.mean())} lux, min {readable(E.min())}, "
              f"max {readable(E.max())}) in {seconds:.2f} s{cluster_note(cluster, costs)}; records per level {stats.records} "
              f"({stats.primary_evaluations} new); {stats.rays:,} rays; {summary_line(doc, extremes=False)} "
              f"-> {args.output}", file=sys.stderr)
    return 0


def _recipe(scene_file, sky=None, sun=None, replace_sky: bool | None = None):
    """How a worker makes the run's scene: the scene file (absolute path) and the sky and sun
    that replace its own, if ``sky`` is given (:class:`lbl_illum.distributed.worker.SceneRecipe`)."""
    from ..distributed.worker import SceneRecipe

    replace = sky is not None if replace_sky is None else replace_sky
    return SceneRecipe(str(Path(scene_file).resolve()), sky, sun, replace)


def _overcast_scene(scene, sky_illuminance: float, ground_reflectance: float | None):
    """The scene under a CIE overcast sky of ``sky_illuminance`` [lux] and no sun."""
    import dataclasses

    from ..daylight.sky import sky_from_table

    if ground_reflectance is None:
        ground_reflectance = float(getattr(scene.sky, "ground_reflectance", 0.2))
    if not 0.0 <= ground_reflectance <= 1.0:
        raise InputError(f"--ground-reflectance must be within 0 and 1, got {ground_reflectance:g}")
    if not sky_illuminance > 0.0 or sky_illuminance == float("inf"):
        raise InputError(f"--sky-illuminance must be a positive illuminance [lux], got {sky_illuminance:g}")
    sky = sky_from_table({"type": "cie-overcast", "horizontal_illuminance": sky_illuminance,
                          "ground_reflectance": ground_reflectance}, "--sky-illuminance")
    return dataclasses.replace(scene, sky=sky, sun=None)


def _run_daylight_factor(args) -> int:
    t0 = time.perf_counter()
    from ..workplane.metrics import daylight_factor, readable, summary_line, unobstructed_horizontal_illuminance
    from ..photometry import luminance
    from ..scene.scenefile import load_scene
    from ..io.points import read_points

    _check_run_files(args)
    cluster = open_study_cluster(args)
    if cluster is None:
        _start_compiling()
    try:
        scene = _overcast_scene(load_scene(args.scene), args.sky_illuminance, args.ground_reflectance)
        E_h = unobstructed_horizontal_illuminance(lambda d: luminance(scene.sky.luminance(d)))
        points, normals, areas = read_points(args.points, scene.unit_scale, with_areas=True)
        recipe = _recipe(args.scene, scene.sky, None) if cluster is not None else None
        result, integ, options, costs = _compute(scene, args, points, normals, cluster, recipe)
    finally:
        if cluster is not None:
            cluster.close()
    stats = result.stats
    E = result.illuminance
    DF = daylight_factor(E, E_h)
    _write_values(args, scene, points, normals, result, DF, areas, daylight_factor=DF)
    thresholds = args.thresholds if args.thresholds is not None else [2.0]
    sky = {"sky": {"type": "cie-overcast", "horizontal_illuminance": args.sky_illuminance,
                   "unobstructed_horizontal_illuminance": E_h,
                   "ground_reflectance": scene.sky.ground_reflectance}}
    doc = _report(args, scene, points, DF, areas, "Daylight factor", "%", thresholds, sky)
    seconds = time.perf_counter() - t0
    if args.stats:
        _write_stats(args, scene, result, options, seconds, {"daylight_factor": DF, "illuminance": E}, costs)
    if not args.quiet:
        print(f"lbl-illum: daylight factor at {len(points)} points (mean {readable(DF.mean())}%, min {readable(DF.min())}, "
              f"max {readable(DF.max())}) in {seconds:.2f} s{cluster_note(cluster, costs)} under a CIE overcast sky (E_h {readable(E_h)} lux); records per "
              f"level {stats.records} ({stats.primary_evaluations} new); {stats.rays:,} rays; "
              f"{summary_line(doc, extremes=False)} -> {args.output}", file=sys.stderr)
    return 0


def _run_grid(args) -> int:
    t0 = time.perf_counter()
    import numpy as np

    from ..workplane.grid import plan_outline, workplane_grid
    from ..viz.plots import check_plot_path
    from ..scene.scenefile import load_scene
    from ..io.points import check_output_path, write_points

    check_output_path(args.output, formats=(".pts",))
    if args.plot:
        check_plot_path(args.plot)
    scene = load_scene(args.scene)
    k = scene.unit_scale
    height = 0.8 if args.height is None else args.height * k
    margin = 0.5 if args.margin is None else args.margin * k
    spacing = None if args.spacing is None else args.spacing * k
    grid = workplane_grid(scene, height=height, spacing=spacing, margin=margin, surfaces=args.surface,
                          align=args.align)
    where = "the floor" if not args.surface else ", ".join(args.surface)
    header = [f"lbl-illum grid {Path(args.scene).name}: {len(grid.points)} points {height / k:g} {scene.units} "
              f"above {where}, normals up; margin {margin / k:g} {scene.units}"]
    for lat in grid.lattices:
        header.append(f"area {lat.name} at z = {lat.level / k:.4g}: {lat.counts[0]} x {lat.counts[1]} cells of "
                      f"{lat.spacing[0] / k:.4g} x {lat.spacing[1] / k:.4g} {scene.units} at {lat.angle:.4g} deg "
                      f"(p = {lat.p / k:.4g} {scene.units}{' given' if spacing else ' by EN 12464-1'}), "
                      f"{lat.points} points" + (f"; left out: {_dropped(lat.dropped)}" if lat.dropped else ""))
    header.append("columns: x y z nx ny nz" + ("" if args.no_names else " area"))
    write_points(args.output, grid.points / k, grid.normals, None if args.no_names else grid.areas,
                 header="\n".join(header))
    if args.plot:
        from ..viz.plots import plan_plot

        walls, glazing = plan_outline(scene, float(np.median(grid.points[:, 2])))
        plan_plot(args.plot, grid.points, None, areas=grid.areas, outline=walls, windows=glazing,
                  title=f"Sensor grid, {Path(args.scene).name}: {len(grid.points)} points at {height:g} m")
    if not args.quiet:
        for warning in scene.warnings + grid.warnings:
            print(f"lbl-illum: warning: {warning}", file=sys.stderr)
        parts = []
        for name in dict.fromkeys(lat.name for lat in grid.lattices):
            lats = [lat for lat in grid.lattices if lat.name == name]
            count = sum(lat.points for lat in lats)
            if len(lats) == 1:
                lat = lats[0]
                parts.append(f"{name}: {count} on {lat.counts[0]} x {lat.counts[1]} cells of "
                             f"{lat.spacing[0] / k:.3g} x {lat.spacing[1] / k:.3g} {scene.units}")
            else:
                parts.append(f"{name}: {count} in {len(lats)} pieces")
        areas = "; ".join(parts)
        print(f"lbl-illum: grid: {len(grid.points)} points in {len(grid.area_names)} "
              f"{'area' if len(grid.area_names) == 1 else 'areas'} ({areas}) in {time.perf_counter() - t0:.2f} s "
              f"-> {args.output}", file=sys.stderr)
    return 0


def _dropped(counts: dict) -> str:
    return ", ".join(f"{n} {rule}" for rule, n in counts.items())


def _run_view(args) -> int:
    t0 = time.perf_counter()
    from ..viz import view3d
    from ..scene.scenefile import load_scene
    from ..io.points import read_results

    view3d.require_pyvista()
    if args.screenshot:
        view3d.check_view_path(args.screenshot)
    levels = None
    if args.levels is not None:
        if not args.cache:
            raise InputError("--levels: give the cache file with --cache FILE")
        try:
            levels = sorted({int(k) for k in args.levels.split(",") if k.strip()})
        except ValueError:
            raise InputError(f"--levels {args.levels}: give level numbers separated by commas, e.g. 0,1") from None
        if not levels or levels[0] < 0:
            raise InputError(f"--levels {args.levels}: give level numbers 0, 1, 2 ... separated by commas")
    scene = load_scene(args.scene)
    records = view3d.read_cache_layer(args.cache, levels) if args.cache else None
    points = values = areas = None
    label = "points"
    if args.results:
        points, _, columns, areas = read_results(args.results, scene.unit_scale)
        for key, name in (("daylight_factor", "Daylight factor [%]"), ("illuminance", "Illuminance [lux]")):
            if key in columns:
                values, label = columns[key], name
                break
    layers = [view3d.GeometryLayer(scene)]
    if points is not None:
        layers.append(view3d.PointLayer(points, values, label=label, areas=areas))
    if records is not None:
        layers.append(records)
    try:
        view3d.render(scene, layers, points=points, screenshot=args.screenshot, title=Path(args.scene).name)
    except InputError:
        raise
    except Exception as exc:  # VTK reports a missing OpenGL as anything from RuntimeError up
        reason = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        raise RunError(f"{args.screenshot or 'window'}: the 3-D view failed ({reason})") from None
    if not args.quiet and args.screenshot:
        what = [f"{len(points)} points"] if points is not None else []
        if records is not None:
            what.append(f"{sum(records.drawn.values()):,} of {sum(len(lv['R']) for lv in records.levels):,} "
                        "records")
        print(f"lbl-illum: view: {', '.join(what) or 'the scene'} in {time.perf_counter() - t0:.2f} s "
              f"-> {args.screenshot}", file=sys.stderr)
    return 0


def _run_export(args) -> int:
    if args.format is None:
        raise InputError("lbl-illum export: give a format (radiance)")
    t0 = time.perf_counter()
    from tqdm import tqdm

    from ..io.radiance import export_radiance
    from ..scene.scenefile import load_scene
    from ..io.points import read_points

    out = Path(args.dir)
    if out.exists() and not out.is_dir():
        raise InputError(f"{args.dir}: exists and is not a folder")
    if out.is_dir() and any(out.iterdir()) and not args.force:
        raise InputError(f"{args.dir}: folder is not empty (use --force to write into it)")
    if not out.resolve().parent.is_dir():
        raise InputError(f"{args.dir}: folder {out.parent} does not exist")
    scene = load_scene(args.scene)
    points = normals = None
    if args.points:
        points, normals = read_points(args.points, scene.unit_scale)
    if not args.quiet:
        for warning in scene.warnings:
            print(f"lbl-illum: warning: {warning}", file=sys.stderr)
    bar = tqdm(total=None, unit="step", delay=1.0, file=sys.stderr, disable=True if args.quiet else None,
               leave=False, dynamic_ncols=True, desc="export radiance")

    def step(text):
        bar.set_postfix_str(text, refresh=False)
        bar.update(1)

    try:
        ex = export_radiance(scene, out, points, normals, glass=args.glass, progress=step)
    finally:
        bar.close()
    if not args.quiet:
        shape = "mesh" if ex.mesh else "polygons"
        print(f"lbl-illum: export radiance: {len(ex.files)} files, {ex.triangles:,} triangles ({shape}), "
              f"{ex.spheres} spheres in {time.perf_counter() - t0:.2f} s -> {args.dir}", file=sys.stderr)
    return 0


def _run_validate(args) -> int:
    from tqdm import tqdm

    studies = _studies()
    STUDIES, StudyContext, run_study = studies.STUDIES, studies.StudyContext, studies.run_study

    check_optional("matplotlib", "validate: the reports")
    names = list(STUDIES) if args.study == "all" else [args.study]
    report_dir = Path(args.report)
    if report_dir.exists() and not report_dir.is_dir():
        raise InputError(f"{args.report}: not a folder")
    why_not = getattr(studies, "unavailable", lambda name: None)
    if args.study != "all" and (why := why_not(args.study)) is not None:
        raise InputError(f"validate {args.study}: cannot run here: {why}")
    there = [name for name in names if (report_dir / name / "report.md").exists()]
    if there and not args.force:
        raise InputError(f"{report_dir / there[0]}: a report is there already"
                         f"{f' (and {len(there) - 1} more)' if len(there) > 1 else ''}; "
                         "give --force to replace it, or another --report folder")
    start, written, skipped = time.perf_counter(), [], []
    for name in names:
        why = why_not(name) if args.study == "all" else None
        if why is not None:      # said even with --quiet: the summary would otherwise hide it
            print(f"lbl-illum: validate {name}: skipped: {why}", file=sys.stderr)
            skipped.append(name)
            continue
        t0 = time.perf_counter()
        bar = tqdm(total=None, unit="run", delay=1.0, file=sys.stderr, disable=True if args.quiet else None,
                   leave=False, dynamic_ncols=True, desc=name)
        ctx = StudyContext(quick=args.quick)

        def plan(total, bar=bar):
            bar.total = total
            bar.refresh()

        def step(label, bar=bar):
            bar.set_postfix_str(label, refresh=False)
            bar.update(1)

        ctx.on_plan, ctx.progress = plan, step
        try:
            folder = run_study(name, ctx, report_dir, command_dir=args.report)
        finally:
            bar.close()
        written.append(name)
        if not args.quiet:
            print(f"lbl-illum: validate {name}{' (quick)' if args.quick else ''}: {ctx.runs} runs, "
                  f"{ctx.records:,} records, {ctx.rays:,} rays in {time.perf_counter() - t0:.1f} s "
                  f"-> {folder / 'report.md'}", file=sys.stderr)
    if args.study == "all" and not args.quiet:
        from ..errors import plural

        left = f", {len(skipped)} skipped ({', '.join(skipped)})" if skipped else ""
        print(f"lbl-illum: validate all{' (quick)' if args.quick else ''}: {plural(len(written), 'report')} "
              f"written{left} in {time.perf_counter() - start:.1f} s -> {report_dir}", file=sys.stderr)
    return 0


def _one_line(exc: BaseException) -> str:
    """An error message as one line (line breaks of a message quoted from elsewhere become spaces)."""
    return " ".join(str(exc).split("\n")).replace("\r", " ")


def _freeze_at_exit() -> None:
    """Leave the objects still alive to the operating system (:func:`_no_collection_at_exit`),
    unless OpenImageIO is loaded: its bindings (nanobind) would list them as leaked."""
    import gc

    if "OpenImageIO" not in sys.modules:
        gc.freeze()


def _no_collection_at_exit() -> None:
    """At the process's exit, leave the objects still alive to the operating system
    instead of the last garbage collections through them (numba's types and kernels: 0.13 s
    of every run's exit).  Every file a command writes is closed before it returns."""
    import atexit

    atexit.unregister(_freeze_at_exit)
    atexit.register(_freeze_at_exit)


def main(argv=None) -> int:
    _no_collection_at_exit()
    words = sys.argv[1:] if argv is None else list(argv)
    command = words[0] if words and words[0] in COMMANDS and words[0] != "batch" else None
    parser = _build_parser(command)     # batch parses its studies with every command's parser
    try:
        args = parser.parse_args(argv)
        if args.command is None:
            parser.print_help()
            return 2
        if args.command == "illuminance":
            return _run_illuminance(args)
        if args.command == "daylight-factor":
            return _run_daylight_factor(args)
        if args.command == "grid":
            return _run_grid(args)
        if args.command == "view":
            return _run_view(args)
        if args.command == "render":
            from .render import check_image_size, render_command
            check_image_size(args)          # before the scene is even read
            return render_command(args)
        if args.command == "glare":
            from .glare import glare_command
            return glare_command(args)
        if args.command == "annual":
            from .annual import annual_command
            return annual_command(args)
        if args.command == "validate":
            return _run_validate(args)
        if args.command == "export":
            return _run_export(args)
        if args.command == "batch":
            from .batch import batch_command
            return batch_command(args, parser)
        if args.command == "cache":
            from .cache import run_cache_command
            return run_cache_command(args)
        raise InputError(f"lbl-illum: unknown command {args.command!r}")
    except InputError as exc:
        print(f"lbl-illum: error: {_one_line(exc)}", file=sys.stderr)
        return 2
    except RunError as exc:
        print(f"lbl-illum: error: {_one_line(exc)}", file=sys.stderr)
        return 1
    except KeyboardInterrupt as exc:
        kept = ""
        if getattr(exc, "saved_cache", None):
            kept = f"; {sum(exc.saved_records):,} complete records kept in {exc.saved_cache}"
        terminated = type(exc).__name__ == "Terminated"      # SIGTERM (lbl_illum.io.cachefile.Terminated)
        print(f"lbl-illum: {'terminated' if terminated else 'interrupted'}{kept}", file=sys.stderr)
        return 143 if terminated else 130
    except OSError as exc:
        print(f"lbl-illum: error: {exc.filename or ''}: {exc.strerror or exc}", file=sys.stderr)
        return 1


if __name__ == "__main__":
    sys.exit(main())

"""Command line: ``lbl-illum illuminance SCENE --points PTS -o OUT``, ``lbl-illum validate``
and ``lbl-illum export radiance SCENE DIR``.

The command line only parses arguments and calls the library.  Bad input ends with
one line on standard error naming the file, line or key, exit status 2 and no
output file written.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

from . import __version__
from .errors import InputError
from .options import PRESETS, preset_table

__all__ = ["main"]

QUALITY_HELP = """\
quality options (also settable under [settings] in the scene file; the command line wins):
  accuracy  the paper's a: smaller = more records, more accurate, slower (0 = pure Monte Carlo)
  bounces   diffuse reflections followed (Radiance's -ab is bounces + 1 for daylight)
  samples   hemisphere rays of a first-level primary evaluation (Radiance's -ad)
"""


class _ProgressBar:
    """Adapter from the integrator's progress calls to a tqdm bar on standard error
    (shown after one second, and only on a terminal)."""

    def __init__(self, enabled: bool):
        from tqdm import tqdm

        self.bar = tqdm(total=None, unit="ray", unit_scale=True, delay=1.0, file=sys.stderr,
                        disable=None if enabled else True, leave=False, dynamic_ncols=True)

    def update(self, rays: int) -> None:
        if rays:
            self.bar.update(rays)

    def describe(self, text: str) -> None:
        self.bar.set_description_str(text, refresh=False)

    def close(self) -> None:
        self.bar.close()


def _positive_int(text):
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a whole number, got {text!r}") from None
    return value


def _number(text):
    try:
        return float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None


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

        init = Path(__file__).resolve().parent.parent / "validation" / "studies" / "__init__.py"
        if not init.is_file():
            raise InputError("lbl-illum: the validation studies are not installed (pip install lbl_illum)") from None
        spec = importlib.util.spec_from_file_location("lbl_illum_studies", init,
                                                      submodule_search_locations=[str(init.parent)])
        lbl_illum_studies = importlib.util.module_from_spec(spec)
        sys.modules["lbl_illum_studies"] = lbl_illum_studies
        spec.loader.exec_module(lbl_illum_studies)
    return lbl_illum_studies


def _build_parser() -> argparse.ArgumentParser:
    parser = _Parser(prog="lbl-illum", description="Illuminance in daylit rooms by the irradiance cache of "
                     "Ward, Rubinstein & Clear (1988).")
    parser.add_argument("--version", action="version", version=f"lbl-illum {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)
    p = sub.add_parser("illuminance", help="illuminance at sensor points",
                       description="Compute the illuminance [lux] at the sensor points of a .pts file "
                       "(x y z nx ny nz per line, scene units): direct light plus diffuse "
                       "interreflection through the irradiance cache.",
                       epilog=QUALITY_HELP + preset_table(), formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("scene", help="scene file (.toml)")
    p.add_argument("--points", required=True, metavar="PTS", help="sensor points (.pts)")
    p.add_argument("-o", "--output", required=True, metavar="OUT",
                   help=".csv (x,y,z,nx,ny,nz,illuminance,direct,indirect) or .txt (one value per line)")
    q = p.add_argument_group("quality")
    q.add_argument("--preset", choices=tuple(PRESETS), metavar="NAME",
                   help=f"quality preset: {', '.join(PRESETS)} (see below; options given here win over it)")
    q.add_argument("--accuracy", type=_number, metavar="A", help="the paper's a (default 0.1; 0 = no interpolation)")
    q.add_argument("--bounces", type=_positive_int, metavar="N", help="diffuse reflections followed (default 8)")
    q.add_argument("--samples", type=_positive_int, metavar="N",
                   help="hemisphere samples of a first-level primary evaluation (default 1024)")
    q.add_argument("--point-samples", type=_positive_int, metavar="N",
                   help="evaluate every point on its own with N hemisphere samples; the cache starts at the "
                        "first reflection (for sparse sensor grids)")
    q.add_argument("--ambient", type=_number, metavar="E", help="illuminance [lux] at the bounce limit (default 0)")
    q.add_argument("--min-spacing", type=_number, metavar="D", help="lower clamp on record R_i [scene units]")
    q.add_argument("--max-spacing", type=_number, metavar="D", help="upper clamp on record R_i [scene units]")
    q.add_argument("--no-bounce-scaling", action="store_true",
                   help="keep a and samples the same at every level (§3.4 scaling off)")
    q.add_argument("--seed", type=_positive_int, metavar="S", help="random seed (default 0)")
    q.add_argument("--interpolation", choices=("paper", "gradients"),
                   help="Eq. 5 as published, or over values extrapolated by each record's irradiance "
                        "gradients (Ward & Heckbert 1992; default)")
    r = p.add_argument_group("files")
    r.add_argument("--cache", metavar="FILE", help="read records from FILE if it exists; write all records back")
    r.add_argument("--stats", metavar="FILE", help="write run statistics as JSON")
    p.add_argument("-q", "--quiet", action="store_true", help="no progress bar and no summary line")

    try:
        STUDIES = _studies().STUDIES
    except InputError:        # said when the command is used
        STUDIES = {}
    v = sub.add_parser("validate", help="run a validation study and write its report",
                       description="Run a validation study against analytic or converged reference values "
                       "and write DIR/NAME/report.md, report.html, PNG plots and results.json (every number "
                       "in the report).", epilog=_STUDY_HELP, formatter_class=argparse.RawDescriptionHelpFormatter)
    v.add_argument("study", choices=[*STUDIES, "all"], metavar="NAME", help="a study, or all")
    v.add_argument("--report", default="docs/validation", metavar="DIR",
                   help="folder of the reports (default docs/validation)")
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
    x.add_argument("--glass", choices=("brtdfunc", "glass"), default="brtdfunc",
                   help="a BRTDfunc with constant coefficients (default: exactly lbl-illum's angle-independent "
                        "glass) or Radiance's glass (Fresnel angle dependence: less light at oblique angles)")
    x.add_argument("-q", "--quiet", action="store_true", help="no progress bar and no summary line")
    return parser


_STUDY_HELP = """\
studies:
  sphere-plane        the paper's §4: sphere on a plane against a closed form; Radiance side by side
  integrating-sphere  closed-form interreflection to many bounces, reflectance up to 0.99
  office-tradeoff     seconds against error on examples/office; the --preset ladder
  extremes            every knob at its extremes: finite, plausible, checked values
  scene-requires      records and rays go only where the queries need them
"""


def _run_illuminance(args) -> int:
    t0 = time.perf_counter()
    from .cache import IrradianceCache
    from .integrator import Integrator
    from .photometry import luminance
    from .scene import load_scene
    from .files import atomic_write_text
    from .sensors import check_output_path, read_points, write_results

    check_output_path(args.output)
    for extra in (args.stats, args.cache):
        if extra and not Path(extra).resolve().parent.is_dir():
            raise InputError(f"{extra}: folder {Path(extra).parent} does not exist")
    scene = load_scene(args.scene)
    options = scene.options.with_preset(args.preset) if args.preset else scene.options
    options = options.replace(
        accuracy=args.accuracy, bounces=args.bounces, samples=args.samples, ambient=args.ambient,
        min_spacing=args.min_spacing, max_spacing=args.max_spacing, seed=args.seed,
        interpolation=args.interpolation, point_samples=args.point_samples,
        bounce_scaling=False if args.no_bounce_scaling else None)
    points, normals = read_points(args.points, scene.unit_scale)
    if not args.quiet:
        for warning in scene.warnings:
            print(f"lbl-illum: warning: {warning}", file=sys.stderr)
    bar = _ProgressBar(enabled=not args.quiet)
    try:
        integ = Integrator(scene, options, progress=bar)
        if args.cache and Path(args.cache).exists():
            integ.cache = IrradianceCache.load(args.cache, integ.fingerprint)
        result = integ.compute(points, normals)
    finally:
        bar.close()
    stats = result.stats
    E = result.illuminance
    write_results(args.output, points / scene.unit_scale, normals, E,
                  luminance(result.direct), luminance(result.indirect))
    if args.cache:
        integ.cache.save(args.cache)
    seconds = time.perf_counter() - t0
    if args.stats:
        doc = {
            "points": len(points),
            "records": stats.records,
            "new_records": stats.new_records,
            "primary_evaluations": stats.primary_evaluations,
            "cache_hits": stats.cache_hits,
            "queries": stats.queries,
            "rays": stats.rays,
            "seconds": seconds,
            "compute_seconds": stats.seconds,
            "illuminance": {"mean": float(E.mean()), "min": float(E.min()), "max": float(E.max())},
            "settings": {**options.as_dict(),
                         "min_spacing": stats.min_spacing / scene.unit_scale,
                         "max_spacing": stats.max_spacing / scene.unit_scale,
                         "units": scene.units},
        }
        atomic_write_text(args.stats, json.dumps(doc, indent=2) + "\n")
    if not args.quiet:
        print(f"lbl-illum: illuminance at {len(points)} points (mean {E.mean():.4g} lux, min {E.min():.4g}, "
              f"max {E.max():.4g}) in {seconds:.2f} s; records per level {stats.records} "
              f"({stats.primary_evaluations} new); {stats.rays:,} rays -> {args.output}", file=sys.stderr)
    return 0


def _run_export(args) -> int:
    if args.format is None:
        raise InputError("lbl-illum export: give a format (radiance)")
    t0 = time.perf_counter()
    from tqdm import tqdm

    from .radiance import export_radiance
    from .scene import load_scene
    from .sensors import read_points

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

    import importlib.util

    if importlib.util.find_spec("matplotlib") is None:
        raise InputError("validate: the reports need matplotlib; install it with pip install 'lbl_illum[plots]'")
    names = list(STUDIES) if args.study == "all" else [args.study]
    report_dir = Path(args.report)
    if report_dir.exists() and not report_dir.is_dir():
        raise InputError(f"{args.report}: not a folder")
    for name in names:
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
        if not args.quiet:
            print(f"lbl-illum: validate {name}{' (quick)' if args.quick else ''}: {ctx.runs} runs, "
                  f"{ctx.records:,} records, {ctx.rays:,} rays in {time.perf_counter() - t0:.1f} s "
                  f"-> {folder / 'report.md'}", file=sys.stderr)
    return 0


def main(argv=None) -> int:
    parser = _build_parser()
    try:
        args = parser.parse_args(argv)
        if args.command is None:
            parser.print_help()
            return 2
        if args.command == "illuminance":
            return _run_illuminance(args)
        if args.command == "validate":
            return _run_validate(args)
        if args.command == "export":
            return _run_export(args)
        raise InputError(f"lbl-illum: unknown command {args.command!r}")
    except InputError as exc:
        print(f"lbl-illum: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("lbl-illum: interrupted", file=sys.stderr)
        return 130
    except OSError as exc:
        print(f"lbl-illum: error: {exc.filename or ''}: {exc.strerror or exc}", file=sys.stderr)
        return 1


if __name__ == "__main__":
    sys.exit(main())

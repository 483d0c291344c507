"""``lbl-illum render``: a luminance image of a scene's view through the irradiance cache.

The command's side of :mod:`lbl_illum.engine.render`: its arguments, the view by name,
string or file, the checks made before any work (output folders and formats, the image's
size against the memory), the image files written and the summary line.
"""

from __future__ import annotations

import difflib
import math
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

from ..optional import check as check_optional
from ..options import Options
from ..errors import InputError, plural
from ..scene.scenefile import Scene
from ..scene.views import View, view_from_file, view_from_string, views_from_table
from .progress import ProgressBar as _Bar, compile_notice
from ..workplane.metrics import readable
from .shared import (add_cluster_arguments, check_cluster_arguments, check_output_file, cluster_compute, cluster_note,
                     open_study_cluster, run_options)
from ..viz.falsecolor import SCALES, STYLES

__all__ = ["add_render_arguments", "render_command", "resolve_view", "scene_views", "check_image_size",
           "MAX_IMAGE_SIDE"]


# ---------------------------------------------------------------------------
# Views by name, string or file
# ---------------------------------------------------------------------------

def _looks_like_options(text: str) -> bool:
    words = text.split()
    return len(words) != 1 or words[0].startswith("-") or words[0].startswith("VIEW=")


def scene_views(scene: Scene) -> dict[str, View]:
    """The named views of a scene: ``scene.views`` when the loader keeps them, else the
    ``[views.NAME]`` tables read from the scene file."""
    views = getattr(scene, "views", None)
    if views:
        return dict(views)
    if scene.path is None:
        return {}
    try:
        import tomllib
    except ModuleNotFoundError:  # Python < 3.11
        import tomli as tomllib
    data = tomllib.loads(Path(scene.path).read_text(encoding="utf-8"))
    return views_from_table(data.get("views"), Path(scene.path).name, scene.unit_scale)


def resolve_view(scene: Scene, view: str | None = None, view_file: str | None = None) -> View:
    """The view of a render command.

    ``view`` is Radiance view options (``"-vtv -vp 2 5.7 1.5 -vd 0 -1 -0.1"``, lengths in
    the scene's units, as everything else typed) or the name of a ``[views.NAME]`` table
    of the scene file; ``view_file`` a ``.vf`` file or Radiance picture (lengths in the
    scene's units too).  With both a file and options, the options change the file's
    view (as ``rpict -vf file -vp ...``).
    """
    base = view_from_file(view_file, unit_scale=scene.unit_scale) if view_file else None
    if view is None:
        if base is None:
            raise InputError("render: give a view (--view OPTIONS or NAME, or --view-file FILE)")
        return base
    text = view.strip()
    if _looks_like_options(text):
        return view_from_string(text, "--view", base=base, unit_scale=scene.unit_scale)
    if base is not None:
        raise InputError(f"--view {text}: a named view cannot be combined with --view-file")
    views = scene_views(scene)
    if text in views:
        return views[text]
    where = scene.path.name if scene.path is not None else "scene"
    if not views:
        raise InputError(f"--view {text}: {where} has no [views] tables (or give Radiance view options)")
    near = difflib.get_close_matches(text, list(views), n=1)
    hint = f" (did you mean '{near[0]}'?)" if near else f" (views: {', '.join(views)})"
    raise InputError(f"--view {text}: no [views.{text}] in {where}{hint}")


# ---------------------------------------------------------------------------
# The command
# ---------------------------------------------------------------------------

def add_render_arguments(parser) -> None:
    """Arguments of ``lbl-illum render`` other than the quality options (added by the CLI)."""
    parser.add_argument("scene", help="scene file (.toml)")
    v = parser.add_argument_group("view")
    v.add_argument("--view", metavar="VIEW",
                   help="Radiance view options in one argument (--view=\"-vtv -vp 2 5.7 1.5 -vd 0 -1 -0.1 -vh 80 "
                        "-vv 60\", lengths in the scene's units) or the NAME of a [views.NAME] table of the scene file")
    v.add_argument("--view-file", metavar="VF", help="a .vf file as rvu writes it (or a Radiance picture); "
                   "--view options, if given, change it")
    v.add_argument("-x", type=int, default=512, metavar="W", help="largest width in pixels (default 512)")
    v.add_argument("-y", type=int, default=512, metavar="H", help="largest height in pixels (default 512); "
                   "as rpict, one of them shrinks so that pixels are square")
    v.add_argument("--pixel-samples", type=int, default=1, metavar="N",
                   help="jittered rays per pixel, averaged (default 1); a pixel on an edge between "
                        "surfaces gets 8 more")
    o = parser.add_argument_group("output")
    o.add_argument("-o", "--output", required=True, metavar="IMAGE",
                   help="luminance image: .exr (float cd/m2), .hdr (Radiance RGBE with VIEW=), .tif")
    o.add_argument("--preview", metavar="PNG", help="tone-mapped sRGB preview (Reinhard et al. 2002)")
    o.add_argument("--falsecolor", metavar="PNG", help="false-colour luminance with a legend in cd/m2")
    o.add_argument("--falsecolor-max", type=float, metavar="L", help="top of the false-colour scale [cd/m2] "
                   "(default: a round number at or above the 99th percentile of the room's pixels, those that "
                   "do not see the sky, the sun or a lamp directly)")
    o.add_argument("--falsecolor-scale", choices=SCALES, default="linear",
                   help="false-colour bands at round numbers: steps of luminance (linear, default) or of ratio "
                        "(log: 2 decades, 1-2-5)")
    o.add_argument("--falsecolor-style", choices=STYLES, default="bands",
                   help="fill the bands (default), or draw their edges as contour lines in the bands' colours "
                        "over a grey picture (as falsecolor -cl)")
    o.add_argument("--falsecolor-title", metavar="TEXT",
                   help="the false-colour picture's title, wrapped to its width (default: the scene file)")
    o.add_argument("--glare", action="store_true", help="report the glare of the fisheye rendered (-vta or -vth, "
                   "180 degrees): DGP, Ev, sources, DGI, UGR, as lbl-illum glare does")
    o.add_argument("--glare-json", metavar="JSON", help="with or without --glare: write its figures as JSON")
    from .cache import add_cache_file_arguments

    add_cache_file_arguments(o)
    add_cluster_arguments(parser)
    parser.add_argument("-q", "--quiet", action="store_true", help="no progress bar and no summary line")


def _arg(args, name, default=None):
    return getattr(args, name, default)


def _options_from_args(scene: Scene, args) -> Options:
    """The scene's [settings], then ``--preset``, then the options given (as the
    illuminance command), without ``point_samples``."""
    if _arg(args, "point_samples") is not None:
        raise InputError("--point-samples does not apply to images (every pixel would get its own evaluation)")
    from ..engine.render import image_options

    return image_options(run_options(scene, args))



#: Largest -x or -y of ``render`` [pixels] (OpenEXR and TIFF take more, but the one batch of
#: camera rays would not fit any machine's memory long before).
MAX_IMAGE_SIDE = 16384
#: Memory a camera ray (one pixel sample) takes through ``render``'s single batch [bytes]:
#: measured 0.45 KiB on examples/office (1024 × 1024 pixels, one sample, through glass and
#: onto diffuse walls: 470 MB above the 160 MB the process starts with); twice that for
#: scenes whose glass splits more paths.
BYTES_PER_CAMERA_RAY = 1024


def _available_memory() -> int | None:
    """Memory available to a new allocation [bytes] (Linux ``MemAvailable``, else the free
    physical pages), or None when the system does not say."""
    import os

    try:
        with open("/proc/meminfo", encoding="ascii") as fh:
            for line in fh:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    try:
        return int(os.sysconf("SC_AVPHYS_PAGES")) * int(os.sysconf("SC_PAGE_SIZE"))
    except (AttributeError, ValueError, OSError):
        return None


def check_image_size(args) -> None:
    """Refuse an image that cannot be rendered before any work: -x, -y or --pixel-samples
    below 1, a side above :data:`MAX_IMAGE_SIDE`, or more camera rays (x · y · pixel samples,
    all traced in one batch) than the available memory holds at
    :data:`BYTES_PER_CAMERA_RAY` each.  The count is an upper bound: the view's aspect may
    reduce one side (rpict's square pixels), never enlarge it."""
    sizes = {}
    for name, flag in (("x", "-x"), ("y", "-y"), ("pixel_samples", "--pixel-samples")):
        value = getattr(args, name, None)
        if value is None:
            continue
        if isinstance(value, bool) or not isinstance(value, int) or value < 1:
            raise InputError(f"{flag} must be a positive whole number, got {value}")
        if flag != "--pixel-samples" and value > MAX_IMAGE_SIDE:
            raise InputError(f"{flag} {value} is more than the {MAX_IMAGE_SIDE} pixels allowed per side")
        sizes[name] = value
    rays = sizes.get("x", 512) * sizes.get("y", 512) * sizes.get("pixel_samples", 1)
    need = rays * BYTES_PER_CAMERA_RAY
    have = _available_memory()
    if have is not None and need > have:
        raise InputError(f"-x {sizes.get('x', 512)} -y {sizes.get('y', 512)} with "
                         f"{plural(sizes.get('pixel_samples', 1), 'pixel sample')} is {rays:,} camera rays, traced in "
                         f"one batch: about {need / 2 ** 30:.3g} GiB of memory, more than the {have / 2 ** 30:.3g} GiB "
                         "available; render a smaller image")


def _check_outputs(args) -> None:
    """Refuse bad output paths and numbers before any work."""
    from ..io.images import check_image_path

    check_image_path(args.output)
    for png in (_arg(args, "preview"), _arg(args, "falsecolor")):
        if png:
            check_image_path(png, (".png",))
    if _arg(args, "falsecolor"):
        check_optional("matplotlib", f"--falsecolor {Path(args.falsecolor).name}")
    elif (_arg(args, "falsecolor_max") is not None or _arg(args, "falsecolor_title") is not None
          or (_arg(args, "falsecolor_scale") or "linear") != "linear"
          or (_arg(args, "falsecolor_style") or "bands") != "bands"):
        raise InputError("--falsecolor-max, --falsecolor-scale, --falsecolor-style and --falsecolor-title "
                         "go with --falsecolor PNG")
    for extra in (_arg(args, "cache"), _arg(args, "stats")):
        check_output_file(extra)
    check_image_size(args)
    check_output_file(_arg(args, "glare_json"), ".json", "--glare-json")
    top = _arg(args, "falsecolor_max")
    if top is not None and not (math.isfinite(top) and top > 0):
        raise InputError(f"--falsecolor-max must be a positive luminance [cd/m2], got {top:g}")
    check_cluster_arguments(args)


def render_command(args, progress=None) -> int:
    """``lbl-illum render``: render, write the image (and preview, false colour, cache,
    stats), print a one-line summary; return the exit status (0).

    ``args`` has the attributes :func:`add_render_arguments` and the illuminance
    command's quality options define (missing quality options count as not given).
    Bad input raises :class:`~lbl_illum.errors.InputError` before any file is written.
    ``progress`` replaces the tqdm bar (tests).
    """
    t0 = time.perf_counter()
    _check_outputs(args)
    quiet = bool(_arg(args, "quiet", False))
    cluster = open_study_cluster(args)
    try:
        return _render(args, cluster, progress, quiet, t0)
    finally:
        if cluster is not None:
            cluster.close()


def _render(args, cluster, progress, quiet, t0) -> int:
    """:func:`render_command` once the outputs are checked and the cluster (or None) is open.
    The engine is imported here, not with the module: the parser (--help) needs none of it."""
    from ..engine.integrator import Integrator
    from ..engine.render import render_image
    from ..io.images import write_image, write_preview
    from ..scene.scenefile import load_scene

    scene = load_scene(args.scene)
    view = resolve_view(scene, _arg(args, "view"), _arg(args, "view_file"))
    glare = bool(_arg(args, "glare") or _arg(args, "glare_json"))
    if glare:
        from ..glare.metrics import check_fisheye
        check_fisheye(view, "--glare")
    width, height = view.resolution(_arg(args, "x", 512), _arg(args, "y", 512))
    options = _options_from_args(scene, args)
    if not quiet:
        for warning in scene.warnings:
            print(f"lbl-illum: warning: {warning}", file=sys.stderr)
    integ = Integrator(scene, options)
    if not quiet:
        for note in integ.portal_notes():
            print(f"lbl-illum: note: {note}", file=sys.stderr)
    bar = progress if progress is not None else _Bar(enabled=not quiet)
    integ.progress = bar
    shade, costs = None, []
    if cluster is not None:
        from ..distributed.worker import SceneRecipe

        recipe = SceneRecipe(str(Path(args.scene).resolve()))

        def shade(points, normals, spacing, taper):
            result, cost = cluster_compute(cluster, integ, recipe, points, normals, args, bar, spacing, taper)
            costs.append(cost)
            return result
    try:
        cache_file = _arg(args, "cache")
        if cache_file and cluster is None:
            try:
                from ..io.cachefile import attach_cache_file
                attach_cache_file(integ, cache_file, rebuild=bool(_arg(args, "rebuild_cache")))
            except InputError as exc:
                if "other settings" in str(exc):
                    raise InputError(f"{exc}; images do not use point_samples, so a cache made with them "
                                     "(e.g. --preset medium) is not shared") from None
                raise
        with compile_notice(enabled=not quiet and progress is None, bar=bar if progress is None else None):
            result = render_image(scene, view, width, height, pixel_samples=_arg(args, "pixel_samples", 1) or 1,
                                  progress=bar, integrator=integ, shade=shade)
    finally:
        if progress is None:
            bar.close()
    write_image(args.output, result.rgb, view=view)
    if _arg(args, "preview"):
        write_preview(args.preview, result.rgb)
    if _arg(args, "falsecolor"):
        from ..viz.falsecolor import write_falsecolor

        write_falsecolor(args.falsecolor, result.rgb, maximum=_arg(args, "falsecolor_max"),
                         scale=_arg(args, "falsecolor_scale") or "linear",
                         style=_arg(args, "falsecolor_style") or "bands", valid=result.valid, source=result.source,
                         title=_arg(args, "falsecolor_title") or f"{Path(args.scene).name}: luminance")
    seconds = time.perf_counter() - t0
    stats = result.stats
    if _arg(args, "stats"):
        import json

        from ..io.files import atomic_write_text

        doc = {"command": "render", "scene": str(args.scene), "output": str(args.output), "view": view.options(),
               **stats.as_dict(), "total_seconds": seconds,
               **({"cluster": costs[0].as_dict()} if costs else {}),
               "luminance": _luminance_summary(result), "settings": {**options.as_dict(), "units": scene.units}}
        atomic_write_text(args.stats, json.dumps(doc, indent=2) + "\n")
    if not quiet:
        lum = _luminance_summary(result)
        print(f"lbl-illum: render {width} x {height} ({view.type_name}, {stats.pixel_samples} "
              f"sample{'s' if stats.pixel_samples != 1 else ''}/pixel) in {seconds:.2f} s"
              f"{cluster_note(cluster, costs[0] if costs else None)}; records per level "
              f"{stats.records} ({stats.records_made} new); {stats.rays:,} rays; luminance median "
              f"{readable(lum['median'])}, max {readable(lum['max'])} cd/m2 -> {args.output}", file=sys.stderr)
    if glare:
        from .glare import report_glare
        report_glare(result.luminance, view, args.output, _arg(args, "glare_json"), quiet)
    return 0


def _luminance_summary(result: "RenderResult") -> dict[str, Any]:
    lum = result.luminance[result.valid]
    if lum.size == 0:
        return {"median": 0.0, "mean": 0.0, "max": 0.0}
    return {"median": float(np.median(lum)), "mean": float(lum.mean()), "max": float(lum.max())}

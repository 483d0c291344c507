"""``lbl-illum glare``: the glare figures of a 180° fisheye luminance image, and the
report ``lbl-illum render --glare`` adds to a rendered fisheye.

The command's side of :mod:`lbl_illum.glare.metrics`: its arguments, the JSON file
(written whole or not at all) and the one line it prints.  See docs/glare.md.
"""

from __future__ import annotations

import json
import math
import sys
from pathlib import Path

from ..errors import InputError
from .shared import check_output_file, finite

__all__ = ["add_glare_arguments", "glare_command", "report_glare"]


#: argparse type of the glare command's luminances, factors and angles.
_positive = finite(0.0, above=True)


def add_glare_arguments(parser) -> None:
    """Arguments of ``lbl-illum glare``."""
    from ..glare.metrics import DEFAULT_THRESHOLD, PEAK_LUMINANCE, SEARCH_ANGLE, TASK_FACTOR

    parser.add_argument("image", help="180 degree fisheye luminance image (-vta or -vth): a Radiance .hdr with its "
                        "VIEW= line (ours or rpict's), or an .exr/.tif written by lbl-illum render")
    parser.add_argument("--json", metavar="OUT", help="write every figure, and each glare source, as JSON")
    parser.add_argument("--view", metavar="VIEW", help="Radiance view options replacing the image's own, in one "
                        "argument: --view=\"-vta -vp 2 4 1.2 -vd 0 -1 0 -vu 0 0 1 -vh 180 -vv 180\"")
    g = parser.add_argument_group("glare sources", "Pixels brighter than the threshold, grouped when within the "
                                  "search angle of each other (evalglare's defaults).")
    how = g.add_mutually_exclusive_group()
    how.add_argument("--threshold", type=_positive, metavar="L",
                     help=f"source threshold [cd/m2] (default {DEFAULT_THRESHOLD:g}, evalglare's)")
    how.add_argument("--factor", type=_positive, metavar="F",
                     help="sources above F times the average luminance of the image (of the task area with --task); "
                          "evalglare -b F")
    g.add_argument("--task", nargs=3, type=float, metavar=("COL", "ROW", "ANGLE"),
                   help=f"task area: a cone of full angle ANGLE [deg] around pixel COL (from the left), ROW (from the "
                        f"top); sources above {TASK_FACTOR:g} x its luminance unless --factor is given")
    g.add_argument("--search-angle", type=_positive, default=math.degrees(SEARCH_ANGLE), metavar="DEG",
                   help=f"largest angle between two pixels of one source (default {math.degrees(SEARCH_ANGLE):.2f}, "
                        "evalglare -r 0.2)")
    g.add_argument("--peak", type=_positive, default=PEAK_LUMINANCE, metavar="L",
                   help=f"pixels at or above L [cd/m2] form sources of their own (default {PEAK_LUMINANCE:g}, "
                        "evalglare -Y)")
    g.add_argument("--no-peak", action="store_true", help="no peak extraction (evalglare -x)")
    g.add_argument("--no-low-light", action="store_true",
                   help="report the DGP without the low-light correction below 1000 lux (evalglare's default)")
    parser.add_argument("-q", "--quiet", action="store_true", help="no summary line")


def _write_json(path: str, doc: dict) -> None:
    from ..io.files import atomic_write_text

    atomic_write_text(path, json.dumps(_plain(doc), indent=2) + "\n")


def _plain(obj):
    """JSON-ready: non-finite floats to None."""
    if isinstance(obj, dict):
        return {k: _plain(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_plain(v) for v in obj]
    if isinstance(obj, float) and not math.isfinite(obj):
        return None
    return obj


def _line(name: str, result, json_path: str | None) -> str:
    return f"lbl-illum: glare {name}: {result.summary()}" + (f" -> {json_path}" if json_path else "")


def glare_command(args) -> int:
    """``lbl-illum glare``: evaluate the image, write the JSON, print one line; 0."""
    from ..glare.metrics import glare_from_image
    from ..scene.views import view_from_string

    check_output_file(args.json, ".json", "--json")
    view = view_from_string(args.view, "--view") if args.view else None
    result = glare_from_image(args.image, view=view, threshold=args.threshold, factor=args.factor,
                              task=tuple(args.task) if args.task else None,
                              search_angle=math.radians(args.search_angle),
                              peak=None if args.no_peak else args.peak, low_light=not args.no_low_light)
    if args.json:
        _write_json(args.json, {"command": "glare", "image": str(args.image), **result.as_dict()})
    if not args.quiet:
        print(_line(Path(args.image).name, result, args.json))
    return 0


def report_glare(luminance, view, image: str, json_path: str | None = None, quiet: bool = False) -> None:
    """``render --glare``: the glare figures of the rendered luminance (before RGBE rounding),
    the JSON if asked, one line unless ``quiet``."""
    from ..glare.metrics import evaluate_glare

    result = evaluate_glare(luminance, view, where="--glare")
    if json_path:
        _write_json(json_path, {"command": "render --glare", "image": str(image), **result.as_dict()})
    if not quiet:
        print(_line(Path(image).name, result, json_path), file=sys.stdout)

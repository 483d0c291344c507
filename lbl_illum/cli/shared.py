"""What the commands share: argument types for numbers, and the quality options a run
uses, from the scene file, the preset and the command line."""

from __future__ import annotations

import argparse
import math
from pathlib import Path

from ..errors import InputError
from ..options import Options

__all__ = ["run_options", "whole", "finite", "check_output_file", "add_cluster_arguments", "check_cluster_arguments",
           "open_study_cluster", "cluster_compute", "cluster_note"]


def whole(minimum: int = 0, maximum: int | None = None):
    """An argparse type: a whole number within [minimum, maximum]."""
    def parse(text):
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected a whole number, got {text!r}") from None
        if value < minimum:
            raise argparse.ArgumentTypeError(f"must be >= {minimum}, got {value}")
        if maximum is not None and value > maximum:
            raise argparse.ArgumentTypeError(f"must be <= {maximum}, got {value}")
        return value
    return parse


def finite(minimum: float | None = None, maximum: float | None = None, above: bool = False):
    """An argparse type: a finite number, at least ``minimum`` (greater with ``above``) and
    at most ``maximum``."""
    def parse(text):
        try:
            value = float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
        if not math.isfinite(value):
            raise argparse.ArgumentTypeError(f"must be a finite number, got {text!r}")
        if minimum is not None and (value < minimum or (above and value == minimum)):
            raise argparse.ArgumentTypeError(f"must be {'>' if above else '>='} {minimum:g}, got {value:g}")
        if maximum is not None and value > maximum:
            raise argparse.ArgumentTypeError(f"must be <= {maximum:g}, got {value:g}")
        return value
    return parse


def check_output_file(path: str | None, suffix: str | None = None, option: str | None = None) -> None:
    """Refuse, before any work, an output file (``--stats``, ``--cache``, a JSON report)
    whose folder does not exist, that is a folder, or (with ``suffix``) whose name does
    not end in it; ``option`` names the flag in the message."""
    if not path:
        return
    out = Path(path)
    where = f"{option} {path}" if option else str(path)
    if suffix and out.suffix.lower() != suffix:
        raise InputError(f"{where}: the file must end in {suffix}")
    if out.is_dir():
        raise InputError(f"{where}: is a folder; give a file name")
    if not out.resolve().parent.is_dir():
        raise InputError(f"{where}: folder {out.parent} does not exist")


def run_options(scene, args) -> Options:
    """The scene's ``[settings]``, then ``--preset``, then the options given on the command
    line (absent ones, as in a namespace built by hand, count as not given)."""
    def given(name):
        return getattr(args, name, None)

    def metres(name):               # spacings are typed in the scene's units
        value = given(name)
        return None if value is None else value * scene.unit_scale

    options = scene.options.with_preset(given("preset")) if given("preset") else scene.options
    try:
        return options.replace(
            accuracy=given("accuracy"), bounces=given("bounces"), samples=given("samples"), ambient=given("ambient"),
            min_spacing=metres("min_spacing"), max_spacing=metres("max_spacing"), seed=given("seed"),
            interpolation=given("interpolation"), point_samples=given("point_samples"),
            bounce_scaling=False if given("no_bounce_scaling") else None)
    except InputError as exc:   # each value passed its own check: a combination (min > max spacing)
        where = f"the command line with {Path(args.scene).name} [settings]:"
        message = str(exc).replace("options:", where, 1)
        if "spacing" in message:    # its values in the units they were typed in
            lo, hi = (metres(k) or getattr(options, k) for k in ("min_spacing", "max_spacing"))
            message = f"{where} 'min_spacing' ({lo / scene.unit_scale:g}) must not exceed max_spacing " \
                      f"({hi / scene.unit_scale:g})"
        raise InputError(message) from None


# -- runs on a Dask cluster (docs/distributed.md) ---------------------------------------------

def add_cluster_arguments(parser) -> None:
    """``--workers``, ``--scheduler``, ``--chunk-size`` and ``--round-chunks`` of the commands
    that compute (:mod:`lbl_illum.distributed`)."""
    from ..distributed.plan import CHUNK_POINTS, ROUND_CHUNKS

    g = parser.add_argument_group("cluster", "Run on a Dask cluster with one shared cache, in rounds of chunks of "
                                  "points (docs/distributed.md): the results depend on --chunk-size and "
                                  "--round-chunks (and the seed), never on the number of workers.")
    g.add_argument("--workers", type=whole(0), metavar="N", help="start a local Dask cluster of N worker processes "
                   "on this machine; 0: the same rounds in this process, without Dask (default: an ordinary run)")
    g.add_argument("--scheduler", metavar="ADDRESS", help="run on the Dask cluster whose scheduler is at "
                   "tcp://HOST:PORT (its workers must read the scene files at the same paths)")
    g.add_argument("--chunk-size", type=whole(1), metavar="N",
                   help=f"query points per work unit (default {CHUNK_POINTS})")
    g.add_argument("--round-chunks", type=whole(1), metavar="N",
                   help=f"most work units per round; rounds hold 1, 2, 4, ... of them (default {ROUND_CHUNKS})")


def check_cluster_arguments(args) -> None:
    """Refuse, before any work, cluster options that do not go together, and a cluster
    without the ``distributed`` extra installed."""
    from ..optional import check as check_optional

    workers, scheduler = getattr(args, "workers", None), getattr(args, "scheduler", None)
    if workers is not None and scheduler is not None:
        raise InputError("give either --workers or --scheduler, not both")
    if workers is None and scheduler is None:
        if getattr(args, "chunk_size", None) is not None or getattr(args, "round_chunks", None) is not None:
            raise InputError("--chunk-size and --round-chunks go with --workers N or --scheduler ADDRESS")
        return
    if scheduler is not None or workers > 0:
        check_optional("distributed", "--workers/--scheduler")


def open_study_cluster(args):
    """The cluster of ``args`` (connected and checked: :func:`lbl_illum.distributed.cluster.open_cluster`),
    or None for an ordinary run; the one a batch lends its studies (``args.cluster``) if set."""
    if getattr(args, "cluster", None) is not None:
        return args.cluster
    check_cluster_arguments(args)
    workers, scheduler = getattr(args, "workers", None), getattr(args, "scheduler", None)
    if workers is None and scheduler is None:
        return None
    from ..distributed.cluster import open_cluster

    return open_cluster(workers, scheduler)


def cluster_compute(cluster, integ, recipe, points, normals, args, progress, spacing=None, taper=False):
    """:func:`lbl_illum.distributed.rounds.solve_points` with the options of ``args``
    (chunks, rounds, ``--cache``), after every worker has built the scene: ``(result, costs)``."""
    from ..distributed.plan import CHUNK_POINTS, ROUND_CHUNKS, Decomposition
    from ..distributed.rounds import solve_points

    cluster.prepare(recipe, integ.options, integ.fingerprint, integ.scene, integ.context)
    plan = Decomposition(getattr(args, "chunk_size", None) or CHUNK_POINTS,
                         getattr(args, "round_chunks", None) or ROUND_CHUNKS)
    try:
        result, costs, _ = solve_points(cluster, recipe, integ, points, normals, spacing=spacing, taper=taper,
                                        plan=plan, cache_file=getattr(args, "cache", None),
                                        rebuild=bool(getattr(args, "rebuild_cache", False)), progress=progress)
    finally:
        cluster.release(recipe)          # a batch's next study may be another scene
    return result, costs


def cluster_note(cluster, costs) -> str:
    """What the summary line says of a cluster run ("" for an ordinary one)."""
    if cluster is None or costs is None:
        return ""
    rounds = len(costs.rounds)
    return f" on {cluster.name} ({rounds} round{'s' if rounds != 1 else ''})"

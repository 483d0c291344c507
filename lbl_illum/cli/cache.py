"""``lbl-illum cache info`` and ``lbl-illum cache merge``: inspect and combine cache files
(docs/cache-files.md).

``info`` prints a file's header (format version, program, fingerprint, the settings the
records were made for) and per-level statistics: record counts, the quantiles of the
record radii R_i [m], the range of the irradiances E_i (photometric, [lux]) and the
memory the records take once loaded.  ``merge`` writes the union of compatible caches
(same fingerprint: same scene and settings), dropping records present in several.

The command line only parses arguments and calls :mod:`lbl_illum.engine.cache`; the two
functions below are hooked into :mod:`lbl_illum.cli.main`.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np

from ..errors import InputError

__all__ = ["add_cache_commands", "add_cache_file_arguments", "run_cache_command", "cache_statistics"]

#: Quantiles of R_i reported per level.
RADIUS_QUANTILES = (0.0, 0.1, 0.5, 0.9, 1.0)


def add_cache_file_arguments(group) -> None:
    """``--cache FILE``, ``--rebuild-cache`` and ``--stats FILE`` of the commands that
    compute (illuminance, daylight-factor, render); see docs/cache-files.md."""
    group.add_argument("--cache", metavar="FILE", help="keep the cache's records in FILE: read them if it exists, "
                       "write them back (merged with other runs' records) at the end and when interrupted")
    group.add_argument("--rebuild-cache", action="store_true", help="with --cache: replace FILE, even one made "
                       "for other settings or a damaged one, instead of refusing it")
    group.add_argument("--stats", metavar="FILE", help="write run statistics as JSON")


def add_cache_commands(subparsers) -> None:
    """Add ``cache info`` and ``cache merge`` to the ``lbl-illum`` sub-command parsers."""
    c = subparsers.add_parser(
        "cache", help="inspect (info) or merge cache files",
        description="Inspect or merge irradiance cache files (--cache FILE of illuminance, daylight-factor "
                    "and render).")
    actions = c.add_subparsers(dest="cache_command", metavar="ACTION", parser_class=type(c))
    i = actions.add_parser(
        "info", help="header and per-level record statistics of cache files",
        description="Print a cache file's header (format version, fingerprint, the settings its records were "
                    "made for) and per level: record count, radii R_i [m] (min, 10%, median, 90%, max), "
                    "irradiance E_i [lux] (min, median, max) and the memory the records take once loaded. "
                    "The file is checked completely (checksum, array shapes and values) on the way.")
    i.add_argument("files", nargs="+", metavar="FILE", help="cache file(s)")
    i.add_argument("--json", action="store_true", help="print the header and statistics as JSON")
    m = actions.add_parser(
        "merge", help="write the union of compatible cache files",
        description="Merge cache files made for the same scene and settings (same fingerprint) into one: "
                    "every record of the first file, then the records of the others that it lacks (same "
                    "level, position and normal count as the same record).  Files made for other settings "
                    "are refused.  OUT is written atomically and may be one of the inputs.")
    m.add_argument("inputs", nargs="+", metavar="CACHE", help="cache files to merge (one file: rewrite it "
                   "in the current format)")
    m.add_argument("-o", "--output", required=True, metavar="OUT", help="the merged cache file")
    m.add_argument("-q", "--quiet", action="store_true", help="no summary line")
    c.set_defaults(cache_parser=c)


def run_cache_command(args) -> int:
    """Run ``lbl-illum cache ACTION``; bad input raises :class:`InputError` (exit status 2)."""
    if getattr(args, "cache_command", None) is None:
        args.cache_parser.print_help(sys.stderr)
        return 2
    if args.cache_command == "info":
        return _info(args)
    if args.cache_command == "merge":
        return _merge(args)
    raise InputError(f"lbl-illum cache: unknown action {args.cache_command!r}")


# -- info ----------------------------------------------------------------------------------

def cache_statistics(path) -> dict:
    """Header and per-level statistics of the cache file ``path`` (checked completely).

    Returns a dict: ``file``, ``bytes`` (file size), ``header`` (as stored, without the
    checksum), ``levels`` (per level: ``accuracy``, ``records``, ``radius`` quantiles [m]
    at :data:`RADIUS_QUANTILES`, ``short_radius`` quantiles for elliptical domains,
    ``leak_share`` (records with leak sectors), ``illuminance`` min/median/max [lux]
    (photometric E_i), ``memory_bytes`` once loaded, and the root cube), ``records`` and
    ``memory_bytes`` in total.
    """
    from ..engine.cache import IrradianceCache
    from ..io.cachefile import read_cache_file
    from ..photometry import luminance

    data = read_cache_file(path)
    cache = IrradianceCache.from_data(data)
    levels = []
    for k, (info, lv) in enumerate(zip(data.header["levels"], cache.levels)):
        a = data.level(k)
        n = info["records"]
        entry = {"level": k, "accuracy": info["accuracy"], "records": n, "center": info["center"],
                 "half": info["half"], "radius": None, "illuminance": None}
        if n:
            R = a["R"].astype(np.float64)
            entry["radius"] = dict(zip((f"q{round(100 * q)}" for q in RADIUS_QUANTILES),
                                       np.quantile(R, RADIUS_QUANTILES).tolist()))
            E = luminance(a["E"].astype(np.float64))
            entry["illuminance"] = {"min": float(E.min()), "median": float(np.median(E)), "max": float(E.max())}
            if data.anisotropic:
                stretch = np.sqrt(1.0 + np.einsum("ij,ij->i", a["W"], a["W"]).astype(np.float64))
                entry["short_radius"] = dict(zip((f"q{round(100 * q)}" for q in RADIUS_QUANTILES),
                                                 np.quantile(R / stretch, RADIUS_QUANTILES).tolist()))
                entry["leak_share"] = float(np.mean(a["leak"] != 0))
            if lv.count and lv.accuracy > 0:
                lv.freeze()
        entry["memory_bytes"] = int(sum(lv.nbytes().values())) if lv.count else 0
        levels.append(entry)
    header = {key: value for key, value in data.header.items() if key not in ("checksum", "levels")}
    return {"file": str(path), "bytes": Path(path).stat().st_size, "header": header, "levels": levels,
            "records": int(sum(data.record_counts)),
            "memory_bytes": int(sum(entry["memory_bytes"] for entry in levels))}


def _megabytes(n: int) -> str:
    return f"{n / 1e6:.3g} MB" if n >= 1e5 else f"{n / 1e3:.3g} kB"


def _settings_lines(s: dict | None) -> list[str]:
    if not s:
        return ["settings: not recorded (format version 1)"]
    scaling = "on" if s.get("bounce_scaling") else "off"
    lines = [f"settings: accuracy {s.get('accuracy')}, bounces {s.get('bounces')}, samples {s.get('samples')}, "
             f"ambient {s.get('ambient')} lux, bounce scaling {scaling},",
             f"          point samples {s.get('point_samples') or 'off'}, {s.get('domains')} record domains"]
    sky = s.get("sky") or {}
    sky_text = ", ".join(f"{key} {value:.6g}" if isinstance(value, float) else f"{key} {value}"
                         for key, value in sky.items() if key != "type")
    sun = s.get("sun")
    sun_text = "none" if not sun else (f"altitude {sun['altitude']:.4g} deg, azimuth {sun['azimuth']:.4g} deg, "
                                       f"E_dn {sun['direct_normal_illuminance']:.6g} lux")
    lines.append(f"sky: {sky.get('type')} ({sky_text}); sun: {sun_text}")
    geo = s.get("geometry") or {}
    mats = s.get("materials") or {}
    lines.append(f"geometry: {geo.get('triangles', 0):,} triangles, {geo.get('spheres', 0)} spheres; "
                 f"{len(mats)} materials ({', '.join(mats)})")
    return lines


def _info_text(st: dict) -> str:
    h = st["header"]
    name = Path(st["file"]).name
    out = [f"{name}: lbl_illum irradiance cache, format version {h['version']}"
           + (f", written by {h['program']}" if h.get("program") else "")
           + f"; {_megabytes(st['bytes'])} on disk, checksum correct",
           f"  fingerprint: {h['fingerprint']}"]
    try:
        lines = _settings_lines(h.get("settings"))
    except (AttributeError, TypeError, KeyError, ValueError):
        lines = ["settings: present, but not in the form this program writes"]
    out += [f"  {line}" for line in lines]
    domains = "elliptical domains" if h.get("domains") == "elliptical" else "round domains"
    out.append(f"  records: {st['records']:,} in {len(st['levels'])} levels ({domains}); "
               f"{_megabytes(st['memory_bytes'])} once loaded")
    out.append("  radii R_i [m] (quantiles) and irradiances E_i [lux] of the records, per level:")
    cols = ("level", "a", "records", "R min", "R 10%", "R median", "R 90%", "R max", "E min", "E median", "E max",
            "memory")
    out.append("  " + " ".join(f"{c:>9}" for c in cols))
    for lv in st["levels"]:
        row = f"  {lv['level']:>9} {lv['accuracy']:>9.4g} {lv['records']:>9,}"
        if lv["radius"] is None:
            row += "   (accuracy 0: records are not kept)" if lv["accuracy"] == 0 else ""
        else:
            row += "".join(f" {v:>9.4g}" for v in lv["radius"].values())
            row += "".join(f" {lv['illuminance'][key]:>9.4g}" for key in ("min", "median", "max"))
            row += f" {_megabytes(lv['memory_bytes']):>9}"
        out.append(row)
    if h.get("domains") == "elliptical":
        shares = [f"{lv['level']}: {100 * lv['leak_share']:.0f}%" for lv in st["levels"] if lv.get("leak_share")
                  is not None]
        if shares:
            out.append(f"  records with leak sectors, per level: {', '.join(shares)}")
    return "\n".join(out)


def _info(args) -> int:
    docs = [cache_statistics(path) for path in args.files]
    if args.json:
        print(json.dumps(docs[0] if len(docs) == 1 else docs, indent=2))
    else:
        print("\n\n".join(_info_text(doc) for doc in docs))
    return 0


# -- merge ---------------------------------------------------------------------------------

def _merge(args) -> int:
    from ..io.cachefile import merge_cache_data, read_cache_file, settings_differences, write_cache_file
    from ..io.locking import file_lock

    out = Path(args.output)
    if out.is_dir():
        raise InputError(f"{args.output}: is a folder")
    if not out.resolve().parent.is_dir():
        raise InputError(f"{args.output}: folder {out.parent} does not exist")
    with file_lock(out):
        datas = [read_cache_file(path) for path in args.inputs]
        merged, counts, shared = datas[0], [sum(datas[0].record_counts)], 0
        for path, data in zip(args.inputs[1:], datas[1:]):
            if not merged.compatible(data):
                diff = settings_differences(data.header.get("settings"), merged.header.get("settings"))
                what = f" ({', '.join(diff)} differ)" if diff else ""
                raise InputError(f"{path}: cache was made for another scene or other settings than "
                                 f"{args.inputs[0]}{what}; only caches of the same fingerprint merge")
            merged, added = merge_cache_data(merged, data)
            counts.append(sum(data.record_counts))
            shared += counts[-1] - added
        write_cache_file(out, merged)
    if not args.quiet:
        total = sum(merged.record_counts)
        print(f"lbl-illum: cache merge: {len(datas)} files, {' + '.join(f'{n:,}' for n in counts)} records "
              f"-> {total:,} ({shared:,} already present) -> {args.output}", file=sys.stderr)
    return 0

"""Irradiance cache files (docs/cache-files.md): the format, its checks, merging, and the
file a run keeps.

A cache file is an uncompressed ``.npz`` archive holding the record arrays ``L{k}_P``,
``L{k}_N``, ``L{k}_E``, ``L{k}_R``, ``L{k}_Gr``, ``L{k}_Gt`` of every level k (and ``L{k}_W``,
``L{k}_leak`` for elliptical domains, ``L{k}_zone``) and a JSON ``header``: format name and
version (2), the fingerprint of the scene and the settings the records depend on, a
readable summary of them, the accuracy, record count and octree root cube of every level,
and a SHA-256 checksum of header and arrays.  Files are written atomically under a lock
and merged with what other processes wrote meanwhile (:func:`save_cache`); version-1
files are still read.  A run that keeps a file turns SIGTERM into an interruption and
holds SIGINT and SIGTERM back while the file is written, so that what it completed is
saved whole.
"""

from __future__ import annotations

import hashlib
import io
import json
import math
import os
import signal
import threading
from contextlib import contextmanager
from pathlib import Path

import numpy as np

from ..engine.cache import IrradianceCache, LevelRecords
from ..engine.fingerprint import plain_json, record_settings
from ..errors import InputError
from .files import atomic_write_bytes
from .locking import file_lock

__all__ = ["CacheData", "CacheFile", "attach_cache_file", "CACHE_FORMAT_VERSION", "Terminated", "cache_data", "cache_from_data",
           "save_cache", "save_cache_data", "load_cache", "merge_cache_parts", "read_cache_file", "write_cache_file", "merge_cache_data",
           "record_settings", "settings_differences", "sigterm_as_interrupt", "deferred_interrupts"]

CACHE_FORMAT = "lbl_illum irradiance cache"
#: The format written (docs/cache-files.md)
CACHE_FORMAT_VERSION = 2
#: The formats read
READABLE_VERSIONS = (1, 2)


# -- a cache and its file's contents ---------------------------------------------------------

def cache_data(cache: IrradianceCache) -> "CacheData":
    """The file's contents of ``cache``: header and record arrays.  Levels with accuracy 0 are
    written empty: their records answer only the query they were made for and never
    serve a later run."""
    arrays, levels = {}, []
    for k, lv in enumerate(cache.levels):
        stored = lv.arrays()
        if lv.accuracy == 0.0:
            stored = {name: arr[:0] for name, arr in stored.items()}
        for name, arr in stored.items():
            arrays[f"L{k}_{name}"] = arr
        levels.append({"accuracy": lv.accuracy, "records": int(len(stored["P"])),
                       "center": lv.node_center[0].tolist(), "half": float(lv.node_half[0])})
    header = {"format": CACHE_FORMAT, "version": CACHE_FORMAT_VERSION, "program": _program(),
              "fingerprint": cache.fingerprint, "settings": cache.settings,
              "domains": "elliptical" if cache.anisotropic else "round",
              "center": cache.center.tolist(), "half": cache.half, "levels": levels}
    return CacheData(header, arrays)


def cache_from_data(data: "CacheData") -> IrradianceCache:
    """A cache holding the records of ``data`` (each level under its stored root cube,
    so that its octree and lookup layout are those of the run that wrote it)."""
    h = data.header
    cache = IrradianceCache(h["fingerprint"], [lv["accuracy"] for lv in h["levels"]], h["center"], h["half"],
                data.anisotropic, h.get("settings"))
    levels = []
    for k, info in enumerate(h["levels"]):
        n = info["records"] if info["accuracy"] > 0 else 0
        lv = LevelRecords(info["accuracy"], np.asarray(info["center"], np.float64), float(info["half"]),
                          capacity=max(n, 1), anisotropic=data.anisotropic)
        if n:
            a = data.level(k)
            shape = (a["W"], a["leak"]) if data.anisotropic else (None, None)
            lv.add(a["P"], a["N"], a["R"], a["E"], a["Gr"], a["Gt"], *shape, zone=a.get("zone"))
        levels.append(lv)
    cache.levels = levels
    return cache


def save_cache(cache: IrradianceCache, path: str | os.PathLike, merge: bool = True) -> list[int]:
    """Write ``cache`` to ``path``, atomically (temporary file in the same folder, then
    rename), under the file's lock (:func:`lbl_illum.io.locking.file_lock`).

    With ``merge`` (the default) the file is re-read under the lock first, and the
    records it holds that this cache lacks (by level, position and normal) are kept:
    records that other processes wrote meanwhile are not lost, as with Radiance's
    shared ambient files.  A file for other settings, or a damaged one, is replaced.
    Interruptions (SIGINT, SIGTERM) that arrive while the file is written are acted
    on once it is in place.  Returns the records per level the file now holds.
    """
    return save_cache_data(cache_data(cache), path, merge)


def save_cache_data(data: "CacheData", path: str | os.PathLike, merge: bool = True) -> list[int]:
    """:func:`save_cache` for a file's contents ``data`` (:func:`cache_data`) rather than
    a cache: written atomically under the file's lock, merged with what the file holds
    (``data``'s records first); returns the records per level the file now holds."""
    with file_lock(path):
        with deferred_interrupts():
            if merge and Path(path).exists():
                try:
                    disk = read_cache_file(path)
                except InputError:
                    disk = None
                if disk is not None and disk.compatible(data):
                    data, _ = merge_cache_data(data, disk)
            write_cache_file(path, data)
    return data.record_counts


def load_cache(path: str | os.PathLike, fingerprint: str | None = None,
               settings: dict | None = None) -> IrradianceCache:
    """Read a cache file (format version 1 or 2); refuse (InputError, one line) a
    missing, truncated or damaged file, one of another format version, and — given
    ``fingerprint`` — one made for another scene or other settings (naming what
    differs when ``settings``, the current :func:`record_settings`, is given)."""
    data = read_cache_file(path)
    if fingerprint is not None and data.fingerprint != fingerprint:
        raise InputError(f"{Path(path).name}: {_mismatch(data.header.get('settings'), settings)}; "
                         "use another file or rebuild it (--rebuild-cache)")
    return cache_from_data(data)


# -- the file format -----------------------------------------------------------------------

#: Record arrays of a level: name -> (dtype, shape after the record axis).
RECORD_ARRAYS = {"P": (np.float64, (3,)), "N": (np.float32, (3,)), "E": (np.float32, (3,)), "R": (np.float32, ()),
                 "Gr": (np.float32, (3, 3)), "Gt": (np.float32, (3, 3))}
#: The arrays of levels with elliptical domains, in addition.
SHAPE_ARRAYS = {"W": (np.float32, (3,)), "leak": (np.uint32, ())}
#: Optional arrays (files written before them have none: zone 0 for every record).
OPTIONAL_ARRAYS = {"zone": (np.uint8, ())}
#: Most diffuse levels a file may hold.
MAX_LEVELS = 1024


def _program() -> str:
    from .._version import __version__

    return f"lbl_illum {__version__}"


class CacheData:
    """A cache file's contents as read or about to be written: its header (a dict, see
    docs/cache-files.md) and its record arrays by name (``L{k}_P`` ...), without octrees."""

    def __init__(self, header: dict, arrays: dict):
        self.header = header
        self.arrays = arrays

    @property
    def fingerprint(self) -> str:
        return self.header["fingerprint"]

    @property
    def anisotropic(self) -> bool:
        return self.header.get("domains", "round") == "elliptical"

    @property
    def record_counts(self) -> list[int]:
        return [lv["records"] for lv in self.header["levels"]]

    def level(self, k: int) -> dict:
        """The record arrays of level k by short name (``P``, ``N``, ``E``, ``R``, ...)."""
        prefix = f"L{k}_"
        return {name[len(prefix):]: arr for name, arr in self.arrays.items() if name.startswith(prefix)}

    def compatible(self, other: "CacheData") -> bool:
        """Whether records of ``other`` may join these: the same fingerprint, domains and levels."""
        return (self.fingerprint == other.fingerprint and self.anisotropic == other.anisotropic
                and [lv["accuracy"] for lv in self.header["levels"]]
                == [lv["accuracy"] for lv in other.header["levels"]])


def _checksum(header: dict, arrays: dict) -> str:
    """SHA-256 of the header (without its checksum, as canonical JSON) and of every array's
    name, dtype, shape and bytes in name order (format version 2)."""
    h = hashlib.sha256()
    h.update(json.dumps({k: v for k, v in header.items() if k != "checksum"}, sort_keys=True,
                        separators=(",", ":"), default=plain_json).encode())
    for name in sorted(arrays):
        arr = np.ascontiguousarray(arrays[name])
        h.update(f"\n{name} {arr.dtype.str} {arr.shape}\n".encode())
        h.update(arr.tobytes())
    return h.hexdigest()


def _checksum_v1(arrays: dict) -> str:
    """Format version 1's checksum: SHA-256 of the array names and bytes in name order."""
    h = hashlib.sha256()
    for name in sorted(arrays):
        h.update(name.encode())
        h.update(np.ascontiguousarray(arrays[name]).tobytes())
    return h.hexdigest()


def write_cache_file(path: str | os.PathLike, data: CacheData) -> None:
    """Write ``data`` as a version-2 cache file, atomically (see :func:`files.atomic_write_bytes`)."""
    header = {k: v for k, v in data.header.items() if k != "checksum"}
    header["version"] = CACHE_FORMAT_VERSION
    header["checksum"] = _checksum(header, data.arrays)
    buf = io.BytesIO()
    np.savez(buf, header=np.array(json.dumps(header, sort_keys=True, default=plain_json)), **data.arrays)
    atomic_write_bytes(path, buf.getvalue())


def read_cache_file(path: str | os.PathLike) -> CacheData:
    """Read and check a cache file (format version 1 or 2).

    Raises :class:`InputError` with one line naming the file for a missing or unreadable
    file, a truncated or damaged archive (zip CRC, checksum), a header that is not an
    lbl_illum cache's, another format version, and arrays whose names, types, shapes or
    values do not fit the header or are not physical (non-finite numbers, radii ≤ 0,
    normals that are not unit vectors, negative irradiance): a file whose checksum is right
    but that no run of this program wrote.
    """
    name = Path(path).name
    try:
        with open(path, "rb") as fh:
            magic = fh.read(4)
        if magic != b"PK\x03\x04":
            what = "an empty file" if not magic else "not a NumPy .npz archive"
            raise InputError(f"{name}: not an lbl_illum cache file ({what})")
        with np.load(path, allow_pickle=False) as npz:
            if "header" not in npz.files:
                raise InputError(f"{name}: not an lbl_illum cache file (no header)")
            text = npz["header"]
            arrays = {k: npz[k] for k in npz.files if k != "header"}
    except InputError:
        raise
    except FileNotFoundError:
        raise InputError(f"{name}: no such cache file") from None
    except IsADirectoryError:
        raise InputError(f"{name}: is a folder, not a cache file") from None
    except PermissionError:
        raise InputError(f"{name}: cannot read the cache file (permission denied)") from None
    except Exception as exc:  # zip, CRC, pickle-refusal and numpy format errors: a damaged file
        reason = str(exc).strip().splitlines()[0][:80] if str(exc).strip() else ""
        reason = f"{type(exc).__name__}: {reason}" if reason else type(exc).__name__
        raise InputError(f"{name}: damaged or truncated cache file ({reason}); remove it or rebuild it "
                         "(--rebuild-cache)") from None
    try:
        header = json.loads(str(text)) if text.dtype.kind == "U" and text.ndim == 0 else None
    except ValueError:
        header = None
    if not isinstance(header, dict) or header.get("format") != CACHE_FORMAT:
        raise InputError(f"{name}: not an lbl_illum cache file")
    version = header.get("version")
    if version not in READABLE_VERSIONS:
        raise InputError(f"{name}: cache format version {version!r}; this program reads versions "
                         f"{', '.join(map(str, READABLE_VERSIONS))} (rebuild it: --rebuild-cache)")
    if version == 1:
        if _checksum_v1(arrays) != header.get("checksum"):
            raise InputError(f"{name}: cache file is damaged (checksum mismatch); remove it or rebuild it "
                             "(--rebuild-cache)")
        header = _header_from_v1(header, name)
    elif _checksum(header, arrays) != header.get("checksum"):
        raise InputError(f"{name}: cache file is damaged (checksum mismatch); remove it or rebuild it "
                         "(--rebuild-cache)")
    data = CacheData(header, arrays)
    _check_contents(data, name)
    for k, lv in enumerate(header["levels"]):
        if lv["accuracy"] == 0 and lv["records"]:   # (version 1 kept them) they never serve a query
            for short, arr in data.level(k).items():
                arrays[f"L{k}_{short}"] = arr[:0]
            lv["records"] = 0
    return data


def _header_from_v1(old: dict, name: str) -> dict:
    """A version-2 header for a version-1 file (one root cube for every level, no settings)."""
    try:
        levels = [{"accuracy": a, "records": n, "center": old["center"], "half": old["half"]}
                  for a, n in zip(old["accuracy"], old["records"], strict=True)]
    except (KeyError, TypeError, ValueError):
        raise InputError(f"{name}: damaged cache header (version 1)") from None
    return {"format": CACHE_FORMAT, "version": 1, "program": None, "fingerprint": old.get("fingerprint"),
            "settings": None, "domains": old.get("domains", "round"), "center": old.get("center"),
            "half": old.get("half"), "levels": levels, "checksum": old.get("checksum")}


def _is_number(x) -> bool:
    return isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x)


def _is_point(x) -> bool:
    return isinstance(x, list) and len(x) == 3 and all(_is_number(v) for v in x)


def _check_contents(data: CacheData, name: str) -> None:
    """Refuse a header or arrays that do not fit each other (a file whose checksum matches
    but that no run of this program wrote)."""
    h = data.header

    def bad(what):
        raise InputError(f"{name}: damaged cache file ({what})")

    if not isinstance(h.get("fingerprint"), str) or not h["fingerprint"]:
        bad("no fingerprint")
    if h.get("domains", "round") not in ("round", "elliptical"):
        bad(f"unknown record domains {h.get('domains')!r}")
    if not _is_point(h.get("center")) or not _is_number(h.get("half")) or not h["half"] > 0:
        bad("bad root cube")
    if h.get("settings") is not None and not isinstance(h["settings"], dict):
        bad("bad settings")
    levels = h.get("levels")
    if not isinstance(levels, list) or not 1 <= len(levels) <= MAX_LEVELS:
        bad("bad level list")
    expected = dict(RECORD_ARRAYS, **(SHAPE_ARRAYS if data.anisotropic else {}))
    names = set()
    for k, lv in enumerate(levels):
        if not isinstance(lv, dict):
            bad(f"level {k}")
        n, a = lv.get("records"), lv.get("accuracy")
        if not (isinstance(n, int) and not isinstance(n, bool) and n >= 0):
            bad(f"level {k}: bad record count")
        if not (_is_number(a) and a >= 0):
            bad(f"level {k}: bad accuracy")
        if not _is_point(lv.get("center")) or not _is_number(lv.get("half")) or not lv["half"] > 0:
            bad(f"level {k}: bad root cube")
        for short, (dtype, shape) in expected.items():
            key = f"L{k}_{short}"
            names.add(key)
            arr = data.arrays.get(key)
            if arr is None:
                bad(f"array {key} missing")
            if arr.dtype != np.dtype(dtype) or arr.shape != (n,) + shape:
                bad(f"array {key} is {arr.dtype}{list(arr.shape)}, expected {np.dtype(dtype)}{[n, *shape]}")
            if arr.dtype.kind == "f" and not np.all(np.isfinite(arr)):
                bad(f"array {key} holds non-finite numbers")
        for short, (dtype, shape) in OPTIONAL_ARRAYS.items():
            key = f"L{k}_{short}"
            arr = data.arrays.get(key)
            if arr is None:
                continue
            names.add(key)
            if arr.dtype != np.dtype(dtype) or arr.shape != (n,) + shape:
                bad(f"array {key} is {arr.dtype}{list(arr.shape)}, expected {np.dtype(dtype)}{[n, *shape]}")
            if short == "zone" and np.any(arr > 1):
                bad(f"array {key} holds zones other than 0 and 1")
        if n and not np.all(data.arrays[f"L{k}_R"] > 0):
            bad(f"array L{k}_R holds radii <= 0")
        if n:
            _check_physics(data.arrays, k, bad)
        if n and h.get("version") != 1 and np.any(np.abs(data.arrays[f"L{k}_P"] - lv["center"]) > lv["half"]):
            bad(f"level {k}: records outside the root cube")
    extra = sorted(set(data.arrays) - names)
    if extra:
        bad(f"unexpected array {extra[0]}")


#: Largest departure of a stored normal's length from 1.  The writer stores unit float64
#: normals rounded to float32 (|N| − 1 below 1e-7); a larger departure means the file was
#: edited or written by something else, and Eq. 6's normal term √(1 − N·N_i) would then be
#: undefined or wrong.
NORMAL_LENGTH_TOLERANCE = 1e-3


def _check_physics(arrays: dict, k: int, bad) -> None:
    """Refuse record values of level ``k`` that no evaluation of Eq. 2 gives (finite values
    and positive radii are checked before): a normal N_i that is not a unit vector
    (|N_i| outside 1 ± :data:`NORMAL_LENGTH_TOLERANCE`), or a negative irradiance E_i — an
    integral of non-negative radiance over the hemisphere [lux] — in any channel."""
    N = arrays[f"L{k}_N"].astype(np.float64)
    length = np.sqrt(np.einsum("ij,ij->i", N, N))
    off = np.abs(length - 1.0) > NORMAL_LENGTH_TOLERANCE
    if off.any():
        i = int(np.argmax(off))
        bad(f"array L{k}_N: record {i} has a normal of length {length[i]:.6g}, not a unit vector "
            f"({int(off.sum())} such records)")
    E = arrays[f"L{k}_E"]
    negative = (E < 0).any(axis=1)
    if negative.any():
        i = int(np.argmax(negative))
        bad(f"array L{k}_E: record {i} has a negative irradiance {float(E[i].min()):.6g} lux "
            f"({int(negative.sum())} such records)")


def _level_keys(P: np.ndarray, N: np.ndarray) -> np.ndarray:
    """(n,) opaque row keys of records: the bytes of position (float64) and normal (float32)."""
    n = len(P)
    raw = np.concatenate([np.ascontiguousarray(P, np.float64).view(np.uint8).reshape(n, 24),
                          np.ascontiguousarray(N, np.float32).view(np.uint8).reshape(n, 12)], axis=1)
    return np.ascontiguousarray(raw).view(np.dtype((np.void, 36))).reshape(n)


def _union_cube(c1, h1, c2, h2):
    """The smallest cube centred between two cubes that holds both (one of them if it
    already holds the other)."""
    c1, c2 = np.asarray(c1, np.float64), np.asarray(c2, np.float64)
    if np.all(np.abs(c2 - c1) + h2 <= h1):
        return c1.tolist(), float(h1)
    if np.all(np.abs(c1 - c2) + h1 <= h2):
        return c2.tolist(), float(h2)
    lo = np.minimum(c1 - h1, c2 - h2)
    hi = np.maximum(c1 + h1, c2 + h2)
    return (0.5 * (lo + hi)).tolist(), 0.5 * float(np.max(hi - lo)) * (1 + 1e-9)


def merge_cache_data(base: CacheData, other: CacheData) -> tuple[CacheData, int]:
    """``base`` plus the records of ``other`` it lacks; returns (merged, records added).

    Two records are the same when they belong to the same level and have bit-identical
    positions and normals (a record made twice by the same calculation); ``base``'s copy
    is kept.  The merged records of a level are base's in their order, then the others
    in theirs; each level's root cube holds both.  Raises :class:`InputError` when the
    two are not :meth:`CacheData.compatible`.
    """
    if not base.compatible(other):
        raise InputError(_mismatch(base.header.get("settings"), other.header.get("settings")))
    arrays, levels, added = {}, [], 0
    for k, (lb, lo) in enumerate(zip(base.header["levels"], other.header["levels"])):
        a, b = base.level(k), other.level(k)
        new = ~np.isin(_level_keys(b["P"], b["N"]), _level_keys(a["P"], a["N"])) if len(b["P"]) else \
            np.zeros(0, bool)
        added += int(new.sum())
        for short in a:
            arrays[f"L{k}_{short}"] = np.concatenate([a[short], b[short][new]])
        if new.any():
            center, half = _union_cube(lb["center"], lb["half"], lo["center"], lo["half"])
        else:
            center, half = lb["center"], lb["half"]
        levels.append({**lb, "records": int(len(arrays[f"L{k}_P"])), "center": center, "half": half})
    header = {**base.header, "levels": levels}
    header.pop("checksum", None)
    return CacheData(header, arrays), added


def merge_cache_parts(base: CacheData, parts) -> CacheData:
    """``base`` merged with each of ``parts`` in turn (:func:`merge_cache_data`), the same
    records in the same order and the same root cubes (a record twice within one part is
    kept once too), in one pass: the keys of all the
    parts' records are looked up in ``base`` once and among themselves once, and every
    array is concatenated once (merging k parts into n records one by one costs k times
    the sort of n keys and k copies of the arrays)."""
    parts = list(parts)
    for part in parts:
        if not base.compatible(part):
            raise InputError(_mismatch(base.header.get("settings"), part.header.get("settings")))
    if not parts:
        return base
    arrays, levels = {}, []
    for k, lb in enumerate(base.header["levels"]):
        a = base.level(k)
        own = [part.level(k) for part in parts]
        P = np.concatenate([b["P"] for b in own])
        keys = _level_keys(P, np.concatenate([b["N"] for b in own])) if len(P) else np.zeros(0, np.dtype((np.void, 36)))
        new = ~np.isin(keys, _level_keys(a["P"], a["N"])) if len(keys) else np.zeros(0, bool)
        if new.any():                   # a record made by two parts is kept once, the first's
            _, first = np.unique(keys, return_index=True)
            once = np.zeros(len(keys), bool)
            once[first] = True
            new &= once
        for short in a:
            arrays[f"L{k}_{short}"] = np.concatenate([a[short], *(b[short] for b in own)])[
                np.concatenate([np.ones(len(a[short]), bool), new])]
        center, half = lb["center"], lb["half"]
        lo = 0
        for part, b in zip(parts, own):
            hi = lo + len(b["P"])
            if new[lo:hi].any():
                info = part.header["levels"][k]
                center, half = _union_cube(center, half, info["center"], info["half"])
            lo = hi
        levels.append({**lb, "records": int(len(arrays[f"L{k}_P"])), "center": center, "half": half})
    header = {**base.header, "levels": levels}
    header.pop("checksum", None)
    return CacheData(header, arrays)


# -- what the fingerprint covers, readably ------------------------------------------------

#: Summary keys that follow from others (named in a refusal only if nothing else differs).
_DERIVED = ("level_accuracy", "level_samples")


def settings_differences(a: dict | None, b: dict | None) -> list[str]:
    """Top-level keys of two :func:`record_settings` summaries whose values differ."""
    if not a or not b:
        return []
    keys = [k for k in dict.fromkeys([*a, *b]) if a.get(k) != b.get(k)]
    primary = [k for k in keys if k not in _DERIVED]
    return primary or keys


def _mismatch(stored: dict | None, current: dict | None) -> str:
    diff = settings_differences(stored, current)
    if diff:
        return f"cache was made for another scene or other settings ({', '.join(diff)} differ)"
    return ("cache was made for another scene or other settings (geometry, materials, sky, sun, accuracy, "
            "bounces, samples, ambient or bounce scaling differ)")


# -- runs that keep a cache file ------------------------------------------------------------

class Terminated(KeyboardInterrupt):
    """SIGTERM arrived during a run that keeps a cache file: raised like Ctrl-C's
    KeyboardInterrupt, so that the run saves what it completed and stops."""


@contextmanager
def sigterm_as_interrupt():
    """Within the block, SIGTERM raises :class:`Terminated` instead of ending the process
    at once (only in the main thread, and only if SIGTERM has its default action)."""
    if threading.current_thread() is not threading.main_thread() or \
            signal.getsignal(signal.SIGTERM) is not signal.SIG_DFL:
        yield
        return

    def handler(signum, frame):
        raise Terminated("terminated (SIGTERM)")

    signal.signal(signal.SIGTERM, handler)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, signal.SIG_DFL)


@contextmanager
def deferred_interrupts():
    """SIGINT and SIGTERM that arrive within the block take effect at its end, so that a
    file being written is finished first: the handler they had before is called then (the
    default one of SIGINT raises KeyboardInterrupt; SIGTERM's default action becomes
    :class:`Terminated`).  Ignored signals stay ignored.  Only in the main thread;
    elsewhere the block runs unchanged."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    received = []

    def handler(signum, frame):
        received.append(signum)

    sigs = [s for s in (signal.SIGINT, getattr(signal, "SIGTERM", None)) if s is not None]
    old = {s: signal.getsignal(s) for s in sigs}
    old = {s: h for s, h in old.items() if h is not signal.SIG_IGN}
    for s in old:
        signal.signal(s, handler)
    try:
        yield
    finally:
        for s, h in old.items():
            signal.signal(s, h if h is not None else signal.SIG_DFL)
    for signum in dict.fromkeys(received):
        previous = old[signum]
        if callable(previous):
            previous(signum, None)
        elif signum == signal.SIGINT:
            raise KeyboardInterrupt
        else:
            raise Terminated("terminated (SIGTERM)")


class CacheFile:
    """A cache file that a run reads when it starts and writes when it ends or is
    interrupted.

    path : the file
    rebuild : ignore what the file holds (even a file for other settings, or a damaged
        one) and replace it with this run's records at the first write
    """

    def __init__(self, path: str | os.PathLike, rebuild: bool = False):
        self.path = Path(path)
        self.rebuild = bool(rebuild)

    def read(self, fingerprint: str, settings: dict | None = None) -> IrradianceCache | None:
        """The file's records (None if it does not exist or is to be rebuilt); refuses a
        damaged file or one for other settings with an :class:`InputError`."""
        if self.rebuild or not self.path.exists():
            return None
        return IrradianceCache.load(self.path, fingerprint, settings)

    def write(self, cache: IrradianceCache) -> list[int]:
        """Save ``cache``, merged with what other processes wrote meanwhile (not when
        rebuilding); return the records per level the file now holds."""
        counts = cache.save(self.path, merge=not self.rebuild)
        self.rebuild = False
        return counts

    # -- the record keeper of an Integrator (lbl_illum.engine.integrator.Integrator.keeper)
    @property
    def name(self) -> str:
        """The file's path, as the user gave it."""
        return str(self.path)

    def guard(self):
        """Around a run: SIGTERM stops it as Ctrl-C does, so that it saves what it completed."""
        return sigterm_as_interrupt()

    def hold(self):
        """While records are dropped or saved: Ctrl-C and SIGTERM wait for the end."""
        return deferred_interrupts()

    def save(self, cache: IrradianceCache) -> list[int]:
        """:meth:`write`, as the integrator calls it at the end of a run or on interruption."""
        return self.write(cache)


def attach_cache_file(integrator, path: str | os.PathLike, rebuild: bool = False) -> CacheFile:
    """Keep ``integrator``'s cache in the file ``path`` (docs/cache-files.md).

    Its records are read now (unless it does not exist, or ``rebuild`` is true) and
    replace those the integrator held; the cache is written back at the end of every
    :meth:`~lbl_illum.engine.integrator.Integrator.compute` — merged, under the file's lock,
    with records other processes added meanwhile.  A damaged file, or one made for
    another scene or other settings, is refused with an :class:`~lbl_illum.errors.InputError`;
    with ``rebuild`` it is replaced instead.  A run that is interrupted (Ctrl-C, SIGTERM,
    an error) writes the records of the levels it has evaluated.  Returns the file.
    """
    cache_file = CacheFile(path, rebuild)
    cache = cache_file.read(integrator.fingerprint, record_settings(integrator.scene, integrator.options))
    integrator.keeper = cache_file
    if cache is not None:
        integrator.cache = cache
    return cache_file

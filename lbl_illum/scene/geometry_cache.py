"""Geometry files kept between runs, parsed: a run that reads the same model again skips
the parse and the import of its reader.

Reading an OBJ, PLY, STL, OFF or GLB file goes through trimesh, whose import alone
(with scipy's spatial module) takes about 0.65 s, more than the whole calculation of a
small grid at ``draft``.  Once a file is read, its parts (:class:`~lbl_illum.scene.geometry.MeshPart`:
names and corners in metres) and the warnings the reading gave are kept in a cache
folder; the next run of any scene that uses the same file, at the same scale, reads them
back in milliseconds.  The key is the SHA-256 of the file's bytes, the scale, the place
the file is named (messages quote it), the version of lbl_illum and
:data:`READER_VERSION`: a file edited, moved to other units or read by another version is
parsed again, never served stale.  Only formats that hold all their geometry in one file
are kept this way (not ``.gltf`` with outside buffers).

Radiance files (:func:`radiance_key`, :func:`load_radiance`, :func:`store_radiance`) read
others (``!xform``, a ``mesh``'s OBJ), so an entry lists every file its reading read with
the SHA-256 of its bytes, and is served only while each of them is unchanged; a file whose
reading ran any other ``!`` command (a program's output) is not kept.  What is kept is
what the scene needs of it: its triangles per modifier, the warnings the reading gave, and
its primitives other than surfaces (the modifiers its materials come from, sources and
skies); parsing the LBNL office's 3.3 MB of polygons and triangulating its keyhole desks
took about 2 s of every run.

Where: ``geometry/`` in the user's cache folder (:func:`lbl_illum.photometry.user_cache_dir`:
``$LBL_ILLUM_CACHE_DIR``, else ``$XDG_CACHE_HOME/lbl_illum``, else ``~/.cache/lbl_illum``;
``LBL_ILLUM_CACHE_DIR=off`` keeps nothing).
A folder that cannot be written, or an entry that cannot be read, only costs the parse:
the cache never stops a run.  Entries are written whole (to a temporary name, then
renamed), so two runs at once do not read each other's half-written files.
"""

from __future__ import annotations

import hashlib
import json
import os
import tempfile
from pathlib import Path

import numpy as np

__all__ = ["CACHED_SUFFIXES", "READER_VERSION", "cache_folder", "cache_key", "kept_shape", "load", "load_kept",
           "load_radiance", "radiance_key", "store", "store_kept", "store_radiance"]

#: Formats whose geometry lies wholly in the one file.
CACHED_SUFFIXES = (".obj", ".ply", ".stl", ".off", ".glb")
#: Raised whenever the reading of geometry files changes what it gives.
READER_VERSION = 1


def cache_folder() -> Path | None:
    """The folder of kept geometry (module text), or None when the cache is off."""
    from ..photometry import user_cache_dir

    root = user_cache_dir()
    return None if root is None else root / "geometry"


def cache_key(path: Path, where: str, scale: float) -> str | None:
    """The key of ``path`` read at ``scale`` [m per file unit] for messages starting with
    ``where``, or None when it is not kept (the cache is off, the format reads other
    files, or the file cannot be read here)."""
    from .._version import __version__

    if path.suffix.lower() not in CACHED_SUFFIXES or cache_folder() is None:
        return None
    try:
        digest = hashlib.sha256(path.read_bytes())
    except OSError:
        return None
    digest.update(json.dumps([repr(float(scale)), where, __version__, READER_VERSION]).encode())
    return digest.hexdigest()


def load(key: str | None):
    """``(parts, warnings)`` kept under ``key``, or None (no entry, or one that cannot be read)."""
    kept = _load_entry(key)
    return None if kept is None else kept[:2]


def _load_entry(key: str | None, check=None):
    """``(parts, warnings, meta, data)`` of the entry ``key``; ``check(meta)`` may refuse it."""
    from .geometry import MeshPart

    if key is None:
        return None
    folder = cache_folder()
    try:
        with np.load(folder / f"{key}.npz", allow_pickle=False) as data:
            meta = json.loads(str(data["meta"]))
            if check is not None and not check(meta):
                return None
            parts = [MeshPart(p["name"], p["node"], p["group"], p["material"], np.array(data[f"v{i}"]))
                     for i, p in enumerate(meta["parts"])]
            arrays = {name: np.array(data[name]) for name in data.files if not name.startswith("v") and name != "meta"}
        return parts, list(meta["warnings"]), meta, arrays
    except (OSError, KeyError, ValueError, TypeError):
        return None


def store(key: str | None, parts, warnings, meta: dict | None = None, arrays: dict | None = None) -> None:
    """Keep ``parts`` and the ``warnings`` their reading gave under ``key`` (quietly
    nothing when the folder cannot be written), with more ``meta`` (JSON) and ``arrays``."""
    if key is None:
        return
    folder = cache_folder()
    meta = {"parts": [{"name": p.name, "node": p.node, "group": p.group, "material": p.material} for p in parts],
            "warnings": list(warnings), **(meta or {})}
    arrays = {**{f"v{i}": np.ascontiguousarray(p.vertices, np.float64) for i, p in enumerate(parts)},
              **(arrays or {})}
    try:
        folder.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(dir=folder, suffix=".tmp")
        try:
            with os.fdopen(fd, "wb") as out:
                np.savez(out, meta=np.array(json.dumps(meta)), **arrays)
            os.replace(tmp, folder / f"{key}.npz")
        finally:
            if os.path.exists(tmp):
                os.unlink(tmp)
    except OSError:
        return


def load_kept(key: str | None) -> tuple[dict, dict] | None:
    """``(meta, arrays)`` that :func:`store_kept` kept under ``key``, or None (no entry, or
    one that cannot be read)."""
    kept = _load_entry(key)
    return None if kept is None else (kept[2], kept[3])


def store_kept(key: str | None, meta: dict, arrays: dict) -> None:
    """Keep what was derived from a scene's geometry under ``key`` (the unglazed openings
    found in it, :mod:`lbl_illum.engine.openings`): ``meta`` (JSON, its own keys besides
    ``parts`` and ``warnings``) and ``arrays`` (named not starting with ``v``)."""
    store(key, [], [], meta=meta, arrays=arrays)


def kept_shape(name: str, make) -> np.ndarray:
    """(k, 3, 3) triangles of a shape that ``make()`` builds alike every time (the unit
    sphere of Radiance's ``sphere`` and ``bubble`` primitives, an icosphere from trimesh),
    built once and kept in the cache folder like a geometry file: a scene with a sphere then
    no longer imports trimesh on every run (0.8 s with SciPy's spatial module).  The key is
    ``name``, lbl_illum's version, :data:`READER_VERSION` and trimesh's version, so a new
    trimesh builds it again.  Without a cache folder, or one that cannot be read or
    written, ``make()`` is called each time."""
    from importlib import metadata

    from .._version import __version__
    from .geometry import MeshPart

    try:
        builder = metadata.version("trimesh")
    except metadata.PackageNotFoundError:
        builder = None
    key = None if cache_folder() is None else hashlib.sha256(
        json.dumps(["shape", name, __version__, READER_VERSION, builder]).encode()).hexdigest()
    kept = load(key)
    if kept is not None and len(kept[0]) == 1 and kept[0][0].vertices.ndim == 3:
        return kept[0][0].vertices
    triangles = np.ascontiguousarray(make(), np.float64)
    store(key, [MeshPart(name, name, None, None, triangles)], [])
    return triangles


def _file_digest(path) -> str | None:
    try:
        return hashlib.sha256(Path(path).read_bytes()).hexdigest()
    except OSError:
        return None


def radiance_key(path: Path, where: str, scale: float) -> str | None:
    """The key of the Radiance file ``path`` read at ``scale`` [m per file unit] for
    messages starting with ``where``, or None when the cache is off.  The files its
    reading reads are checked when the entry is loaded (:func:`load_radiance`)."""
    from .._version import __version__

    if cache_folder() is None:
        return None
    try:
        place = str(Path(path).resolve())
    except OSError:
        return None
    return hashlib.sha256(json.dumps(["radiance", place, repr(float(scale)), where, __version__,
                                      READER_VERSION]).encode()).hexdigest()


def load_radiance(key: str | None):
    """``(primitives, parts, warnings)`` kept under ``key`` (the primitives other than
    surfaces, the surfaces' triangles per modifier, the reading's warnings), or None: no
    entry, one that cannot be read, or one whose files are not all unchanged."""
    from .radfile import RadPrimitive

    def unchanged(meta) -> bool:
        return all(_file_digest(path) == digest for path, digest in meta["reads"])

    kept = _load_entry(key, unchanged)
    if kept is None:
        return None
    parts, warnings, meta, arrays = kept
    try:
        reals, ends = arrays["reals"], np.concatenate([[0], np.cumsum(arrays["counts"])])
        prims = [RadPrimitive(p[0], p[1], p[2], list(p[3]), reals[ends[k]:ends[k + 1]].copy(), p[4])
                 for k, p in enumerate(meta["primitives"])]
    except (KeyError, IndexError, TypeError, ValueError):
        return None
    return prims, parts, warnings


def store_radiance(key: str | None, reads, primitives, parts, warnings) -> None:
    """Keep a Radiance file's reading under ``key``: ``reads``, the files it read
    (:func:`lbl_illum.scene.radfile.files_read`; nothing is kept when one is None, a
    command's output), ``primitives`` (those other than surfaces), ``parts`` and
    ``warnings``."""
    if key is None or any(path is None for path in reads):
        return
    digests = [[str(Path(path).resolve()), _file_digest(path)] for path in dict.fromkeys(reads)]
    if any(digest is None for _, digest in digests):
        return
    meta = {"reads": digests,
            "primitives": [[p.modifier, p.kind, p.name, list(p.strings), int(p.line)] for p in primitives]}
    reals = [np.asarray(p.reals, np.float64).reshape(-1) for p in primitives]
    store(key, parts, warnings, meta=meta, arrays={"reals": np.concatenate(reals) if reals else np.zeros(0),
                                                   "counts": np.array([len(r) for r in reals], np.int64)})

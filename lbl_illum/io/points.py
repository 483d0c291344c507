"""Sensor points in and illuminance results out.

Points use the Radiance/Honeybee ``.pts`` layout: one point per line,
``x y z nx ny nz`` separated by white space, in the scene file's units; blank lines
and ``#`` comments are allowed.  A line may end with a seventh field, the name of
the area the point belongs to (``lbl-illum grid`` writes it); a name is one word
without ``#``, ``,`` or ``"`` that does not read as a number.  Lines without a name
belong to the unnamed area ``""``.  (Radiance's ``rtrace`` reads numbers only: give it
the points through ``lbl-illum export radiance --points``, which writes six columns.)
Numbers are decimal, as C's ``atof`` reads them; lines end at line feeds (CR LF and CR
too) and are numbered so in messages.  A point is refused, naming its line, when a value
is not finite, a coordinate is beyond ±:data:`~lbl_illum.scene.geometry.MAX_COORDINATE` metres,
or the normal is shorter than :data:`MIN_NORMAL`.

Results are written to a temporary file in the output's folder and renamed into
place, so a failed run never leaves a partial output file:

* ``.csv``: a header row, then ``x,y,z,nx,ny,nz,illuminance,direct,indirect`` per point
  (illuminance [lux], photometric) in input order.  A daylight-factor run puts
  ``daylight_factor`` [%] before ``illuminance``; points with area names add a last
  column ``area``.  Readers that take columns by name or the first nine by position
  are unaffected;
* ``.txt``: one value per line (the Radiance/Honeybee habit): the illuminance [lux],
  or the daylight factor [%] of a daylight-factor run.
"""

from __future__ import annotations

import math
import os
import re
from pathlib import Path

import numpy as np

from ..errors import InputError, show
from .files import atomic_write_text, read_text_file
from ..scene.geometry import MAX_COORDINATE

__all__ = ["read_points", "write_points", "write_results", "read_results", "check_output_path", "check_area_name",
           "RESULT_FORMATS"]

RESULT_FORMATS = (".csv", ".txt")
#: A decimal number as a ``.pts`` file may write it: sign, digits, point, exponent; or
#: inf / nan (refused as not finite, with their own message).
_NUMBER = re.compile(r"[+-]?((\d+\.?\d*|\.\d+)([eE][+-]?\d+)?|inf|infinity|nan)", re.IGNORECASE)
#: Normals whose length is at most this are refused as zero-length.
MIN_NORMAL = 1e-12


def check_area_name(name: str, where: str) -> str:
    """Refuse an area name that cannot stand as the seventh field of a ``.pts`` line
    (or in a CSV cell unquoted): empty, white space, control characters, ``#``, ``,``,
    ``"``, or a number."""
    if not name or any(c.isspace() or not c.isprintable() for c in name) or any(c in name for c in '#,"'):
        raise InputError(f"{where}: area name {show(name)} must be one word without '#', ',' or '\"'")
    try:
        float(name)
    except ValueError:
        return name
    raise InputError(f"{where}: area name {show(name)} looks like a number")


def _lines(text: str):
    """(line number, line) pairs, lines split at LF (CR LF and CR-only endings are read
    too), numbered as editors number them; unlike ``str.splitlines`` the separators
    U+001C…U+001E, U+0085 and U+2028 do not start a line."""
    return enumerate(text.replace("\r\n", "\n").replace("\r", "\n").split("\n"), start=1)


def read_points(path: str | os.PathLike, unit_scale: float = 1.0, *, with_areas: bool = False):
    """Read a ``.pts`` file: ((n, 3) points [m], (n, 3) unit normals).  A Honeybee model
    (``.hbjson``) gives the sensors of all its grids, in metres (``unit_scale`` is not
    applied), each grid's identifier as their area name (:mod:`lbl_illum.scene.honeybee`).

    Coordinates are multiplied by ``unit_scale`` (metres per scene unit).  With
    ``with_areas=True`` a third item is returned: the (n,) area names (object array of
    str, ``""`` on lines without a name).
    """
    path = Path(path)
    name = path.name or str(path)
    if path.suffix.lower() == ".hbjson":           # a Honeybee model's sensor grids, in metres already
        from ..scene.honeybee import read_grids

        grids = read_grids(path, name)
        P = np.concatenate([g.points for g in grids])
        N = np.concatenate([g.normals for g in grids])
        if with_areas:
            return P, N, np.concatenate([np.full(len(g.points), g.identifier, object) for g in grids])
        return P, N
    text = read_text_file(path, " points")
    rows, areas = [], []
    for number, line in _lines(text):
        body = line.split("#", 1)[0].strip()
        if not body:
            continue
        fields = body.split()
        if len(fields) not in (6, 7):
            raise InputError(f"{name}: line {number}: expected 6 numbers 'x y z nx ny nz' and an optional "
                             f"area name, got {len(fields)} fields")
        values = [_number(f) for f in fields[:6]]
        if None in values:
            bad = fields[values.index(None)]
            raise InputError(f"{name}: line {number}: not a number: {show(bad, 30)}")
        if not all(math.isfinite(v) for v in values):
            raise InputError(f"{name}: line {number}: values must be finite")
        if max(abs(v) for v in values[:3]) * unit_scale > MAX_COORDINATE:
            raise InputError(f"{name}: line {number}: a coordinate is beyond ±{MAX_COORDINATE:g} m")
        if _norm(values[3:]) <= MIN_NORMAL:
            raise InputError(f"{name}: line {number}: zero-length normal")
        areas.append(check_area_name(fields[6], f"{name}: line {number}") if len(fields) == 7 else "")
        rows.append(values)
    if not rows:
        raise InputError(f"{name}: no points")
    data = np.array(rows, dtype=np.float64)
    n = data[:, 3:] / np.abs(data[:, 3:]).max(axis=1, keepdims=True)      # scaled first: no overflow
    normals = n / np.linalg.norm(n, axis=1, keepdims=True)
    if with_areas:
        return data[:, :3] * unit_scale, normals, np.array(areas, dtype=object)
    return data[:, :3] * unit_scale, normals


def _number(text: str) -> float | None:
    """A decimal number of a ``.pts`` field (as C's ``atof`` reads it, without hex, digit
    grouping or Unicode digits, which Python's ``float`` would take); None otherwise."""
    if not _NUMBER.fullmatch(text):
        return None
    return float(text)


def _norm(v) -> float:
    """Euclidean length of a short vector without overflow or underflow."""
    top = max(abs(x) for x in v)
    return 0.0 if top == 0.0 else top * math.sqrt(sum((x / top) ** 2 for x in v))


def write_points(path: str | os.PathLike, points: np.ndarray, normals: np.ndarray,
                 areas: np.ndarray | None = None, header: str | None = None) -> None:
    """Write a ``.pts`` file atomically: ``x y z nx ny nz [area]`` per line.

    ``points`` are written as given (the file's units); ``header`` becomes ``#`` comment
    lines at the top.  Coordinates keep 10 significant digits.
    """
    points = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    normals = np.asarray(normals, dtype=np.float64).reshape(-1, 3)
    lines = [f"# {h}" for h in header.splitlines()] if header else []
    for i, (p, n) in enumerate(zip(points, normals)):
        row = " ".join(f"{v:.10g}" for v in p) + " " + " ".join(f"{v:.10g}" for v in n + 0.0)
        if areas is not None and areas[i]:
            row += " " + check_area_name(str(areas[i]), Path(path).name)
        lines.append(row)
    atomic_write_text(path, "\n".join(lines) + "\n")


def check_output_path(path: str | os.PathLike, formats=RESULT_FORMATS) -> Path:
    """Refuse an output whose extension is unknown, whose folder does not exist, or that
    is a folder itself: found before any work, so bad input leaves no file behind."""
    path = Path(path)
    if path.suffix.lower() not in formats:
        raise InputError(f"{path.name}: output must end in {' or '.join(formats)}")
    if not path.parent.is_dir():
        raise InputError(f"{path}: folder {path.parent} does not exist")
    if path.is_dir():
        raise InputError(f"{path}: is a folder; give a file name")
    return path


def write_results(path: str | os.PathLike, points: np.ndarray, normals: np.ndarray, illuminance: np.ndarray,
                  direct: np.ndarray | None = None, indirect: np.ndarray | None = None, *,
                  daylight_factor: np.ndarray | None = None, areas: np.ndarray | None = None) -> None:
    """Write results in the format given by the extension (``points`` in the file's units).

    ``daylight_factor`` [%] adds the column ``daylight_factor`` before ``illuminance``
    and is the value of a ``.txt`` file; ``areas`` adds the last column ``area`` when
    any point has a name.
    """
    path = check_output_path(path)
    if path.suffix.lower() == ".txt":
        values = illuminance if daylight_factor is None else daylight_factor
        atomic_write_text(path, "".join(f"{e:.6g}\n" for e in values))
        return
    cols = ["x", "y", "z", "nx", "ny", "nz"]
    data = [points, normals]
    if daylight_factor is not None:
        cols.append("daylight_factor")
        data.append(np.asarray(daylight_factor)[:, None])
    cols.append("illuminance")
    data.append(np.asarray(illuminance)[:, None])
    if direct is not None and indirect is not None:
        cols += ["direct", "indirect"]
        data += [np.asarray(direct)[:, None], np.asarray(indirect)[:, None]]
    table = np.hstack(data)
    named = areas is not None and any(areas)
    lines = [",".join(cols + (["area"] if named else []))]
    for i, row in enumerate(table):
        line = ",".join(f"{v:.9g}" for v in row)
        lines.append(line + f",{areas[i]}" if named else line)
    atomic_write_text(path, "\n".join(lines) + "\n")


def read_results(path: str | os.PathLike, unit_scale: float = 1.0):
    """Read a results ``.csv`` (or a ``.pts`` file, which has no values).

    Returns ``(points [m], normals, columns, areas)``: ``columns`` maps each value column
    (``illuminance``, ``daylight_factor``, ...) to an (n,) array; ``areas`` is (n,) str.
    """
    path = Path(path)
    if path.suffix.lower() == ".txt":
        raise InputError(f"{path.name}: a .txt result has no positions; give the .csv of the run or its .pts")
    if path.suffix.lower() != ".csv":
        points, normals, areas = read_points(path, unit_scale, with_areas=True)
        return points, normals, {}, areas
    lines = [(n, l) for n, l in _lines(read_text_file(path, " results")) if l.strip()]
    if not lines:
        raise InputError(f"{path.name}: empty file")
    first, top = lines[0]
    header = [h.strip() for h in top.split(",")]
    missing = [c for c in ("x", "y", "z", "nx", "ny", "nz") if c not in header]
    if missing:
        raise InputError(f"{path.name}: line {first}: no column {missing[0]!r} (expected a results file of "
                         "lbl-illum)")
    if len(set(header)) != len(header):
        raise InputError(f"{path.name}: line {first}: a column name appears twice")
    numeric = [h for h in header if h != "area"]
    rows, areas = [], []
    for number, line in lines[1:]:
        fields = [f.strip() for f in line.split(",")]
        if len(fields) != len(header):
            raise InputError(f"{path.name}: line {number}: expected {len(header)} fields, got {len(fields)}")
        record = dict(zip(header, fields))
        values = [_number(record[h]) for h in numeric]
        if None in values:
            raise InputError(f"{path.name}: line {number}: column {numeric[values.index(None)]!r}: not a number")
        rows.append(values)
        areas.append(record.get("area", ""))
    if not rows:
        raise InputError(f"{path.name}: no points")
    data = np.array(rows, dtype=np.float64)
    if not np.isfinite(data).all():
        raise InputError(f"{path.name}: values must be finite")
    col = {h: data[:, i] for i, h in enumerate(numeric)}
    points = np.column_stack([col.pop(c) for c in ("x", "y", "z")]) * unit_scale
    normals = np.column_stack([col.pop(c) for c in ("nx", "ny", "nz")])
    if (np.abs(points) > MAX_COORDINATE).any():
        raise InputError(f"{path.name}: a coordinate is beyond ±{MAX_COORDINATE:g} m")
    return points, normals, col, np.array(areas, dtype=object)

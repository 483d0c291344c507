"""Sensor points in and illuminance results out.

Points use the Radiance/Honeybee ``.pts`` layout: one point per line,
``x y z nx ny nz`` separated by white space, in the scene file's units; blank lines
and ``#`` comments are allowed.

Results are written to a temporary file in the output's folder and renamed into
place, so a failed run never leaves a partial output file:

* ``.csv``: a header row, then ``x,y,z,nx,ny,nz,illuminance,direct,indirect`` per point
  (illuminance [lux], photometric) in input order;
* ``.txt``: one illuminance value [lux] per line (the Radiance/Honeybee habit).
"""

from __future__ import annotations

import math
import os
from pathlib import Path

import numpy as np

from .errors import InputError
from .files import atomic_write_text

__all__ = ["read_points", "write_results", "check_output_path", "RESULT_FORMATS"]

RESULT_FORMATS = (".csv", ".txt")


def read_points(path: str | os.PathLike, unit_scale: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """Read a ``.pts`` file: ((n, 3) points [m], (n, 3) unit normals).

    Coordinates are multiplied by ``unit_scale`` (metres per scene unit).
    """
    path = Path(path)
    name = path.name
    try:
        text = path.read_text()
    except FileNotFoundError:
        raise InputError(f"{name}: no such file") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError(f"{name}: cannot read ({exc.__class__.__name__})") from None
    rows = []
    for number, line in enumerate(text.splitlines(), start=1):
        body = line.split("#", 1)[0].strip()
        if not body:
            continue
        fields = body.split()
        if len(fields) != 6:
            raise InputError(f"{name}: line {number}: expected 6 numbers 'x y z nx ny nz', got {len(fields)}")
        try:
            values = [float(f) for f in fields]
        except ValueError:
            raise InputError(f"{name}: line {number}: not a number in {body!r}") from None
        if not all(math.isfinite(v) for v in values):
            raise InputError(f"{name}: line {number}: values must be finite")
        if math.sqrt(sum(v * v for v in values[3:])) <= 1e-12:
            raise InputError(f"{name}: line {number}: zero-length normal")
        rows.append(values)
    if not rows:
        raise InputError(f"{name}: no points")
    data = np.array(rows, dtype=np.float64)
    normals = data[:, 3:] / np.linalg.norm(data[:, 3:], axis=1, keepdims=True)
    return data[:, :3] * unit_scale, normals


def check_output_path(path: str | os.PathLike, formats=RESULT_FORMATS) -> Path:
    """Refuse an output whose extension is unknown or whose folder does not exist."""
    path = Path(path)
    if path.suffix.lower() not in formats:
        raise InputError(f"{path.name}: output must end in {' or '.join(formats)}")
    if path.parent and not path.parent.exists():
        raise InputError(f"{path}: folder {path.parent} does not exist")
    return path


def write_results(path: str | os.PathLike, points: np.ndarray, normals: np.ndarray, illuminance: np.ndarray,
                  direct: np.ndarray | None = None, indirect: np.ndarray | None = None) -> None:
    """Write results in the format given by the extension (``points`` in the file's units)."""
    path = check_output_path(path)
    if path.suffix.lower() == ".txt":
        atomic_write_text(path, "".join(f"{e:.6g}\n" for e in illuminance))
        return
    cols = ["x", "y", "z", "nx", "ny", "nz", "illuminance"]
    data = [points, normals, np.asarray(illuminance)[:, None]]
    if direct is not None and indirect is not None:
        cols += ["direct", "indirect"]
        data += [np.asarray(direct)[:, None], np.asarray(indirect)[:, None]]
    table = np.hstack(data)
    lines = [",".join(cols)]
    lines += [",".join(f"{v:.9g}" for v in row) for row in table]
    atomic_write_text(path, "\n".join(lines) + "\n")

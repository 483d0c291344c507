"""Honeybee models (``.hbjson``, the honeybee-schema of Ladybug Tools) as geometry,
materials, sensor grids and views.

The Ladybug Tools packages read the model and write its Radiance description
(``honeybee-radiance``'s ``model_to_rad``: rooms' faces, apertures, doors, shades and
orphaned objects with their modifiers, modifier sets resolved); that text is read as any
Radiance file (:mod:`lbl_illum.scene.radfile`), so a Honeybee model's materials become
ours by the same rules.  ``honeybee-radiance`` is the optional extra ``honeybee``
(``pip install lbl_illum[honeybee]``); without it a model is refused in one line.

* **Units**: the model is converted to the scene file's units before it is written, so
  the scene's ``units`` key scales it like any other geometry.
* **Air boundaries** (Honeybee's ``trans`` modifier of colour 1 and transmission 1, fully
  specular: light passes unchanged) are left out, counted in a warning: to rays they are
  not there.
* **Sensor grids** (:func:`read_grids`): each grid's sensors, its identifier as the area
  name of its points, and its ``grids_info.json`` entry, in metres whatever the model's
  units.
* **Views**: the model's views become the scene's named views (``[views.NAME]`` of the
  scene file win over them).
"""

from __future__ import annotations

import functools
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import InputError

__all__ = ["HoneybeeModel", "read_honeybee", "read_grids", "HONEYBEE_SUFFIXES", "UNITS"]

#: Suffixes of Honeybee model files.
HONEYBEE_SUFFIXES = (".hbjson",)
#: The scene file's units by Honeybee's names.
UNITS = {"m": "Meters", "mm": "Millimeters", "cm": "Centimeters", "ft": "Feet", "in": "Inches", "km": "Kilometers"}


@dataclass(frozen=True)
class HoneybeeModel:
    """What a Honeybee model gives a scene: ``primitives`` (Radiance modifiers and surfaces,
    :class:`~lbl_illum.scene.radfile.RadPrimitive`), ``views`` (name → View, metres) and
    ``warnings``."""

    primitives: list
    views: dict
    warnings: list


def _model(path: Path, where: str):
    """The honeybee ``Model`` of ``path``; one line when it cannot be read."""
    from ..optional import require

    require("honeybee_radiance", "Honeybee models (.hbjson)")
    from honeybee.model import Model

    if not path.is_file():
        raise InputError(f"{where}: no such file ({path})")
    try:
        return Model.from_hbjson(str(path))
    except Exception as exc:          # honeybee raises anything from KeyError to ValueError on a bad model
        text = str(exc).strip().splitlines()
        raise InputError(f"{where}: not a Honeybee model that honeybee-core reads ({type(exc).__name__}: "
                         f"{text[0][:120] if text else 'no message'})") from None


def _stamp(path: Path):
    stat = os.stat(path)
    return (str(path.resolve()), stat.st_mtime_ns, stat.st_size)


def read_honeybee(path: str | Path, where: str, units: str = "m") -> HoneybeeModel:
    """The model at ``path`` in the scene's ``units`` (module text)."""
    path = Path(path)
    if not path.is_file():
        raise InputError(f"{where}: no such file ({path})")
    return _read(_stamp(path), where, units)


@functools.lru_cache(maxsize=4)
def _read(stamp, where: str, units: str) -> HoneybeeModel:
    from honeybee_radiance.writer import model_to_rad

    from .radfile import _parse_words
    from .views import view_from_string

    model = _model(Path(stamp[0]), where)
    if units not in UNITS:
        raise InputError(f"{where}: the scene's units '{units}' have no Honeybee name")
    model = model.duplicate()
    model.convert_to_units(UNITS[units])
    geometry, modifiers = model_to_rad(model)
    prims = []
    for label, text in (("modifiers", modifiers), ("geometry", geometry)):
        words, lines = [], []
        for number, line in enumerate(text.splitlines(), 1):
            parts = line.split("#", 1)[0].split()
            words += parts
            lines += [number] * len(parts)
        prims += _parse_words(words, lines, f"{where} ({label} as Radiance text)")
    air = {p.name for p in prims if p.kind == "trans" and len(p.reals) == 7
           and np.allclose(p.reals, [1, 1, 1, 0, 0, 1, 1])}
    kept = [p for p in prims if p.modifier not in air]
    warnings = []
    if len(kept) < len(prims):
        warnings.append(f"{where}: {len(prims) - len(kept)} air boundaries left out (light passes them unchanged)")
    views = {}
    for view in model.properties.radiance.views:
        views[view.identifier] = view_from_string(_view_in_metres(view, units), f"{where}: view {view.identifier}")
    return HoneybeeModel(primitives=kept, views=views, warnings=warnings)


def _view_in_metres(view, units: str) -> str:
    """A honeybee view's Radiance options with its position in metres."""
    from .units import metres_per_unit

    scale = metres_per_unit(units, "units")
    x, y, z = (scale * c for c in view.position)
    options = view.to_radiance().split()
    i = options.index("-vp")
    options[i + 1:i + 4] = [repr(x), repr(y), repr(z)]
    return " ".join(options)


@dataclass(frozen=True)
class SensorGrid:
    """One sensor grid: ``identifier``, (n, 3) ``points`` [m] and unit ``normals``, and its
    ``info`` (the grids_info.json entry Honeybee writes)."""

    identifier: str
    points: np.ndarray
    normals: np.ndarray
    info: dict


def read_grids(path: str | Path, where: str | None = None) -> list[SensorGrid]:
    """The sensor grids of the Honeybee model at ``path``, in metres (module text)."""
    path = Path(path)
    where = where or path.name
    if not path.is_file():
        raise InputError(f"{where}: no such file ({path})")
    return _grids(_stamp(path), where)


@functools.lru_cache(maxsize=4)
def _grids(stamp, where: str) -> list[SensorGrid]:
    model = _model(Path(stamp[0]), where)
    model = model.duplicate()
    model.convert_to_units("Meters")
    grids = []
    for grid in model.properties.radiance.sensor_grids:
        pos = np.array([s.pos for s in grid.sensors], np.float64).reshape(-1, 3)
        dirs = np.array([s.dir for s in grid.sensors], np.float64).reshape(-1, 3)
        length = np.linalg.norm(dirs, axis=1)
        if len(dirs) and not (length > 0).all():
            raise InputError(f"{where}: sensor grid '{grid.identifier}': a sensor has no direction")
        info = grid.info_dict(model) if hasattr(grid, "info_dict") else {
            "count": len(pos), "name": grid.identifier, "identifier": grid.identifier, "group": "",
            "full_id": grid.identifier, "light_path": [["__static_apertures__"]]}
        grids.append(SensorGrid(grid.identifier, pos, dirs / length[:, None], info))
    if not grids:
        raise InputError(f"{where}: the model has no sensor grid")
    return grids

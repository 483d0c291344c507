"""Results in the folders Ladybug Tools reads (Honeybee's grid-based recipes).

* Point in time (:func:`write_res_folder`): ``FOLDER/{grid}.res``, one value a line for the
  grid's sensors in order, and ``FOLDER/grids_info.json``, the grids' entries as Honeybee
  writes them (``count``, ``name``, ``identifier``, ``group``, ``full_id``,
  ``light_path``) — what Ladybug's "Read results" components and
  ``honeybee-radiance-postprocess`` load.
* Annual (:func:`write_annual_folder`): the layout of Honeybee's annual-daylight recipe,
  ``FOLDER/__static_apertures__/default/total/{grid}.npy`` (float32, sensors × sun-up
  hours, lux) and ``.../direct/{grid}.npy`` (the direct sun), with ``grids_info.json``,
  ``sun-up-hours.txt`` (the hours of the year of the sun-up rows, row r as r + 0.5),
  ``study_info.json`` (timestep 1, the 8760 study hours) and ``grid_states.json``
  (static apertures only): what ``honeybee-radiance-postprocess``'s ``Results`` reads.
  With ``ill``, also ``FOLDER/{grid}.ill``: the same total illuminance as text, a row per
  sensor and a tab-separated column per sun-up hour, the layout of the earlier recipes
  that ``honeybee_radiance.postprocess.annualdaylight.metrics_from_folder`` reads.

Every file is written whole (a temporary name, then a rename).
"""

from __future__ import annotations

import io
import json
from pathlib import Path

import numpy as np

from .files import atomic_write_npy, atomic_write_text

__all__ = ["write_res_folder", "write_annual_folder"]


def _split(grids, values):
    """The rows of each grid in ``values`` (the grids' sensors concatenated in order)."""
    start = 0
    for grid in grids:
        n = len(grid.points)
        yield grid, values[start:start + n]
        start += n


def _info(grids) -> str:
    return json.dumps([{**g.info, "count": len(g.points)} for g in grids], indent=2) + "\n"


def write_res_folder(folder: str | Path, grids, values) -> None:
    """``{grid}.res`` and ``grids_info.json`` of point-in-time ``values`` (n,) (module text)."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    for grid, part in _split(grids, np.asarray(values, np.float64)):
        atomic_write_text(folder / f"{grid.identifier}.res", "".join(f"{v:.6g}\n" for v in part))
    atomic_write_text(folder / "grids_info.json", _info(grids))


def _ill_text(values: np.ndarray) -> str:
    """Rows of tab-separated values [lux], each to 2 decimals (0.01 lux; Radiance's
    ``rmtxop -fa`` habit), as numpy formats them in one call."""
    buffer = io.StringIO()
    np.savetxt(buffer, values, fmt="%.2f", delimiter="\t")
    return buffer.getvalue()


def write_annual_folder(folder: str | Path, grids, illuminance, direct_sun, sun_up, ill: bool = False) -> None:
    """The annual layout of Honeybee's recipes (module text): ``illuminance`` and
    ``direct_sun`` (n, 8760) [lux], ``sun_up`` (8760,) bool, the rows written; ``ill``:
    the ``.ill`` text files too."""
    folder = Path(folder)
    rows = np.flatnonzero(sun_up)
    for kind, data in (("total", illuminance), ("direct", direct_sun)):
        target = folder / "__static_apertures__" / "default" / kind
        target.mkdir(parents=True, exist_ok=True)
        for grid, part in _split(grids, data):
            atomic_write_npy(target / f"{grid.identifier}.npy", part[:, rows])
    if ill:
        for grid, part in _split(grids, illuminance):
            atomic_write_text(folder / f"{grid.info['full_id']}.ill", _ill_text(np.asarray(part[:, rows], np.float32)))
    atomic_write_text(folder / "grids_info.json", _info(grids))
    atomic_write_text(folder / "sun-up-hours.txt", "".join(f"{r + 0.5:g}\n" for r in rows))
    atomic_write_text(folder / "study_info.json", json.dumps(
        {"timestep": 1, "study_hours": [h + 0.5 for h in range(len(sun_up))]}) + "\n")
    atomic_write_text(folder / "grid_states.json", json.dumps({g.identifier: {} for g in grids}, indent=2) + "\n")

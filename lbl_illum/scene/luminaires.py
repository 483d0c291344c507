"""Luminaires placed in a scene: ``[[luminaires]]`` entries of the scene file.

::

    [[luminaires]]
    file = "downlight.ies"        # IES LM-63 or EULUMDAT .ldt (lbl_illum.scene.photometric)
    position = [2.0, 3.0, 2.8]    # photometric centre, in the scene's units
    aim = [0, 0, -1]              # direction of the photometric nadir (default straight down)
    rotation = 0                  # degrees about the aim; 0 puts the C0 plane along +x
    multiplier = 1.0              # light loss factor or dimming
    name = "D1"                   # optional, for messages

**Orientation.**  The luminaire's frame (x along C0, y along C90, z up, nadir −z;
:mod:`~lbl_illum.scene.photometric`) is turned by the shortest rotation that takes −z to
``aim`` (for ``aim`` straight up: half a turn about x), then by ``rotation`` degrees about
the aim, counter-clockwise seen from behind the luminaire (from above for a downlight).
A downlight at rotation 0 thus has C0 along +x and C90 along +y, as Radiance's
``ies2rad`` places it; rotation 90 puts C0 along +y.

**Luminous opening.**  The file's opening (:class:`~lbl_illum.scene.photometric.LuminousOpening`)
is centred on ``position`` in the luminaire's frame, its length along C0 and its width
along C90; it lights the receivers near it as cells and shows the luminance I/A_p to
camera rays and specular paths (:mod:`lbl_illum.engine.luminous_openings`).

Units: position [m] (after the scene's units), intensity [cd].
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Mapping

import numpy as np

from ..errors import InputError, check_keys, get_number, get_vector, show
from .photometric import Photometry, read_photometry

__all__ = ["Luminaire", "luminaire_frame", "luminaires_from_table", "LUMINAIRE_KEYS"]

#: Keys of a ``[[luminaires]]`` entry.
LUMINAIRE_KEYS = ("file", "position", "aim", "rotation", "multiplier", "name")


@dataclass(frozen=True)
class Luminaire:
    """One luminaire: its photometry, photometric centre ``position`` [m], ``frame``
    (3, 3) whose rows are its x (C0), y (C90) and z (up) axes in scene coordinates, and
    ``multiplier`` (light loss factor, dimming)."""

    photometry: Photometry
    position: np.ndarray
    frame: np.ndarray
    multiplier: float = 1.0
    name: str = ""

    def intensity(self, directions: np.ndarray) -> np.ndarray:
        """(n,) intensity [cd] along unit emission ``directions`` (n, 3) in scene
        coordinates, the multiplier applied."""
        local = np.asarray(directions, np.float64) @ self.frame.T
        return self.multiplier * self.photometry.intensity(local)

    @property
    def aim(self) -> np.ndarray:
        """Unit direction of the photometric nadir in scene coordinates."""
        return -self.frame[2]


def luminaire_frame(aim, rotation_deg: float) -> np.ndarray:
    """(3, 3) rows x (C0), y (C90), z (up) of a luminaire aimed along ``aim`` and turned by
    ``rotation_deg`` about it (module text)."""
    b = np.asarray(aim, np.float64)
    b = b / np.linalg.norm(b)
    a = np.array([0.0, 0.0, -1.0])
    c = float(a @ b)
    if c < -1.0 + 1e-12:                       # straight up: half a turn about x
        R = np.diag([1.0, -1.0, -1.0])
    else:
        v = np.cross(a, b)
        V = np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])
        R = np.eye(3) + V + V @ V / (1.0 + c)    # Rodrigues' formula for the rotation a → b
    x0, y0, z = R[:, 0], R[:, 1], R[:, 2]
    r = math.radians(rotation_deg)
    x = math.cos(r) * x0 + math.sin(r) * y0
    y = np.cross(z, x)
    return np.array([x, y, z])


def luminaires_from_table(entries: Any, where: str, base_dir: str | Path, scale: float) -> list[Luminaire]:
    """The ``[[luminaires]]`` entries of a parsed scene file (module text); files are found
    relative to ``base_dir``, each read once however many luminaires share it."""
    if entries is None:
        return []
    if not isinstance(entries, (list, tuple)):
        raise InputError(f"{where}: 'luminaires' must be an array of tables ([[luminaires]]), got {show(entries)}")
    read: dict[Path, Photometry] = {}
    out = []
    for i, entry in enumerate(entries):
        label = f"{where}: luminaires[{i}]"
        if not isinstance(entry, Mapping):
            raise InputError(f"{label}: must be a table with 'file' and 'position', got {show(entry)}")
        check_keys(entry, LUMINAIRE_KEYS, label, required=("file", "position"))
        name = entry.get("name", f"luminaires[{i}]")
        if not isinstance(name, str):
            raise InputError(f"{label}: 'name' must be a string, got {show(name)}")
        if not isinstance(entry["file"], str) or not entry["file"]:
            raise InputError(f"{label}: 'file' must be the name of an .ies or .ldt file, got {show(entry['file'])}")
        path = (Path(base_dir) / entry["file"]).resolve()
        if path not in read:
            read[path] = read_photometry(path)
        position = np.asarray(get_vector(entry, "position", label), np.float64) * scale
        aim = np.asarray(get_vector(entry, "aim", label) if "aim" in entry else (0.0, 0.0, -1.0), np.float64)
        if not np.linalg.norm(aim) > 0.0:
            raise InputError(f"{label}: 'aim' must be a non-zero direction, got {show(entry['aim'])}")
        rotation = get_number(entry, "rotation", label, default=0.0)
        multiplier = get_number(entry, "multiplier", label, default=1.0, minimum=0.0, min_inclusive=False)
        out.append(Luminaire(read[path], position, luminaire_frame(aim, rotation), multiplier, name))
    return out

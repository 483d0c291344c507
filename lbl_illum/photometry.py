"""Photometric value of linear RGB light (docs/design.md §2).

Light is carried as linear RGB whose channels are photometric: a grey triple
``(L, L, L)`` has luminance ``L`` cd/m² and an irradiance triple ``(E, E, E)``
has illuminance ``E`` lux.  The photometric value of any triple is its Rec. 709
luminance ``Y = w_r R + w_g G + w_b B`` where ``(w_r, w_g, w_b)`` is the
middle row of the ITU-R BT.709 RGB→XYZ matrix, taken from colour-science.

Importing colour-science costs seconds, so the three weights are read from it
once per installed colour-science version and remembered in the user's cache
directory (:func:`user_cache_dir`).
"""

from __future__ import annotations

import json
import os
from functools import lru_cache
from importlib import metadata
from pathlib import Path

import numpy as np

__all__ = ["luminance_weights", "luminance", "user_cache_dir", "RADIANCE_WHITE_EFFICACY", "RADIANCE_SKY_EFFICACY",
           "RADIANCE_SUN_EFFICACY"]

#: Radiance's luminous efficacy of its RGB radiance [lm/W]: luminance [cd/m²] = 179 ×
#: radiance (``WHTEFFICACY`` of Radiance's color.h).
RADIANCE_WHITE_EFFICACY = 179.0
#: The efficacies gensky divides its sky's and sun's luminance by to write radiance
#: (``SKYEFFICACY`` = D65, 203 lm/W; ``SUNEFFICACY``, 208 lm/W): read back at 179, the
#: sky Radiance renders is 179/203 of gensky's formula and the sun 179/208.
RADIANCE_SKY_EFFICACY = 203.0
RADIANCE_SUN_EFFICACY = 208.0


def user_cache_dir() -> Path | None:
    """The folder of what lbl_illum keeps between runs (these weights, parsed geometry
    files: :mod:`lbl_illum.scene.geometry_cache`): ``$LBL_ILLUM_CACHE_DIR``, else
    ``$XDG_CACHE_HOME/lbl_illum``, else ``~/.cache/lbl_illum``; None when
    ``LBL_ILLUM_CACHE_DIR=off`` (nothing kept)."""
    root = os.environ.get("LBL_ILLUM_CACHE_DIR")
    if root is not None and root.strip().lower() in ("off", "0", "no", "false"):
        return None
    return Path(root or os.path.join(
        os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache"), "lbl_illum"))


def _cache_file() -> Path:
    root = user_cache_dir()
    if root is None:
        raise OSError("the cache is off")
    version = metadata.version("colour-science")
    return root / f"bt709-luminance-weights-colour-{version}.json"


def _weights_from_colour() -> np.ndarray:
    import colour  # deferred: a slow import

    return np.asarray(colour.RGB_COLOURSPACES["ITU-R BT.709"].matrix_RGB_to_XYZ[1], dtype=np.float64)


@lru_cache(maxsize=1)
def luminance_weights() -> np.ndarray:
    """(3,) float: Rec. 709 luminance weights of linear RGB, from colour-science."""
    try:
        path = _cache_file()
        weights = np.asarray(json.loads(path.read_text())["weights"], dtype=np.float64)
        if weights.shape == (3,) and np.all(np.isfinite(weights)):
            return weights
    except (OSError, ValueError, KeyError, metadata.PackageNotFoundError):
        pass
    weights = _weights_from_colour()
    try:
        path = _cache_file()
        path.parent.mkdir(parents=True, exist_ok=True)
        tmp = path.with_suffix(f".{os.getpid()}.tmp")
        tmp.write_text(json.dumps({"weights": weights.tolist()}))
        os.replace(tmp, path)
    except OSError:
        pass  # a read-only home only costs the slow import next time
    return weights


def luminance(rgb: np.ndarray) -> np.ndarray:
    """Photometric value of ``(..., 3)`` linear RGB: ``(...)`` [cd/m² or lux]."""
    return np.asarray(rgb, dtype=np.float64) @ luminance_weights()

"""Photometric value of linear RGB light (docs/design.md §2).

Light is carried as linear RGB whose channels are photometric: a grey triple
``(L, L, L)`` has luminance ``L`` cd/m² and an irradiance triple ``(E, E, E)``
has illuminance ``E`` lux.  The photometric value of any triple is its Rec. 709
luminance ``Y = w_r R + w_g G + w_b B`` where ``(w_r, w_g, w_b)`` is the
middle row of the ITU-R BT.709 RGB→XYZ matrix: the normalised primary matrix of
SMPTE RP 177-1993 for the BT.709 primaries and the D65 white point, derived here as
colour-science derives it (``colour.normalised_primary_matrix``), which the tests
check bit for bit.  Importing colour-science for three numbers took 0.8 s of a run
whose cache folder was empty (every first run).
"""

from __future__ import annotations

import os
from functools import lru_cache
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
#: ITU-R BT.709 chromaticities (x, y) of the red, green and blue primaries, and of the
#: D65 white point.
BT709_PRIMARIES = ((0.64, 0.33), (0.30, 0.60), (0.15, 0.06))
BT709_WHITE = (0.3127, 0.3290)


def user_cache_dir() -> Path | None:
    """The folder of what lbl_illum keeps between runs (parsed geometry files:
    :mod:`lbl_illum.scene.geometry_cache`): ``$LBL_ILLUM_CACHE_DIR``, else
    ``$XDG_CACHE_HOME/lbl_illum``, else ``~/.cache/lbl_illum``; None when
    ``LBL_ILLUM_CACHE_DIR=off`` (nothing kept)."""
    root = os.environ.get("LBL_ILLUM_CACHE_DIR")
    if root is not None and root.strip().lower() in ("off", "0", "no", "false"):
        return None
    return Path(root or os.path.join(
        os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache"), "lbl_illum"))


@lru_cache(maxsize=1)
def luminance_weights() -> np.ndarray:
    """(3,) float: Rec. 709 luminance weights of linear RGB, the Y row of the normalised
    primary matrix M = P diag(P⁻¹ W) (SMPTE RP 177-1993): P's columns the primaries'
    (x, y, 1 − x − y), W the white point's XYZ with Y = 1 — the operations of
    colour-science's ``normalised_primary_matrix``, in its order."""
    xy = np.asarray(BT709_PRIMARIES, np.float64)
    primaries = np.transpose(np.hstack([xy, (1.0 - xy[:, 0] - xy[:, 1])[:, None]]))
    x, y = BT709_WHITE
    white = np.array([x / y, 1.0, (1.0 - x - y) / y])
    coefficients = np.diagflat(np.dot(np.linalg.inv(primaries), white))
    return np.dot(primaries, coefficients)[1].copy()


def luminance(rgb: np.ndarray) -> np.ndarray:
    """Photometric value of ``(..., 3)`` linear RGB: ``(...)`` [cd/m² or lux]."""
    return np.asarray(rgb, dtype=np.float64) @ luminance_weights()

"""False-colour luminance pictures with a legend in cd/m², as Radiance's ``falsecolor``.

A luminance image [cd/m²] is cut into ``steps`` bands between a lower value and a
``maximum`` — equal steps of luminance (``scale="linear"``, from 0) or equal ratios
(``scale="log"``, from ``maximum / 10**decades``) — and each band is painted in one
colour of a colour map, from dark blue (low) to red (high) with the default
``"turbo"`` map (Mikhailov, "Turbo, an improved rainbow colormap", Google AI blog,
2019).  Values above the maximum take the top colour and values below the lowest
edge the bottom one, as in Radiance's ``falsecolor`` (``-s``, ``-n``, ``-log``; Ward,
*Rendering with Radiance*, 1998, ch. 10).  ``steps = 0`` gives continuous colours.
Pixels marked invalid (outside a fisheye's circle) are black.

The picture is the image at its own pixels (enlarged by a whole factor when it is
shorter than the legend needs) with the legend to its right: one swatch per band,
labelled with the band edges in cd/m².  Without a ``maximum`` the scale ends at the
smallest of 1, 2, 2.5, 5 × 10ⁿ cd/m² at or above the 99th percentile of the image's
luminance; give one to compare several pictures on the same scale.
"""

from __future__ import annotations

import io
import math
import os
from pathlib import Path

import numpy as np

from ..errors import InputError
from ..io.files import atomic_write_bytes
from ..io.images import check_image_path
from ..photometry import luminance

__all__ = ["SCALES", "band_edges", "nice_maximum", "falsecolor_pixels", "write_falsecolor"]

#: Band spacings.
SCALES = ("linear", "log")
#: Width of the legend strip [px] and the least picture height that fits it [px].
LEGEND_WIDTH, MIN_HEIGHT = 170, 260


def nice_maximum(values: np.ndarray, percentile: float = 99.0) -> float:
    """Smallest of 1, 2, 2.5, 5 × 10ⁿ at or above the ``percentile`` of positive ``values``."""
    values = np.asarray(values, dtype=np.float64)
    values = values[np.isfinite(values) & (values > 0)]
    if values.size == 0:
        return 1.0
    top = float(np.percentile(values, percentile))
    exponent = math.floor(math.log10(top))
    for mantissa in (1.0, 2.0, 2.5, 5.0, 10.0):
        candidate = mantissa * 10.0 ** exponent
        if candidate >= top * (1 - 1e-12):
            return candidate
    return 10.0 ** (exponent + 1)  # pragma: no cover


def _check(scale: str, steps: int, maximum: float, decades: float) -> None:
    if scale not in SCALES:
        raise InputError(f"false colour: scale must be one of {', '.join(SCALES)}, got {scale!r}")
    if isinstance(steps, bool) or int(steps) != steps or not 0 <= steps <= 100:
        raise InputError(f"false colour: steps must be a whole number from 0 to 100, got {steps!r}")
    if not (math.isfinite(maximum) and maximum > 0):
        raise InputError(f"false colour: the maximum must be a positive number of cd/m², got {maximum!r}")
    if scale == "log" and not (math.isfinite(decades) and decades > 0):
        raise InputError(f"false colour: decades must be positive, got {decades!r}")


def band_edges(maximum: float, steps: int, scale: str = "linear", decades: float = 2.0) -> np.ndarray:
    """(steps + 1,) band edges [cd/m²]: from 0 (linear) or ``maximum/10**decades`` (log) to ``maximum``."""
    _check(scale, steps, maximum, decades)
    count = max(int(steps), 1)
    if scale == "linear":
        return np.linspace(0.0, maximum, count + 1)
    return np.logspace(math.log10(maximum) - decades, math.log10(maximum), count + 1)


def _position(lum: np.ndarray, maximum: float, scale: str, decades: float) -> np.ndarray:
    """Where each luminance lies on the scale, 0 (bottom) … 1 (maximum), clipped."""
    if scale == "linear":
        t = lum / maximum
    else:
        with np.errstate(divide="ignore"):
            t = (np.log10(np.maximum(lum, 0.0)) - (math.log10(maximum) - decades)) / decades
    return np.clip(np.nan_to_num(t, nan=0.0, neginf=0.0), 0.0, 1.0)


def _colours(cmap: str, positions: np.ndarray) -> np.ndarray:
    from matplotlib import colormaps

    try:
        colour_map = colormaps[cmap]
    except KeyError:
        raise InputError(f"false colour: unknown colour map {cmap!r}") from None
    return np.asarray(colour_map(positions))[..., :3]


def falsecolor_pixels(lum: np.ndarray, maximum: float, *, scale: str = "linear", steps: int = 8,
                      decades: float = 2.0, cmap: str = "turbo", valid: np.ndarray | None = None) -> np.ndarray:
    """(h, w, 3) uint8 false colours of a (h, w) luminance image [cd/m²].

    Band ``k`` (0-based, of ``steps``) holds luminances between edges ``k`` and ``k+1``
    of :func:`band_edges` and is painted ``cmap((k + ½) / steps)``; with ``steps = 0``
    each pixel is painted ``cmap(t)`` at its own position ``t`` on the scale.
    """
    lum = np.asarray(lum, dtype=np.float64)
    if lum.ndim != 2:
        raise ValueError(f"luminance must be a (height, width) array, got shape {lum.shape}")
    _check(scale, steps, maximum, decades)
    t = _position(lum, maximum, scale, decades)
    if steps:
        band = np.minimum(np.floor(t * steps), steps - 1)
        t = (band + 0.5) / steps
    rgb = np.round(_colours(cmap, t) * 255.0).astype(np.uint8)
    if valid is not None:
        rgb[~np.asarray(valid, dtype=bool).reshape(lum.shape)] = 0
    return rgb


def _legend_labels(edges: np.ndarray) -> list[str]:
    return [f"{v:.0f}" if v >= 1000 else f"{v:.3g}" for v in edges]


def write_falsecolor(path: str | os.PathLike, image: np.ndarray, *, maximum: float | None = None,
                     scale: str = "linear", steps: int = 8, decades: float = 2.0, cmap: str = "turbo",
                     valid: np.ndarray | None = None, title: str | None = None) -> Path:
    """Write a false-colour PNG of ``image`` with a legend in cd/m².

    Parameters
    ----------
    image : (h, w, 3) or (h, w) float
        Photometric RGB [cd/m²] (its luminance is shown) or luminance [cd/m²].
    maximum : float, optional
        Top of the scale [cd/m²]; default :func:`nice_maximum` of the image.
    scale, steps, decades, cmap, valid
        As :func:`falsecolor_pixels`.
    title : str, optional
        A line above the legend.

    The image occupies the top-left of the PNG at whole-pixel scale (factor
    ``ceil(260 / h)`` when ``h`` < 260 px, else 1); the legend fills a 170 px strip
    to its right.
    """
    path = check_image_path(path, (".png",))
    image = np.asarray(image, dtype=np.float64)
    lum = luminance(image) if image.ndim == 3 else image
    if valid is not None:
        valid = np.asarray(valid, dtype=bool).reshape(lum.shape)
    if maximum is None:
        maximum = nice_maximum(lum if valid is None else lum[valid])
    maximum = float(maximum)
    pixels = falsecolor_pixels(lum, maximum, scale=scale, steps=steps, decades=decades, cmap=cmap, valid=valid)

    import matplotlib
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.colorbar import ColorbarBase
    from matplotlib.colors import BoundaryNorm, ListedColormap, LogNorm, Normalize
    from matplotlib.figure import Figure

    h, w = lum.shape
    factor = max(1, math.ceil(MIN_HEIGHT / h))
    big = np.repeat(np.repeat(pixels, factor, axis=0), factor, axis=1)
    height, width = big.shape[0], big.shape[1] + LEGEND_WIDTH
    dpi = 100.0
    with matplotlib.rc_context({"font.size": 9}):
        figure = Figure(figsize=(width / dpi, height / dpi), dpi=dpi, facecolor="white")
        FigureCanvasAgg(figure)
        figure.figimage(big, xo=0, yo=0, origin="upper", resize=False)
        left = (big.shape[1] + 12) / width
        top_margin = (34 if title else 18) / height
        bar = figure.add_axes((left, 12 / height, 18 / width, 1 - top_margin - 12 / height))
        edges = band_edges(maximum, steps, scale, decades)
        if steps:
            colours = _colours(cmap, (np.arange(steps) + 0.5) / steps)
            ColorbarBase(bar, cmap=ListedColormap(colours), norm=BoundaryNorm(edges, steps),
                         boundaries=edges, spacing="uniform", ticks=edges, orientation="vertical")
            bar.set_yticklabels(_legend_labels(edges))
        else:
            norm = Normalize(0.0, maximum) if scale == "linear" else LogNorm(edges[0], maximum)
            from matplotlib import colormaps
            ColorbarBase(bar, cmap=colormaps[cmap], norm=norm, orientation="vertical")
        bar.set_ylabel("luminance [cd/m²]")
        if title:
            figure.text(left, 1 - 6 / height, title, ha="left", va="top")
        buffer = io.BytesIO()
        figure.savefig(buffer, format="png", dpi=dpi, facecolor="white")
    atomic_write_bytes(path, buffer.getvalue())
    return path

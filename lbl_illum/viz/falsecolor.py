"""False-colour luminance pictures with a legend in cd/m², as Radiance's ``falsecolor``.

A luminance image [cd/m²] is cut into bands between a lower value and a ``maximum`` —
steps of luminance (``scale="linear"``, from 0) or of ratio (``scale="log"``, from
``maximum / 10**decades``) — and each band is painted in one colour of a colour map,
from dark blue (low) to red (high) with the default ``"turbo"`` map (Mikhailov, "Turbo,
an improved rainbow colormap", Google AI blog, 2019).  Values above the maximum take the
top colour and values below the lowest edge the bottom one, as in Radiance's
``falsecolor`` (``-s``, ``-n``, ``-log``; Ward, *Rendering with Radiance*, 1998, ch. 10).
``steps = 0`` gives continuous colours.  Pixels marked invalid (outside a fisheye's
circle) are black.

**Round band edges.**  ``steps`` is the number of bands asked for; the edges drawn are
round numbers, so that every label reads plainly (:func:`band_edges`):

* linear: multiples of a step of 1, 2, 2.5 or 5 × 10ⁿ cd/m², the step whose band count
  is nearest to ``steps`` (the coarser on a tie) among those that divide the maximum into
  ``steps/2`` to ``2·steps`` equal bands — else among all steps: 0, 100, …, 1,000 for a
  maximum of 1,000 (10 bands; 125, 250, … were the equal eighths), 0, 25, …, 200 for 200;
* log: the numbers of a round series in every decade — 1; 1, 3; 1, 2, 5; 1, 1.5, 2.5,
  4, 6; 1, 1.2, 1.5, 2, 2.5, 3, 4, 5, 6, 8 (the last two ISO 3's rounded series R''5 and
  R''10) — the series whose bands per decade are nearest to ``steps / decades`` (the
  coarser on a tie): 2, 5, 10, 20, 50, 100, 200 for a maximum of 200 over 2 decades (the
  equal ratios were 2, 3.56, 6.32, 11.2, …).

The two ends are the scale's own (0 or ``maximum / 10**decades``, and ``maximum``);
a round number within half a step of an end is left out, so that no band is a sliver
when the maximum given is not itself round.

**Bands or contour lines.**  ``style="bands"`` paints every pixel its band's colour;
``style="contours"`` draws the band edges as lines over a grey picture of the image (its
luminance tone-mapped as the preview is, :func:`lbl_illum.io.images.preview_pixels`),
each line one pixel wide on the brighter side of its edge in the colour of the band
above it, as Radiance's ``falsecolor -cl``.

**The picture.**  A title band across the top (the title wrapped to the picture's width,
never cut), under it the image at its own pixels (enlarged by a whole factor when it is
shorter than the legend needs) and the legend to its right: one swatch per band,
labelled with the band edges in cd/m² (thousands separated, no trailing zeros).

**The default maximum** is the smallest of 1, 2, 2.5, 5 × 10ⁿ cd/m² at or above the 99th
percentile of the luminance of the pixels that show the room (:func:`default_maximum`):
pixels marked ``source`` — those that see the sky through a window, the sun, a lamp
(:attr:`lbl_illum.engine.render.RenderResult.source`) — are left out, so that the
interior spreads over the bands instead of falling into the lowest one.  The 99th
percentile keeps what the room shows (a sunlit patch on the floor, the brightest
walls) and lets the top 1 % (a few specular glints, a patch of a lamp's edge) take the
top colour.  When fewer than 1 % of the valid pixels show the room (a view of the sky),
the percentile is that of all valid pixels.  Give a ``maximum`` to compare several
pictures on one scale.
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
from ..optional import check as check_optional
from ..photometry import luminance

__all__ = ["SCALES", "STYLES", "band_edges", "default_maximum", "nice_maximum", "falsecolor_pixels",
           "falsecolor_figure", "write_falsecolor"]

#: Band spacings.
SCALES = ("linear", "log")
#: How the bands are drawn: filled, or as contour lines over a grey picture.
STYLES = ("bands", "contours")
#: Width of the legend strip [px] and the least picture height that fits it [px].
LEGEND_WIDTH, MIN_HEIGHT = 170, 260
#: Mantissas of round maxima and linear band steps.
ROUND_MANTISSAS = (1.0, 2.0, 2.5, 5.0)
#: Band edges within a decade of a log scale, coarse to fine (ISO 3's R''5 and R''10 last).
LOG_SERIES = ((1.0,), (1.0, 3.0), (1.0, 2.0, 5.0), (1.0, 1.5, 2.5, 4.0, 6.0),
              (1.0, 1.2, 1.5, 2.0, 2.5, 3.0, 4.0, 5.0, 6.0, 8.0))
#: Least share of the valid pixels showing the room for the default maximum to be theirs.
MIN_ROOM_SHARE = 0.01
#: Bands whose edges label a continuous scale (``steps = 0``).
CONTINUOUS_TICKS = 8
#: Font sizes [pt] of the title and the legend; margin around the title [px].
TITLE_SIZE, LEGEND_SIZE, TITLE_PAD = 10.0, 9.0, 8
#: Resolution of the figure [dots per inch]: one point is 100/72 px.
DPI = 100.0


def nice_maximum(values: np.ndarray, percentile: float = 99.0) -> float:
    """Smallest of 1, 2, 2.5, 5 × 10ⁿ at or above the ``percentile`` of positive ``values``."""
    values = np.asarray(values, dtype=np.float64)
    values = values[np.isfinite(values) & (values > 0)]
    if values.size == 0:
        return 1.0
    top = float(np.percentile(values, percentile))
    exponent = math.floor(math.log10(top))
    for mantissa in ROUND_MANTISSAS + (10.0,):
        candidate = mantissa * 10.0 ** exponent
        if candidate >= top * (1 - 1e-12):
            return candidate
    return 10.0 ** (exponent + 1)  # pragma: no cover


def default_maximum(lum: np.ndarray, valid: np.ndarray | None = None, source: np.ndarray | None = None,
                    percentile: float = 99.0) -> float:
    """Top of the false-colour scale [cd/m²] when none is given: :func:`nice_maximum` of the
    luminance ``lum`` [cd/m²] of the pixels that are ``valid`` and not ``source`` (the
    room's own surfaces), or of all valid pixels when fewer than :data:`MIN_ROOM_SHARE`
    of them show the room."""
    lum = np.asarray(lum, dtype=np.float64)
    valid = np.ones(lum.shape, bool) if valid is None else np.asarray(valid, dtype=bool).reshape(lum.shape)
    room = valid if source is None else valid & ~np.asarray(source, dtype=bool).reshape(lum.shape)
    shown = room if room.sum() >= max(1.0, MIN_ROOM_SHARE * valid.sum()) else valid
    return nice_maximum(lum[shown], percentile)


def _check(scale: str, steps: int, maximum: float, decades: float, style: str = "bands") -> None:
    if scale not in SCALES:
        raise InputError(f"false colour: scale must be one of {', '.join(SCALES)}, got {scale!r}")
    if style not in STYLES:
        raise InputError(f"false colour: style must be one of {', '.join(STYLES)}, got {style!r}")
    if isinstance(steps, bool) or int(steps) != steps or not 0 <= steps <= 100:
        raise InputError(f"false colour: steps must be a whole number from 0 to 100, got {steps!r}")
    if style == "contours" and steps == 0:
        raise InputError("false colour: contour lines need bands (steps from 1 to 100)")
    if not (math.isfinite(maximum) and maximum > 0):
        raise InputError(f"false colour: the maximum must be a positive number of cd/m², got {maximum!r}")
    if scale == "log" and not (math.isfinite(decades) and decades > 0):
        raise InputError(f"false colour: decades must be positive, got {decades!r}")


def _tidy(value: float) -> float:
    """``value`` without the float noise of a product (0.30000000000000004 → 0.3)."""
    return float(f"{value:.12g}")


def _linear_edges(maximum: float, count: int) -> np.ndarray:
    """Edges [cd/m²] from 0 to ``maximum`` at multiples of the round step for about ``count``
    bands (the module text gives the rule)."""
    best, best_key = None, None
    exponent = math.floor(math.log10(maximum / count))
    for step in (m * 10.0 ** e for e in range(exponent - 2, exponent + 2) for m in ROUND_MANTISSAS):
        inner = [_tidy(k * step) for k in range(1, math.ceil(maximum / step) + 1)]
        edges = [0.0] + [v for v in inner if v < maximum - step / 2] + [maximum]
        bands = len(edges) - 1
        whole = math.isclose(maximum / step, round(maximum / step)) and count / 2 <= bands <= 2 * count
        key = (not whole, abs(bands - count), -step)     # equal bands first; nearest count; the coarser
        if best_key is None or key < best_key:
            best, best_key = edges, key
    return np.array(best)


def _log_edges(maximum: float, count: int, decades: float) -> np.ndarray:
    """Edges [cd/m²] from ``maximum / 10**decades`` to ``maximum`` at the numbers of the round
    series for about ``count`` bands (the module text gives the rule)."""
    bottom = _tidy(maximum / 10.0 ** decades)
    per_decade = count / decades
    series = min(LOG_SERIES, key=lambda s: (abs(len(s) - per_decade), len(s)))
    half_step = 10.0 ** (0.5 / len(series))
    values = (_tidy(m * 10.0 ** e) for e in range(math.floor(math.log10(bottom)), math.ceil(math.log10(maximum)) + 1)
              for m in series)
    inner = sorted(v for v in values if bottom * half_step * (1 - 1e-9) <= v <= maximum / half_step * (1 + 1e-9))
    return np.array([bottom] + inner + [maximum])


def band_edges(maximum: float, steps: int, scale: str = "linear", decades: float = 2.0) -> np.ndarray:
    """Band edges [cd/m²], increasing: from 0 (linear) or ``maximum/10**decades`` (log) to
    ``maximum``, the inner ones round numbers (the module text gives the rule); about
    ``steps`` bands (one for ``steps`` 0 or 1 on a linear scale)."""
    _check(scale, steps, maximum, decades)
    count = max(int(steps), 1)
    maximum = float(maximum)
    return _linear_edges(maximum, count) if scale == "linear" else _log_edges(maximum, count, decades)


def _band_index(lum: np.ndarray, edges: np.ndarray) -> np.ndarray:
    """The band (0 … len(edges) − 2) each luminance falls in; below the lowest edge (and
    NaN) the first, above the maximum the last; a value on an edge in the band above it."""
    index = np.searchsorted(edges, np.nan_to_num(lum, nan=0.0), side="right") - 1
    return np.clip(index, 0, len(edges) - 2)


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


def _band_colours(cmap: str, count: int) -> np.ndarray:
    """(count, 3) colours of the bands in [0, 1]: band ``k`` is ``cmap((k + ½) / count)``."""
    return _colours(cmap, (np.arange(count) + 0.5) / count)


def _grey(lum: np.ndarray) -> np.ndarray:
    """(h, w) uint8 grey picture of a luminance image [cd/m²], tone-mapped as the preview."""
    from ..io.images import preview_pixels

    grey = np.repeat(np.nan_to_num(np.maximum(lum, 0.0))[..., None], 3, axis=2)
    return preview_pixels(grey)[..., 1]


def _contour_lines(band: np.ndarray, valid: np.ndarray) -> np.ndarray:
    """(h, w) bool: the valid pixels in a higher band than a valid 4-neighbour (the bright
    side of every band edge, one pixel wide)."""
    line = np.zeros(band.shape, bool)
    for axis in (0, 1):
        head = (slice(None, -1), slice(None)) if axis == 0 else (slice(None), slice(None, -1))
        tail = (slice(1, None), slice(None)) if axis == 0 else (slice(None), slice(1, None))
        both = valid[head] & valid[tail]
        line[tail] |= both & (band[tail] > band[head])
        line[head] |= both & (band[head] > band[tail])
    return line


def falsecolor_pixels(lum: np.ndarray, maximum: float, *, scale: str = "linear", steps: int = 8,
                      decades: float = 2.0, cmap: str = "turbo", valid: np.ndarray | None = None,
                      style: str = "bands") -> np.ndarray:
    """(h, w, 3) uint8 false colours of a (h, w) luminance image [cd/m²].

    Band ``k`` (0-based, of the ``n`` bands of :func:`band_edges`) holds luminances
    between edges ``k`` and ``k+1`` and its colour is ``cmap((k + ½) / n)``.  ``style``
    ``"bands"`` paints each pixel its band's colour — with ``steps = 0`` its own position
    ``t`` on the scale, ``cmap(t)``; ``"contours"`` draws the band edges as one-pixel lines
    in the colour of the band above them over the grey tone-mapped image.  Invalid pixels
    are black.
    """
    lum = np.asarray(lum, dtype=np.float64)
    if lum.ndim != 2:
        raise ValueError(f"luminance must be a (height, width) array, got shape {lum.shape}")
    _check(scale, steps, maximum, decades, style)
    valid = np.ones(lum.shape, bool) if valid is None else np.asarray(valid, dtype=bool).reshape(lum.shape)
    if not steps:
        rgb = np.round(_colours(cmap, _position(lum, maximum, scale, decades)) * 255.0).astype(np.uint8)
    else:
        edges = band_edges(maximum, steps, scale, decades)
        band = _band_index(lum, edges)
        colours = np.round(_band_colours(cmap, len(edges) - 1) * 255.0).astype(np.uint8)
        if style == "bands":
            rgb = colours[band]
        else:
            rgb = np.repeat(_grey(np.where(valid, lum, 0.0))[..., None], 3, axis=2)
            line = _contour_lines(band, valid)
            rgb[line] = colours[band[line]]
    rgb[~valid] = 0
    return rgb


def _label(value: float) -> str:
    """A legend label [cd/m²]: three significant digits at most below 1,000, whole numbers
    with thousands separated above, no trailing zeros (2.5, 0.25, 100, 12,500)."""
    if value == 0:
        return "0"
    decimals = max(0, 2 - math.floor(math.log10(abs(value))))
    text = f"{value:,.{decimals}f}"
    return text.rstrip("0").rstrip(".") if "." in text else text


def _wrap(text: str, width: float, size: float) -> list[str]:
    """``text`` in lines no wider than ``width`` [px] at ``size`` [pt] (:data:`DPI`): broken
    between words, and inside a word only when it alone is wider."""
    from matplotlib.backends.backend_agg import RendererAgg
    from matplotlib.font_manager import FontProperties

    renderer, font = RendererAgg(1, 1, DPI), FontProperties(size=size)

    def fits(line: str) -> bool:
        return renderer.get_text_width_height_descent(line, font, ismath=False)[0] <= width

    lines = []
    for paragraph in text.splitlines() or [""]:
        line = ""
        for word in paragraph.split():
            if fits(f"{line} {word}" if line else word):
                line = f"{line} {word}" if line else word
                continue
            if line:
                lines.append(line)
            while not fits(word):
                cut = 1                                 # the longest head that fits, one letter at least
                while cut < len(word) - 1 and fits(word[:cut + 1]):
                    cut += 1
                lines.append(word[:cut])
                word = word[cut:]
            line = word
        lines.append(line)
    return lines


def _title_height(text: str) -> int:
    """Height [px] of ``text`` set at :data:`TITLE_SIZE` (its lines, ascent to descent)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    scratch = Figure(dpi=DPI)
    canvas = FigureCanvasAgg(scratch)
    box = scratch.text(0, 0, text, fontsize=TITLE_SIZE, parse_math=False).get_window_extent(canvas.get_renderer())
    return math.ceil(box.height)


def falsecolor_figure(image: np.ndarray, *, maximum: float | None = None, scale: str = "linear", steps: int = 8,
                      decades: float = 2.0, cmap: str = "turbo", style: str = "bands",
                      valid: np.ndarray | None = None, source: np.ndarray | None = None,
                      title: str | None = None):
    """The matplotlib figure :func:`write_falsecolor` saves (its arguments; sized in pixels
    at :data:`DPI`)."""
    image = np.asarray(image, dtype=np.float64)
    lum = luminance(image) if image.ndim == 3 else image
    if lum.ndim != 2:
        raise ValueError(f"the image must be (height, width) luminance or (height, width, 3) RGB, got {image.shape}")
    valid = np.ones(lum.shape, bool) if valid is None else np.asarray(valid, dtype=bool).reshape(lum.shape)
    maximum = float(default_maximum(lum, valid, source) if maximum is None else maximum)
    _check(scale, steps, maximum, decades, style)

    import matplotlib
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.colorbar import ColorbarBase
    from matplotlib.colors import BoundaryNorm, ListedColormap, LogNorm, Normalize
    from matplotlib.figure import Figure

    h, w = lum.shape
    factor = max(1, math.ceil(MIN_HEIGHT / h))

    def enlarge(a: np.ndarray) -> np.ndarray:
        return np.repeat(np.repeat(a, factor, axis=0), factor, axis=1)

    big = falsecolor_pixels(enlarge(lum), maximum, scale=scale, steps=steps, decades=decades, cmap=cmap,
                            valid=enlarge(valid), style=style)
    width = big.shape[1] + LEGEND_WIDTH
    heading = "\n".join(_wrap(title, width - 2 * TITLE_PAD, TITLE_SIZE)) if title else ""
    band = _title_height(heading) + 2 * TITLE_PAD if heading else 0
    height = big.shape[0] + band
    with matplotlib.rc_context({"font.size": LEGEND_SIZE}):
        figure = Figure(figsize=(width / DPI, height / DPI), dpi=DPI, facecolor="white")
        FigureCanvasAgg(figure)
        figure.figimage(big, xo=0, yo=0, origin="upper", resize=False)
        left, bar_height = (big.shape[1] + 12) / width, big.shape[0] - 30
        bar = figure.add_axes((left, 12 / height, 18 / width, bar_height / height))
        if steps:
            edges = band_edges(maximum, steps, scale, decades)
            count = len(edges) - 1
            ColorbarBase(bar, cmap=ListedColormap(_band_colours(cmap, count)), norm=BoundaryNorm(edges, count),
                         boundaries=edges, spacing="uniform", ticks=edges, orientation="vertical")
        else:
            edges = band_edges(maximum, CONTINUOUS_TICKS, scale, decades)
            from matplotlib import colormaps

            norm = Normalize(0.0, maximum) if scale == "linear" else LogNorm(edges[0], maximum)
            ColorbarBase(bar, cmap=colormaps[cmap], norm=norm, ticks=edges, orientation="vertical")
            bar.minorticks_off()
        # every edge labelled where they are 1.5 em apart or more, else every second, third, ...
        # (the maximum always, the one before it when that close)
        every, last = math.ceil(1.5 * LEGEND_SIZE * DPI / 72 / (bar_height / (len(edges) - 1))), len(edges) - 1
        bar.set_yticks(edges, [_label(v) if (k % every == 0 and last - k >= every) or k == last else ""
                               for k, v in enumerate(edges)])
        bar.set_ylabel("luminance [cd/m²]")
        if heading:
            figure.text(TITLE_PAD / width, 1 - TITLE_PAD / height, heading, ha="left", va="top",
                        fontsize=TITLE_SIZE, parse_math=False)
    return figure


def write_falsecolor(path: str | os.PathLike, image: np.ndarray, *, maximum: float | None = None,
                     scale: str = "linear", steps: int = 8, decades: float = 2.0, cmap: str = "turbo",
                     style: str = "bands", valid: np.ndarray | None = None, source: np.ndarray | None = None,
                     title: str | None = None) -> Path:
    """Write a false-colour PNG of ``image`` with a legend in cd/m².

    Parameters
    ----------
    image : (h, w, 3) or (h, w) float
        Photometric RGB [cd/m²] (its luminance is shown) or luminance [cd/m²].
    maximum : float, optional
        Top of the scale [cd/m²]; default :func:`default_maximum`: a round number at or
        above the 99th percentile of the luminance of the valid pixels that are not
        ``source`` (the room, not the window).
    scale, steps, decades, cmap, style, valid
        As :func:`falsecolor_pixels` (``steps``: the bands asked for; :func:`band_edges`
        makes their edges round).
    source : (h, w) bool, optional
        Pixels that see a light source directly (sky, sun, a lamp:
        :attr:`lbl_illum.engine.render.RenderResult.source`); only the default maximum
        uses them.
    title : str, optional
        A title across the top, wrapped to the picture's width.

    The image occupies the bottom left of the PNG at whole-pixel scale (factor
    ``ceil(260 / h)`` when ``h`` < 260 px, else 1), under the title's band; the legend
    fills a 170 px strip to its right.  Needs matplotlib (checked before any work); the
    file is written whole (a temporary file renamed).
    """
    path = check_image_path(path, (".png",))
    check_optional("matplotlib", f"false colour {path.name}")
    figure = falsecolor_figure(image, maximum=maximum, scale=scale, steps=steps, decades=decades, cmap=cmap,
                               style=style, valid=valid, source=source, title=title)
    buffer = io.BytesIO()
    figure.savefig(buffer, format="png", dpi=DPI, facecolor="white")
    atomic_write_bytes(path, buffer.getvalue())
    return path

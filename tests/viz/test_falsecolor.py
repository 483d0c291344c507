"""False-colour luminance pictures: round band edges and labels, the colour of each band,
clamping above the maximum and below the log scale, invalid pixels, the default maximum
from the room's pixels (not the window's), contour lines, titles that fit, and the PNG
layout (image pixels exact at the bottom left under the title, the legend to the right)."""

from __future__ import annotations

import math

import numpy as np
import pytest

pytest.importorskip("matplotlib")

from matplotlib import colormaps  # noqa: E402
from matplotlib.image import imread  # noqa: E402

from lbl_illum.errors import InputError  # noqa: E402
from lbl_illum.viz.falsecolor import (LEGEND_WIDTH, LOG_SERIES, MIN_HEIGHT, ROUND_MANTISSAS,  # noqa: E402
                                      band_edges, default_maximum, falsecolor_figure, falsecolor_pixels,
                                      nice_maximum, write_falsecolor)


def colour(position, cmap="turbo"):
    return np.round(np.asarray(colormaps[cmap](position))[:3] * 255).astype(np.uint8).tolist()


def test_band_edges():
    # round steps: the count nearest the steps asked for (10 of 100, not 8 of 125)
    assert np.array_equal(band_edges(1000, 8), np.arange(11) * 100.0)
    assert np.array_equal(band_edges(200, 8), np.arange(9) * 25.0)
    assert np.array_equal(band_edges(500, 10), np.arange(11) * 50.0)
    assert band_edges(0.25, 10).tolist() == [0, 0.025, 0.05, 0.075, 0.1, 0.125, 0.15, 0.175, 0.2, 0.225, 0.25]
    assert np.array_equal(band_edges(2.5, 12), np.arange(11) * 0.25)     # equal bands before the nearest count
    # a maximum that is not round keeps its own top edge; no sliver band below it
    assert np.array_equal(band_edges(730, 8), [0, 100, 200, 300, 400, 500, 600, 730])
    # log: 1-2-5 for 8 steps over 2 decades (not 2, 3.56, 6.32, ...), 1-3 for 2 a decade
    assert np.array_equal(band_edges(200, 8, "log"), [2, 5, 10, 20, 50, 100, 200])
    assert np.array_equal(band_edges(250, 8, "log"), [2.5, 5, 10, 20, 50, 100, 250])
    assert np.array_equal(band_edges(1000, 6, "log", decades=3), [1, 3, 10, 30, 100, 300, 1000])
    assert np.array_equal(band_edges(1000, 10, "log"), [10, 15, 25, 40, 60, 100, 150, 250, 400, 600, 1000])
    with pytest.raises(InputError, match="scale must be one of"):
        band_edges(1000, 8, "cubic")
    with pytest.raises(InputError, match="maximum"):
        band_edges(-1, 8)
    with pytest.raises(InputError, match="steps"):
        band_edges(10, 2.5)


def test_linear_bands():
    # centres of the 8 bands of 0..200 (steps of 25), one above the maximum, zero
    lum = np.array([[12.5, 37.5, 62.5, 87.5, 112.5, 137.5, 162.5, 187.5, 5000.0, 0.0]])
    pixels = falsecolor_pixels(lum, 200.0, steps=8)
    for k in range(8):
        assert pixels[0, k].tolist() == colour((k + 0.5) / 8)
    assert pixels[0, 8].tolist() == colour(7.5 / 8)        # above the maximum: top colour
    assert pixels[0, 9].tolist() == colour(0.5 / 8)        # zero: bottom colour
    edge = falsecolor_pixels(np.array([[99.9, 100.1]]), 1000.0, steps=8)    # 10 bands of 100
    assert edge[0, 0].tolist() == colour(0.5 / 10) and edge[0, 1].tolist() == colour(1.5 / 10)
    # unequal bands (a maximum that is not round): 600..730 is the top band
    top = falsecolor_pixels(np.array([[599.0, 601.0, 729.0]]), 730.0, steps=8)
    assert top[0].tolist() == [colour(5.5 / 7), colour(6.5 / 7), colour(6.5 / 7)]


def test_log_bands_and_mask():
    # 4 decades, 4 steps: one band per decade from 0.1 to 1000 cd/m²
    lum = np.array([[0.0, 0.05, 0.3, 3.0, 30.0, 300.0, 1e6]])
    valid = np.array([[True, True, True, True, True, True, False]])
    pixels = falsecolor_pixels(lum, 1000.0, scale="log", steps=4, decades=4, valid=valid)
    expected = [colour(0.125)] * 3 + [colour(0.375), colour(0.625), colour(0.875), [0, 0, 0]]
    assert pixels[0].tolist() == expected


def test_continuous_scale_is_monotone_in_the_map():
    lum = np.linspace(0, 1000, 11)[None, :]
    pixels = falsecolor_pixels(lum, 1000.0, steps=0, cmap="gray")
    assert np.all(np.diff(pixels[0, :, 0].astype(int)) > 0)
    assert pixels[0, 0].tolist() == [0, 0, 0] and pixels[0, -1].tolist() == [255, 255, 255]


def test_nice_maximum():
    assert nice_maximum(np.full(100, 730.0)) == 1000.0
    assert nice_maximum(np.full(100, 180.0)) == 200.0
    assert nice_maximum(np.full(100, 2.2)) == 2.5
    assert nice_maximum(np.full(100, 5000.0)) == 5000.0
    assert nice_maximum(np.zeros(10)) == 1.0
    assert nice_maximum(np.r_[np.full(999, 40.0), 1e6]) == 50.0    # the 99th percentile, not the sun


def test_png_layout(tmp_path):
    rng = np.random.default_rng(0)
    lum = rng.uniform(0, 900, (40, 60))
    rgb = np.repeat(lum[..., None], 3, axis=2)
    valid = np.ones_like(lum, dtype=bool)
    valid[0, 0] = False
    path = write_falsecolor(tmp_path / "fc.png", rgb, maximum=1000, steps=8, valid=valid, title="desk view")
    png = np.round(imread(path)[..., :3] * 255).astype(np.uint8)
    factor = math.ceil(MIN_HEIGHT / 40)
    band = png.shape[0] - 40 * factor                                      # the title's band on top
    assert 20 <= band <= 40 and png.shape == (band + 40 * factor, 60 * factor + LEGEND_WIDTH, 3)
    expected = falsecolor_pixels(lum, 1000.0, steps=8, valid=valid)
    big = np.repeat(np.repeat(expected, factor, axis=0), factor, axis=1)
    assert np.array_equal(png[band:, :60 * factor], big)                  # the image, pixel for pixel
    assert (png[:band].sum(axis=-1) < 200).sum() > 30                      # the title drawn above it
    legend = png[band:, 60 * factor:]
    assert (legend.sum(axis=-1) < 200).sum() > 50                          # label text drawn
    for k in range(10):                                                    # every swatch present
        assert (np.abs(legend.astype(int) - colour((k + 0.5) / 10)).sum(axis=-1) <= 3).sum() > 20
    assert sorted(p.name for p in tmp_path.iterdir()) == ["fc.png"]
    untitled = imread(write_falsecolor(tmp_path / "plain.png", rgb, maximum=1000))
    assert untitled.shape[0] == 40 * factor


def test_png_from_luminance_log_and_errors(tmp_path):
    lum = np.logspace(-1, 4, 300 * 20).reshape(300, 20)
    path = write_falsecolor(tmp_path / "log.png", lum, scale="log", decades=3, steps=0)
    png = imread(path)
    assert png.shape[:2] == (300, 20 + LEGEND_WIDTH)
    with pytest.raises(InputError, match="must end in .png"):
        write_falsecolor(tmp_path / "x.hdr", lum)
    with pytest.raises(InputError, match="unknown colour map"):
        write_falsecolor(tmp_path / "x.png", lum, cmap="nope")
    with pytest.raises(InputError, match="decades"):
        write_falsecolor(tmp_path / "x.png", lum, scale="log", decades=0)
    with pytest.raises(InputError, match="style must be one of bands, contours"):
        write_falsecolor(tmp_path / "x.png", lum, style="lines")
    with pytest.raises(InputError, match="contour lines need bands"):
        write_falsecolor(tmp_path / "x.png", lum, style="contours", steps=0)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["log.png"]


# -- the default maximum: the room, not the window -------------------------------------------

def test_default_maximum_ignores_a_bright_window():
    """5 % of the pixels see the sky at 10,000 cd/m² and are marked ``source``; the room's
    are 40-60 cd/m²: the scale ends at 100 (the round number above the room's 99th
    percentile), not at 10,000 (all pixels' 99th percentile)."""
    rng = np.random.default_rng(1)
    lum = rng.uniform(40.0, 60.0, (100, 100))
    source = np.zeros_like(lum, dtype=bool)
    source[10:15, :] = True                                                # 5 % of the pixels
    lum[source] = 10000.0
    assert np.percentile(lum[~source], 99) > 59
    assert default_maximum(lum, source=source) == 100.0
    assert default_maximum(lum) == 10000.0 == nice_maximum(lum)           # without the mask
    valid = np.ones_like(source)
    valid[50:, :] = False                                                  # invalid pixels do not count
    lum[60:, :] = 1e6
    assert default_maximum(lum, valid, source) == 100.0
    # (almost) nothing but sources: all valid pixels set the scale
    almost_all = np.ones_like(source)
    almost_all[0, :20] = False                                             # 0.4 % of the pixels
    assert default_maximum(lum[:50], source=almost_all[:50]) == 10000.0
    almost_all[0, :60] = False                                             # 1.2 %: the room's
    assert default_maximum(lum[:50], source=almost_all[:50]) == 100.0
    # the picture's legend ends at the room's maximum
    figure = falsecolor_figure(lum[:50], valid=valid[:50], source=source[:50])
    assert [t.get_text() for t in figure.axes[0].get_yticklabels()][-1] == "100"


# -- round labels ------------------------------------------------------------------------------

def _is_round_linear(values):
    """Every value a whole multiple of one step of 1, 2, 2.5 or 5 × 10ⁿ."""
    step = values[1] - values[0]
    mantissa = step / 10 ** math.floor(math.log10(step))
    return any(math.isclose(mantissa, m) for m in ROUND_MANTISSAS) and \
        all(math.isclose(v / step, round(v / step), abs_tol=1e-9) for v in values)


def _in_series(value):
    mantissa = value / 10 ** math.floor(math.log10(value) + 1e-12)
    return any(math.isclose(mantissa, m, rel_tol=1e-9) for series in LOG_SERIES for m in series + (10.0,))


@pytest.mark.parametrize("maximum", [0.5, 1, 2, 2.5, 5, 20, 25, 50, 100, 200, 250, 500, 1000, 2500, 20000])
@pytest.mark.parametrize("steps", [4, 6, 8, 10, 12])
def test_band_labels_are_round_numbers(maximum, steps):
    """The legend's labels (read back from the figure) are round numbers: linear ones whole
    multiples of a 1, 2, 2.5 or 5 × 10ⁿ step, log ones in a round series; written with
    thousands separated and no trailing zeros."""
    lum = np.linspace(0, maximum, 300 * 20).reshape(300, 20)
    for scale in ("linear", "log"):
        figure = falsecolor_figure(lum, maximum=maximum, steps=steps, scale=scale)
        labels = [t.get_text() for t in figure.axes[0].get_yticklabels()]
        shown = [label for label in labels if label]
        assert len(shown) >= 4, labels
        values = [float(label.replace(",", "")) for label in shown]
        for label, value in zip(shown, values):
            assert "." not in label or not label.endswith("0"), label        # no trailing zeros
            assert ("," in label) == (value >= 1000), label                 # thousands separated
        edges = band_edges(maximum, steps, scale)
        assert len(labels) == len(edges) and values[-1] == maximum
        if scale == "linear":
            assert _is_round_linear(values) and steps / 2 <= len(edges) - 1 <= 2 * steps, values
        else:
            assert all(_in_series(v) for v in values), values


# -- contour lines -----------------------------------------------------------------------------

def test_contour_lines_in_the_band_colours(tmp_path):
    """A ramp of 0 to 1,000 cd/m² from left to right (10 bands of 100): contour mode draws
    one vertical line at each band edge, on its bright side, in the colour of the band above
    it; everything else is grey.  Its PNG differs from the bands' and holds those colours."""
    lum = np.tile(np.linspace(0.0, 999.0, 200), (60, 1))
    valid = np.ones(lum.shape, bool)
    valid[:, :5] = False
    pixels = falsecolor_pixels(lum, 1000.0, steps=8, style="contours", valid=valid)
    grey = (pixels[..., 0] == pixels[..., 1]) & (pixels[..., 1] == pixels[..., 2])
    columns = [int(np.argmax(lum[0] >= 100.0 * k)) for k in range(1, 10)]
    for k, column in enumerate(columns, start=1):
        assert np.all(pixels[:, column] == colour((k + 0.5) / 10)), k
    others = np.setdiff1d(np.arange(5, 200), columns)
    assert grey[:, others].all()
    assert np.all(pixels[:, :5] == 0)                                      # invalid: black, no line
    assert len(np.unique(pixels[0, others, 0])) > 50                      # a grey picture, not one grey
    # the PNGs: the bands' and the contours' differ, the contours' has every band colour on lines
    bands = imread(write_falsecolor(tmp_path / "bands.png", lum, maximum=1000.0))[..., :3]
    lines = imread(write_falsecolor(tmp_path / "lines.png", lum, maximum=1000.0, style="contours"))[..., :3]
    assert bands.shape == lines.shape and not np.array_equal(bands, lines)
    image = np.round(lines[-300:, :1000] * 255).astype(int)                # 60 px tall: enlarged 5 times
    for k in range(1, 10):                                                 # a line of one pixel, 300 tall
        on_line = (np.abs(image - colour((k + 0.5) / 10)).sum(axis=-1) == 0).sum(axis=0)
        assert sorted(on_line[on_line > 0].tolist()) == [300], k


# -- titles that fit ---------------------------------------------------------------------------

@pytest.mark.parametrize("width", [20, 120, 400])
def test_long_titles_are_wrapped_inside_the_picture(width):
    """A client's title on a narrow, a small and a wide picture: every text of the figure
    (title, labels) lies inside it, and the title's lines hold all its words in order."""
    title = "Office, 21 June 12:00, CIE clear sky with sun; south-facing window, desk height view " \
            "averyveryverylongprojectnamewithoutanyspacesinit.toml"
    lum = np.random.default_rng(0).uniform(0, 300, (80, width))
    figure = falsecolor_figure(lum, title=title)
    renderer = figure.canvas.get_renderer()
    figure.draw(renderer)
    box = figure.bbox
    texts = [figure.texts[0]] + figure.axes[0].get_yticklabels() + [figure.axes[0].yaxis.label]
    for text in texts:
        extent = text.get_window_extent(renderer)
        assert box.x0 <= extent.x0 and extent.x1 <= box.x1 and box.y0 <= extent.y0 and extent.y1 <= box.y1, \
            (text.get_text(), extent, box)
    lines = figure.texts[0].get_text().split("\n")
    assert "".join(lines).replace(" ", "") == title.replace(" ", "")
    assert len(lines) >= (2 if width < 400 else 1)


"""False-colour luminance pictures: band edges, the colour of each band, clamping above the
maximum and below the log scale, invalid pixels, and the PNG layout (image pixels exact at
the top left, the legend to the right)."""

from __future__ import annotations

import math

import numpy as np
import pytest

pytest.importorskip("matplotlib")

from matplotlib import colormaps  # noqa: E402
from matplotlib.image import imread  # noqa: E402

from lbl_illum.errors import InputError  # noqa: E402
from lbl_illum.viz.falsecolor import (LEGEND_WIDTH, MIN_HEIGHT, band_edges, falsecolor_pixels,  # noqa: E402
                                  nice_maximum, write_falsecolor)


def colour(position, cmap="turbo"):
    return np.round(np.asarray(colormaps[cmap](position))[:3] * 255).astype(np.uint8).tolist()


def test_band_edges():
    assert np.allclose(band_edges(1000, 8), np.arange(9) * 125)
    assert np.allclose(band_edges(1000, 6, "log", decades=3), np.logspace(0, 3, 7))
    with pytest.raises(InputError, match="scale must be one of"):
        band_edges(1000, 8, "cubic")
    with pytest.raises(InputError, match="maximum"):
        band_edges(-1, 8)
    with pytest.raises(InputError, match="steps"):
        band_edges(10, 2.5)


def test_linear_bands():
    # centres of the 8 bands of 0..1000, one above the maximum, zero
    lum = np.array([[62.5, 187.5, 312.5, 437.5, 562.5, 687.5, 812.5, 937.5, 5000.0, 0.0]])
    pixels = falsecolor_pixels(lum, 1000.0, steps=8)
    for k in range(8):
        assert pixels[0, k].tolist() == colour((k + 0.5) / 8)
    assert pixels[0, 8].tolist() == colour(7.5 / 8)        # above the maximum: top colour
    assert pixels[0, 9].tolist() == colour(0.5 / 8)        # zero: bottom colour
    edge = falsecolor_pixels(np.array([[124.9, 125.1]]), 1000.0, steps=8)
    assert edge[0, 0].tolist() == colour(0.5 / 8) and edge[0, 1].tolist() == colour(1.5 / 8)


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
    assert png.shape == (40 * factor, 60 * factor + LEGEND_WIDTH, 3)
    expected = falsecolor_pixels(lum, 1000.0, steps=8, valid=valid)
    big = np.repeat(np.repeat(expected, factor, axis=0), factor, axis=1)
    assert np.array_equal(png[:, :60 * factor], big)                      # the image, pixel for pixel
    legend = png[:, 60 * factor:]
    assert (legend.sum(axis=-1) < 200).sum() > 50                          # label text drawn
    for k in range(8):                                                     # every swatch present
        assert (np.abs(legend.astype(int) - colour((k + 0.5) / 8)).sum(axis=-1) <= 3).sum() > 20
    assert sorted(p.name for p in tmp_path.iterdir()) == ["fc.png"]


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

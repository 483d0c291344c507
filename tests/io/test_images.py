"""Image files: RGBE precision and Radiance's units, our run-length encoding decoded by an
independent plain decoder, header lines, EXR/TIFF round trips through OpenImageIO, and our
.hdr read by Radiance's own programs (getinfo, pvalue, vwrays, evalglare) when pyradiance
is installed.

Tolerances.  RGBE keeps 8 bits of the largest channel: each channel decodes within
max(R, G, B)/256 of the value written (Radiance units).  The conversion between our
cd/m² and Radiance's units is exact (1e-12); a grey pixel therefore round-trips within
L/256.  EXR and TIFF hold float32: they round-trip to float32 exactly.
"""

from __future__ import annotations

import math
import os
import subprocess

import numpy as np
import pytest

from lbl_illum.io import images
from lbl_illum.errors import InputError
from lbl_illum.photometry import luminance, luminance_weights
from lbl_illum.io.radiance import radiance_programs
from lbl_illum.scene.views import view_from_string

from conftest import radiance_tool

PROGRAMS = radiance_programs()


needs_radiance = pytest.mark.skipif(radiance_tool("pvalue") is None or radiance_tool("getinfo") is None,
                                    reason="Radiance (pyradiance) is not installed")
try:
    import OpenImageIO  # noqa: F401
    HAVE_OIIO = True
except ImportError:  # pragma: no cover
    HAVE_OIIO = False
needs_oiio = pytest.mark.skipif(not HAVE_OIIO, reason="OpenImageIO is not installed")

VIEW = view_from_string("-vtv -vp 2 5.7 1.5 -vd 0 -1 -0.1 -vu 0 0 1 -vh 80 -vv 60")
RAD_W = np.array([0.265, 0.670, 0.065])


def sample_image(h=23, w=41, seed=0):
    """Luminance-like pixels: smooth grey areas (long runs), noise, a bright patch, black."""
    rng = np.random.default_rng(seed)
    rgb = np.exp(rng.normal(3.0, 1.5, (h, w, 1))) * rng.uniform(0.6, 1.0, (h, w, 3))
    rgb[2:9, 5:30] = [120.0, 118.0, 100.0]
    rgb[10:12] = 0.0
    rgb[-1, -3:] = [2.0e9, 1.9e9, 1.7e9]         # the sun's disk, beyond half floats
    return rgb


def rle_decode(data: bytes, h: int, w: int) -> np.ndarray:
    """Plain decoder of Radiance's new run-length encoding (reference for the tests)."""
    out = np.zeros((h, w, 4), dtype=np.uint8)
    pos = 0
    for row in range(h):
        assert data[pos:pos + 2] == b"\x02\x02" and (data[pos + 2] << 8 | data[pos + 3]) == w
        pos += 4
        for channel in range(4):
            x = 0
            while x < w:
                code = data[pos]
                pos += 1
                if code > 128:
                    count = code & 127
                    out[row, x:x + count, channel] = data[pos]
                    pos += 1
                else:
                    assert code > 0
                    out[row, x:x + code, channel] = np.frombuffer(data[pos:pos + code], dtype=np.uint8)
                    pos += code
                x += code & 127 if code > 128 else code
            assert x == w
    assert pos == len(data)
    return out


def split_hdr(data: bytes):
    end = data.index(b"\n\n")
    eol = data.index(b"\n", end + 2)
    return data[:end].decode().splitlines(), data[end + 2:eol].decode(), data[eol + 1:]


# ---------------------------------------------------------------------------
# RGBE and units
# ---------------------------------------------------------------------------

def test_rgbe_precision_and_setcolr():
    rng = np.random.default_rng(1)
    values = np.exp(rng.uniform(-40, 40, (5000, 1))) * rng.uniform(0, 1, (5000, 3))
    rgbe = images.rgbe_encode(values)
    top = values.max(axis=1)
    assert ((rgbe[:, :3].max(axis=1) >= 128) & (rgbe[:, :3].max(axis=1) <= 255)).all()
    decoded = images.rgbe_decode(rgbe)
    assert (np.abs(decoded - values) <= top[:, None] * images.RGBE_TOLERANCE).all()
    # one value by hand: 1.0 -> frexp 0.5 * 2^1 -> mantissa 128, exponent 129
    assert images.rgbe_encode(np.array([1.0, 0.5, 0.0])).tolist() == [128, 64, 0, 129]
    assert images.rgbe_decode(np.array([128, 64, 0, 129], np.uint8)) == pytest.approx([128.5 / 128, 64.5 / 128,
                                                                                          0.5 / 128])
    assert images.rgbe_encode(np.array([[0.0, 0, 0], [1e-33, 0, 0], [-1, -2, 0]])).tolist() == [[0, 0, 0, 0]] * 3
    assert images.rgbe_decode(np.zeros(4, np.uint8)).tolist() == [0.0, 0.0, 0.0]


def test_radiance_units_keep_our_luminance():
    rng = np.random.default_rng(2)
    rgb = rng.uniform(0, 1000, (50, 3))
    for exposure in (1.0, 0.25):
        p = images.radiance_pixels(rgb, exposure)
        assert np.allclose(179.0 * (p @ RAD_W) / exposure, luminance(rgb), rtol=1e-12)
        ratio = p / rgb
        assert np.allclose(ratio, ratio[:, :1])                     # one factor per pixel: same chromaticity
        assert np.allclose(images.photometric_pixels(p, exposure), rgb, rtol=1e-12)
    grey = np.full((2, 3), 358.0)
    assert np.allclose(images.radiance_pixels(grey), 2.0, rtol=1e-15)   # L / 179 exactly for grey
    assert np.allclose(luminance_weights(), [0.2126, 0.7152, 0.0722], atol=1e-4)


def test_primaries_are_colour_sciences_rec709():
    import colour

    space = colour.RGB_COLOURSPACES["ITU-R BT.709"]
    assert np.allclose(images.REC709_PRIMARIES[:6], np.ravel(space.primaries), atol=1e-9)
    assert np.allclose(images.REC709_PRIMARIES[6:], space.whitepoint, atol=1e-4)


# ---------------------------------------------------------------------------
# Radiance HDR written by our code
# ---------------------------------------------------------------------------

@pytest.mark.parametrize("h, w", [(23, 41), (3, 8), (2, 300), (1, 1000)])
def test_rle_decodes_to_the_rgbe_pixels(h, w):
    rgb = sample_image(h, w, seed=w)
    if w >= 300:                                   # runs longer than 127 and literal blocks longer than 128
        rgb[:, : w // 2] = 42.0
    data = images.hdr_bytes(rgb, view=VIEW, command="lbl-illum render test")
    header, resolution, body = split_hdr(data)
    assert resolution == f"-Y {h} +X {w}"
    expected = images.rgbe_encode(images.radiance_pixels(rgb))
    assert np.array_equal(rle_decode(body, h, w), expected)
    if w >= 300:
        assert len(body) < 0.75 * expected.size                   # the runs were compressed


def test_flat_scanlines():
    rgb = sample_image(4, 5)
    for kwargs in ({}, {"rle": False}):
        body = split_hdr(images.hdr_bytes(rgb, command="x", **kwargs))[2]
        assert np.array_equal(np.frombuffer(body, np.uint8).reshape(4, 5, 4),
                              images.rgbe_encode(images.radiance_pixels(rgb)))
    wide = sample_image(2, 20)
    body = split_hdr(images.hdr_bytes(wide, command="x", rle=False))[2]
    assert len(body) == 2 * 20 * 4


def test_header_lines(tmp_path):
    path = images.write_hdr(tmp_path / "out.hdr", sample_image(), view=VIEW, exposure=0.5,
                            command="lbl-illum render office.toml\n--view desk")
    header, resolution, _ = split_hdr(path.read_bytes())
    assert header[0] == "#?RADIANCE"
    assert header[1] == "lbl-illum render office.toml --view desk"
    assert header[-1] == "FORMAT=32-bit_rle_rgbe"
    assert VIEW.to_radiance() in header
    assert "EXPOSURE=5.000000e-01" in header
    assert "PRIMARIES= 0.6400 0.3300 0.3000 0.6000 0.1500 0.0600 0.3127 0.3290" in header
    parsed = images.read_hdr_header(path)
    assert parsed.view == VIEW and parsed.exposure == 0.5 and parsed.format == "32-bit_rle_rgbe"
    assert (parsed.width, parsed.height, parsed.orientation) == (41, 23, "-Y +X")
    assert parsed.primaries == images.REC709_PRIMARIES


@pytest.mark.parametrize("length", [127, 128, 129, 256, 384])
def test_header_lines_of_any_length_read_back(tmp_path, length):
    """A command line of a multiple of 128 characters (a long path, or pytest's own
    command line) once ended the header for OpenImageIO's reader, which reads lines in
    128-byte pieces ("no FORMAT specifier found"): every length reads back."""
    rgb = np.full((4, 4, 3), 50.0)
    path = images.write_hdr(tmp_path / "a.hdr", rgb, command="x" * length)
    back = images.read_image(path)
    np.testing.assert_allclose(back.rgb, rgb, rtol=0.01)
    assert back.metadata["header"][1].strip() == "x" * length


def test_exposure_lines_accumulate(tmp_path):
    path = tmp_path / "two.hdr"
    path.write_bytes(b"#?RADIANCE\nEXPOSURE=2\npfilt\nEXPOSURE=1.5\nFORMAT=32-bit_rle_rgbe\n\n-Y 1 +X 1\n"
                     + bytes([128, 128, 128, 129]))
    assert images.read_hdr_header(path).exposure == 3.0
    assert images.read_hdr_header(path).view is None


@pytest.mark.parametrize("content, words", [
    (b"P6\n1 1\n255\n", "not a Radiance picture"),
    (b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n", "no end"),
    (b"#?RADIANCE\n\n+Y 2 Z 3\n", "bad resolution line"),
    (b"#?RADIANCE\nEXPOSURE=abc\n\n-Y 1 +X 1\n", "header line 2"),
])
def test_bad_headers(tmp_path, content, words):
    path = tmp_path / "bad.hdr"
    path.write_bytes(content)
    with pytest.raises(InputError, match=words):
        images.read_hdr_header(path)


def test_writes_are_atomic_and_checked(tmp_path):
    target = tmp_path / "keep.hdr"
    target.write_bytes(b"old")
    bad = sample_image()
    bad[0, 0, 0] = np.nan
    with pytest.raises(ValueError, match="finite"):
        images.write_image(target, bad)
    assert target.read_bytes() == b"old" and os.listdir(tmp_path) == ["keep.hdr"]
    with pytest.raises(InputError, match=r"out\.jpg: an image must end in"):
        images.write_image(tmp_path / "out.jpg", sample_image())
    with pytest.raises(InputError, match="does not exist"):
        images.write_image(tmp_path / "nowhere" / "out.hdr", sample_image())
    with pytest.raises(ValueError, match="shape"):
        images.write_image(tmp_path / "x.hdr", np.zeros((4, 4)))


# ---------------------------------------------------------------------------
# Through OpenImageIO
# ---------------------------------------------------------------------------

@needs_oiio
def test_hdr_read_back(tmp_path):
    rgb = sample_image()
    path = images.write_image(tmp_path / "a.hdr", rgb, view=VIEW, exposure=2.0, command="test")
    image = images.read_image(path)
    assert image.view == VIEW and image.exposure == 2.0 and image.units == "cd/m2"
    # pixels exactly as Radiance decodes them (OpenImageIO's missing half step restored)
    expected = images.photometric_pixels(images.rgbe_decode(images.rgbe_encode(images.radiance_pixels(rgb, 2.0))), 2.0)
    expected[rgb.max(axis=-1) == 0] = 0.0
    assert np.allclose(image.rgb, expected, rtol=1e-6, atol=0)
    grey = np.full((6, 9, 3), 1.0) * np.linspace(1, 5000, 9)[None, :, None]
    back = images.read_image(images.write_hdr(tmp_path / "g.hdr", grey, command="t")).rgb
    assert (np.abs(back - grey) <= grey * images.RGBE_TOLERANCE).all()
    import OpenImageIO as oiio
    spec = oiio.ImageInput.open(str(path)).spec()
    assert (spec.width, spec.height, spec.nchannels) == (41, 23, 3)


@needs_oiio
@pytest.mark.parametrize("suffix", [".exr", ".tif"])
def test_float_formats_round_trip(tmp_path, suffix):
    rgb = sample_image()
    path = images.write_image(tmp_path / f"a{suffix}", rgb, view=VIEW, exposure=0.01, command="lbl-illum x")
    image = images.read_image(path)
    assert np.array_equal(image.rgb, rgb.astype(np.float32).astype(np.float64))
    assert image.rgb.max() == pytest.approx(2.0e9, rel=1e-7)    # beyond half floats' 65504
    assert image.view == VIEW and image.exposure == 0.01 and image.units == "cd/m2"
    assert os.listdir(tmp_path) == [path.name]
    if suffix == ".exr":
        assert image.metadata["whiteLuminance"] == 1.0
        assert image.metadata["lbl_illum:view"] == VIEW.to_radiance()


@needs_oiio
def test_read_errors(tmp_path):
    with pytest.raises(InputError, match="no such file"):
        images.read_image(tmp_path / "none.exr")
    junk = tmp_path / "junk.exr"
    junk.write_bytes(b"not an image")
    with pytest.raises(InputError, match="junk.exr: cannot read"):
        images.read_image(junk)


# ---------------------------------------------------------------------------
# Radiance's own programs reading our .hdr
# ---------------------------------------------------------------------------

def run(name, *args, check=True):
    return subprocess.run([radiance_tool(name), *map(str, args)], capture_output=True, check=check,
                          env=PROGRAMS["env"] if PROGRAMS else None)


@needs_radiance
def test_getinfo_reads_header(tmp_path):
    path = images.write_hdr(tmp_path / "a.hdr", sample_image(), view=VIEW, exposure=0.5, command="lbl-illum t")
    info = run("getinfo", path).stdout.decode()
    assert VIEW.to_radiance() in info and "EXPOSURE=5.000000e-01" in info and "FORMAT=32-bit_rle_rgbe" in info
    assert run("getinfo", "-d", path).stdout.decode().split() == [f"{path}:", "-Y", "23", "+X", "41"]


@needs_radiance
def test_pvalue_reads_our_values_and_luminance(tmp_path):
    rgb = sample_image()
    path = images.write_hdr(tmp_path / "a.hdr", rgb, view=VIEW, exposure=4.0, command="t")
    raw = np.frombuffer(run("pvalue", "-o", "-h", "-H", "-df", path).stdout, dtype=np.float32)
    raw = raw.reshape(23, 41, 3).astype(np.float64)       # -o: exposure divided out
    p = images.radiance_pixels(rgb)                        # what we meant to store (Radiance units)
    top = p.max(axis=-1, keepdims=True)
    assert (np.abs(raw - p) <= top * images.RGBE_TOLERANCE * (1 + 1e-6)).all()
    decoded = images.rgbe_decode(images.rgbe_encode(images.radiance_pixels(rgb, 4.0))) / 4.0
    assert np.allclose(raw, decoded, rtol=1e-6)            # same decoding, float32 printing
    lum = 179.0 * np.frombuffer(run("pvalue", "-o", "-h", "-H", "-b", "-df", path).stdout, np.float32).reshape(23, 41)
    bound = 179.0 * top[..., 0] * images.RGBE_TOLERANCE * (1 + 1e-6)
    assert (np.abs(lum - luminance(rgb)) <= bound).all()   # Radiance reads our luminance


@needs_radiance
def test_vwrays_reads_our_view(tmp_path):
    if radiance_tool("vwrays") is None:
        pytest.skip("no vwrays")
    view = view_from_string("-vta -vp 1 2 1.2 -vd 0.3 1 0 -vh 180 -vv 180 -vs 0.05")
    path = images.write_hdr(tmp_path / "f.hdr", np.ones((20, 20, 3)), view=view, command="t")
    ref = np.frombuffer(run("vwrays", "-fd", path).stdout, np.float64).reshape(-1, 6)
    o, d, ok = view.rays(20, 20)
    assert ref.shape[0] == 400 and np.abs(ref[:, :3] - o).max() < 1e-5 and np.abs(ref[:, 3:] - d).max() < 1e-5


@needs_radiance
def test_evalglare_vertical_illuminance(tmp_path):
    """A 180 deg fisheye of L = 100 (1 + cos θ) cd/m²: E_v = 100 π + 100 · 2π/3 lux.

    evalglare takes the projection from our VIEW= and the luminance from our pixels;
    1 % allows the pixelation of the 400 px circle.
    """
    if radiance_tool("evalglare") is None:
        pytest.skip("no evalglare")
    view = view_from_string("-vta -vp 0 0 1.2 -vd 0 1 0 -vu 0 0 1 -vh 180 -vv 180")
    x, y = view.resolution(400, 400)
    _, d, _ = view.rays(x, y)
    cos = d @ view.unit_direction
    lum = np.where(cos > 0, 100.0 * (1.0 + cos), 0.0).reshape(y, x)
    path = images.write_hdr(tmp_path / "glare.hdr", np.repeat(lum[..., None], 3, axis=2), view=view, command="t")
    result = run("evalglare", "-V", path, check=False)     # evalglare exits with 1 after printing
    ev = float(result.stdout.split()[0])
    assert ev == pytest.approx(100 * math.pi + 100 * 2 * math.pi / 3, rel=0.01)


# ---------------------------------------------------------------------------
# Preview
# ---------------------------------------------------------------------------

def test_tonemap_operator():
    grey = np.full((4, 4, 3), 250.0)
    key = images.tonemap(grey, key=0.18, white=math.inf)
    assert np.allclose(key, 0.18 / 1.18)                          # L = key, Ld = L / (1 + L)
    rng = np.random.default_rng(5)
    rgb = np.repeat(np.exp(rng.normal(4, 2, (16, 16, 1))), 3, axis=2)
    out = images.tonemap(rgb)
    lum = luminance(rgb)
    assert luminance(out).max() == pytest.approx(1.0)                                       # Lwhite = max
    assert luminance(out)[np.unravel_index(lum.argmax(), lum.shape)] == pytest.approx(1.0)
    order = np.argsort(lum, axis=None)
    assert np.all(np.diff(luminance(out).ravel()[order]) >= -1e-12)                         # monotonic
    # chromaticity kept where no channel clips
    warm = rgb * np.array([1.0, 0.9, 0.7])
    out = images.tonemap(warm)
    unclipped = out.max(axis=-1) < 1.0
    assert unclipped.sum() > 200
    assert np.allclose(out[unclipped, 1] / out[unclipped, 0], 0.9)
    assert np.allclose(out[unclipped, 2] / out[unclipped, 0], 0.7)
    # a fixed exposure maps the same luminance the same way in any image
    a = images.tonemap(np.full((2, 2, 3), 10.0), exposure=0.01, white=math.inf)
    b = images.tonemap(np.concatenate([np.full((2, 2, 3), 10.0), np.full((2, 2, 3), 1e4)]), exposure=0.01,
                       white=math.inf)
    assert np.allclose(a, b[:2])
    assert images.tonemap(np.zeros((2, 2, 3))).max() == 0.0


def test_preview_png(tmp_path):
    from matplotlib.image import imread

    rgb = np.full((10, 12, 3), 100.0)
    rgb[:, 6:] = 400.0
    pixels = images.preview_pixels(rgb, exposure=0.18 / 100.0, white=math.inf)
    # 0.18 / 1.18 display -> sRGB: 1.055 * x^(1/2.4) - 0.055
    expected = round(255 * (1.055 * (0.18 / 1.18) ** (1 / 2.4) - 0.055))
    assert pixels[0, 0].tolist() == [expected] * 3 and pixels[0, 11, 0] > expected
    path = images.write_preview(tmp_path / "p.png", rgb)
    back = np.round(imread(path) * 255).astype(np.uint8)
    assert back.shape == (10, 12, 3) and np.array_equal(back, images.preview_pixels(rgb))
    with pytest.raises(InputError):
        images.write_preview(tmp_path / "p.jpg", rgb)

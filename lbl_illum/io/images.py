"""Luminance images on disk: OpenEXR, Radiance HDR (RGBE), float TIFF, and an sRGB preview.

Pixel values.  An image is a ``(height, width, 3)`` array of linear RGB whose channels
are photometric (docs/design.md §2, :mod:`lbl_illum.photometry`): a grey pixel ``(L, L, L)``
has luminance ``L`` cd/m², and any pixel's luminance is its Rec. 709 value
``Y = 0.2126 R + 0.7152 G + 0.0722 B``.  Row 0 is the top of the image, column 0 its
left (:mod:`lbl_illum.scene.views`).

==========  ========================================================================
format      what the file holds
==========  ========================================================================
``.exr``    32-bit float RGB in cd/m², unscaled (OpenImageIO; ZIP compression).
            Half floats are not used: their largest value, 65504, is far below the
            luminance of the sun's disk (~1.6e9 cd/m²) and of sunlit glazing.
            Attributes: ``lbl_illum:view`` (the ``VIEW=`` line),
            ``lbl_illum:units`` = ``"cd/m2"``, ``lbl_illum:exposure``,
            ``lbl_illum:command``, the standard ``whiteLuminance`` = 1 (cd/m² of RGB
            (1, 1, 1)) and ``chromaticities`` (Rec. 709, D65), ``ImageDescription``.
``.tif``    32-bit float RGB in cd/m² (OpenImageIO; ZIP).  TIFF keeps no custom
            attributes, so units, exposure, command and view are lines of its
            ``ImageDescription`` (``units=cd/m2``, ``exposure=...``, ``VIEW= ...``).
``.hdr``    Radiance RGBE picture written by this module (Ward, "Real Pixels",
            *Graphics Gems II*, 1991; Radiance ``color.c``, ``header.c``,
            ``resolu.c``), in Radiance's units: see below.
==========  ========================================================================

The exposure.  ``exposure`` is the factor a viewer should multiply pixel values by for
display.  EXR and TIFF hold cd/m² unscaled and only record it; the HDR file holds
values already multiplied by it with an ``EXPOSURE=`` line, which is Radiance's own
convention (``pvalue -o`` and :func:`read_image` divide it out again).

Radiance's units.  Radiance carries radiance [W sr⁻¹ m⁻²] with a luminous efficacy of
179 lm/W for its white, and takes the luminance of a pixel as
``179 × (0.265 R + 0.670 G + 0.065 B)`` (``bright()`` × ``WHTEFFICACY``), which is
what ``pvalue``, ``falsecolor`` and ``evalglare`` compute.  So that these tools read
*our* luminance exactly, an HDR pixel is::

    P = exposure · rgb / 179 · Y709(rgb) / Yrad(rgb)

with ``Yrad(c) = 0.265 c_R + 0.670 c_G + 0.065 c_B``: each pixel is scaled by one
factor, which keeps its chromaticity and makes Radiance's luminance of it equal our
Rec. 709 luminance.  For grey pixels (all the light of grey materials under the sky
and sun) the factor is exactly 1, i.e. ``P = exposure · L / 179``.  The inverse,
used by :func:`read_image`, is ``rgb = 179 · P · Yrad(P) / Y709(P) / exposure``.
``PRIMARIES=`` states the Rec. 709 primaries with the D65 white point, the colour
space of the RGB values.

RGBE precision.  Each pixel shares one exponent: the largest channel keeps 8
significant bits.  Encoding truncates as Radiance's ``setcolr()`` does, decoding adds
half a step as ``colr_color()`` does, so each channel is recovered within
``max(R, G, B) / 256`` (≈ 0.4 % of the pixel's largest channel) — the tolerance the
tests use.  Negative values cannot be stored and are written as 0; values below
1e-32 are written as black.

Preview.  :func:`write_preview` writes an 8-bit sRGB PNG through the global
photographic operator of Reinhard, Stark, Shirley & Ferwerda, "Photographic Tone
Reproduction for Digital Images" (SIGGRAPH 2002), eqs. 1-4: the world luminance
``Lw`` is scaled by ``key / L̄w`` (``L̄w`` the log-average luminance, eq. 1, over pixels
with ``Lw > 0``; or by a fixed ``exposure``), compressed by
``Ld = L (1 + L/Lwhite²)/(1 + L)`` with ``Lwhite`` the largest scaled luminance
(eq. 4), each pixel's RGB is scaled by ``Ld / Lw`` (chromaticity kept), clipped to
[0, 1] and encoded with the sRGB transfer function of IEC 61966-2-1 (colour-science's
``cctf_encoding``).
"""

from __future__ import annotations

import math
import os
import shlex
import sys
import tempfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .._version import __version__
from ..errors import InputError
from .files import atomic_write_bytes
from ..optional import require
from ..photometry import luminance, luminance_weights
from .radiance import RADIANCE_EFFICACY, RADIANCE_RGB_WEIGHTS
from ..scene.views import View, view_from_header

__all__ = [
    "IMAGE_FORMATS", "REC709_PRIMARIES", "RGBE_TOLERANCE", "ImageData", "HdrHeader",
    "radiance_pixels", "photometric_pixels", "rgbe_encode", "rgbe_decode", "hdr_bytes",
    "write_image", "write_hdr", "write_exr", "write_tiff", "read_hdr_header", "read_image",
    "tonemap", "preview_pixels", "write_preview", "write_png", "check_image_path",
]

#: Extensions written by :func:`write_image`.
IMAGE_FORMATS = (".exr", ".hdr", ".pic", ".tif", ".tiff")
#: Chromaticities (x, y) of the Rec. 709 red, green, blue primaries and the D65 white
#: (ITU-R BT.709-6, Table "Derivation of luminance signal"; the white of IEC 61966-2-1).
REC709_PRIMARIES = (0.640, 0.330, 0.300, 0.600, 0.150, 0.060, 0.3127, 0.3290)
#: Largest RGBE decoding error of a channel, as a fraction of the pixel's largest channel.
RGBE_TOLERANCE = 1.0 / 256.0
#: Below this (in Radiance units) a pixel is stored as black (``setcolr()``).
RGBE_MIN = 1e-32
#: Scanline widths for which Radiance's run-length encoding is defined (``MINELEN``,
#: ``MAXELEN`` in ``color.c``); other widths are written flat.
RLE_MIN_WIDTH, RLE_MAX_WIDTH = 8, 0x7FFF
#: Shortest run written as a run packet (``MINRUN``).
_MIN_RUN = 4


def _oiio():
    """The OpenImageIO module, or a readable error when it is not installed."""
    return require("OpenImageIO", "EXR, TIFF and PNG files, and reading images,")


def _check_pixels(rgb: Any) -> np.ndarray:
    rgb = np.asarray(rgb, dtype=np.float64)
    if rgb.ndim != 3 or rgb.shape[2] != 3 or rgb.shape[0] < 1 or rgb.shape[1] < 1:
        raise ValueError(f"an image must be a (height, width, 3) array, got shape {rgb.shape}")
    if not np.all(np.isfinite(rgb)):
        raise ValueError("image pixels must be finite (found NaN or infinity)")
    return rgb


def _check_exposure(exposure: float) -> float:
    exposure = float(exposure)
    if not (math.isfinite(exposure) and exposure > 0):
        raise ValueError(f"exposure must be a positive number, got {exposure!r}")
    return exposure


def check_image_path(path: str | os.PathLike, formats=IMAGE_FORMATS) -> Path:
    """Refuse an output whose extension is unknown or whose folder does not exist."""
    path = Path(path)
    if path.suffix.lower() not in formats:
        raise InputError(f"{path.name}: an image must end in {', '.join(formats)}")
    if str(path.parent) and not path.parent.exists():
        raise InputError(f"{path}: folder {path.parent} does not exist")
    return path


def _default_command() -> str:
    args = [Path(sys.argv[0]).name if sys.argv and sys.argv[0] else "python", *sys.argv[1:]]
    return shlex.join(args)


def _one_line(text: str) -> str:
    return " ".join(str(text).split())


# ---------------------------------------------------------------------------
# Radiance units
# ---------------------------------------------------------------------------

def _radiance_weights() -> np.ndarray:
    return np.asarray(RADIANCE_RGB_WEIGHTS, dtype=np.float64)


def radiance_pixels(rgb: np.ndarray, exposure: float = 1.0) -> np.ndarray:
    """(h, w, 3) photometric RGB [cd/m²] → Radiance pixel values (× ``exposure``).

    ``P = exposure · rgb / 179 · Y709(rgb) / Yrad(rgb)``; negative channels are first
    set to 0.  Radiance's luminance of the result, ``179 · Yrad(P) / exposure``,
    equals our ``Y709(rgb)``.
    """
    rgb = np.maximum(np.asarray(rgb, dtype=np.float64), 0.0)
    y709 = rgb @ luminance_weights()
    yrad = rgb @ _radiance_weights()
    with np.errstate(invalid="ignore", divide="ignore"):
        factor = np.where(yrad > 0.0, y709 / yrad, 0.0)
    return rgb * (factor * (_check_exposure(exposure) / RADIANCE_EFFICACY))[..., None]


def photometric_pixels(values: np.ndarray, exposure: float = 1.0) -> np.ndarray:
    """Radiance pixel values → photometric RGB [cd/m²]: the inverse of :func:`radiance_pixels`."""
    values = np.asarray(values, dtype=np.float64)
    y709 = values @ luminance_weights()
    yrad = values @ _radiance_weights()
    with np.errstate(invalid="ignore", divide="ignore"):
        factor = np.where(y709 > 0.0, yrad / y709, 0.0)
    return values * (factor * (RADIANCE_EFFICACY / _check_exposure(exposure)))[..., None]


# ---------------------------------------------------------------------------
# RGBE
# ---------------------------------------------------------------------------

def rgbe_encode(values: np.ndarray) -> np.ndarray:
    """(..., 3) non-negative floats → (..., 4) uint8 RGBE (Radiance's ``setcolr()``).

    The exponent is that of the largest channel (``frexp``: ``max = m · 2^e``,
    ``m ∈ [½, 1)``); each channel is stored as ``floor(c · 2^(8−e))`` and the exponent
    as ``e + 128``, so the largest channel has 8 significant bits (128…255).  The
    scaling is by a power of two, hence exact.
    """
    values = np.maximum(np.asarray(values, dtype=np.float64), 0.0)
    top = values.max(axis=-1)
    _, exponent = np.frexp(top)
    keep = top > RGBE_MIN
    exponent = np.where(keep, exponent, 0)
    mantissa = np.floor(np.ldexp(values, (8 - exponent)[..., None]))
    out = np.zeros(values.shape[:-1] + (4,), dtype=np.uint8)
    out[..., :3] = np.where(keep[..., None], np.clip(mantissa, 0, 255), 0).astype(np.uint8)
    out[..., 3] = np.where(keep, np.clip(exponent + 128, 0, 255), 0).astype(np.uint8)
    return out


def rgbe_decode(rgbe: np.ndarray) -> np.ndarray:
    """(..., 4) uint8 RGBE → (..., 3) float64 as Radiance's ``colr_color()``: ``(m + ½) · 2^(E−136)``."""
    rgbe = np.asarray(rgbe, dtype=np.uint8)
    exponent = rgbe[..., 3].astype(np.int64)
    values = np.ldexp(rgbe[..., :3].astype(np.float64) + 0.5, (exponent - 136)[..., None])
    return np.where((exponent == 0)[..., None], 0.0, values)


def _rle_scanlines(rgbe: np.ndarray) -> bytes:
    """Radiance's "new" run-length encoding of (h, w, 4) RGBE scanlines, vectorised.

    Each scanline is ``2 2 w>>8 w&255`` followed by its four components one after
    another; a component is a series of packets: ``128+n, value`` repeats a byte
    ``n`` ≤ 127 times, ``n, b1..bn`` copies ``n`` ≤ 128 bytes.  Runs of at least 4 equal
    bytes become repeat packets, the rest literal packets (``fwritecolrs()``).
    """
    h, w, _ = rgbe.shape
    seq = np.ascontiguousarray(rgbe.transpose(0, 2, 1)).reshape(-1)   # row, component, x
    n = seq.size
    change = np.ones(n, dtype=bool)
    change[1:] = seq[1:] != seq[:-1]
    change[::w] = True                                                 # runs stop at component ends
    starts = np.flatnonzero(change)
    lengths = np.diff(np.append(starts, n))
    segment = starts // w
    is_run = lengths >= _MIN_RUN

    def chunks(begin: np.ndarray, length: np.ndarray, size: int) -> tuple[np.ndarray, np.ndarray]:
        count = (length + size - 1) // size
        within = np.arange(count.sum()) - np.repeat(np.cumsum(count) - count, count)
        return np.repeat(begin, count) + size * within, np.minimum(size, np.repeat(length, count) - size * within)

    run_start, run_len = chunks(starts[is_run], lengths[is_run], 127)
    # literal blocks: consecutive short runs of one component
    literal = ~is_run
    first = np.ones(starts.size, dtype=bool)
    first[1:] = is_run[:-1] | (segment[1:] != segment[:-1])
    block_id = np.cumsum(first[literal]) - 1
    block_start = starts[literal][first[literal]]
    block_len = np.bincount(block_id, weights=lengths[literal], minlength=block_start.size).astype(np.int64)
    lit_start, lit_len = chunks(block_start, block_len, 128)

    pk_start = np.concatenate([run_start, lit_start])
    pk_len = np.concatenate([run_len, lit_len])
    pk_run = np.concatenate([np.ones(run_start.size, bool), np.zeros(lit_start.size, bool)])
    order = np.argsort(pk_start, kind="stable")
    pk_start, pk_len, pk_run = pk_start[order], pk_len[order], pk_run[order]
    size = np.where(pk_run, 2, 1 + pk_len)
    row = pk_start // (4 * w)
    offset = np.cumsum(size) - size + 4 * (row + 1)                    # after each row's marker
    out = np.empty(int(size.sum()) + 4 * h, dtype=np.uint8)
    out[offset] = np.where(pk_run, 128 + pk_len, pk_len).astype(np.uint8)
    out[offset[pk_run] + 1] = seq[pk_start[pk_run]]
    lit = ~pk_run
    count = pk_len[lit]
    within = np.arange(count.sum()) - np.repeat(np.cumsum(count) - count, count)
    out[np.repeat(offset[lit] + 1, count) + within] = seq[np.repeat(pk_start[lit], count) + within]
    first_packet = np.searchsorted(pk_start, np.arange(h) * 4 * w)
    marker = offset[first_packet] - 4
    out[marker] = 2
    out[marker + 1] = 2
    out[marker + 2] = w >> 8
    out[marker + 3] = w & 0xFF
    return out.tobytes()


# ---------------------------------------------------------------------------
# Radiance HDR
# ---------------------------------------------------------------------------

#: Bytes in which rgbe.c-style readers read a Radiance header's lines (:func:`hdr_bytes`).
HEADER_CHUNK = 128


def hdr_bytes(rgb: np.ndarray, *, view: View | None = None, exposure: float = 1.0,
              command: str | None = None, rle: bool = True, pixel_aspect: float | None = None) -> bytes:
    """The bytes of a Radiance picture of photometric ``rgb`` [cd/m²] (see the module text).

    Header: ``#?RADIANCE``, the command line (``command``, default this process's),
    ``SOFTWARE=``, ``VIEW=`` (when ``view`` is given), ``EXPOSURE=``, ``PRIMARIES=``
    (Rec. 709, D65), ``PIXASPECT=`` (when given and not 1), ``FORMAT=32-bit_rle_rgbe``,
    an empty line, then ``-Y height +X width`` (top row first, left to right).
    Scanlines are run-length encoded when ``rle`` and the width allows it (8 to
    32767 pixels), flat otherwise.
    """
    rgb = _check_pixels(rgb)
    exposure = _check_exposure(exposure)
    h, w, _ = rgb.shape
    lines = ["#?RADIANCE", _one_line(command if command is not None else _default_command()) or "lbl-illum",
             f"SOFTWARE= lbl_illum {__version__}"]
    if view is not None:
        lines.append(view.to_radiance())
    lines.append(f"EXPOSURE={exposure:e}")
    lines.append("PRIMARIES= " + " ".join(f"{v:.4f}" for v in REC709_PRIMARIES))
    if pixel_aspect is not None and abs(pixel_aspect - 1.0) > 1e-6:
        lines.append(f"PIXASPECT={float(pixel_aspect):f}")
    lines.append("FORMAT=32-bit_rle_rgbe")
    # Readers built on Ward's rgbe.c (OpenImageIO among them) read the header in pieces of
    # 128 bytes: a line of a multiple of 128 characters leaves its newline to be read
    # alone, as the empty line that ends the header, before FORMAT.  A trailing space
    # keeps every line off those lengths (Radiance ignores it).
    lines = [line + " " if len(line) % HEADER_CHUNK == 0 else line for line in lines]
    header = ("\n".join(lines) + "\n\n" + f"-Y {h} +X {w}\n").encode("ascii", "replace")
    rgbe = rgbe_encode(radiance_pixels(rgb, exposure))
    if rle and RLE_MIN_WIDTH <= w <= RLE_MAX_WIDTH:
        body = _rle_scanlines(rgbe)
    else:
        body = rgbe.tobytes()
    return header + body


def write_hdr(path: str | os.PathLike, rgb: np.ndarray, *, view: View | None = None, exposure: float = 1.0,
              command: str | None = None, rle: bool = True, pixel_aspect: float | None = None) -> Path:
    """Write a Radiance ``.hdr`` picture atomically (see :func:`hdr_bytes`)."""
    path = check_image_path(path, (".hdr", ".pic"))
    atomic_write_bytes(path, hdr_bytes(rgb, view=view, exposure=exposure, command=command, rle=rle,
                                       pixel_aspect=pixel_aspect))
    return path


@dataclass
class HdrHeader:
    """What the header of a Radiance picture says.

    ``exposure`` is the product of all ``EXPOSURE=`` lines (they accumulate, as
    ``pvalue -o`` reads them); ``view`` applies every view line in order.
    """

    lines: list[str]
    format: str | None
    exposure: float
    view: View | None
    primaries: tuple | None
    pixel_aspect: float
    width: int
    height: int
    orientation: str
    data_offset: int


def _split_header(raw: bytes, name: str) -> tuple[str, str, int]:
    if not raw.startswith(b"#?"):
        raise InputError(f"{name}: not a Radiance picture (no '#?' magic line)")
    end = raw.find(b"\n\n")
    if end < 0:
        raise InputError(f"{name}: the Radiance header has no end (empty line)")
    eol = raw.find(b"\n", end + 2)
    if eol < 0:
        raise InputError(f"{name}: no resolution line after the header")
    return raw[:end].decode("latin-1"), raw[end + 2:eol].decode("latin-1"), eol + 1


def read_hdr_header(path: str | os.PathLike) -> HdrHeader:
    """Parse the header and resolution line of a Radiance picture."""
    path = Path(path)
    name = path.name
    try:
        with open(path, "rb") as fh:
            raw = fh.read(65536)
    except FileNotFoundError:
        raise InputError(f"{name}: no such file") from None
    except OSError as exc:
        raise InputError(f"{name}: cannot read ({exc.__class__.__name__})") from None
    text, resolution, offset = _split_header(raw, name)
    lines = text.splitlines()
    fmt, exposure, primaries, aspect = None, 1.0, None, 1.0
    for number, line in enumerate(lines, start=1):
        key, _, value = line.partition("=")
        try:
            if line.startswith("FORMAT="):
                fmt = value.strip()
            elif line.startswith("EXPOSURE="):
                exposure *= float(value)
            elif line.startswith("PIXASPECT="):
                aspect *= float(value)
            elif line.startswith("PRIMARIES="):
                primaries = tuple(float(v) for v in value.split())
                if len(primaries) != 8:
                    raise ValueError
        except ValueError:
            raise InputError(f"{name}: header line {number}: cannot read {line!r}") from None
    words = resolution.split()
    if len(words) != 4 or words[0][1:] not in ("X", "Y") or words[2][1:] not in ("X", "Y") \
            or words[0][1] == words[2][1] or not (words[1].isdigit() and words[3].isdigit()):
        raise InputError(f"{name}: bad resolution line {resolution!r}")
    sizes = {words[0][1]: int(words[1]), words[2][1]: int(words[3])}
    return HdrHeader(lines=lines, format=fmt, exposure=exposure,
                     view=view_from_header(text, name), primaries=primaries, pixel_aspect=aspect,
                     width=sizes["X"], height=sizes["Y"], orientation=f"{words[0]} {words[2]}",
                     data_offset=offset)


# ---------------------------------------------------------------------------
# EXR and TIFF through OpenImageIO
# ---------------------------------------------------------------------------

def _oiio_write(path: Path, pixels: np.ndarray, pixel_type: str, attributes: dict[str, Any]) -> None:
    """Write ``pixels`` with OpenImageIO to a temporary file beside ``path``, then rename."""
    oiio = _oiio()
    h, w, channels = pixels.shape
    spec = oiio.ImageSpec(w, h, channels, pixel_type)
    for key, value in attributes.items():
        if key == "chromaticities":
            spec.attribute(key, oiio.TypeDesc("float[8]"), tuple(float(v) for v in value))
        else:
            spec.attribute(key, value)
    folder = path.parent if str(path.parent) else Path(".")
    fd, tmp = tempfile.mkstemp(prefix=f".{path.stem}.", suffix=path.suffix, dir=folder)
    os.close(fd)
    try:
        out = oiio.ImageOutput.create(tmp)
        if out is None or not out.open(tmp, spec):
            raise OSError(f"{path.name}: OpenImageIO cannot write it: {oiio.geterror()}")
        ok = out.write_image(np.ascontiguousarray(pixels))
        out.close()
        if not ok:
            raise OSError(f"{path.name}: OpenImageIO failed to write pixels: {oiio.geterror()}")
        mask = os.umask(0)
        os.umask(mask)
        os.chmod(tmp, 0o666 & ~mask)
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise


def _description(view: View | None, exposure: float, command: str) -> str:
    lines = ["lbl_illum luminance image", "units=cd/m2", f"exposure={exposure:.9g}", f"command={command}"]
    if view is not None:
        lines.append(view.to_radiance())
    return "\n".join(lines)


def write_exr(path: str | os.PathLike, rgb: np.ndarray, *, view: View | None = None, exposure: float = 1.0,
              command: str | None = None) -> Path:
    """Write float32 RGB in cd/m² as OpenEXR, with the view, units and exposure as attributes."""
    path = check_image_path(path, (".exr",))
    rgb = _check_pixels(rgb)
    exposure = _check_exposure(exposure)
    command = _one_line(command if command is not None else _default_command())
    attributes = {
        "compression": "zip",
        "Software": f"lbl_illum {__version__}",
        "ImageDescription": _description(view, exposure, command),
        "lbl_illum:units": "cd/m2",
        "lbl_illum:exposure": exposure,
        "lbl_illum:command": command,
        "whiteLuminance": 1.0,
        "chromaticities": REC709_PRIMARIES,
    }
    if view is not None:
        attributes["lbl_illum:view"] = view.to_radiance()
    _oiio_write(path, rgb.astype(np.float32), "float", attributes)
    return path


def write_tiff(path: str | os.PathLike, rgb: np.ndarray, *, view: View | None = None, exposure: float = 1.0,
               command: str | None = None) -> Path:
    """Write float32 RGB in cd/m² as TIFF; units, exposure and view in ``ImageDescription``."""
    path = check_image_path(path, (".tif", ".tiff"))
    rgb = _check_pixels(rgb)
    exposure = _check_exposure(exposure)
    command = _one_line(command if command is not None else _default_command())
    attributes = {"compression": "zip", "Software": f"lbl_illum {__version__}",
                  "ImageDescription": _description(view, exposure, command)}
    _oiio_write(path, rgb.astype(np.float32), "float", attributes)
    return path


def write_image(path: str | os.PathLike, rgb: np.ndarray, *, view: View | None = None, exposure: float = 1.0,
                command: str | None = None) -> Path:
    """Write ``rgb`` [cd/m²] in the format of the extension: ``.exr``, ``.hdr``/``.pic``, ``.tif``/``.tiff``."""
    path = check_image_path(path)
    suffix = path.suffix.lower()
    writer = write_exr if suffix == ".exr" else write_hdr if suffix in (".hdr", ".pic") else write_tiff
    return writer(path, rgb, view=view, exposure=exposure, command=command)


# ---------------------------------------------------------------------------
# Reading
# ---------------------------------------------------------------------------

@dataclass
class ImageData:
    """An image read back: ``rgb`` (h, w, 3) float64 photometric [cd/m²], top row first."""

    rgb: np.ndarray
    view: View | None = None
    exposure: float = 1.0
    units: str | None = None
    metadata: dict = field(default_factory=dict)

    @property
    def luminance(self) -> np.ndarray:
        """(h, w) luminance [cd/m²]."""
        return luminance(self.rgb)


def _oiio_read(path: Path) -> tuple[np.ndarray, dict]:
    oiio = _oiio()
    inp = oiio.ImageInput.open(str(path))
    if inp is None:
        raise InputError(f"{path.name}: cannot read the image ({_one_line(oiio.geterror())})")
    try:
        spec = inp.spec()
        pixels = inp.read_image(0, 0, 0, 3, "float")
        attributes = {a.name: a.value for a in spec.extra_attribs}
    finally:
        inp.close()
    if pixels is None or spec.nchannels < 3:
        raise InputError(f"{path.name}: expected an RGB image")
    return np.asarray(pixels, dtype=np.float64).reshape(spec.height, spec.width, 3), attributes


def _radiance_half_step(values: np.ndarray) -> np.ndarray:
    """OpenImageIO decodes RGBE as ``m · 2^(E−136)``; add Radiance's half step ``½ · 2^(E−136)``.

    The step of a pixel is found from its largest channel (``m`` in 128…255).  Applied
    only when every non-zero pixel lies on that grid, so a reader that already adds
    the half step is left alone.
    """
    top = values.max(axis=-1)
    nonzero = top > 0
    if not nonzero.any():
        return values
    _, exponent = np.frexp(np.where(nonzero, top, 1.0))               # top = f·2^e, f in [½, 1)
    step = np.ldexp(1.0, exponent - 8)
    scaled = values / step[..., None]
    if not np.all(scaled[nonzero] == np.round(scaled[nonzero])):
        return values
    return np.where(nonzero[..., None], values + 0.5 * step[..., None], 0.0)


def _description_fields(text: str) -> dict:
    found = {}
    for line in str(text).splitlines():
        if line.startswith("VIEW="):
            found["view"] = line
        elif "=" in line:
            key, _, value = line.partition("=")
            found[key.strip()] = value.strip()
    return found


def read_image(path: str | os.PathLike) -> ImageData:
    """Read an EXR, TIFF or Radiance HDR image back as photometric RGB [cd/m²].

    Pixels are read with OpenImageIO.  For ``.hdr`` the header is parsed here
    (:func:`read_hdr_header`: view and exposure), the pixels decoded as Radiance decodes
    them, divided by the exposure and converted from Radiance's units (module text).
    For EXR and TIFF the view, units and exposure come from the attributes
    :func:`write_exr` and :func:`write_tiff` write.
    """
    path = Path(path)
    if not path.exists():
        raise InputError(f"{path.name}: no such file")
    with open(path, "rb") as fh:
        magic = fh.read(2)
    if magic == b"#?":
        header = read_hdr_header(path)
        if header.orientation != "-Y +X":
            raise InputError(f"{path.name}: only top-to-bottom, left-to-right pictures (-Y h +X w) are read, "
                             f"got {header.orientation}")
        if header.format not in (None, "32-bit_rle_rgbe"):
            raise InputError(f"{path.name}: FORMAT={header.format} is not read (only 32-bit_rle_rgbe)")
        values, attributes = _oiio_read(path)
        values = _radiance_half_step(values)
        rgb = photometric_pixels(values, header.exposure)
        metadata = dict(attributes, header=header.lines)
        return ImageData(rgb=rgb, view=header.view, exposure=header.exposure, units="cd/m2", metadata=metadata)
    values, attributes = _oiio_read(path)
    fields_ = _description_fields(attributes.get("ImageDescription", ""))
    view_text = attributes.get("lbl_illum:view", fields_.get("view"))
    view = view_from_header(view_text, path.name) if view_text else None
    exposure = float(fields_.get("exposure", attributes.get("lbl_illum:exposure", 1.0)))   # text keeps 9 digits
    units = attributes.get("lbl_illum:units", fields_.get("units"))
    return ImageData(rgb=values, view=view, exposure=exposure, units=units, metadata=attributes)


# ---------------------------------------------------------------------------
# Preview
# ---------------------------------------------------------------------------

def tonemap(rgb: np.ndarray, key: float = 0.18, exposure: float | None = None,
            white: float | None = None) -> np.ndarray:
    """Reinhard et al. (2002) global operator: (h, w, 3) cd/m² → display-linear RGB in [0, 1].

    Parameters
    ----------
    rgb : (h, w, 3) float
        Photometric RGB [cd/m²].
    key : float
        Middle grey the log-average luminance is mapped to (eq. 2; 0.18 is the
        paper's "normal key").
    exposure : float, optional
        Fixed scale [m²/cd] instead of ``key / L̄w``, so that several images share one
        mapping.
    white : float, optional
        Smallest *scaled* luminance mapped to white (``Lwhite``, eq. 4); default the
        largest scaled luminance of the image.
    """
    rgb = _check_pixels(rgb)
    lw = np.maximum(luminance(rgb), 0.0)
    lit = lw > 0
    if exposure is None:
        if not lit.any():
            return np.zeros_like(rgb)
        log_average = math.exp(float(np.mean(np.log(lw[lit]))))       # eq. 1 over lit pixels
        scale = key / log_average
    else:
        scale = _check_exposure(exposure)
    scaled = scale * lw                                                # eq. 2
    l_white = float(scaled.max()) if white is None else float(white)
    if l_white > 0 and math.isfinite(l_white):
        display = scaled * (1.0 + scaled / (l_white * l_white)) / (1.0 + scaled)   # eq. 4
    else:
        display = scaled / (1.0 + scaled)                              # eq. 3
    with np.errstate(invalid="ignore", divide="ignore"):
        ratio = np.where(lit, display / lw, 0.0)
    return np.clip(rgb * ratio[..., None], 0.0, 1.0)


def preview_pixels(rgb: np.ndarray, key: float = 0.18, exposure: float | None = None,
                   white: float | None = None) -> np.ndarray:
    """(h, w, 3) uint8 sRGB preview: :func:`tonemap`, then the sRGB encoding (IEC 61966-2-1)."""
    import colour  # deferred: a slow import

    display = tonemap(rgb, key=key, exposure=exposure, white=white)
    encoded = np.asarray(colour.cctf_encoding(display, function="sRGB"), dtype=np.float64)
    return np.clip(np.round(encoded * 255.0), 0, 255).astype(np.uint8)


def write_png(path: str | os.PathLike, pixels: np.ndarray, description: str | None = None) -> Path:
    """Write (h, w, 3 or 4) uint8 pixels as a PNG, atomically (OpenImageIO), with the
    software and ``description`` as text chunks."""
    path = check_image_path(path, (".png",))
    pixels = np.asarray(pixels)
    if pixels.dtype != np.uint8 or pixels.ndim != 3 or pixels.shape[2] not in (3, 4):
        raise ValueError(f"a PNG needs (h, w, 3|4) uint8 pixels, got {pixels.dtype} {pixels.shape}")
    attributes = {"Software": f"lbl_illum {__version__}"}
    if description:
        attributes["ImageDescription"] = description
    _oiio_write(path, pixels, "uint8", attributes)
    return path


def write_preview(path: str | os.PathLike, rgb: np.ndarray, *, key: float = 0.18, exposure: float | None = None,
                  white: float | None = None) -> Path:
    """Write a tone-mapped sRGB PNG of ``rgb`` [cd/m²] (see :func:`tonemap`)."""
    path = check_image_path(path, (".png",))
    return write_png(path, preview_pixels(rgb, key=key, exposure=exposure, white=white),
                     "lbl_illum preview: Reinhard et al. 2002 global operator, sRGB")

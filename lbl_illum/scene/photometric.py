"""Luminous intensity distributions of luminaires from photometric files.

Two formats, read by this module (no maintained Python reader covers both with type B
photometry and errors that name the line; see docs/luminaires.md):

* **IES LM-63** (ANSI/IES LM-63-1986, -1991, -1995, -2002 and -2019): keyword lines, a
  ``TILT=`` line, then numbers separated by blanks, commas or line breaks: lamps, lumens
  per lamp (−1: absolute photometry), candela multiplier, the counts of vertical and
  horizontal angles, the photometric type (1 = C, 2 = B, 3 = A), the units (1 = feet,
  2 = metres), the luminous opening's width, length and height, the ballast factor, a
  field that was the ballast-lamp photometric factor before 1995, the input watts, then
  the vertical angles, the horizontal angles and, per horizontal angle, the candela at
  every vertical angle.  The candela values are for the rated lamps as they are (also
  for relative photometry, whose lumens per lamp are only informative), so
  I = candela × multiplier × ballast factor (× the photometric factor before 1995), as
  Radiance's ``ies2rad`` takes them.
* **EULUMDAT** (``.ldt``, Stockmar 1990): one field per line; the intensities are in
  cd/klm of the lamps' total flux, so I = value × conversion factor × Σ flux / 1000.

Angles (degrees) in the luminaire's frame: x along the C0 plane, y along C90, z up, the
photometric nadir along −z.  Type C: γ from the nadir, C counter-clockwise seen from
above, γ = acos(−e_z), C = atan2(e_y, e_x), e the unit direction of emission.  Type B
(the planes share the x axis): the plane angle H = atan2(−e_y, −e_z), as Radiance's
``source.cal`` measures it, and the angle within the plane V = asin(e_x) (LM-63-2002 §3,
"Type B photometry").  Tables given for a quadrant, a half or one plane are completed
by the symmetry they imply (LM-63-2002, "horizontal angles"; EULUMDAT's Isym); beyond
the vertical angles tabulated the intensity is 0.  Between tabulated angles it is
interpolated linearly in both angles, as Radiance's ``brightdata`` interpolates the
data file ``ies2rad`` writes.

Units: candela [cd], lengths of the luminous opening [m], flux [lm].
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import InputError
from ..io.files import read_text_file

__all__ = ["LuminousOpening", "Photometry", "read_photometry", "FEET"]

#: Metres per foot (IES units type 1).
FEET = 0.3048
#: Tolerance [deg] on the angles that name a symmetry (0, 90, 180, 270, 360).
ANGLE_TOLERANCE = 1e-6
#: Photometric types of LM-63.
_TYPES = {1: "C", 2: "B", 3: "A"}
#: Symmetries of a type C table: the range of C it covers.
SYMMETRIES = {"axial": (0.0, 0.0), "quadrant": (0.0, 90.0), "c0-c180": (0.0, 180.0),
              "c90-c270": (90.0, 270.0), "none": (0.0, 360.0)}


@dataclass(frozen=True)
class LuminousOpening:
    """The luminous opening of a luminaire [m] in its frame (module text): ``shape`` one of
    point, rectangle (in the plane z = 0, lit downwards and, if the table has upward light,
    upwards), box, disk, cylinder (axis z), sphere; ``length`` along x (C0–C180),
    ``width`` along y (C90–C270), ``height`` along z; a disk's, a cylinder's and a
    sphere's diameter is ``length``.  Centred on the photometric centre, as ``ies2rad``
    places it.  Its luminance along ω is I(ω)/:meth:`projected_area` (ω)
    (:mod:`lbl_illum.engine.luminous_openings`)."""

    shape: str
    length: float = 0.0
    width: float = 0.0
    height: float = 0.0

    def projected_area(self, directions: np.ndarray) -> np.ndarray:
        """(n,) area [m²] the opening shows along unit ``directions`` (n, 3) (0 for a
        point), as Radiance's ``source.cal`` projects its box, cylinder and flat sources."""
        d = np.abs(np.asarray(directions, np.float64))
        L, W, H = self.length, self.width, self.height
        if self.shape == "point":
            return np.zeros(len(d))
        if self.shape == "rectangle":
            return L * W * d[:, 2]
        if self.shape == "box":
            return d[:, 0] * W * H + d[:, 1] * L * H + d[:, 2] * L * W
        if self.shape == "disk":
            return math.pi / 4 * L * L * d[:, 2]
        if self.shape == "cylinder":
            return L * H * np.sqrt(np.maximum(0.0, 1.0 - d[:, 2] ** 2)) + math.pi / 4 * L * L * d[:, 2]
        return np.full(len(d), math.pi / 4 * L * L)            # sphere


@dataclass(frozen=True)
class Photometry:
    """A luminaire's luminous intensity distribution (module text).

    ``kind`` "C" or "B"; ``horizontal`` the C (or B: H) angles [deg] of the table's rows
    after completion by symmetry, ascending; ``vertical`` the γ (or V) angles [deg],
    ascending; ``candela`` (rows, columns) [cd] with every factor of the file applied;
    ``symmetry`` (type C) a key of :data:`SYMMETRIES`, (type B) "none" or "lateral"
    (I(H) = I(−H)); ``lamp_lumens`` the rated lamp flux [lm] (None: absolute
    photometry).
    """

    name: str
    kind: str
    horizontal: np.ndarray
    vertical: np.ndarray
    candela: np.ndarray
    symmetry: str
    opening: LuminousOpening
    lamp_lumens: float | None = None
    watts: float | None = None
    #: what the reader passed over that the user should hear of (one line each, naming
    #: the file and line), e.g. keywords LM-63 does not define
    notes: tuple[str, ...] = ()

    def angles(self, directions: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(horizontal, vertical) angles [deg] of unit emission ``directions`` (n, 3) in
        the luminaire's frame, folded into the table's range by its symmetry."""
        e = np.asarray(directions, np.float64)
        if self.kind == "B":
            h = np.degrees(np.arctan2(-e[:, 1], -e[:, 2]))
            v = np.degrees(np.arcsin(np.clip(e[:, 0], -1.0, 1.0)))
            return (np.abs(h) if self.symmetry == "lateral" else h), v
        v = np.degrees(np.arccos(np.clip(-e[:, 2], -1.0, 1.0)))
        c = np.mod(np.degrees(np.arctan2(e[:, 1], e[:, 0])), 360.0)
        if self.symmetry == "axial":
            c = np.zeros_like(c)
        elif self.symmetry == "quadrant":
            c = np.where(c > 180.0, 360.0 - c, c)
            c = np.where(c > 90.0, 180.0 - c, c)
        elif self.symmetry == "c0-c180":
            c = np.where(c > 180.0, 360.0 - c, c)
        elif self.symmetry == "c90-c270":
            c = np.where(c < 90.0, 180.0 - c, np.where(c > 270.0, 540.0 - c, c))
        return c, v

    def intensity(self, directions: np.ndarray) -> np.ndarray:
        """(n,) luminous intensity [cd] along unit emission ``directions`` (n, 3) in the
        luminaire's frame: bilinear in the table's angles, 0 beyond its vertical range."""
        h, v = self.angles(directions)
        I = _bilinear(self.horizontal, self.vertical, self.candela, h, v)
        if self.kind == "B":            # the planes cover the front half only
            I[(h < self.horizontal[0] - ANGLE_TOLERANCE) | (h > self.horizontal[-1] + ANGLE_TOLERANCE)] = 0.0
        return I

    def direction(self, horizontal, vertical) -> np.ndarray:
        """(n, 3) unit emission directions in the luminaire's frame at the given angles
        [deg] (the inverse of :meth:`angles` before folding)."""
        h, v = np.radians(np.asarray(horizontal, np.float64)), np.radians(np.asarray(vertical, np.float64))
        if self.kind == "B":
            return np.stack([np.sin(v), -np.cos(v) * np.sin(h), -np.cos(v) * np.cos(h)], axis=-1)
        return np.stack([np.sin(v) * np.cos(h), np.sin(v) * np.sin(h), -np.cos(v)], axis=-1)

    def flux(self, steps: int = 720) -> float:
        """Luminaire flux Φ = ∫ I dω [lm], by the midpoint rule on ``steps`` × 2·``steps``
        cells of equal angle (interpolation included, so it is the flux of what is lit)."""
        t = (np.arange(steps) + 0.5) * math.pi / steps
        p = (np.arange(2 * steps) + 0.5) * math.pi / steps
        T, P = np.meshgrid(t, p, indexing="ij")
        d = np.stack([np.sin(T) * np.cos(P), np.sin(T) * np.sin(P), -np.cos(T)], axis=-1).reshape(-1, 3)
        w = (np.sin(T) * (math.pi / steps) ** 2).ravel()
        return float(np.sum(self.intensity(d) * w))


def _cell(nodes, x):
    """Per value of x, the interval of the ascending ``nodes`` holding it (clamped at the
    ends): its first and last node and x's fraction along it (one node: 0, 0, 0)."""
    if len(nodes) == 1:
        zero = np.zeros(len(x), np.int64)
        return zero, zero, np.zeros(len(x))
    xc = np.clip(x, nodes[0], nodes[-1])
    i = np.clip(np.searchsorted(nodes, xc, side="right") - 1, 0, len(nodes) - 2)
    return i, i + 1, (xc - nodes[i]) / (nodes[i + 1] - nodes[i])


def _bilinear(rows, cols, table, r, c):
    """Bilinear interpolation of ``table`` (len(rows), len(cols)) at (r, c); 0 outside the
    columns' range, rows clamped (a single row: no dependence on r)."""
    out = np.zeros(len(r))
    inside = (c >= cols[0] - ANGLE_TOLERANCE) & (c <= cols[-1] + ANGLE_TOLERANCE)
    cj, cj1, fc = _cell(cols, c)
    ri, ri1, fr = _cell(rows, r)
    value = ((1 - fr) * ((1 - fc) * table[ri, cj] + fc * table[ri, cj1])
             + fr * ((1 - fc) * table[ri1, cj] + fc * table[ri1, cj1]))
    out[inside] = value[inside]
    return out


# ---------------------------------------------------------------------------
# Reading
# ---------------------------------------------------------------------------

def read_photometry(path: str | Path) -> Photometry:
    """The :class:`Photometry` of an IES LM-63 (``.ies``) or EULUMDAT (``.ldt``) file,
    told apart by the extension (any other: by the content, IES if it has a ``TILT=``
    line).  Every problem is an :class:`InputError` naming the file and line."""
    path = Path(path)
    text = read_text_file(path, " photometric", latin1=True)
    name = path.name
    is_ldt = path.suffix.lower() == ".ldt" or (path.suffix.lower() != ".ies" and "TILT=" not in text.upper())
    photometry = _read_ldt(text, name) if is_ldt else _read_ies(text, name)
    if not np.any(photometry.candela > 0.0):
        raise InputError(f"{name}: every intensity is zero: the luminaire gives no light")
    return photometry


def _parse(tok: str, name: str, line: int, what: str) -> float:
    """The finite number ``tok`` on ``line`` of file ``name``, else an error naming both."""
    try:
        value = float(tok)
    except ValueError:
        raise InputError(f"{name}: line {line}: {what} must be a number, got '{tok[:30]}'") from None
    if not math.isfinite(value):
        raise InputError(f"{name}: line {line}: {what} must be finite, got '{tok[:30]}'")
    return value


class _Numbers:
    """The numbers of a text from a given line on, each with its line number."""

    def __init__(self, lines: list[str], start: int, name: str):
        self.name = name
        self.items = [(tok, i + 1) for i in range(start, len(lines))
                      for tok in re.split(r"[\s,]+", lines[i].strip()) if tok]
        self.k = 0
        self.last_line = len(lines)

    def line(self) -> int:
        return self.items[self.k][1] if self.k < len(self.items) else self.last_line

    def number(self, what: str) -> float:
        if self.k >= len(self.items):
            raise InputError(f"{self.name}: line {self.last_line}: the file ends before {what}")
        tok, line = self.items[self.k]
        value = _parse(tok, self.name, line, what)
        self.k += 1
        return value

    def integer(self, what: str, minimum: int | None = None) -> int:
        line = self.line()
        value = self.number(what)
        if value != int(value) or (minimum is not None and value < minimum):
            bound = f" of at least {minimum}" if minimum is not None else ""
            raise InputError(f"{self.name}: line {line}: {what} must be a whole number{bound}, got {value:g}")
        return int(value)

    def array(self, n: int, what: str) -> tuple[np.ndarray, int]:
        line = self.line()
        return np.array([self.number(f"{what} ({j + 1} of {n})") for j in range(n)]), line


def _ascending(angles: np.ndarray, name: str, line: int, what: str) -> None:
    if len(angles) > 1 and np.any(np.diff(angles) <= 0.0):
        raise InputError(f"{name}: line {line}: the {what} must increase, got {_list(angles)}")


def _list(values) -> str:
    text = " ".join(f"{v:g}" for v in values[:8])
    return text + (" ..." if len(values) > 8 else "")


def _near(a: float, b: float) -> bool:
    return abs(a - b) <= ANGLE_TOLERANCE


def _read_ies(text: str, name: str) -> Photometry:
    lines = text.splitlines()
    tilt = next((i for i, line in enumerate(lines) if line.strip().upper().startswith("TILT")), None)
    if tilt is None:
        raise InputError(f"{name}: no 'TILT=' line: not an IES LM-63 file")
    first = lines[0].strip().upper() if lines else ""
    year = 1986
    match = re.search(r"LM-63-(\d{4})", first) or (re.match(r"IESNA\s*:?\s*(\d{2})\b", first))
    if match:
        y = int(match.group(1))
        year = y if y > 100 else 1900 + y
    setting = lines[tilt].split("=", 1)[1].strip() if "=" in lines[tilt] else ""
    nums = _Numbers(lines, tilt + 1, name)
    if setting.upper() == "INCLUDE":
        nums.integer("the lamp-to-luminaire geometry", 1)
        n = nums.integer("the number of tilt angles", 0)
        nums.array(n, "a tilt angle")
        factors, line = nums.array(n, "a tilt factor")
        if np.any(np.abs(factors - 1.0) > 1e-9):
            raise InputError(f"{name}: line {line}: TILT=INCLUDE with factors other than 1 "
                             "(light output that changes with the lamp's tilt) is not supported; "
                             "give the photometry of the luminaire as aimed")
    elif setting.upper() != "NONE":
        raise InputError(f"{name}: line {tilt + 1}: TILT={setting[:40]}: a separate tilt file is not supported; "
                         "use TILT=NONE (or TILT=INCLUDE with the data in the file)")
    nums.integer("the number of lamps", 1)
    line = nums.line()
    lumens = nums.number("the lumens per lamp")
    if lumens == 0.0:
        raise InputError(f"{name}: line {line}: the lumens per lamp must be > 0, or -1 for absolute photometry, "
                         "got 0")
    line = nums.line()
    multiplier = nums.number("the candela multiplier")
    if multiplier <= 0.0:
        raise InputError(f"{name}: line {line}: the candela multiplier must be > 0, got {multiplier:g}")
    n_v = nums.integer("the number of vertical angles", 1)
    n_h = nums.integer("the number of horizontal angles", 1)
    line = nums.line()
    ptype = nums.integer("the photometric type (1 = C, 2 = B, 3 = A)")
    if ptype not in (1, 2):
        raise InputError(f"{name}: line {line}: photometric type {ptype} "
                         f"({'type A' if ptype == 3 else 'unknown'}) is not supported (1 = C, 2 = B)")
    line = nums.line()
    units = nums.integer("the units type (1 = feet, 2 = metres)")
    if units not in (1, 2):
        raise InputError(f"{name}: line {line}: units type must be 1 (feet) or 2 (metres), got {units}")
    scale = FEET if units == 1 else 1.0
    width, length, height = (nums.number(w) * scale for w in ("the width", "the length", "the height"))
    line = nums.line()
    ballast = nums.number("the ballast factor")
    if ballast <= 0.0:
        raise InputError(f"{name}: line {line}: the ballast factor must be > 0, got {ballast:g}")
    photometric_factor = nums.number("the ballast-lamp photometric factor")
    watts = nums.number("the input watts")
    vertical, v_line = nums.array(n_v, "a vertical angle")
    horizontal, h_line = nums.array(n_h, "a horizontal angle")
    _ascending(vertical, name, v_line, "vertical angles")
    _ascending(horizontal, name, h_line, "horizontal angles")
    c_line = nums.line()
    values = np.array([nums.number(f"a candela value ({j + 1} of {n_v * n_h})") for j in range(n_v * n_h)])
    if np.any(values < 0.0):
        j = int(np.argmax(values < 0.0))
        raise InputError(f"{name}: line {nums.items[nums.k - n_v * n_h + j][1]}: negative candela value "
                         f"{values[j]:g}")
    if nums.k < len(nums.items):
        tok, line = nums.items[nums.k]
        raise InputError(f"{name}: line {line}: unexpected '{tok[:30]}' after the {n_v * n_h} candela values")
    factor = multiplier * ballast * (photometric_factor if year < 1995 and photometric_factor > 0 else 1.0)
    candela = values.reshape(n_h, n_v) * factor
    kind = "C" if ptype == 1 else "B"
    if kind == "C":
        horizontal, candela, symmetry = _complete_c(horizontal, candela, name, h_line)
        if not (vertical[0] >= -ANGLE_TOLERANCE and vertical[-1] <= 180.0 + ANGLE_TOLERANCE):
            raise InputError(f"{name}: line {v_line}: type C vertical angles must lie in 0..180, "
                             f"got {_list(vertical)}")
    else:
        if not (-90.0 - ANGLE_TOLERANCE <= horizontal[0] and horizontal[-1] <= 90.0 + ANGLE_TOLERANCE
                and -90.0 - ANGLE_TOLERANCE <= vertical[0] and vertical[-1] <= 90.0 + ANGLE_TOLERANCE):
            raise InputError(f"{name}: line {h_line}: type B angles must lie in -90..90, "
                             f"got horizontal {_list(horizontal)}, vertical {_list(vertical)}")
        symmetry = "lateral" if _near(horizontal[0], 0.0) and len(horizontal) > 1 else "none"
    del c_line
    return Photometry(name, kind, horizontal, vertical, candela, symmetry,
                      _ies_opening(width, length, height, name, tilt + 2),
                      None if lumens < 0 else lumens, watts if watts > 0 else None,
                      _keyword_notes(lines[1:tilt], name, year))


#: The keywords of IES LM-63-1995, -2002 and -2019 (user keywords start with "_").
IES_KEYWORDS = frozenset((
    "TEST", "TESTLAB", "TESTDATE", "ISSUEDATE", "MANUFAC", "LUMCAT", "LUMINAIRE", "LAMPCAT", "LAMP",
    "BALLAST", "BALLASTCAT", "MAINTCAT", "DISTRIBUTION", "FLASHAREA", "COLORCONSTANT", "LAMPPOSITION",
    "NEARFIELD", "FILEGENINFO", "SEARCH", "OTHER", "MORE", "DATE", "PHOTOMETRIC_TYPE"))


def _keyword_notes(lines: list[str], name: str, year: int) -> tuple[str, ...]:
    """Notes on the keyword lines between the first line and ``TILT=`` of a file of
    LM-63-1995 or later (files of 1986 have free text there): a line that is no
    ``[KEYWORD] text`` line, or a keyword that the standard does not define and that does
    not start with "_" (a user keyword), is passed over with a note naming its line."""
    if year < 1995:
        return ()
    notes = []
    for i, line in enumerate(lines, start=2):
        text = line.strip()
        if not text:
            continue
        match = re.match(r"\[([^\]]*)\]", text)
        if match is None:
            notes.append(f"{name}: line {i}: not a [KEYWORD] line, passed over: {text[:40]!r}")
        elif not (match.group(1).upper() in IES_KEYWORDS or match.group(1).startswith("_")):
            notes.append(f"{name}: line {i}: unknown keyword [{match.group(1)[:30]}] passed over "
                         "(user keywords start with '_')")
    return tuple(notes)


def _complete_c(horizontal, candela, name, line):
    """The symmetry a type C table's horizontal angles name (LM-63-2002) and the table
    completed to the range it covers (a full table closed at 360°)."""
    first, last = horizontal[0], horizontal[-1]
    if len(horizontal) == 1:
        return np.zeros(1), candela, "axial"
    if _near(first, 0.0) and _near(last, 90.0):
        return horizontal, candela, "quadrant"
    if _near(first, 0.0) and _near(last, 180.0):
        return horizontal, candela, "c0-c180"
    if _near(first, 90.0) and _near(last, 270.0):
        return horizontal, candela, "c90-c270"
    if _near(first, 0.0) and 180.0 < last <= 360.0 + ANGLE_TOLERANCE:
        if not _near(last, 360.0):
            horizontal = np.append(horizontal, 360.0)
            candela = np.vstack([candela, candela[:1]])
        return horizontal, candela, "none"
    raise InputError(f"{name}: line {line}: type C horizontal angles must run 0..90, 0..180, 90..270 or "
                     f"0..360 (or be a single angle), got {_list(horizontal)}")


def _ies_opening(width, length, height, name, line):
    """The luminous opening of LM-63-2002's shape table (negative sizes name round
    shapes).  Shapes this module does not model (ellipses, ellipsoids, horizontal
    cylinders) are an error."""
    w, l, h = width, length, height
    if w == 0 and l == 0 and h == 0:
        return LuminousOpening("point")
    if w > 0 and l > 0 and h >= 0:
        return LuminousOpening("rectangle" if h == 0 else "box", l, w, h)
    # round shapes: the diameter as a negative width, the length the same or (LM-63-1995) 0
    if w < 0 and (l == 0 or (l < 0 and _close(w, l))):
        if h == 0:
            return LuminousOpening("disk", -w, -w, 0.0)
        if h < 0 and _close(h, w):
            return LuminousOpening("sphere", -w, -w, -h)
        if h > 0:
            return LuminousOpening("cylinder", -w, -w, h)
    return _bad_shape(w, l, h, name, line)


def _close(a, b):
    return abs(a - b) <= 1e-6 * max(abs(a), abs(b))


def _bad_shape(w, l, h, name, line):
    raise InputError(f"{name}: line {line}: a luminous opening of width {w:g}, length {l:g}, height {h:g} m "
                     "(an ellipse, ellipsoid or horizontal cylinder, or inconsistent signs) is not supported; "
                     "point, rectangle, box, disk, vertical cylinder and sphere are")


def _read_ldt(text: str, name: str) -> Photometry:
    """EULUMDAT: one field per line (module text)."""
    lines = text.splitlines()

    def field(i: int, what: str) -> str:
        if i >= len(lines):
            raise InputError(f"{name}: line {len(lines)}: the file ends before {what} (line {i + 1})")
        return lines[i].strip()

    def number(i: int, what: str) -> float:
        return _parse(field(i, what).replace(",", "."), name, i + 1, what)

    def integer(i: int, what: str, minimum: int = 0) -> int:
        value = number(i, what)
        if value != int(value) or value < minimum:
            raise InputError(f"{name}: line {i + 1}: {what} must be a whole number of at least {minimum}, "
                             f"got {value:g}")
        return int(value)

    isym = integer(2, "the symmetry indicator Isym")
    if isym > 4:
        raise InputError(f"{name}: line 3: the symmetry indicator Isym must be 0..4, got {isym}")
    mc = integer(3, "the number of C-planes Mc", 1)
    ng = integer(5, "the number of intensities per C-plane Ng", 1)
    mm = 0.001
    length, width = number(15, "the length of the luminous area") * mm, number(16, "the width of the luminous area") * mm
    heights = [number(i, "a height of the luminous area") * mm for i in range(17, 21)]
    factor = number(23, "the conversion factor")
    if factor <= 0.0:
        raise InputError(f"{name}: line 24: the conversion factor must be > 0, got {factor:g}")
    sets = integer(25, "the number of lamp sets", 1)
    flux = 0.0
    watts = 0.0
    for k in range(sets):
        base = 26 + 6 * k
        number(base, "a number of lamps")            # negative: absolute photometry
        f = number(base + 2, "a lamps' total flux")
        if f <= 0.0:
            raise InputError(f"{name}: line {base + 3}: the lamps' flux must be > 0, got {f:g}")
        flux += f
        watts += number(base + 5, "a wattage")
    base = 26 + 6 * sets + 10                        # after the ten direct ratios
    c_angles = np.array([number(base + j, f"C angle {j + 1} of {mc}") for j in range(mc)])
    g_angles = np.array([number(base + mc + j, f"gamma angle {j + 1} of {ng}") for j in range(ng)])
    _ascending(c_angles, name, base + 1, "C angles")
    _ascending(g_angles, name, base + mc + 1, "gamma angles")
    if c_angles[0] < -ANGLE_TOLERANCE or c_angles[-1] >= 360.0 - ANGLE_TOLERANCE:
        raise InputError(f"{name}: line {base + 1}: C angles must lie in 0..360 (360 excluded), got {_list(c_angles)}")
    if g_angles[0] < -ANGLE_TOLERANCE or g_angles[-1] > 180.0 + ANGLE_TOLERANCE:
        raise InputError(f"{name}: line {base + mc + 1}: gamma angles must lie in 0..180, got {_list(g_angles)}")
    start = 0
    if isym == 0:
        rows, symmetry = mc, "none"
    elif isym == 1:
        rows, symmetry = 1, "axial"
    elif isym == 2:
        rows, symmetry = mc // 2 + 1, "c0-c180"
    elif isym == 3:
        rows, symmetry = mc // 2 + 1, "c90-c270"
        start = int(np.searchsorted(c_angles, 90.0 - ANGLE_TOLERANCE))
    else:
        rows, symmetry = mc // 4 + 1, "quadrant"
    first = base + mc + ng
    count = rows * ng
    values = np.array([number(first + j, f"intensity {j + 1} of {count}") for j in range(count)])
    if np.any(values < 0.0):
        j = int(np.argmax(values < 0.0))
        raise InputError(f"{name}: line {first + j + 1}: negative intensity {values[j]:g}")
    table = values.reshape(rows, ng) * factor * flux / 1000.0
    if symmetry == "axial":
        horizontal = np.zeros(1)
    else:
        if start + rows > mc:
            raise InputError(f"{name}: line {base + 1}: the C angles do not hold the {rows} planes Isym {isym} stores")
        horizontal = c_angles[start:start + rows]
        lo, hi = SYMMETRIES[symmetry]
        if symmetry == "none":
            horizontal = np.append(horizontal, 360.0)
            table = np.vstack([table, table[:1]])
        if not (_near(horizontal[0], lo) and _near(horizontal[-1], hi)):
            raise InputError(f"{name}: line {base + 1}: Isym {isym} stores the planes C{lo:g}..C{hi:g}, "
                             f"but the C angles give C{horizontal[0]:g}..C{horizontal[-1]:g}")
    if length > 0 and width > 0:
        opening = LuminousOpening("rectangle" if max(heights) == 0 else "box", length, width, max(heights))
    elif length > 0:
        opening = LuminousOpening("disk" if max(heights) == 0 else "cylinder", length, length, max(heights))
    else:
        opening = LuminousOpening("point")
    return Photometry(name, "C", horizontal, g_angles, table, symmetry, opening, flux, watts or None)

"""Camera views with Radiance's meaning of every option, and the rays of their pixels.

A :class:`View` is Radiance's ``VIEW`` (``src/common/view.h`` and ``image.c`` in the
Radiance sources; the ``rpict`` manual page; Larson & Shakespeare, *Rendering with
Radiance*, 1998, ch. 2), so a designer's Radiance view gives the same picture here:

==========  ==========================  ===============================================
option      field                       meaning
==========  ==========================  ===============================================
``-vt?``    ``type``                    ``v`` perspective, ``a`` angular fisheye,
                                        ``l`` parallel, ``h`` hemispherical fisheye,
                                        ``c`` cylindrical panorama
``-vp``     ``position`` [m]            eye point (centre of a parallel view)
``-vd``     ``direction``               view direction (its length is kept, unused)
``-vu``     ``up``                      view up vector (need not be normal to ``-vd``)
``-vh``     ``horizontal`` [° or m]     horizontal size of the view
``-vv``     ``vertical`` [° or m]       vertical size of the view
``-vs``     ``shift``                   image shifted right by this many image widths
``-vl``     ``lift``                    image lifted by this many image heights
``-vo``     ``fore`` [m]                fore clipping distance (rays start there)
``-va``     ``aft`` [m]                 aft clipping distance (0: none)
==========  ==========================  ===============================================

Frame (``setview()``): ``d`` = unit ``direction``; right ``r`` = unit(``d`` × ``up``);
image up ``u`` = ``r`` × ``d``.  Image coordinates ``(x, y)`` run over [0, 1]² from the
left and from the bottom edge of the image; with ``X = x + shift − ½``,
``Y = y + lift − ½`` the ray through ``(x, y)`` is (``viewray()``):

* ``v`` perspective: direction ∝ ``d + X·2tan(h/2)·r + Y·2tan(v/2)·u`` — the image
  plane one unit in front of the eye spans ``2·tan(h/2)`` by ``2·tan(v/2)``
  (``h``, ``v`` < 180°).  Origin ``position + fore·(that unnormalised vector)``, i.e.
  on the plane at distance ``fore`` along ``d``.
* ``l`` parallel: direction ``d``; origin ``position + fore·d + X·h·r + Y·v·u`` —
  ``-vh`` and ``-vv`` are the width and height of the view in metres.
* ``a`` angular fisheye: with ``x' = X·h/180``, ``y' = Y·v/180`` and
  ``ρ = √(x'² + y'²)``, the angle from ``d`` is ``π·ρ``, linear in the image radius:
  ``-vh 180 -vv 180`` puts a hemisphere in the inscribed circle, 360 the whole
  sphere.  Direction ``cos(πρ)·d + sin(πρ)/ρ·(x'·r + y'·u)``; pixels with ``ρ > 1``
  see nothing (invalid).  The corners of a 180° image lie outside the hemisphere's
  circle but are valid rays that look behind the view direction, as in ``rpict``.
* ``h`` hemispherical fisheye (orthographic projection of the hemisphere): direction
  ``√(1 − a² − b²)·d + a·r + b·u`` with ``a = X·2sin(h/2)``, ``b = Y·2sin(v/2)``;
  ``h = v = 180`` fills the inscribed circle with the hemisphere, pixels with
  ``a² + b² > 1`` are invalid.
* ``c`` cylindrical panorama: azimuth ``X·h`` degrees about ``u``, height as a
  perspective view: direction ∝ ``cos(X·h)·d + sin(X·h)·r + Y·2tan(v/2)·u``.

Fore clipping moves each origin ``fore`` along its (unnormalised, as above) direction;
:meth:`View.aft_distances` gives the distance at which the aft plane ends each ray.
Radiance's planispheric fisheye (``-vts``) is not supported.

Pixels.  Images are arrays ``(y_res, x_res, 3)`` whose row 0 is the *top* row and
column 0 the *left* column — the order in which Radiance writes a picture
(``-Y y_res +X x_res``) and in which OpenImageIO and image viewers hold one.  Pixel
``(i, j)`` covers image coordinates ``x ∈ [j, j+1)/x_res``,
``y ∈ [y_res−1−i, y_res−i)/y_res``.  :meth:`View.rays` returns the rays of every pixel
and sample in that order (sample index fastest).

Resolution.  As in ``rpict``, ``-x`` and ``-y`` are maxima: :meth:`View.resolution`
reduces one of them so that pixels are square (pixel aspect 1) for the view's own
aspect ``√(vn2/hn2)`` (``normaspect()``): an 80° × 60° perspective view asked for
512 × 512 gives 512 × 352.

Sources of a view: :func:`view_from_string` (a Radiance option string),
:func:`view_from_file` (a ``.vf`` file as ``rvu`` writes it, or the header of a Radiance
picture), :func:`view_from_table` / :func:`views_from_table` (``[views.NAME]`` tables of
a scene file).  Bad input raises :class:`~lbl_illum.errors.InputError` with a one-line
message naming the file, option or key.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, fields, replace
from functools import cached_property
from pathlib import Path
from typing import Any, Mapping

import numpy as np

from ..errors import InputError, check_keys, get_number, get_vector
from .geometry import MAX_COORDINATE

__all__ = ["View", "VIEW_TYPES", "TYPE_NAMES", "view_from_string", "view_from_file",
           "view_from_header", "view_from_table", "views_from_table", "view_lines", "sample_offsets"]

#: Radiance's view type letters and what they are.
VIEW_TYPES = {"v": "perspective", "l": "parallel", "a": "angular fisheye",
              "h": "hemispherical fisheye", "c": "cylindrical panorama"}
#: Names accepted for ``type`` in a ``[views.NAME]`` table (the letters are accepted too).
TYPE_NAMES = {"perspective": "v", "parallel": "l", "fisheye": "a", "angular": "a",
              "hemispherical": "h", "cylindrical": "c"}
#: Radiance's tolerance in ``setview()`` (``FTINY`` in ``rtmath.h``).
FTINY = 1e-6
#: First words of the header or ``.vf`` lines that carry view options (Radiance's
#: ``isview()``, plus the programs whose command lines carry views).
VIEW_LINE_WORDS = ("VIEW=", "rvu", "rpict", "rpiece", "pinterp", "rtrace", "vwrays", "rholo", "rview")
#: Options of each kind and the count of numbers they take.
_OPTION_ARGS = {"p": 3, "d": 3, "u": 3, "h": 1, "v": 1, "o": 1, "a": 1, "s": 1, "l": 1}
_OPTION_FIELDS = {"p": "position", "d": "direction", "u": "up", "h": "horizontal",
                  "v": "vertical", "o": "fore", "a": "aft", "s": "shift", "l": "lift"}
#: Golden-ratio conjugate: the second coordinate of the pixel-sample lattice.
_GOLDEN = (math.sqrt(5.0) - 1.0) / 2.0
#: Each field's Radiance option, for messages.
_FIELD_OPTIONS = {field: f"-v{letter}" for letter, field in _OPTION_FIELDS.items()}
#: Largest eye coordinate, fore clipping distance and parallel view size [m]: the extent of
#: any scene (:data:`lbl_illum.scene.geometry.MAX_COORDINATE`; twice that for a view's size).
MAX_VIEW_COORDINATE = MAX_COORDINATE
#: Largest image shift or lift (``-vs``, ``-vl``) in image widths or heights.  Radiance sets
#: no limit; rpiece's tiles use shifts of up to half their count.  Beyond this the rays of a
#: perspective view would come near the float range.
MAX_IMAGE_OFFSET = 1e6


def _unit(v: np.ndarray) -> np.ndarray:
    """``v`` / |v|, computed after dividing by the largest component, so that a vector of
    any finite, non-zero size gives its direction (neither |v|² overflowing at 1e200 nor
    underflowing at 1e-200); zero for a zero vector."""
    v = np.asarray(v, dtype=np.float64)
    big = float(np.max(np.abs(v))) if v.size else 0.0
    if not big > 0.0:
        return np.zeros_like(v)
    w = v / big
    return w / np.linalg.norm(w)


def _a(noun: str) -> str:
    """``noun`` with its indefinite article."""
    return f"{'an' if noun[:1] in 'aeiou' else 'a'} {noun}"


def _number_text(value: float) -> str:
    """Shortest text that reads back to the same float (``2`` for 2.0)."""
    value = float(value) + 0.0          # no negative zero
    text = repr(value)
    return text[:-2] if text.endswith(".0") else text


@dataclass(frozen=True)
class View:
    """A camera view with Radiance's meaning of each field (see the module text).

    Parameters
    ----------
    type : str
        ``"v"``, ``"l"``, ``"a"``, ``"h"`` or ``"c"`` (Radiance's ``-vt`` letter).
    position : (3,) float
        Eye point [m] (``-vp``).
    direction : (3,) float
        View direction (``-vd``), any non-zero length.
    up : (3,) float
        Up vector (``-vu``), not parallel to ``direction``.
    horizontal, vertical : float
        View size [°], or [m] for a parallel view (``-vh``, ``-vv``).
    shift, lift : float
        Image offsets in image widths and heights (``-vs``, ``-vl``).
    fore, aft : float
        Fore and aft clipping distances [m] (``-vo``, ``-va``; aft 0 means none).

    The defaults are Radiance's standard view (``STDVIEW``): a 45° × 45° perspective from
    the origin looking north (+y) with +z up.
    """

    type: str = "v"
    position: tuple = (0.0, 0.0, 0.0)
    direction: tuple = (0.0, 1.0, 0.0)
    up: tuple = (0.0, 0.0, 1.0)
    horizontal: float = 45.0
    vertical: float = 45.0
    shift: float = 0.0
    lift: float = 0.0
    fore: float = 0.0
    aft: float = 0.0

    def __post_init__(self):
        for name in ("position", "direction", "up"):
            value = tuple(float(v) for v in getattr(self, name))
            object.__setattr__(self, name, value)
        for name in ("horizontal", "vertical", "shift", "lift", "fore", "aft"):
            object.__setattr__(self, name, float(getattr(self, name)))
        problem = self.problem()
        if problem:
            raise InputError(f"view: {problem}")

    # -- checks and frame --------------------------------------------------------

    def problem(self) -> str | None:
        """What makes the view illegal (Radiance's ``setview()`` checks), or None."""
        if len(self.position) != 3 or len(self.direction) != 3 or len(self.up) != 3:
            return "position, direction and up need 3 numbers each"
        for name, option in _FIELD_OPTIONS.items():
            value = getattr(self, name)
            if not all(math.isfinite(v) for v in (value if isinstance(value, tuple) else (value,))):
                shown = " ".join(f"{v:g}" for v in value) if isinstance(value, tuple) else f"{value:g}"
                return f"{option} ({name}) must be finite, got {shown}"
        if self.type not in VIEW_TYPES:
            return f"unknown view type '{self.type}' (valid: {', '.join(VIEW_TYPES)})"
        far = [v for v in self.position if abs(v) > MAX_VIEW_COORDINATE]
        if far:
            return f"-vp (position) {far[0]:g} m is beyond ±{MAX_VIEW_COORDINATE:g} m"
        for name in ("shift", "lift"):
            if abs(getattr(self, name)) > MAX_IMAGE_OFFSET:
                return (f"{_FIELD_OPTIONS[name]} ({name}) {getattr(self, name):g} image "
                        f"{'widths' if name == 'shift' else 'heights'} is beyond ±{MAX_IMAGE_OFFSET:g}")
        if self.fore < -FTINY or self.aft < -FTINY or (self.aft > FTINY and self.aft <= self.fore):
            return f"illegal fore/aft clipping distances -vo {self.fore:g} -va {self.aft:g}"
        if self.fore > MAX_VIEW_COORDINATE:
            return f"-vo (fore) {self.fore:g} m is beyond {MAX_VIEW_COORDINATE:g} m"
        d = _unit(self.direction)
        u = _unit(self.up)
        if not d.any():
            return "zero view direction (-vd)"
        if not u.any():
            return "zero view up vector (-vu)"
        if np.linalg.norm(np.cross(d, u)) <= FTINY:
            return "view up (-vu) parallel to view direction (-vd)"
        h, v, t = self.horizontal, self.vertical, self.type
        if h <= FTINY:
            return f"illegal horizontal view size -vh {h:g}"
        if v <= FTINY:
            return f"illegal vertical view size -vv {v:g}"
        limit_h = {"v": 180.0, "c": 360.0, "a": 360.0, "h": 180.0}.get(t)
        limit_v = {"v": 180.0, "c": 180.0, "a": 360.0, "h": 180.0}.get(t)
        open_h = t == "v"
        open_v = t in "vc"
        if limit_h is not None and (h >= limit_h - FTINY if open_h else h > limit_h + FTINY):
            return (f"illegal horizontal view size -vh {h:g} for {_a(VIEW_TYPES[t])} view "
                    f"({'below' if open_h else 'at most'} {limit_h:g} degrees)")
        if limit_v is not None and (v >= limit_v - FTINY if open_v else v > limit_v + FTINY):
            return (f"illegal vertical view size -vv {v:g} for {_a(VIEW_TYPES[t])} view "
                    f"({'below' if open_v else 'at most'} {limit_v:g} degrees)")
        if t == "l" and max(h, v) > 2.0 * MAX_VIEW_COORDINATE:
            return (f"illegal {'horizontal' if h > v else 'vertical'} view size {'-vh' if h > v else '-vv'} "
                    f"{max(h, v):g} m for a parallel view (beyond {2.0 * MAX_VIEW_COORDINATE:g} m)")
        return None

    @cached_property
    def _frame(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, float, float]:
        """(unit direction, right, image up, horizontal scale, vertical scale).

        The scales are the lengths of Radiance's ``hvec`` and ``vvec`` (``√hn2``,
        ``√vn2``): the extent of the image in the projection's own measure.
        """
        d = _unit(np.asarray(self.direction, dtype=np.float64))
        r = _unit(np.cross(d, np.asarray(self.up, dtype=np.float64)))
        u = np.cross(r, d)
        h, v = self.horizontal, self.vertical
        if self.type == "l":
            sh, sv = h, v
        elif self.type == "v":
            sh, sv = 2.0 * math.tan(math.radians(h) / 2), 2.0 * math.tan(math.radians(v) / 2)
        elif self.type == "c":
            sh, sv = math.radians(h), 2.0 * math.tan(math.radians(v) / 2)
        elif self.type == "a":
            sh, sv = math.radians(h), math.radians(v)
        else:  # "h"
            sh, sv = 2.0 * math.sin(math.radians(h) / 2), 2.0 * math.sin(math.radians(v) / 2)
        return d, r, u, sh, sv

    @property
    def unit_direction(self) -> np.ndarray:
        """(3,) unit view direction."""
        return self._frame[0].copy()

    @property
    def right(self) -> np.ndarray:
        """(3,) unit vector to the right of the image (Radiance's ``hvec`` direction)."""
        return self._frame[1].copy()

    @property
    def image_up(self) -> np.ndarray:
        """(3,) unit vector up the image (Radiance's ``vvec`` direction)."""
        return self._frame[2].copy()

    @property
    def aspect(self) -> float:
        """Height over width of the view, ``√(vn2/hn2)`` (Radiance's ``viewaspect()``)."""
        _, _, _, sh, sv = self._frame
        return sv / sh

    @property
    def type_name(self) -> str:
        """``"perspective"``, ``"angular fisheye"``, ..."""
        return VIEW_TYPES[self.type]

    # -- resolution --------------------------------------------------------------

    def resolution(self, x_max: int, y_max: int, pixel_aspect: float = 1.0) -> tuple[int, int]:
        """Pixel counts ``(x_res, y_res)`` for ``rpict -x x_max -y y_max -pa pixel_aspect``.

        Radiance's ``normaspect()``: the two counts are maxima; one of them is reduced
        (rounded to nearest) so that a pixel's height over width is ``pixel_aspect`` for
        this view's aspect.  ``pixel_aspect = 0`` keeps both maxima (pixels then have the
        aspect ``aspect · x / y``).
        """
        for name, value in (("x", x_max), ("y", y_max)):
            if isinstance(value, bool) or int(value) != value or value < 1:
                raise InputError(f"-{name} resolution must be a positive whole number, got {value!r}")
        x, y = int(x_max), int(y_max)
        if not math.isfinite(pixel_aspect) or pixel_aspect < 0:
            raise InputError(f"pixel aspect must be >= 0, got {pixel_aspect!r}")
        va = self.aspect
        if pixel_aspect <= FTINY:
            return x, y
        if va * x > pixel_aspect * y:
            x = int(y / va * pixel_aspect + 0.5)
        else:
            y = int(x * va / pixel_aspect + 0.5)
        return max(x, 1), max(y, 1)

    # -- rays --------------------------------------------------------------------

    def image_rays(self, x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Rays through image coordinates ``(x, y)`` (Radiance's ``viewray()``, vectorised).

        Parameters
        ----------
        x, y : (n,) float
            Image coordinates in [0, 1]: ``x`` from the left edge, ``y`` from the
            *bottom* edge (Radiance's convention).

        Returns
        -------
        origins : (n, 3) float [m]
        directions : (n, 3) float, unit length
        valid : (n,) bool
            False where the image point sees nothing (outside a fisheye's circle);
            those rays get ``origins = position`` and ``directions`` = the view direction.
        """
        d, r, u, sh, sv = self._frame
        X = np.asarray(x, dtype=np.float64).reshape(-1) + (self.shift - 0.5)
        Y = np.asarray(y, dtype=np.float64).reshape(-1) + (self.lift - 0.5)
        n = X.shape[0]
        eye = np.asarray(self.position, dtype=np.float64)
        valid = np.ones(n, dtype=bool)
        if self.type == "l":
            origins = eye + self.fore * d + (X * sh)[:, None] * r + (Y * sv)[:, None] * u
            directions = np.broadcast_to(d, (n, 3)).copy()
            return origins, directions, valid
        if self.type == "v":
            raw = d + (X * sh)[:, None] * r + (Y * sv)[:, None] * u
        elif self.type == "c":
            azimuth = X * math.radians(self.horizontal)
            raw = np.cos(azimuth)[:, None] * d + np.sin(azimuth)[:, None] * r + (Y * sv)[:, None] * u
        elif self.type == "h":
            a, b = X * sh, Y * sv
            z2 = 1.0 - a * a - b * b
            valid = z2 >= 0.0
            z = np.sqrt(np.where(valid, z2, 0.0))
            raw = z[:, None] * d + a[:, None] * r + b[:, None] * u
        else:  # "a": angle from the view direction linear in image radius
            a = X * (self.horizontal / 180.0)
            b = Y * (self.vertical / 180.0)
            rho = np.sqrt(a * a + b * b)
            valid = rho <= 1.0
            angle = np.pi * np.minimum(rho, 1.0)
            with np.errstate(invalid="ignore", divide="ignore"):
                s = np.where(rho <= FTINY, np.pi, np.sin(angle) / rho)
            raw = np.cos(angle)[:, None] * d + (a * s)[:, None] * r + (b * s)[:, None] * u
        origins = eye + self.fore * raw
        directions = raw / np.linalg.norm(raw, axis=1, keepdims=True)
        if not valid.all():
            bad = ~valid
            origins[bad] = eye
            directions[bad] = d
        return origins, directions, valid

    def pixel_coordinates(self, x_res: int, y_res: int, rng: np.random.Generator | None = None,
                          pixel_samples: int = 1) -> tuple[np.ndarray, np.ndarray]:
        """Image coordinates ``(x, y)`` of every sample, ``(y_res·x_res·pixel_samples,)`` each.

        Order: rows from the top, then columns from the left, then samples.  Sample
        ``k`` of ``s`` sits at the offset :func:`sample_offsets` gives within its pixel;
        with ``rng`` each pixel's pattern is shifted by one uniform random offset, modulo
        the pixel (Cranley–Patterson rotation), so every sample is uniform over its pixel
        — an unbiased pixel average — while the pattern stays stratified.  Without
        ``rng`` one sample per pixel is the pixel's centre, as ``rpict -pj 0``.
        """
        for name, value in (("x_res", x_res), ("y_res", y_res), ("pixel_samples", pixel_samples)):
            if isinstance(value, bool) or int(value) != value or value < 1:
                raise ValueError(f"{name} must be a positive whole number, got {value!r}")
        x_res, y_res, s = int(x_res), int(y_res), int(pixel_samples)
        offsets = sample_offsets(s)                                   # (s, 2)
        col = np.arange(x_res, dtype=np.float64)
        row_from_bottom = (y_res - 1) - np.arange(y_res, dtype=np.float64)
        du = np.broadcast_to(offsets[:, 0], (y_res, x_res, s))
        dv = np.broadcast_to(offsets[:, 1], (y_res, x_res, s))
        if rng is not None:
            shift = rng.random((y_res, x_res, 1, 2))
            du = (du + shift[..., 0]) % 1.0
            dv = (dv + shift[..., 1]) % 1.0
        x = (col[None, :, None] + du) / x_res
        y = (row_from_bottom[:, None, None] + dv) / y_res
        return x.reshape(-1), y.reshape(-1)

    def rays(self, x_res: int, y_res: int, rng: np.random.Generator | None = None,
             pixel_samples: int = 1) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Primary rays of an ``x_res`` × ``y_res`` image.

        Returns ``origins (n, 3)`` [m], unit ``directions (n, 3)`` and ``valid (n,)``
        with ``n = y_res · x_res · pixel_samples`` in the order of
        :meth:`pixel_coordinates` (reshape to ``(y_res, x_res, pixel_samples, 3)``:
        row 0 is the top of the image).  Invalid rays (outside a fisheye's circle) see
        nothing; give those pixels zero.  ``x_res`` and ``y_res`` are used as given —
        call :meth:`resolution` first for rpict's square pixels.
        """
        x, y = self.pixel_coordinates(x_res, y_res, rng, pixel_samples)
        return self.image_rays(x, y)

    def aft_distances(self, directions: np.ndarray) -> np.ndarray:
        """(n,) distance [m] from each ray's origin to the aft clipping plane (``-va``).

        ``inf`` when the view has no aft plane.  As Radiance's ``viewray()``: the plane
        is at ``aft − fore`` along the view direction for perspective rays, along the
        ray for fisheye and parallel rays, and at the same horizontal distance for a
        cylindrical panorama.
        """
        directions = np.asarray(directions, dtype=np.float64).reshape(-1, 3)
        n = directions.shape[0]
        if self.aft <= FTINY:
            return np.full(n, np.inf)
        span = self.aft - self.fore
        d, _, u, _, _ = self._frame
        if self.type == "v":
            return span / np.maximum(directions @ d, FTINY)
        if self.type == "c":
            return span / np.sqrt(np.maximum(1.0 - (directions @ u) ** 2, FTINY))
        return np.full(n, span)

    # -- text --------------------------------------------------------------------

    def options(self) -> str:
        """Radiance view options, all of them, as ``fprintview()`` writes them."""
        f = _number_text
        return (f"-vt{self.type} -vp {' '.join(map(f, self.position))} "
                f"-vd {' '.join(map(f, self.direction))} -vu {' '.join(map(f, self.up))} "
                f"-vh {f(self.horizontal)} -vv {f(self.vertical)} -vo {f(self.fore)} -va {f(self.aft)} "
                f"-vs {f(self.shift)} -vl {f(self.lift)}")

    def to_radiance(self) -> str:
        """The ``VIEW=`` line of a Radiance picture header for this view."""
        return f"VIEW= {self.options()}"

    def replaced(self, **changes: Any) -> "View":
        """A copy with some fields changed (checked again)."""
        return replace(self, **changes)


# ---------------------------------------------------------------------------
# Pixel samples
# ---------------------------------------------------------------------------

def sample_offsets(count: int) -> np.ndarray:
    """(count, 2) offsets in [0, 1)² of the samples within a pixel.

    A rank-1 (Fibonacci) lattice: sample ``k`` at ``((k + ½)/count, frac(½ + k·φ'))``
    with φ' = (√5 − 1)/2, well spread for any count; one sample is the pixel centre.
    """
    k = np.arange(int(count), dtype=np.float64)
    return np.column_stack([(k + 0.5) / count, (0.5 + k * _GOLDEN) % 1.0])


# ---------------------------------------------------------------------------
# Parsing Radiance view options
# ---------------------------------------------------------------------------

#: View options whose numbers are lengths (in the scene's units as typed; metres in a View).
_LENGTHS = ("p", "o", "a")


def _apply_options(tokens: list[str], values: dict, where: str, strict: bool, unit_scale: float = 1.0) -> int:
    """Apply the view options among ``tokens`` to ``values``; return how many were found.

    Recognised options (``-vt?``, ``-vp``, ``-vd``, ``-vu``, ``-vh``, ``-vv``, ``-vo``,
    ``-va``, ``-vs``, ``-vl``) must have their numbers.  Other tokens are errors when
    ``strict``, and skipped one by one otherwise (Radiance's ``sscanview()``, which
    reads views out of command lines with other options in them).  Lengths (``-vp``,
    ``-vo``, ``-va``, and ``-vh``/``-vv`` of a parallel view) are in the scene's units,
    ``unit_scale`` metres each, as everything else the user types.
    """
    found = 0
    given = set()
    i = 0
    while i < len(tokens):
        token = tokens[i]
        if token.startswith("-vt"):
            letter = token[3:]
            if len(letter) != 1:
                raise InputError(f"{where}: bad view type option '{token}' (use -vtv, -vta, -vtl, -vth or -vtc)")
            if letter == "s":
                raise InputError(f"{where}: the planispheric fisheye view (-vts) is not supported")
            if letter not in VIEW_TYPES:
                raise InputError(f"{where}: unknown view type '{token}' (use -vtv, -vta, -vtl, -vth or -vtc)")
            values["type"] = letter
            found += 1
            i += 1
            continue
        key = token[2:] if token.startswith("-v") else None
        if key in _OPTION_ARGS:
            count = _OPTION_ARGS[key]
            args = tokens[i + 1:i + 1 + count]
            numbers = []
            for arg in args:
                try:
                    number = float(arg)
                except ValueError:
                    break
                if not math.isfinite(number):
                    raise InputError(f"{where}: {token} needs finite numbers, got '{arg}'")
                numbers.append(number)
            if len(numbers) != count:
                what = "a number" if count == 1 else f"{count} numbers"
                got = " ".join(args) if args else "nothing"
                raise InputError(f"{where}: {token} needs {what}, got '{got}'")
            if key in _LENGTHS:
                numbers = [x * unit_scale for x in numbers]
            values[_OPTION_FIELDS[key]] = tuple(numbers) if count == 3 else numbers[0]
            given.add(key)
            found += 1
            i += 1 + count
            continue
        if strict:
            if token.startswith("-v"):
                raise InputError(f"{where}: unknown view option '{token}'")
            raise InputError(f"{where}: unexpected '{token}' in a view (options are -vt? -vp -vd -vu -vh -vv "
                             "-vo -va -vs -vl)")
        i += 1
    if values["type"] == "l":              # a parallel view's width and height are lengths
        for key in given & {"h", "v"}:
            values[_OPTION_FIELDS[key]] *= unit_scale
    return found


def _tokens(text: str, where: str) -> list[str]:
    """Words separated by white space (Radiance splits view options on blanks)."""
    return text.split()


def _make_view(values: dict, where: str) -> View:
    try:
        return View(**values)
    except InputError as exc:
        raise InputError(f"{where}: {str(exc).removeprefix('view: ')}") from None


def _is_view_line_word(word: str) -> bool:
    if word.startswith("VIEW="):
        return True
    base = word.replace("\\", "/").rsplit("/", 1)[-1]
    return base in VIEW_LINE_WORDS


def view_from_string(text: str, where: str = "--view", base: View | None = None, unit_scale: float = 1.0) -> View:
    """A view from Radiance view options, e.g. ``"-vtv -vp 2 5.7 1.5 -vd 0 -1 -0.1 -vh 80 -vv 60"``.

    Options not given keep the value of ``base`` (Radiance's standard view by default,
    see :class:`View`).  The text may start with ``VIEW=`` or with the name of a
    Radiance program (``rvu``, ``rpict``, ...); anything else that is not a view option
    is an error naming ``where``.  Lengths are in the scene's units, ``unit_scale``
    metres each (:func:`_apply_options`).
    """
    if not isinstance(text, str):
        raise InputError(f"{where}: a view must be text, got {text!r}")
    body = text.strip()
    if body.startswith("VIEW="):
        body = body[len("VIEW="):]
    tokens = _tokens(body, where)
    if tokens and not tokens[0].startswith("-") and _is_view_line_word(tokens[0]):
        tokens = tokens[1:]
    values = _view_values(base or View())
    if _apply_options(tokens, values, where, strict=True, unit_scale=unit_scale) == 0:
        raise InputError(f"{where}: no view options in {text.strip()!r}")
    return _make_view(values, where)


def _view_values(view: View) -> dict:
    return {f.name: getattr(view, f.name) for f in fields(View)}


def view_lines(header_text: str) -> list[str]:
    """The lines of a Radiance header or ``.vf`` file that carry view options.

    A line counts when its first word is ``VIEW=`` or a Radiance program that takes
    views (``rvu``, ``rpict``, ...; Radiance's ``isview()``), or when it starts with a
    ``-v`` option.
    """
    lines = []
    for line in header_text.splitlines():
        words = line.strip().split(None, 1)
        if not words:
            continue
        if _is_view_line_word(words[0]) or words[0].startswith("-v"):
            lines.append(line.strip())
    return lines


def view_from_file(path: str | os.PathLike, base: View | None = None, unit_scale: float = 1.0) -> View:
    """A view from a ``.vf`` file (as ``rvu`` writes it) or a Radiance picture's header.

    Every view line (see :func:`view_lines`; the first line of a ``.vf`` is usually
    ``rvu -vtv -vp ...``) is applied in turn, so options may be spread over several
    lines and later ones win, as in Radiance's ``viewfile()``.  Other words on those
    lines (``rpict -x 512 ...``) are skipped; a view option without its numbers is an
    error naming the file and line.  A picture's header ends at its first empty line.
    Lengths are in the scene's units, ``unit_scale`` metres each (a ``.vf`` written
    beside a model in feet is in feet).
    """
    path = Path(path)
    name = path.name
    try:
        raw = path.read_bytes()
    except FileNotFoundError:
        raise InputError(f"{name}: no such view file") from None
    except OSError as exc:
        raise InputError(f"{name}: cannot read ({exc.__class__.__name__})") from None
    view = view_from_header(_header_text(raw), name, base, unit_scale)
    if view is None:
        raise InputError(f"{name}: no view found (expected a line like 'rvu -vtv -vp ...' or 'VIEW= -vtv ...')")
    return view


def view_from_header(text: str, where: str, base: View | None = None, unit_scale: float = 1.0) -> View | None:
    """The view carried by the lines of a Radiance header or ``.vf`` text, None if none.

    See :func:`view_from_file` for the rules; ``where`` names the source in messages.
    """
    values = _view_values(base or View())
    found = 0
    for number, line in enumerate(text.splitlines(), start=1):
        words = line.strip().split(None, 1)
        if not words or not (_is_view_line_word(words[0]) or words[0].startswith("-v")):
            continue
        body = line.strip()
        if body.startswith("VIEW="):
            body = body[len("VIEW="):]
        tokens = _tokens(body, f"{where}: line {number}")
        if tokens and not tokens[0].startswith("-"):
            tokens = tokens[1:]                       # the program name
        found += _apply_options(tokens, values, f"{where}: line {number}", strict=False, unit_scale=unit_scale)
    return _make_view(values, where) if found else None


def _header_text(raw: bytes) -> str:
    """Text of a view file, or of a Radiance picture's header (up to its empty line)."""
    if raw.startswith(b"#?"):
        end = raw.find(b"\n\n")
        raw = raw if end < 0 else raw[:end]
    return raw.decode("latin-1")


# ---------------------------------------------------------------------------
# [views.NAME] tables
# ---------------------------------------------------------------------------

#: Keys of a ``[views.NAME]`` table.
VIEW_KEYS = ("type", "position", "direction", "target", "up", "horizontal", "vertical",
             "shift", "lift", "fore", "aft", "radiance")


def view_from_table(table: Mapping[str, Any], where: str, unit_scale: float = 1.0) -> View:
    """A view from one ``[views.NAME]`` table of a scene file.

    Keys (lengths in the scene's units, converted to metres with ``unit_scale``):

    ==============  =============================================================
    ``type``        ``"perspective"`` (default), ``"fisheye"`` (= ``"angular"``),
                    ``"parallel"``, ``"hemispherical"``, ``"cylindrical"``, or
                    Radiance's letter
    ``position``    ``[x, y, z]`` eye point (required)
    ``direction``   ``[dx, dy, dz]`` view direction, or instead
    ``target``      ``[x, y, z]`` a point looked at
    ``up``          ``[ux, uy, uz]``, default ``[0, 0, 1]``
    ``horizontal``  horizontal size [°], or [scene units] for ``parallel`` (required
                    there); default 45 (perspective, cylindrical), 180 (fisheyes)
    ``vertical``    vertical size, default the horizontal one
    ``shift``,      image offsets in image widths / heights (``-vs``, ``-vl``),
    ``lift``        default 0
    ``fore``,       clipping distances [scene units] (``-vo``, ``-va``), default 0
    ``aft``
    ``radiance``    instead of all of the above: Radiance view options as text,
                    e.g. ``"-vta -vp 2 3 1.2 -vd 0 1 0 -vh 180 -vv 180"`` [m]
    ==============  =============================================================
    """
    if not isinstance(table, Mapping):
        raise InputError(f"{where} must be a table, got {table!r}")
    check_keys(table, VIEW_KEYS, where)
    if "radiance" in table:
        others = [k for k in table if k != "radiance"]
        if others:
            raise InputError(f"{where}: 'radiance' gives the whole view; remove '{others[0]}'")
        return view_from_string(table["radiance"], f"{where}: 'radiance'", unit_scale=unit_scale)
    kind = table.get("type", "perspective")
    if not isinstance(kind, str) or (kind not in TYPE_NAMES and kind not in VIEW_TYPES):
        raise InputError(f"{where}: 'type' must be one of {', '.join(TYPE_NAMES)}, got {kind!r}")
    letter = TYPE_NAMES.get(kind, kind)
    position = np.asarray(get_vector(table, "position", where)) * unit_scale
    if ("direction" in table) == ("target" in table):
        raise InputError(f"{where}: give either 'direction' or 'target'")
    if "direction" in table:
        direction = np.asarray(get_vector(table, "direction", where))
    else:
        direction = np.asarray(get_vector(table, "target", where)) * unit_scale - position
        if np.linalg.norm(direction) == 0.0:
            raise InputError(f"{where}: 'target' is the same point as 'position'")
    up = get_vector(table, "up", where) if "up" in table else (0.0, 0.0, 1.0)
    length = unit_scale if letter == "l" else 1.0
    if letter == "l" and "horizontal" not in table:
        raise InputError(f"{where}: missing key 'horizontal' (the width of a parallel view)")
    default = {"v": 45.0, "c": 45.0, "a": 180.0, "h": 180.0}.get(letter)
    horizontal = get_number(table, "horizontal", where, default=default, minimum=0.0, min_inclusive=False)
    vertical = get_number(table, "vertical", where, default=horizontal, minimum=0.0, min_inclusive=False)
    values = dict(
        type=letter, position=tuple(position), direction=tuple(direction), up=tuple(up),
        horizontal=horizontal * length, vertical=vertical * length,
        shift=get_number(table, "shift", where, default=0.0),
        lift=get_number(table, "lift", where, default=0.0),
        fore=get_number(table, "fore", where, default=0.0, minimum=0.0) * unit_scale,
        aft=get_number(table, "aft", where, default=0.0, minimum=0.0) * unit_scale)
    return _make_view(values, where)


def views_from_table(table: Mapping[str, Any] | None, where: str, unit_scale: float = 1.0) -> dict[str, View]:
    """All ``[views.NAME]`` tables of a scene file: ``{NAME: View}`` in file order.

    ``table`` is the scene file's ``views`` table (None when absent); ``where`` names
    the file.  Messages name the table, e.g. ``scene.toml: [views.desk]: ...``.
    """
    if table is None:
        return {}
    if not isinstance(table, Mapping):
        raise InputError(f"{where}: [views] must be a table of named views, got {table!r}")
    return {name: view_from_table(entry, f"{where}: [views.{name}]", unit_scale)
            for name, entry in table.items()}

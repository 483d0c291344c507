"""Sky luminance distributions (docs/design.md §2), one class per model, with a registry.

Directions are unit vectors in the scene frame (+z up, +y north, +x east).  Above
the horizon each model gives the sky luminance; below it every model gives the
ground glow of Radiance's ``gensky`` convention, a uniform luminance
``ρ_g E_gh / π`` where ``E_gh`` is the unobstructed horizontal illuminance from sky
and sun together and ``ρ_g`` the ground reflectance.  Unlike ``gensky`` the sky
and the ground are not blended near the horizon.

A model that depends on the sun's position holds it (``sun_altitude``, ``sun_azimuth``),
so :meth:`Sky.luminance` takes directions only.  Every model states its own unobstructed
horizontal illuminance ``horizontal_illuminance`` E_h [lux]; where that is not a closed
form it is the integral ∫ L cos Z dω over the upper hemisphere, computed once when the
sky is made (:func:`hemisphere_integral`, error below 1e-5 relative).

==================  ==========================================================  ======================
type                luminance above the horizon (Z zenith angle of the          reference
                    direction, χ its angle from the sun, Z_s the sun's)
==================  ==========================================================  ======================
``uniform``         L = E_h / π                                                 —
``cie-overcast``    L = L_z (1 + 2 cos Z) / 3,   E_h = 7 π L_z / 9              Moon & Spencer 1942
                                                                                (CIE traditional
                                                                                overcast sky)
``cie-general``     L = L_z f(χ) φ(Z) / (f(Z_s) φ(0)),                          ISO 15469:2004 /
                    φ(Z) = 1 + a exp(b / cos Z)  (φ = 1 at the horizon),        CIE S 011/E:2003
                    f(χ) = 1 + c (exp(d χ) − exp(d π/2)) + e cos² χ,
                    a…e of ``sky_type`` 1…15 (:data:`CIE_GENERAL_SKY_TYPES`)
``cie-clear``       ``cie-general`` type 12 (CIE standard clear sky)            ISO 15469
``cie-intermediate``  ``cie-general`` type 7 (see :data:`SKY_ALIASES`)          ISO 15469
``perez``           L ∝ (1 + a exp(b / cos Z)) (1 + c exp(d χ) + e cos² χ),     Perez, Seals &
                    a…e from the sky's clearness ε and brightness Δ, scaled     Michalsky 1993
                    so that E_h is the diffuse horizontal illuminance
``none``            0 (and no ground glow)                                      —
==================  ==========================================================  ======================

References
----------
1. P. Moon, D. E. Spencer, "Illumination from a non-uniform sky", Illuminating Engineering
   37, 707–726 (1942).
2. ISO 15469:2004 / CIE S 011/E:2003, *Spatial distribution of daylight — CIE standard general
   sky*; S. Darula, R. Kittler, "CIE general sky standard defining luminance distributions",
   Proc. eSim 2002, Montréal, 11–13.
3. R. Perez, R. Seals, J. Michalsky, "All-weather model for sky luminance distribution —
   preliminary configuration and validation", Solar Energy 50(3), 235–245 (1993); erratum
   Solar Energy 51(5), 423 (1993).
4. R. Perez, P. Ineichen, R. Seals, J. Michalsky, R. Stewart, "Modeling daylight availability
   and irradiance components from direct and global irradiance", Solar Energy 44(5), 271–289
   (1990).
5. Radiance ``gendaylit`` (J.-J. Delaunay 1994, Fraunhofer ISE; G. Ward, J. Wienold) and
   ``gendaymtx`` (I. Ashdown): the Perez model as used in practice, whose conventions
   (Δ ≥ 0.2 for 1.065 < ε < 2.8, cos Z ≥ 0.01, L ≥ 0) this module follows.
6. J. W. Spencer, "Fourier series representation of the position of the Sun", Search 2(5),
   172 (1971): the Sun–Earth distance factor, at most 1.0351 (early January).
7. S. Darula, R. Kittler, C. A. Gueymard, "Reference luminous solar constant and solar
   luminance for illuminance calculations", Solar Energy 79(5), 559–565 (2005): the
   extraterrestrial normal illuminance at the mean distance, 133 334 lx.

Input checks.  Every value of a ``[sky]`` table is a finite number in its range, or the
table is refused naming the key (:class:`~lbl_illum.errors.InputError`).  The CIE skies
are shapes scaled by ``horizontal_illuminance`` (or ``zenith_luminance``), so any finite
value ≥ 0 is accepted.  The Perez inputs are measurements of real daylight on which the
model's ε, Δ and efficacies depend, so they are bounded by what reaches the top of the
atmosphere: direct normal and diffuse horizontal irradiance ≤ :data:`MAX_EXTRATERRESTRIAL_IRRADIANCE`
(1367 W/m² × 1.0351 = 1415 W/m²), illuminance ≤ :data:`MAX_EXTRATERRESTRIAL_ILLUMINANCE`
(133 334 lx × 1.0351 = 138 011 lx).  The sky brightness Δ that results has no such bound
(Δ = E_dh m / E_0 grows with the air mass m, up to 38 at the horizon); the model was fitted
for Δ up to about 0.6 (``gendaylit`` clamps to 0.6 with a warning), and a larger Δ is used
as it is, or refused when it makes the distribution negative everywhere.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from functools import lru_cache
from typing import Any, Mapping

import numpy as np

from ..errors import InputError, check_keys, get_number
from .solar import air_mass_kasten1966, extraterrestrial_normal_irradiance, precipitable_water
from ..photometry import RADIANCE_SKY_EFFICACY, RADIANCE_SUN_EFFICACY, RADIANCE_WHITE_EFFICACY

__all__ = [
    "Sky", "UniformSky", "CIEOvercastSky", "CIEGeneralSky", "PerezSky", "NoSky", "SKY_MODELS", "SKY_ALIASES",
    "SKY_TYPES", "CIE_GENERAL_SKY_TYPES", "PerezParameters", "sky_from_table", "hemisphere_integral",
    "sun_vector", "perez_clearness", "perez_brightness", "perez_coefficients", "perez_coefficients_array",
    "perez_luminous_efficacy", "perez_luminous_efficacy_array",
    "perez_from_irradiance", "perez_from_illuminance", "perez_sky", "perez_sky_from_weather",
]


def sun_vector(altitude: float, azimuth: float) -> np.ndarray:
    """(3,) unit vector towards altitude [°], azimuth [° clockwise from north]."""
    alt, az = math.radians(altitude), math.radians(azimuth)
    return np.array([math.cos(alt) * math.sin(az), math.cos(alt) * math.cos(az), math.sin(alt)])


#: μ = cos Z where the hemisphere rule splits: the Perez gradation is held constant below
#: it (:data:`PEREZ_MIN_COS_ZENITH`), which makes a kink there.
_MU_SPLIT = 0.01


@lru_cache(maxsize=4)
def _hemisphere_rule(n_mu: int, n_az: int) -> tuple[np.ndarray, np.ndarray]:
    """Directions (N, 3) and weights (N,) with Σ w g(d) ≈ ∫ g(d) cos Z dω over the upper
    hemisphere: Gauss–Legendre in μ = cos Z (weight μ folded in) on [0, 0.01] (n_mu/8
    nodes) and [0.01, 1] (n_mu nodes), midpoint rule in azimuth.  The sky models are
    smooth in μ up to the horizon (exp(b/μ) → 0 with all its derivatives for b < 0) and
    periodic in azimuth, so the rule converges fast; the cusp of exp(d χ) at the sun is a
    single point."""
    x, w = np.polynomial.legendre.leggauss(n_mu)
    xs, ws = np.polynomial.legendre.leggauss(max(2, n_mu // 8))
    lo, hi = _MU_SPLIT, 1.0
    mu = np.concatenate([0.5 * lo * (xs + 1.0), lo + 0.5 * (hi - lo) * (x + 1.0)])
    wmu = np.concatenate([0.5 * lo * ws, 0.5 * (hi - lo) * w])
    az = (np.arange(n_az) + 0.5) * (2.0 * np.pi / n_az)
    s = np.sqrt(1.0 - mu * mu)
    d = np.stack([np.outer(s, np.sin(az)), np.outer(s, np.cos(az)), np.repeat(mu[:, None], n_az, axis=1)], axis=-1)
    weights = np.repeat((wmu * mu)[:, None], n_az, axis=1) * (2.0 * np.pi / n_az)
    d, weights = d.reshape(-1, 3), weights.reshape(-1)
    d.setflags(write=False)
    weights.setflags(write=False)
    return d, weights


#: Nodes of the horizontal-illuminance quadrature (μ, azimuth): about 1 ms a sky, and
#: an error below 2e-4 relative on every model (tests/test_sky.py checks against a 4×
#: finer rule).
HEMISPHERE_RULE = (128, 256)


def hemisphere_integral(relative_luminance, rule: tuple[int, int] = HEMISPHERE_RULE) -> float:
    """∫ L(d) cos Z dω over the upper hemisphere of a vectorised ``relative_luminance``
    ((m, 3) directions with z ≥ 0 → (m,)) [lux per unit of L]."""
    d, w = _hemisphere_rule(*rule)
    return float(np.dot(relative_luminance(d), w))


# ---------------------------------------------------------------------------
# Base class and the sun-independent models
# ---------------------------------------------------------------------------

def _set(obj, **values) -> None:
    """Set derived fields of a frozen dataclass in ``__post_init__``."""
    for k, v in values.items():
        object.__setattr__(obj, k, v)


def _check_finite(obj, name: str, minimum: float | None = None, maximum: float | None = None) -> None:
    """Raise ValueError unless field ``name`` of ``obj`` is a finite number within [minimum, maximum]."""
    value = getattr(obj, name)
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)) or \
            not math.isfinite(value):
        raise ValueError(f"{name} must be a finite number, got {value!r}")
    if (minimum is not None and value < minimum) or (maximum is not None and value > maximum):
        bounds = f"within {minimum:g} and {maximum:g}" if minimum is not None and maximum is not None else (
            f">= {minimum:g}" if minimum is not None else f"<= {maximum:g}")
        raise ValueError(f"{name} must be {bounds}, got {value!r}")


@dataclass(frozen=True)
class Sky:
    """Base class.  ``horizontal_illuminance`` is the sky's own unobstructed E_h [lux]."""

    horizontal_illuminance: float = 0.0
    ground_reflectance: float = 0.2
    #: unobstructed horizontal illuminance of the sun, added to the ground glow [lux]
    sun_horizontal_illuminance: float = 0.0

    name = "base"
    #: whether :meth:`sky_luminance` is cheap enough to evaluate on every direction (it must
    #: then accept directions below the horizon, whose values are discarded)
    _cheap = False

    def __post_init__(self):
        _check_finite(self, "horizontal_illuminance", minimum=0.0)
        _check_finite(self, "ground_reflectance", minimum=0.0, maximum=1.0)
        _check_finite(self, "sun_horizontal_illuminance", minimum=0.0)

    @property
    def is_dark(self) -> bool:
        """True when no direction carries light."""
        return self.horizontal_illuminance <= 0.0 and self.ground_luminance <= 0.0

    @property
    def ground_luminance(self) -> float:
        """Uniform luminance below the horizon, ρ_g E_gh / π [cd/m²]."""
        return self.ground_reflectance * (self.horizontal_illuminance + self.sun_horizontal_illuminance) / np.pi

    @property
    def sun_direction(self) -> np.ndarray | None:
        """(3,) unit vector towards the sun that shapes the sky, or None."""
        return None

    @property
    def label(self) -> str:
        """One line for logs and reports."""
        return f"{self.name} sky, E_h {self.horizontal_illuminance:.6g} lux"

    @property
    def parameters(self) -> dict:
        """Everything the sky's luminance depends on, as plain numbers and strings (for
        cache fingerprints and reports)."""
        return {"type": self.name, "horizontal_illuminance": float(self.horizontal_illuminance),
                "ground_reflectance": float(self.ground_reflectance),
                "ground_luminance": float(self.ground_luminance)}

    def sky_luminance(self, directions: np.ndarray) -> np.ndarray:
        """(m,) luminance [cd/m²] along (m, 3) unit directions with z ≥ 0."""
        raise NotImplementedError

    def luminance(self, directions: np.ndarray) -> np.ndarray:
        """(n, 3) RGB luminance [cd/m²] seen along (n, 3) unit ``directions``."""
        d = np.asarray(directions, dtype=np.float64).reshape(-1, 3)
        up = d[:, 2] >= 0.0
        if self._cheap:
            # a formula cheaper than gathering the upward rays: evaluate it everywhere
            lum = np.where(up, self.sky_luminance(d), float(self.ground_luminance))
        else:
            lum = np.full(len(d), float(self.ground_luminance))
            if up.all():
                lum = self.sky_luminance(d)
            elif up.any():
                lum[up] = self.sky_luminance(d[up])
        return np.repeat(lum[:, None], 3, axis=1)


@dataclass(frozen=True)
class UniformSky(Sky):
    """Uniform sky: the same luminance E_h/π in every direction above the horizon."""

    name = "uniform"
    _cheap = True

    @property
    def zenith_luminance(self) -> float:
        return self.horizontal_illuminance / np.pi

    def sky_luminance(self, directions):
        return np.full(len(directions), self.horizontal_illuminance / np.pi)


@dataclass(frozen=True)
class CIEOvercastSky(Sky):
    """CIE traditional overcast sky, L(γ) = L_z (1 + 2 sin γ)/3 with E_h = 7π L_z/9."""

    name = "cie-overcast"
    _cheap = True

    @property
    def zenith_luminance(self) -> float:
        return 9.0 * self.horizontal_illuminance / (7.0 * np.pi)

    def sky_luminance(self, directions):
        return self.zenith_luminance * (1.0 + 2.0 * np.asarray(directions)[:, 2]) / 3.0


@dataclass(frozen=True)
class NoSky(Sky):
    """No sky and no ground glow: an interior lit only by its own sources."""

    name = "none"
    _cheap = True

    @property
    def ground_luminance(self) -> float:
        return 0.0

    def sky_luminance(self, directions):
        return np.zeros(len(directions))


# ---------------------------------------------------------------------------
# CIE standard general sky
# ---------------------------------------------------------------------------

#: ISO 15469:2004 / CIE S 011/E:2003, Table 1: sky type → (a, b, c, d, e, description).
#: Gradation groups I–VI: (a, b) = (4, −0.7), (1.1, −0.8), (0, −1), (−1, −0.55), (−1, −0.32),
#: (−1, −0.15); indicatrix groups 1–6: (c, d, e) = (0, −1, 0), (2, −1.5, 0.15),
#: (5, −2.5, 0.3), (10, −3, 0.45), (16, −3, 0.3), (24, −2.8, 0.15).
CIE_GENERAL_SKY_TYPES = {
    1: (4.0, -0.70, 0.0, -1.0, 0.00, "CIE standard overcast sky, steep luminance gradation towards zenith, "
                                     "azimuthal uniformity"),
    2: (4.0, -0.70, 2.0, -1.5, 0.15, "overcast, with steep luminance gradation and slight brightening "
                                     "towards the sun"),
    3: (1.1, -0.80, 0.0, -1.0, 0.00, "overcast, moderately graded with azimuthal uniformity"),
    4: (1.1, -0.80, 2.0, -1.5, 0.15, "overcast, moderately graded and slight brightening towards the sun"),
    5: (0.0, -1.00, 0.0, -1.0, 0.00, "sky of uniform luminance"),
    6: (0.0, -1.00, 2.0, -1.5, 0.15, "partly cloudy sky, no gradation towards zenith, slight brightening "
                                     "towards the sun"),
    7: (0.0, -1.00, 5.0, -2.5, 0.30, "partly cloudy sky, no gradation towards zenith, brighter circumsolar "
                                     "region"),
    8: (0.0, -1.00, 10.0, -3.0, 0.45, "partly cloudy sky, no gradation towards zenith, distinct solar corona"),
    9: (-1.0, -0.55, 2.0, -1.5, 0.15, "partly cloudy, with the obscured sun"),
    10: (-1.0, -0.55, 5.0, -2.5, 0.30, "partly cloudy, with brighter circumsolar region"),
    11: (-1.0, -0.55, 10.0, -3.0, 0.45, "white-blue sky with distinct solar corona"),
    12: (-1.0, -0.32, 10.0, -3.0, 0.45, "CIE standard clear sky, low luminance turbidity"),
    13: (-1.0, -0.32, 16.0, -3.0, 0.30, "CIE standard clear sky, polluted atmosphere"),
    14: (-1.0, -0.15, 16.0, -3.0, 0.30, "cloudless turbid sky with broad solar corona"),
    15: (-1.0, -0.15, 24.0, -2.8, 0.15, "white-blue turbid sky with broad solar corona"),
}

#: Names for the usual CIE general sky types.  ``cie-clear`` is type 12, the CIE standard
#: clear sky.  ``cie-intermediate`` is type 7, "partly cloudy sky, no gradation towards
#: zenith, brighter circumsolar region": ISO 15469 has no type of that name; 7 is the middle
#: of its partly cloudy (intermediate) types 6–10 with a circumsolar brightening of moderate
#: strength.  (Radiance's ``gensky -i`` is the Matsuura intermediate sky, which is none of
#: the 15 types.)
SKY_ALIASES = {"cie-clear": 12, "cie-intermediate": 7}
#: The CIE standard clear sky (ISO 15469 type 12): the distribution of Radiance's gensky +s
#: (skybright.cal: 0.91 + 10 exp(−3χ) + 0.45 cos² χ is 1 + 10 (exp(−3χ) − exp(−3π/2)) + …)
CLEAR_SKY_TYPE = 12


@dataclass(frozen=True)
class CIEGeneralSky(Sky):
    """CIE standard general sky (ISO 15469:2004 / CIE S 011/E:2003).

    L(Z, χ) = L_z · f(χ) φ(Z) / (f(Z_s) φ(0)) above the horizon, with the gradation
    φ(Z) = 1 + a exp(b / cos Z) (φ(90°) = 1: b < 0 for every type), the indicatrix
    f(χ) = 1 + c (exp(d χ) − exp(d π/2)) + e cos² χ, Z the direction's zenith angle, χ its
    angle from the sun and Z_s the sun's zenith angle.  ``horizontal_illuminance`` E_h
    [lux] fixes the zenith luminance L_z = E_h / ∫ (f φ / f(Z_s) φ(0)) cos Z dω
    (:func:`hemisphere_integral`); :meth:`from_zenith_luminance` goes the other way.

    sky_type : 1…15 (:data:`CIE_GENERAL_SKY_TYPES`)
    sun_altitude, sun_azimuth : [°] the sun that shapes the sky (needed unless the type is
        azimuthally uniform: 1, 3 and 5)
    """

    sky_type: int = 12
    sun_altitude: float | None = None
    sun_azimuth: float | None = None
    zenith_luminance: float = field(init=False, default=0.0)
    _coef: tuple = field(init=False, default=(), repr=False, compare=False)
    _sun: Any = field(init=False, default=None, repr=False, compare=False)
    _norm: float = field(init=False, default=1.0, repr=False, compare=False)
    _scale: float = field(init=False, default=0.0, repr=False, compare=False)

    name = "cie-general"

    def __post_init__(self):
        super().__post_init__()
        if self.sun_altitude is not None:
            _check_finite(self, "sun_altitude", -90.0, 90.0)
        if self.sun_azimuth is not None:
            _check_finite(self, "sun_azimuth")
        if self.sky_type not in CIE_GENERAL_SKY_TYPES:
            raise ValueError(f"sky_type must be 1…15, got {self.sky_type!r}")
        a, b, c, d, e, _ = CIE_GENERAL_SKY_TYPES[self.sky_type]
        if self.sun_altitude is None or self.sun_azimuth is None:
            if c != 0.0 or e != 0.0:
                raise ValueError(f"CIE general sky type {self.sky_type} needs the sun's position")
            sun = np.array([0.0, 0.0, 1.0])
        else:
            sun = sun_vector(self.sun_altitude, self.sun_azimuth)
        _set(self, _coef=(a, b, c, d, e, math.exp(d * math.pi / 2.0)), _sun=sun)
        # f(Z_s) φ(0): the zenith's angle from the sun is Z_s, so L(zenith) = L_z
        _set(self, _norm=float(self.indicatrix(sun[2:3])[0]) * (1.0 + a * math.exp(b)))
        per_lz = hemisphere_integral(self._relative)               # E_h / L_z [sr]
        lz = self.horizontal_illuminance / per_lz
        _set(self, zenith_luminance=lz, _scale=lz / self._norm)

    @classmethod
    def from_zenith_luminance(cls, zenith_luminance: float, **kwargs) -> "CIEGeneralSky":
        """The sky of zenith luminance L_z [cd/m²]; its E_h is computed."""
        unit = cls(horizontal_illuminance=1.0, **kwargs)
        return cls(horizontal_illuminance=zenith_luminance / unit.zenith_luminance, **kwargs)

    @property
    def description(self) -> str:
        return CIE_GENERAL_SKY_TYPES[self.sky_type][5]

    @property
    def sun_direction(self):
        return None if self.sun_altitude is None else self._sun.copy()

    @property
    def label(self) -> str:
        sun = "" if self.sun_altitude is None else (
            f", sun at altitude {self.sun_altitude:.4g}°, azimuth {self.sun_azimuth:.4g}°")
        return (f"CIE general sky type {self.sky_type} ({self.description}), E_h {self.horizontal_illuminance:.6g} "
                f"lux, L_z {self.zenith_luminance:.6g} cd/m²{sun}")

    @property
    def parameters(self) -> dict:
        return {**super().parameters, "sky_type": int(self.sky_type), "sun_altitude": self.sun_altitude,
                "sun_azimuth": self.sun_azimuth}

    @property
    def coefficients(self) -> tuple[float, float, float, float, float]:
        """(a, b, c, d, e) of the type."""
        return tuple(self._coef[:5])

    @property
    def luminance_scale(self) -> float:
        """L_z / (f(Z_s) φ(0)) [cd/m²]: L = scale · f(χ) φ(Z)."""
        return self._scale

    def gradation(self, cos_z: np.ndarray) -> np.ndarray:
        """φ(Z) = 1 + a exp(b / cos Z), exactly 1 at the horizon (cos Z = 0)."""
        a, b = self._coef[:2]
        cz = np.asarray(cos_z, dtype=np.float64)
        with np.errstate(divide="ignore", over="ignore"):
            return 1.0 + a * np.exp(np.where(cz > 0.0, b / np.where(cz > 0.0, cz, 1.0), -np.inf))

    def indicatrix(self, cos_chi: np.ndarray) -> np.ndarray:
        """f(χ) = 1 + c (exp(d χ) − exp(d π/2)) + e cos² χ."""
        a, b, c, d, e, edh = self._coef
        cc = np.clip(np.asarray(cos_chi, dtype=np.float64), -1.0, 1.0)
        return 1.0 + c * (np.exp(d * np.arccos(cc)) - edh) + e * cc * cc

    def _relative(self, directions: np.ndarray) -> np.ndarray:
        """L / L_z along (m, 3) directions above the horizon."""
        return self._scale_free(directions) / self._norm

    def _scale_free(self, directions: np.ndarray) -> np.ndarray:
        """f(χ) φ(Z) along (m, 3) directions above the horizon."""
        a, b, c, d, e, _ = self._coef
        out = np.ones(len(directions))
        if a != 0.0:
            out = out * self.gradation(directions[:, 2])
        if c != 0.0 or e != 0.0:
            out = out * self.indicatrix(directions @ self._sun)
        return out

    def sky_luminance(self, directions):
        d = np.asarray(directions, dtype=np.float64)
        a, b, c, d_, e, edh = self._coef
        out = np.full(len(d), self.luminance_scale)
        if a != 0.0:
            z = d[:, 2]
            with np.errstate(divide="ignore"):
                out *= 1.0 + a * np.exp(b / z)          # z = 0: b / 0 = −inf, φ = 1 exactly (b < 0)
        if c != 0.0 or e != 0.0:
            cos_chi = np.clip(d @ self._sun, -1.0, 1.0)
            out *= 1.0 + c * (np.exp(d_ * np.arccos(cos_chi)) - edh) + e * cos_chi * cos_chi
        return out


# ---------------------------------------------------------------------------
# Perez all-weather sky
# ---------------------------------------------------------------------------

#: Upper bounds of the eight sky-clearness bins of ε (Perez et al. 1990, 1993).
PEREZ_CLEARNESS_BINS = (1.065, 1.230, 1.500, 1.950, 2.800, 4.500, 6.200, math.inf)

#: Perez, Seals & Michalsky (1993), Table 1: for each clearness bin, the coefficients
#: (x1, x2, x3, x4) of x = x1 + x2 Z + Δ (x3 + x4 Z) for x = a, b, c, d, e (Z the solar
#: zenith angle [rad]).  In bin 1, c = exp((Δ (c1 + c2 Z))^c3) − c4 and
#: d = −exp(Δ (d1 + d2 Z)) + d3 + Δ d4.
PEREZ_1993 = np.array([
    # bin 1: 1.000 ≤ ε < 1.065
    [[  1.3525,  -0.2576,  -0.2690,  -1.4366],  # a
     [ -0.7670,   0.0007,   1.2734,  -0.1233],  # b
     [  2.8000,   0.6004,   1.2375,   1.0000],  # c
     [  1.8734,   0.6297,   0.9738,   0.2809],  # d
     [  0.0356,  -0.1246,  -0.5718,   0.9938]],  # e
    # bin 2: 1.065 ≤ ε < 1.230
    [[ -1.2219,  -0.7730,   1.4148,   1.1016],  # a
     [ -0.2054,   0.0367,  -3.9128,   0.9156],  # b
     [  6.9750,   0.1774,   6.4477,  -0.1239],  # c
     [ -1.5798,  -0.5081,  -1.7812,   0.1080],  # d
     [  0.2624,   0.0672,  -0.2190,  -0.4285]],  # e
    # bin 3: 1.230 ≤ ε < 1.500
    [[ -1.1000,  -0.2515,   0.8952,   0.0156],  # a
     [  0.2782,  -0.1812,  -4.5000,   1.1766],  # b
     [ 24.7219, -13.0812, -37.7000,  34.8438],  # c
     [ -5.0000,   1.5218,   3.9229,  -2.6204],  # d
     [ -0.0156,   0.1597,   0.4199,  -0.5562]],  # e
    # bin 4: 1.500 ≤ ε < 1.950
    [[ -0.5484,  -0.6654,  -0.2672,   0.7117],  # a
     [  0.7234,  -0.6219,  -5.6812,   2.6297],  # b
     [ 33.3389, -18.3000, -62.2500,  52.0781],  # c
     [ -3.5000,   0.0016,   1.1477,   0.1062],  # d
     [  0.4659,  -0.3296,  -0.0876,  -0.0329]],  # e
    # bin 5: 1.950 ≤ ε < 2.800
    [[ -0.6000,  -0.3566,  -2.5000,   2.3250],  # a
     [  0.2937,   0.0496,  -5.6812,   1.8415],  # b
     [ 21.0000,  -4.7656, -21.5906,   7.2492],  # c
     [ -3.5000,  -0.1554,   1.4062,   0.3988],  # d
     [  0.0032,   0.0766,  -0.0656,  -0.1294]],  # e
    # bin 6: 2.800 ≤ ε < 4.500
    [[ -1.0156,  -0.3670,   1.0078,   1.4051],  # a
     [  0.2875,  -0.5328,  -3.8500,   3.3750],  # b
     [ 14.0000,  -0.9999,  -7.1406,   7.5469],  # c
     [ -3.4000,  -0.1078,  -1.0750,   1.5702],  # d
     [ -0.0672,   0.4016,   0.3017,  -0.4844]],  # e
    # bin 7: 4.500 ≤ ε < 6.200
    [[ -1.0000,   0.0211,   0.5025,  -0.5119],  # a
     [ -0.3000,   0.1922,   0.7023,  -1.6317],  # b
     [ 19.0000,  -5.0000,   1.2438,  -1.9094],  # c
     [ -4.0000,   0.0250,   0.3844,   0.2656],  # d
     [  1.0468,  -0.3788,  -2.4517,   1.4656]],  # e
    # bin 8: 6.200 ≤ ε < ∞
    [[ -1.0500,   0.0289,   0.4260,   0.3590],  # a
     [ -0.3250,   0.1156,   0.7781,   0.0025],  # b
     [ 31.0625, -14.5000, -46.1148,  55.3750],  # c
     [ -7.2312,   0.4050,  13.3500,   0.6234],  # d
     [  1.5000,  -0.6426,   1.8564,   0.5636]],  # e
])

#: Perez et al. (1990), Table 4: luminous efficacy [lm/W] K = a + b W + c cos Z + d ln Δ of
#: diffuse horizontal light and K = max(0, a + b W + c exp(5.73 Z − 5) + d Δ) of direct
#: normal light, per clearness bin: rows a, b, c, d.
PEREZ_1990_DIFFUSE_EFFICACY = np.array([
    [97.24, 107.22, 104.97, 102.39, 100.71, 106.42, 141.88, 152.23],
    [-0.46, 1.15, 2.96, 5.59, 5.94, 3.83, 1.90, 0.35],
    [12.00, 0.59, -5.53, -13.95, -22.75, -36.15, -53.24, -45.27],
    [-8.91, -3.95, -8.77, -13.90, -23.74, -28.83, -14.03, -7.98],
])
PEREZ_1990_DIRECT_EFFICACY = np.array([
    [57.20, 98.99, 109.83, 110.34, 106.36, 107.19, 105.75, 101.18],
    [-4.55, -3.46, -4.90, -5.84, -3.97, -1.25, 0.77, 1.58],
    [-2.98, -1.21, -1.71, -1.99, -1.75, -1.51, -1.26, -1.10],
    [117.12, 12.38, -8.81, -4.56, -6.16, -26.73, -34.44, -8.29],
])
#: Smallest Δ used in the efficacy model's ln Δ (Radiance's gendaylit: ``skybriginf``).
PEREZ_MIN_BRIGHTNESS = 0.01
#: Δ is raised to this in clearness bins 2–5 (1.065 < ε < 2.8) for the luminance
#: coefficients, as in Radiance's gendaylit and gendaymtx.
PEREZ_BIN2_5_MIN_BRIGHTNESS = 0.2
#: cos Z is not taken below this in the gradation term, as in Radiance's perezlum.cal.
PEREZ_MIN_COS_ZENITH = 0.01
#: The clearness formula's 1.041 Z³ term (Z in radians).
_KAPPA = 1.041


def perez_clearness(diffuse_horizontal: float, direct_normal: float, zenith: float) -> float:
    """Sky clearness ε = ((E_dh + E_dn)/E_dh + κ Z³) / (1 + κ Z³), κ = 1.041, Z the solar
    zenith angle [°] (used in radians), irradiances in W/m² (Perez et al. 1990, eq. 1)."""
    z3 = _KAPPA * math.radians(min(zenith, 90.0)) ** 3
    return ((diffuse_horizontal + direct_normal) / diffuse_horizontal + z3) / (1.0 + z3)


def perez_brightness(diffuse_horizontal: float, zenith: float, day: float | None = None) -> float:
    """Sky brightness Δ = E_dh m / E_0: diffuse horizontal irradiance [W/m²], relative air
    mass m (Kasten 1966) at the solar zenith angle [°], extraterrestrial normal irradiance
    E_0 on day of year ``day`` (None: the mean, 1367 W/m²) (Perez et al. 1990, eq. 2)."""
    return diffuse_horizontal * float(air_mass_kasten1966(zenith)) / extraterrestrial_normal_irradiance(day)


def perez_coefficients_array(epsilon, delta, zenith_rad) -> np.ndarray:
    """(5, n) a…e of Perez et al. (1993) Table 1 for n values of clearness ε, brightness Δ
    and solar zenith angle [rad]: x = x1 + x2 Z + Δ (x3 + x4 Z), Δ raised to 0.2 in bins
    2–5, bin 1's c and d by its own formulas (:func:`perez_coefficients` for one hour)."""
    eps, delta, z = (np.atleast_1d(np.asarray(v, np.float64)) for v in (epsilon, delta, zenith_rad))
    k = np.searchsorted(np.asarray(PEREZ_CLEARNESS_BINS[:7]), eps, side="right")
    delta = np.where((eps > 1.065) & (eps < 2.8), np.maximum(delta, PEREZ_BIN2_5_MIN_BRIGHTNESS), delta)
    x = PEREZ_1993[k]                                                   # (n, 5, 4)
    zz, dd = z[:, None], delta[:, None]
    coef = x[..., 0] + x[..., 1] * zz + dd * (x[..., 2] + x[..., 3] * zz)
    first = k == 0
    if first.any():
        (c1, c2, c3, c4), (d1, d2, d3, d4) = PEREZ_1993[0, 2], PEREZ_1993[0, 3]
        zf, df = z[first], delta[first]
        coef[first, 2] = np.exp((df * (c1 + c2 * zf)) ** c3) - c4
        coef[first, 3] = -np.exp(df * (d1 + d2 * zf)) + d3 + df * d4
    return coef.T


def perez_coefficients(epsilon: float, delta: float, zenith: float) -> tuple[float, float, float, float, float]:
    """(a, b, c, d, e) of the Perez (1993) luminance distribution for clearness ε,
    brightness Δ and solar zenith angle [°] (limited to 90°)."""
    coef = perez_coefficients_array(epsilon, delta, math.radians(min(zenith, 90.0)))
    return tuple(float(v) for v in coef[:, 0])


def perez_luminous_efficacy_array(epsilon, delta, zenith_rad, water) -> tuple[np.ndarray, np.ndarray]:
    """(K_diffuse, K_direct) [lm/W] of the Perez et al. (1990) model for arrays of ε, Δ,
    solar zenith angle [rad] and precipitable water W [cm] (:func:`perez_luminous_efficacy`)."""
    eps, delta, z, water = (np.asarray(v, np.float64) for v in (epsilon, delta, zenith_rad, water))
    k = np.searchsorted(np.asarray(PEREZ_CLEARNESS_BINS[:7]), eps, side="right")
    a, b, c, d = PEREZ_1990_DIFFUSE_EFFICACY[:, k]
    k_dif = a + b * water + c * np.cos(z) + d * np.log(np.maximum(delta, PEREZ_MIN_BRIGHTNESS))
    a, b, c, d = PEREZ_1990_DIRECT_EFFICACY[:, k]
    k_dir = np.maximum(0.0, a + b * water + c * np.exp(5.73 * z - 5.0) + d * delta)
    return k_dif, k_dir


def perez_luminous_efficacy(epsilon: float, delta: float, zenith: float, water: float) -> tuple[float, float]:
    """(K_diffuse, K_direct) [lm/W] of the Perez et al. (1990) model: diffuse horizontal
    K = a + b W + c cos Z + d ln Δ and direct normal K = max(0, a + b W + c exp(5.73 Z − 5) + d Δ),
    W the precipitable water [cm], Z the solar zenith angle [°] (limited to 90°)."""
    k_dif, k_dir = perez_luminous_efficacy_array(epsilon, delta, math.radians(min(zenith, 90.0)), water)
    return float(k_dif), float(k_dir)


@dataclass(frozen=True)
class PerezParameters:
    """The inputs of a Perez sky: clearness ε, brightness Δ, and the direct normal and
    diffuse horizontal light as irradiance [W/m²] and illuminance [lux]."""

    clearness: float
    brightness: float
    direct_normal_irradiance: float
    diffuse_horizontal_irradiance: float
    direct_normal_illuminance: float
    diffuse_horizontal_illuminance: float


def perez_from_irradiance(direct_normal: float, diffuse_horizontal: float, zenith: float,
                          day: float | None = None, dew_point: float = 10.0) -> PerezParameters:
    """ε and Δ from direct normal and diffuse horizontal irradiance [W/m²] at solar zenith
    angle [°], and the illuminances by the Perez et al. (1990) efficacy model with the
    precipitable water of the dew point [°C] (:func:`~lbl_illum.daylight.solar.precipitable_water`)."""
    if diffuse_horizontal <= 0.0:
        return PerezParameters(1.0, 0.0, direct_normal, 0.0, 0.0, 0.0)
    eps = perez_clearness(diffuse_horizontal, direct_normal, zenith)
    delta = perez_brightness(diffuse_horizontal, zenith, day)
    k_dif, k_dir = perez_luminous_efficacy(eps, delta, zenith, precipitable_water(dew_point))
    return PerezParameters(eps, delta, direct_normal, diffuse_horizontal, direct_normal * k_dir,
                           diffuse_horizontal * k_dif)


def perez_from_illuminance(direct_normal: float, diffuse_horizontal: float, zenith: float,
                           day: float | None = None, dew_point: float = 10.0,
                           max_iterations: int = 50) -> PerezParameters:
    """ε and Δ from direct normal and diffuse horizontal illuminance [lux]: the irradiances
    that the Perez (1990) efficacy model turns into these illuminances, found by fixed-point
    iteration from 93.3 lm/W (127.5 klux / 1367 W/m²) as in Radiance's gendaylit ``-L``
    (which stops after 5 steps; this goes on until the irradiances change by < 1e-9
    relative, or ``max_iterations``)."""
    if diffuse_horizontal <= 0.0:
        return PerezParameters(1.0, 0.0, 0.0, 0.0, direct_normal, 0.0)
    water = precipitable_water(dew_point)
    k_dif = k_dir = 127500.0 / 1367.0
    e_dh, e_dn = diffuse_horizontal / k_dif, direct_normal / k_dir
    for _ in range(max_iterations):
        eps = perez_clearness(e_dh, e_dn, zenith)
        delta = perez_brightness(e_dh, zenith, day)
        k_dif, k_dir = perez_luminous_efficacy(eps, delta, zenith, water)
        new_dh = diffuse_horizontal / k_dif
        new_dn = direct_normal / k_dir if k_dir > 0.0 else 0.0
        done = abs(new_dh - e_dh) <= 1e-9 * e_dh and abs(new_dn - e_dn) <= 1e-9 * max(e_dn, 1e-12)
        e_dh, e_dn = new_dh, new_dn
        if done:
            break
    eps = perez_clearness(e_dh, e_dn, zenith)
    delta = perez_brightness(e_dh, zenith, day)
    return PerezParameters(eps, delta, e_dn, e_dh, direct_normal, diffuse_horizontal)


@dataclass(frozen=True)
class PerezSky(Sky):
    """Perez all-weather sky (Perez, Seals & Michalsky 1993).

    Relative luminance lv = (1 + a exp(b / max(cos Z, 0.01))) (1 + c exp(d χ) + e cos² χ),
    not below 0, with a…e from the clearness ε, the brightness Δ and the solar zenith angle
    (:func:`perez_coefficients`); the luminance is E_dh · lv / ∫ lv cos Z dω, so that the
    sky's unobstructed horizontal illuminance is the diffuse horizontal illuminance E_dh
    (``horizontal_illuminance``, lux).  A sun below the horizon is taken at the horizon for
    the coefficients.

    sun_altitude, sun_azimuth : [°] the sun's position
    clearness, brightness : ε (≥ 1) and Δ (≥ 0)
    direct_normal_illuminance : [lux] the direct normal illuminance that goes with the sky
        (for the scene's sun; it does not enter the luminance)
    coefficients_given : (a, b, c, d, e) to use instead of those of ε, Δ and the sun
        (a sky written by Radiance's ``gendaylit``: :meth:`from_coefficients`)
    """

    sun_altitude: float = 45.0
    sun_azimuth: float = 180.0
    clearness: float = 1.0
    brightness: float = 0.2
    direct_normal_illuminance: float = 0.0
    coefficients_given: tuple | None = None
    _coef: tuple = field(init=False, default=(), repr=False, compare=False)
    _sun: Any = field(init=False, default=None, repr=False, compare=False)
    _scale: float = field(init=False, default=0.0, repr=False, compare=False)

    name = "perez"

    def __post_init__(self):
        super().__post_init__()
        _check_finite(self, "sun_altitude", -90.0, 90.0)
        _check_finite(self, "sun_azimuth")
        _check_finite(self, "clearness", minimum=1.0)
        _check_finite(self, "brightness", minimum=0.0)
        _check_finite(self, "direct_normal_illuminance", minimum=0.0)
        coef = (tuple(float(v) for v in self.coefficients_given) if self.coefficients_given is not None else
                perez_coefficients(self.clearness, self.brightness, 90.0 - self.sun_altitude))
        if len(coef) != 5 or not all(math.isfinite(v) for v in coef):
            raise ValueError(f"PerezSky: coefficients_given must be five finite numbers, got {self.coefficients_given!r}")
        _set(self, _sun=sun_vector(self.sun_altitude, self.sun_azimuth), _coef=coef)
        scale = 0.0
        if self.horizontal_illuminance > 0.0:
            integral = hemisphere_integral(self.relative_luminance)
            if not integral > 0.0:
                raise ValueError(f"the Perez distribution of ε = {self.clearness:.4g}, Δ = {self.brightness:.4g} at "
                                 f"sun altitude {self.sun_altitude:.4g}° is negative everywhere (these values are "
                                 "outside the range the model was fitted to)")
            scale = self.horizontal_illuminance / integral
        _set(self, _scale=scale)

    @property
    def coefficients(self) -> tuple[float, float, float, float, float]:
        """(a, b, c, d, e)."""
        return self._coef

    @classmethod
    def from_coefficients(cls, coefficients, sun_altitude: float, sun_azimuth: float, scale: float,
                          sun_horizontal_illuminance: float = 0.0, ground_reflectance: float = 0.2) -> "PerezSky":
        """The sky L = ``scale`` · lv of the Perez coefficients (a, b, c, d, e) given, as
        ``gendaylit`` writes it for ``perezlum.cal`` (``scale`` [cd/m²], its diffuse
        normalisation times 179 and the glow's colour)."""
        unit = cls(horizontal_illuminance=1.0, sun_altitude=sun_altitude, sun_azimuth=sun_azimuth,
                   coefficients_given=tuple(coefficients))
        return cls(horizontal_illuminance=float(scale) / unit.luminance_scale, ground_reflectance=ground_reflectance,
                   sun_horizontal_illuminance=sun_horizontal_illuminance, sun_altitude=sun_altitude,
                   sun_azimuth=sun_azimuth, coefficients_given=tuple(coefficients))

    @property
    def luminance_scale(self) -> float:
        """E_dh / ∫ lv cos Z dω [cd/m²]: L = scale · lv."""
        return self._scale

    @property
    def zenith_luminance(self) -> float:
        return float(self.sky_luminance(np.array([[0.0, 0.0, 1.0]]))[0])

    @property
    def sun_direction(self):
        return self._sun.copy()

    @property
    def label(self) -> str:
        if self.coefficients_given is not None:
            return (f"Perez sky of coefficients {', '.join(f'{v:.4g}' for v in self._coef)}, diffuse horizontal "
                    f"{self.horizontal_illuminance:.6g} lux, sun at altitude {self.sun_altitude:.4g}°, azimuth "
                    f"{self.sun_azimuth:.4g}°")
        return (f"Perez sky, ε {self.clearness:.4g}, Δ {self.brightness:.4g}, diffuse horizontal "
                f"{self.horizontal_illuminance:.6g} lux, sun at altitude {self.sun_altitude:.4g}°, "
                f"azimuth {self.sun_azimuth:.4g}°")

    @property
    def parameters(self) -> dict:
        extra = {} if self.coefficients_given is None else {"coefficients": [float(v) for v in self._coef]}
        return {**super().parameters, "clearness": float(self.clearness), "brightness": float(self.brightness),
                "sun_altitude": float(self.sun_altitude), "sun_azimuth": float(self.sun_azimuth), **extra}

    def relative_luminance(self, directions: np.ndarray) -> np.ndarray:
        """lv along (m, 3) directions above the horizon (not normalised)."""
        a, b, c, d, e = self._coef
        cz = np.maximum(directions[:, 2], PEREZ_MIN_COS_ZENITH)
        cos_chi = np.clip(directions @ self._sun, -1.0, 1.0)
        with np.errstate(over="ignore"):
            lv = (1.0 + a * np.exp(b / cz)) * (1.0 + c * np.exp(d * np.arccos(cos_chi)) + e * cos_chi * cos_chi)
        return np.maximum(lv, 0.0)

    def sky_luminance(self, directions):
        if self._scale == 0.0:
            return np.zeros(len(directions))
        return self._scale * self.relative_luminance(np.asarray(directions, dtype=np.float64))


# ---------------------------------------------------------------------------
# Registry and the [sky] table
# ---------------------------------------------------------------------------

SKY_MODELS = {cls.name: cls for cls in (UniformSky, CIEOvercastSky, CIEGeneralSky, PerezSky, NoSky)}
#: Every ``type`` a ``[sky]`` table may name.
SKY_TYPES = ("uniform", "cie-overcast", "cie-general", *SKY_ALIASES, "perez", "none")
#: Default diffuse-light dew point [°C] for the Perez efficacy model when none is given.
DEFAULT_DEW_POINT = 10.0
#: Largest Sun–Earth distance factor (E_0 / solar constant) of Spencer's (1971) formula, early January.
MAX_DISTANCE_FACTOR = 1.0351
#: Extraterrestrial normal irradiance at perihelion [W/m²]: no direct normal or diffuse
#: horizontal irradiance at the ground exceeds it.
MAX_EXTRATERRESTRIAL_IRRADIANCE = 1367.0 * MAX_DISTANCE_FACTOR
#: Extraterrestrial normal illuminance at perihelion [lux] (Darula, Kittler & Gueymard 2005:
#: 133 334 lx at the mean distance): no direct normal or diffuse horizontal illuminance at the
#: ground exceeds it.
MAX_EXTRATERRESTRIAL_ILLUMINANCE = 133334.0 * MAX_DISTANCE_FACTOR

_COMMON_KEYS = ("type", "ground_reflectance")
_SCALE_KEYS = ("horizontal_illuminance", "zenith_luminance")
_PEREZ_KEYS = ("direct_normal_illuminance", "diffuse_horizontal_illuminance", "direct_normal_irradiance",
               "diffuse_horizontal_irradiance", "dew_point")


def _sky_type(table: Mapping[str, Any], where: str) -> int:
    value = table.get("sky_type")
    if value is None:
        raise InputError(f"{where}: type 'cie-general' needs 'sky_type' (1…15; 12 is the CIE standard clear sky)")
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value) or \
            value != int(value) or int(value) not in CIE_GENERAL_SKY_TYPES:
        raise InputError(f"{where}: 'sky_type' must be a whole number 1…15, got {value!r}")
    return int(value)


#: gensky's default atmospheric turbidity (Radiance's gensky ``-t``).
GENSKY_TURBIDITY = 2.45
#: [sr] Solid angle of the sun's disk in gensky's description (``source sun`` of 0.5°).
GENSKY_SUN_SOLID_ANGLE = 2.0 * math.pi * (1.0 - math.cos(math.radians(0.25)))


def gensky_clear_zenith_luminance(sun_altitude: float, turbidity: float = GENSKY_TURBIDITY) -> float:
    """Zenith luminance L_z [cd/m²] of the clear sky that Radiance renders from ``gensky +s``
    when no brightness is given.  gensky's formula gives 1000 [(1.376 T − 1.81) tan h +
    0.38] cd/m² (Karayel, Navvab, Ne'eman & Selkowitz, "Zenith luminance and sky luminance
    distributions for daylighting calculations", Energy and Buildings 6, 1984), T the
    turbidity and h the sun's altitude, taken at 87° above that; 0 when negative.  gensky
    writes it as radiance at 203 lm/W and Radiance reads luminance back at 179 lm/W, so the
    sky rtrace computes with is 179/203 of the formula: that is returned, so that a scene
    and its gensky twin agree (:data:`~lbl_illum.photometry.RADIANCE_SKY_EFFICACY`)."""
    h = math.radians(min(float(sun_altitude), 87.0))
    formula = max(0.0, 1000.0 * ((1.376 * turbidity - 1.81) * math.tan(h) + 0.38))
    return formula * RADIANCE_WHITE_EFFICACY / RADIANCE_SKY_EFFICACY


def gensky_direct_normal(sun_altitude: float) -> float:
    """Direct normal illuminance E_dn [lux] of gensky's sun as Radiance renders it: gensky's
    luminance 1.5e9 (1.147 − 0.147 / max(sin h, 0.16)) cd/m², written at 208 lm/W and read
    back at 179 (:data:`~lbl_illum.photometry.RADIANCE_SUN_EFFICACY`), over a disk of 0.5°
    (:data:`GENSKY_SUN_SOLID_ANGLE`), the sun's altitude h taken at 87° above that; 0 with
    the sun below the horizon."""
    if sun_altitude <= 0.0:
        return 0.0
    s = math.sin(math.radians(min(float(sun_altitude), 87.0)))
    luminance = 1.5e9 * (1.147 - 0.147 / max(s, 0.16)) * RADIANCE_WHITE_EFFICACY / RADIANCE_SUN_EFFICACY
    return luminance * GENSKY_SUN_SOLID_ANGLE


def _turbidity_refused(where: str) -> InputError:
    """``turbidity`` given where it sets nothing (any sky but a clear one without a brightness)."""
    return InputError(f"{where}: 'turbidity' sets the brightness of a clear sky (cie-clear) whose "
                      "horizontal_illuminance and zenith_luminance are not given")


def _scale(table: Mapping[str, Any], where: str) -> tuple[str, float]:
    """('horizontal_illuminance' | 'zenith_luminance', value) of a table (default E_h 10 000 lux)."""
    if "horizontal_illuminance" in table and "zenith_luminance" in table:
        raise InputError(f"{where}: give 'horizontal_illuminance' or 'zenith_luminance', not both")
    if "zenith_luminance" in table:
        return "zenith_luminance", get_number(table, "zenith_luminance", where, minimum=0.0)
    return "horizontal_illuminance", get_number(table, "horizontal_illuminance", where, default=10000.0,
                                                minimum=0.0)


def sky_from_table(table: Mapping[str, Any] | None, where: str, sun_horizontal_illuminance: float = 0.0,
                   sun_position: tuple[float, float] | None = None, day: float | None = None,
                   extra_keys: tuple[str, ...] = ()) -> Sky:
    """Build the sky of a ``[sky]`` table (no table: no sky).

    sun_horizontal_illuminance : the direct sun's E_dn sin(altitude) [lux], for the ground glow
    sun_position : (altitude, azimuth) [°] of the sun that shapes the sky, or None
    day : day of the year, for the Perez sky's brightness (None: mean Sun–Earth distance)
    extra_keys : further keys the caller reads from the table (``time``, ``weather``)

    Messages name ``where`` (``scene.toml: [sky]``) and the key.
    """
    if table is None:
        return NoSky()
    if sun_position is not None:
        _check_sun_position(sun_position, where)
    kind = table.get("type", "cie-overcast")
    if kind not in SKY_TYPES:
        raise InputError(f"{where}: 'type' must be one of {', '.join(SKY_TYPES)}, got {kind!r}")
    if kind == "none":
        check_keys(table, ("type", *extra_keys), where)
        return NoSky()
    if kind == "perez":
        check_keys(table, (*_COMMON_KEYS, *_PEREZ_KEYS, *extra_keys), where)
        return _perez_from_table(table, where, sun_horizontal_illuminance, sun_position, day)
    general = kind == "cie-general" or kind in SKY_ALIASES
    check_keys(table, (*_COMMON_KEYS, *_SCALE_KEYS, *(("sky_type",) if kind == "cie-general" else ()),
                       "turbidity", *extra_keys), where)
    rho = get_number(table, "ground_reflectance", where, default=0.2, minimum=0.0, maximum=1.0)
    which, value = _scale(table, where)
    common = {"ground_reflectance": rho, "sun_horizontal_illuminance": sun_horizontal_illuminance}
    if not general:
        if "turbidity" in table:
            raise _turbidity_refused(where)
        if which == "zenith_luminance":
            value = _finite_product(value, np.pi if kind == "uniform" else 7.0 * np.pi / 9.0, where, which)
        return SKY_MODELS[kind](horizontal_illuminance=value, **common)
    sky_type = _sky_type(table, where) if kind == "cie-general" else SKY_ALIASES[kind]
    a, b, c, d, e, _ = CIE_GENERAL_SKY_TYPES[sky_type]
    if sun_position is None:
        if c != 0.0 or e != 0.0:
            raise InputError(f"{where}: CIE general sky type {sky_type} needs the sun's position: give a [sun] "
                             "table (altitude, azimuth; direct_normal_illuminance = 0 for no direct sun) or a "
                             "'time' with a [site]")
        common.update(sun_altitude=None, sun_azimuth=None)
    else:
        common.update(sun_altitude=float(sun_position[0]), sun_azimuth=float(sun_position[1]) % 360.0)
    if sky_type == CLEAR_SKY_TYPE and not any(key in table for key in _SCALE_KEYS):
        # no brightness given: gensky's, from the sun's altitude and the turbidity
        turbidity = get_number(table, "turbidity", where, default=GENSKY_TURBIDITY, minimum=1.0, maximum=20.0)
        which, value = "zenith_luminance", gensky_clear_zenith_luminance(common["sun_altitude"], turbidity)
    elif "turbidity" in table:
        raise _turbidity_refused(where)
    if which == "zenith_luminance":
        unit = CIEGeneralSky(horizontal_illuminance=1.0, sky_type=sky_type, **common)
        value = _finite_product(value, 1.0 / unit.zenith_luminance, where, which)
    return CIEGeneralSky(horizontal_illuminance=value, sky_type=sky_type, **common)


def _finite_product(value: float, factor: float, where: str, key: str) -> float:
    """``value · factor``, the horizontal illuminance [lux] a ``zenith_luminance`` gives,
    refused naming ``key`` when it is not a finite number (a value near the float range)."""
    with np.errstate(over="ignore"):
        product = float(np.float64(value) * np.float64(factor))
    if not math.isfinite(product):
        raise InputError(f"{where}: '{key}' {value:g} is too large (the sky's horizontal illuminance would not be "
                         "a finite number)")
    return product


def _check_sun_position(sun_position, where: str) -> None:
    """Refuse a sun position (altitude, azimuth) [°] that is not two finite numbers with
    the altitude within ±90° (the [sun] table checks its own keys; this guards other callers)."""
    try:
        alt, az = (float(v) for v in sun_position)
    except (TypeError, ValueError):
        raise InputError(f"{where}: the sun's position must be (altitude, azimuth) in degrees, "
                         f"got {sun_position!r}") from None
    if not (math.isfinite(alt) and math.isfinite(az)):
        raise InputError(f"{where}: the sun's altitude and azimuth must be finite, got {alt:g}, {az:g}")
    if not -90.0 <= alt <= 90.0:
        raise InputError(f"{where}: the sun's altitude must be within -90 and 90 degrees, got {alt:g}")


def _perez_from_table(table, where, sun_horizontal_illuminance, sun_position, day) -> PerezSky:
    lux = ("direct_normal_illuminance", "diffuse_horizontal_illuminance")
    watts = ("direct_normal_irradiance", "diffuse_horizontal_irradiance")
    given_lux, given_watts = [k for k in lux if k in table], [k for k in watts if k in table]
    if given_lux and given_watts:
        raise InputError(f"{where}: give the direct normal and diffuse horizontal values either as illuminance "
                         f"({', '.join(lux)}) or as irradiance ({', '.join(watts)}), not both")
    keys = watts if given_watts else lux
    for k in keys:
        if k not in table:
            raise InputError(f"{where}: type 'perez' needs '{keys[0]}' and '{keys[1]}' (missing key '{k}')")
    # measured daylight: at most what reaches the top of the atmosphere (module text)
    top = MAX_EXTRATERRESTRIAL_IRRADIANCE if given_watts else MAX_EXTRATERRESTRIAL_ILLUMINANCE
    unit = "W/m2" if given_watts else "lux"
    values = []
    for key in keys:
        value = get_number(table, key, where, minimum=0.0)
        if value > top:
            raise InputError(f"{where}: '{key}' {value:g} {unit} is more than reaches the top of the atmosphere "
                             f"({top:.6g} {unit} at the Sun's nearest)")
        values.append(value)
    direct, diffuse = values
    if direct > 0.0 and diffuse <= 0.0:
        raise InputError(f"{where}: '{keys[1]}' must be > 0 when '{keys[0]}' is (a sky with sun but no "
                         "diffuse light is outside the Perez model)")
    dew = get_number(table, "dew_point", where, default=DEFAULT_DEW_POINT, minimum=-80.0, maximum=40.0)
    rho = get_number(table, "ground_reflectance", where, default=0.2, minimum=0.0, maximum=1.0)
    if sun_position is None:
        raise InputError(f"{where}: type 'perez' needs the sun's position: give a [sun] table (altitude, azimuth) "
                         "or a 'time' with a [site]")
    try:
        return perez_sky(direct, diffuse, sun_position, irradiance=bool(given_watts), day=day, dew_point=dew,
                         ground_reflectance=rho, sun_horizontal_illuminance=sun_horizontal_illuminance)
    except (ValueError, ArithmeticError) as exc:
        # ε, Δ or the efficacies out of reach of the model (a diffuse value so small that
        # ε = (E_dh + E_dn)/E_dh is infinite, or that divides by zero on the way)
        reason = str(exc) if isinstance(exc, ValueError) and str(exc) else \
            f"no Perez sky ({type(exc).__name__})"
        raise InputError(f"{where}: {reason}; from '{keys[0]}' {direct:g} and '{keys[1]}' {diffuse:g}") from None


def perez_sky(direct_normal: float, diffuse_horizontal: float, sun_position: tuple[float, float],
              irradiance: bool = False, day: float | None = None, dew_point: float = DEFAULT_DEW_POINT,
              ground_reflectance: float = 0.2, sun_horizontal_illuminance: float = 0.0) -> PerezSky:
    """A :class:`PerezSky` from direct normal and diffuse horizontal illuminance [lux] (or,
    with ``irradiance=True``, irradiance [W/m²], converted by the Perez 1990 efficacy
    model) and the sun's (altitude, azimuth) [°]."""
    alt, az = float(sun_position[0]), float(sun_position[1]) % 360.0
    zenith = 90.0 - alt
    conv = perez_from_irradiance if irradiance else perez_from_illuminance
    p = conv(direct_normal, diffuse_horizontal, zenith, day=day, dew_point=dew_point)
    return PerezSky(horizontal_illuminance=p.diffuse_horizontal_illuminance, ground_reflectance=ground_reflectance,
                    sun_horizontal_illuminance=sun_horizontal_illuminance, sun_altitude=alt, sun_azimuth=az,
                    clearness=p.clearness, brightness=p.brightness,
                    direct_normal_illuminance=p.direct_normal_illuminance)


def perez_sky_from_weather(direct_normal_irradiance: float, diffuse_horizontal_irradiance: float,
                           direct_normal_illuminance: float, diffuse_horizontal_illuminance: float,
                           sun_position: tuple[float, float], day: float | None = None,
                           dew_point: float = DEFAULT_DEW_POINT, use_file_illuminance: bool = True,
                           ground_reflectance: float = 0.2) -> PerezSky:
    """A :class:`PerezSky` from a weather record's values (NaN where missing).

    ε and Δ come from the irradiances [W/m²] (the quantities the model is defined on).  The
    illuminances [lux] are the record's when ``use_file_illuminance`` and both are present,
    otherwise the irradiances times the Perez (1990) efficacies, as Radiance's
    ``gendaylit -W`` does.  Without irradiances, ε and Δ come from the illuminances
    (:func:`perez_from_illuminance`).
    """
    alt, az = float(sun_position[0]), float(sun_position[1]) % 360.0
    zenith = 90.0 - alt
    dew = dew_point if math.isfinite(dew_point) else DEFAULT_DEW_POINT
    have_w = math.isfinite(direct_normal_irradiance) and math.isfinite(diffuse_horizontal_irradiance)
    have_lux = math.isfinite(direct_normal_illuminance) and math.isfinite(diffuse_horizontal_illuminance)
    if have_w:
        p = perez_from_irradiance(direct_normal_irradiance, diffuse_horizontal_irradiance, zenith, day, dew)
        if use_file_illuminance and have_lux:
            p = dataclasses.replace(p, direct_normal_illuminance=direct_normal_illuminance,
                                    diffuse_horizontal_illuminance=diffuse_horizontal_illuminance)
    elif have_lux:
        p = perez_from_illuminance(direct_normal_illuminance, diffuse_horizontal_illuminance, zenith, day, dew)
    else:
        raise ValueError("no direct normal and diffuse horizontal values (irradiance or illuminance)")
    return PerezSky(horizontal_illuminance=p.diffuse_horizontal_illuminance, ground_reflectance=ground_reflectance,
                    sun_altitude=alt, sun_azimuth=az, clearness=p.clearness, brightness=p.brightness,
                    direct_normal_illuminance=p.direct_normal_illuminance)

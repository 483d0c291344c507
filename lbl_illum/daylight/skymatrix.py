"""Annual sky matrices: the luminance of every sky patch in every hour of a weather file,
the role of Radiance's ``gendaymtx`` in a climate-based daylight simulation.

With daylight coefficients D (sensors × patches: the illuminance at a sensor per unit
luminance of each patch, the sky being otherwise black) the illuminance of every sensor in
every hour is the product E = D · S, S the sky matrix of this module (patches × hours)
[Tregenza & Waters 1983; Reinhart & Herkel 2000].

Patches
-------
The sky is cut into the Tregenza (1987) patches or their Reinhart (2000) subdivisions, in
the order of ``gendaymtx`` and of Radiance's ``reinhartb.cal`` (bin + 1):

* row 0 is the **ground**: everything below the horizon, one patch of 2π sr, direction
  (0, 0, −1);
* then the bands of the sky from the horizon up: 7·MF bands of height
  α = 90° / (7 MF + 0.5), band i from altitude i·α to (i + 1)·α; Tregenza's seven bands
  have 30, 30, 24, 24, 18, 12 and 6 patches, and subdivision MF splits each into MF bands
  of MF times as many; within a band of n patches, patch j is centred on azimuth 360° j / n
  (clockwise from north seen from above: the first patch of each band is centred on north,
  the next lies east of it), at the band's middle altitude;
* the last row is the **zenith cap** above 90° − α/2.

MF = 1 gives the 145 Tregenza patches (146 rows with the ground), MF = 2 577 (578), MF = 4
2305 (2306).  Band solid angles are exact, 2π (sin φ_top − sin φ_bottom) / n, so the sky
patches sum to 2π sr.  (The ``gendaymtx`` manual says the second patch lies west of the
first; its code and ``reinhartb.cal`` put it east, in the frame +x east, +y north: measured
against the binary, the sun of 21 June 9:30 in Oakland, azimuth ≈ 95°, lands on row 114,
band 4, j = 5, centred on azimuth 100°.)

Patch luminance (``gendaymtx``, Ashdown's rewrite of Delaunay's ``gendaylit``)
-----------------------------------------------------------------------------
For each hour with light and the sun above the horizon:

1. sky clearness ε and brightness Δ from the direct normal and diffuse horizontal
   irradiance (Perez et al. 1990, eqs. 1–2; Kasten air mass, Spencer's Sun–Earth
   distance), with ``gendaymtx``'s limits: the solar zenith angle taken within 3°…90°,
   ε within 1…11.9, Δ within 0.01…0.6 (:func:`perez_hours`);
2. diffuse horizontal and direct normal illuminance by the Perez et al. (1990) luminous
   efficacies, with the precipitable water of the dew point (or, with
   ``values="illuminance"``, the file's illuminances);
3. the relative luminance lv = (1 + a e^{b/cos Z}) (1 + c e^{dχ} + e cos²χ) (Perez, Seals &
   Michalsky 1993, coefficients a…e from ε, Δ and the sun's zenith angle; not below 0) at
   each patch centre, and the patches scaled so that Σ L_p cos Z_p Ω_p is the diffuse
   horizontal illuminance (a sum over patch centres: the hour's diffuse light is exactly
   what the matrix gives a horizontal sensor under an open sky);
4. the ground patch ρ_g (E_dh + E_dn sin γ_s) / π (γ_s the sun's altitude);
5. with ``sun="patches"`` (``gendaymtx``'s default), the sun added to the 4 sky patches
   nearest to it, patch i receiving the share w_i / Σw of the direct normal illuminance
   E_dn, w_i = 1 / (1.002 − cos θ_i), θ_i its centre's angle from the sun: its luminance
   grows by w_i E_dn / (Σw Ω_i), so Σ ΔL_i Ω_i = E_dn (``gendaymtx.c``, ``AddDirect``).
   With ``sun="separate"`` the matrix has the sky and ground only (``gendaymtx -s``) and
   :attr:`SkyMatrix.sun_illuminance`, :attr:`SkyMatrix.sun_direction` give the sun for an
   exact direct-sun calculation.

Units: luminance in cd/m² (one photometric channel).  ``gendaymtx`` writes RGB radiance
[W sr⁻¹ m⁻²] at Radiance's 179 lm/W: L = 179 · (0.265 R + 0.670 G + 0.065 B), and its
default sky colour (0.960, 1.004, 1.118) has brightness 0.99975, so its default sky
patches are 0.025 % darker than these (``-c 1 1 1`` removes that).  Its ``-O0`` (default)
is this visible radiance; ``-O1`` is total solar radiance (the irradiances × 179, not
luminance).

Differences from ``gendaymtx`` (measured in ``docs/annual-sky.md``)
-----------------------------------------------------------------
* Solar position: ``gendaymtx`` uses the short formulas of Radiance's ``sun.c``
  (declination 0.4093 sin(2π(J − 81)/365), a two-term equation of time, no refraction);
  here the NREL SPA (pvlib) or the NOAA calculator with refraction.  ``solar_position=
  "gendaymtx"`` uses ``sun.c``'s formulas (:func:`gendaymtx_solar_position`), which
  reproduces the binary to its float precision.
* Night: an hour whose sun (at the row's time) is below the horizon is a zero column here
  even when the file gives it some light (the light of the part of the hour after sunrise or
  before sunset); ``gendaymtx`` makes a sky for it, the sun taken at the horizon.  In the
  Oakland TMY3 year that is 0.01 % of the diffuse and 0.02 % of the direct irradiance.
* The Perez limits (Δ ≤ 0.6, ε ≤ 11.9, zenith ≥ 3°) are ``gendaymtx``'s; a single
  :class:`~lbl_illum.daylight.sky.PerezSky` does not apply them.

References
----------
1. P. J. Tregenza, "Subdivision of the sky hemisphere for luminance measurements",
   Lighting Res. Technol. 19(1), 13–14 (1987).
2. P. J. Tregenza, I. M. Waters, "Daylight coefficients", Lighting Res. Technol. 15(2),
   65–71 (1983).
3. C. F. Reinhart, S. Herkel, "The simulation of annual daylight illuminance distributions —
   a state-of-the-art comparison of six RADIANCE-based methods", Energy and Buildings
   32(2), 167–187 (2000).
4. R. Perez, P. Ineichen, R. Seals, J. Michalsky, R. Stewart, "Modeling daylight
   availability and irradiance components from direct and global irradiance", Solar Energy
   44(5), 271–289 (1990).
5. R. Perez, R. Seals, J. Michalsky, "All-weather model for sky luminance distribution —
   preliminary configuration and validation", Solar Energy 50(3), 235–245 (1993).
6. Radiance ``src/gen/gendaymtx.c`` (G. Ward after I. Ashdown, 2013–2025), ``src/gen/sun.c``,
   ``src/gen/loadEPW.c``, ``src/util/reinhartb.cal`` (LBNL-ETA/Radiance).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import numpy as np

from .sky import PEREZ_MIN_BRIGHTNESS, perez_coefficients_array, perez_luminous_efficacy_array
from .solar import SOLAR_POSITION_METHODS, SolarPosition, air_mass_kasten1966, extraterrestrial_normal_irradiance, \
    precipitable_water
from .weather import HourlyWeather, read_weather
from ..errors import InputError

__all__ = [
    "SkyPatches", "SkyMatrix", "sky_patches", "patch_index", "sky_matrix", "perez_hours", "PerezHours",
    "gendaymtx_solar_position", "TREGENZA_BANDS", "SUN_OPTIONS", "VALUE_OPTIONS", "GENDAYMTX_DEW_POINT",
    "SUN_PATCHES", "sun_patch_weights",
]

#: Patches per band of the Tregenza sky, from the horizon up (the zenith cap apart).
TREGENZA_BANDS = (30, 30, 24, 24, 18, 12, 6)
#: ``sun`` values of :func:`sky_matrix`.
SUN_OPTIONS = ("patches", "separate")
#: ``values`` values of :func:`sky_matrix`.
VALUE_OPTIONS = ("irradiance", "illuminance")
#: Dew point [°C] for the precipitable water of the efficacy model when the file gives none
#: (a ``.wea``): ``gendaymtx``'s default (sky.py's single skies use 10 °C).
GENDAYMTX_DEW_POINT = 11.0
#: Patches the sun is spread over with ``sun="patches"`` (``gendaymtx``'s ``NSUNPATCH``).
SUN_PATCHES = 4
#: w = 1 / (SUN_WEIGHT_OFFSET − cos θ): the proximity weights of ``gendaymtx``'s ``AddDirect``.
SUN_WEIGHT_OFFSET = 1.002
#: ``gendaymtx``'s limits of the Perez inputs: the solar zenith angle [°] within
#: MIN_SUN_ZENITH…90, the clearness ε ≤ MAX_CLEARNESS, the brightness Δ ≤ MAX_BRIGHTNESS
#: (and ≥ :data:`~lbl_illum.daylight.sky.PEREZ_MIN_BRIGHTNESS`).
MIN_SUN_ZENITH = 3.0
MAX_CLEARNESS = 11.9
MAX_BRIGHTNESS = 0.6
#: The clearness formula's 1.041 Z³ term (Z in radians; Perez et al. 1990, eq. 1).
_KAPPA = 1.041
#: A relative horizontal illuminance below this makes a uniform sky (``gendaymtx``, FTINY).
_TINY = 1e-6
#: Sky-patch × hour elements computed at once: arrays of 0.8 MB stay in cache (the Oakland
#: year at MF 4 in 0.3 s, against 1.0–1.7 s with 2 000 000).
_CHUNK_ELEMENTS = 100_000


# ---------------------------------------------------------------------------
# Patches
# ---------------------------------------------------------------------------

@dataclass(frozen=True, eq=False)
class SkyPatches:
    """The patches of a Tregenza/Reinhart sky of subdivision ``mf``, in matrix row order
    (module text): row 0 the ground, rows 1… the sky bands from the horizon up, the last
    row the zenith cap.

    directions : (n, 3) unit vectors to the patch centres (+x east, +y north, +z up)
    solid_angles : (n,) [sr]; the sky rows sum to 2π, the ground is 2π
    altitudes, azimuths : (n,) [°] of the centres (azimuth clockwise from north)
    bounds : (n, 4) [°] altitude from, altitude to, azimuth from, azimuth to of each patch
        (a band's first patch runs from −w/2 to w/2 about north; the ground is −90…0 and
        the zenith cap 90 − α/2…90, both 0…360 in azimuth)
    """

    mf: int
    directions: np.ndarray
    solid_angles: np.ndarray
    altitudes: np.ndarray
    azimuths: np.ndarray
    bounds: np.ndarray

    #: Row of the ground patch.
    GROUND = 0

    def __len__(self) -> int:
        return len(self.solid_angles)

    @property
    def sky(self) -> slice:
        """The rows of the sky patches (all but the ground)."""
        return slice(1, None)

    @property
    def band_height(self) -> float:
        """α = 90° / (7 MF + 0.5) [°]."""
        return 90.0 / (len(TREGENZA_BANDS) * self.mf + 0.5)


def _readonly(*arrays):
    for a in arrays:
        a.setflags(write=False)


@lru_cache(maxsize=8)
def sky_patches(mf: int = 1) -> SkyPatches:
    """The :class:`SkyPatches` of Reinhart subdivision ``mf`` (1: Tregenza's 145 sky
    patches), as ``gendaymtx`` (``rh_init``) lays them out."""
    if isinstance(mf, bool) or not isinstance(mf, (int, np.integer)) or mf < 1:
        raise ValueError(f"mf must be a whole number >= 1, got {mf!r}")
    mf = int(mf)
    alpha = 90.0 / (len(TREGENZA_BANDS) * mf + 0.5)
    alt, az, dom, bounds = [-90.0], [0.0], [2.0 * math.pi], [(-90.0, 0.0, 0.0, 360.0)]
    for i in range(len(TREGENZA_BANDS) * mf):
        n = TREGENZA_BANDS[i // mf] * mf
        lo, hi = i * alpha, (i + 1) * alpha
        omega = 2.0 * math.pi * (math.sin(math.radians(hi)) - math.sin(math.radians(lo))) / n
        for j in range(n):
            c, w = 360.0 * j / n, 360.0 / n
            alt.append(lo + 0.5 * alpha)
            az.append(c)
            dom.append(omega)
            bounds.append((lo, hi, c - 0.5 * w, c + 0.5 * w))
    top = 90.0 - 0.5 * alpha
    alt.append(90.0)
    az.append(0.0)
    dom.append(2.0 * math.pi * (1.0 - math.cos(math.radians(0.5 * alpha))))
    bounds.append((top, 90.0, 0.0, 360.0))
    alt, az = np.array(alt), np.array(az)
    a, z = np.radians(alt), np.radians(az)
    directions = np.column_stack([np.cos(a) * np.sin(z), np.cos(a) * np.cos(z), np.sin(a)])
    directions[0] = (0.0, 0.0, -1.0)
    directions[-1] = (0.0, 0.0, 1.0)
    patches = SkyPatches(mf=mf, directions=directions, solid_angles=np.array(dom), altitudes=alt, azimuths=az,
                         bounds=np.array(bounds))
    _readonly(patches.directions, patches.solid_angles, patches.altitudes, patches.azimuths, patches.bounds)
    return patches


def patch_index(directions, mf: int = 1) -> np.ndarray:
    """The matrix row of the patch each of the (m, 3) unit ``directions`` falls in (0 for
    the ground, z ≤ 0), the binning of Radiance's ``reinhartb.cal`` (``rbin + 1``): band
    floor(altitude / α), the zenith cap above 90° − α/2, and within a band the patch whose
    centre is nearest in azimuth."""
    d = np.asarray(directions, dtype=np.float64).reshape(-1, 3)
    patches = sky_patches(mf)
    bands = len(TREGENZA_BANDS) * patches.mf
    alpha = math.radians(patches.band_height)
    per_band = np.repeat(np.array(TREGENZA_BANDS) * patches.mf, patches.mf)
    first = 1 + np.concatenate([[0], np.cumsum(per_band)])           # row of each band's patch 0
    alt = np.arcsin(np.clip(d[:, 2], -1.0, 1.0))
    band = np.minimum(np.floor(alt / alpha).astype(np.int64), bands)
    sky = d[:, 2] > 0.0
    band = np.where(sky, band, 0)
    n = np.where(band < bands, per_band[np.minimum(band, bands - 1)], 1)
    az = np.mod(np.degrees(np.arctan2(d[:, 0], d[:, 1])), 360.0)
    j = np.mod(np.floor(az * n / 360.0 + 0.5).astype(np.int64), n)
    return np.where(sky, first[band] + j, 0)


# ---------------------------------------------------------------------------
# Perez inputs, vectorised over hours
# ---------------------------------------------------------------------------

@dataclass(frozen=True, eq=False)
class PerezHours:
    """The Perez model's inputs and outputs per hour (arrays of one value an hour).

    zenith : the solar zenith angle the model uses [°] (within 3…90)
    clearness, brightness : ε and Δ (within ``gendaymtx``'s limits)
    diffuse_efficacy, direct_efficacy : [lm/W] (Perez et al. 1990)
    coefficients : (5, hours) a, b, c, d, e of the luminance distribution (Perez et al. 1993)
    """

    zenith: np.ndarray
    clearness: np.ndarray
    brightness: np.ndarray
    diffuse_efficacy: np.ndarray
    direct_efficacy: np.ndarray
    coefficients: np.ndarray


def perez_hours(direct_normal_irradiance, diffuse_horizontal_irradiance, sun_altitude, day,
                precipitable_water_cm) -> PerezHours:
    """ε, Δ, the luminous efficacies and the luminance coefficients of many hours at once,
    as ``gendaymtx`` computes them (``ComputeSky``, ``CalcPerezParam``): the solar zenith
    angle Z taken within 3°…90° for all of them, ε = ((E_dh + E_dn)/E_dh + κZ³)/(1 + κZ³)
    within 1…11.9 (11.9 when E_dh = 0), Δ = E_dh m(Z)/E_0(day) within 0.01…0.6; then
    the luminous efficacies and luminance coefficients of those values
    (:func:`~lbl_illum.daylight.sky.perez_luminous_efficacy_array`,
    :func:`~lbl_illum.daylight.sky.perez_coefficients_array`).

    Irradiances [W/m²], sun altitude [°], day of year, precipitable water [cm]: arrays of
    one length (or scalars; the results are arrays of at least one value).
    """
    dn, dh, alt = np.broadcast_arrays(*(np.atleast_1d(np.asarray(v, dtype=np.float64)) for v in
                                        (direct_normal_irradiance, diffuse_horizontal_irradiance, sun_altitude)))
    zenith = np.clip(90.0 - alt, MIN_SUN_ZENITH, 90.0)
    z = np.radians(zenith)
    z3 = _KAPPA * z ** 3
    with np.errstate(divide="ignore", invalid="ignore"):
        eps = np.where(dh > 0.0, ((dh + dn) / np.where(dh > 0.0, dh, 1.0) + z3) / (1.0 + z3), MAX_CLEARNESS)
    eps = np.clip(eps, 1.0, MAX_CLEARNESS)
    delta = dh * air_mass_kasten1966(zenith) / extraterrestrial_normal_irradiance(np.asarray(day, dtype=np.float64))
    delta = np.clip(delta, PEREZ_MIN_BRIGHTNESS, MAX_BRIGHTNESS)
    k_dif, k_dir = perez_luminous_efficacy_array(eps, delta, z, precipitable_water_cm)
    return PerezHours(zenith=zenith, clearness=eps, brightness=delta, diffuse_efficacy=k_dif,
                      direct_efficacy=k_dir, coefficients=perez_coefficients_array(eps, delta, z))


# ---------------------------------------------------------------------------
# Solar position as gendaymtx has it
# ---------------------------------------------------------------------------

#: Day of a common year before each month (Radiance ``sun.c``, ``jdate``).
_COMMON_MONTH_START = np.array([0, 31, 59, 90, 120, 151, 181, 212, 243, 273, 304, 334])


def gendaymtx_solar_position(weather: HourlyWeather) -> SolarPosition:
    """The sun of each row as ``gendaymtx`` places it, by Radiance's ``sun.c``: day J =
    ``jdate`` (+1 after a 29 February of the file), declination δ = 0.4093 sin(2π(J − 81)/365),
    solar time t = hour + 0.170 sin(4π(J − 80)/373) − 0.129 sin(2π(J − 8)/355) + (standard
    meridian − longitude)/15°, altitude asin(sin φ sin δ − cos φ cos δ cos(πt/12)) and the
    azimuth of ``sazi`` + 180°; no refraction.  Errors against the SPA reach about 0.5°; use it
    to reproduce ``gendaymtx`` (method ``"gendaymtx"`` of the result)."""
    month, day = weather.month, weather.day
    feb29 = (month == 2) & (day == 29)
    after = np.maximum.accumulate(feb29.astype(np.int64))
    jd = np.where(feb29, 60, _COMMON_MONTH_START[month - 1] + day + after).astype(np.float64)
    lat = math.radians(weather.site.latitude)
    west = math.radians(-weather.site.longitude)                       # sun.c: radians west
    meridian = math.radians(-15.0 * weather.site.time_zone)
    dec = 0.4093 * np.sin(2.0 * np.pi / 365.0 * (jd - 81.0))
    st = weather.hour + (0.170 * np.sin(4.0 * np.pi / 373.0 * (jd - 80.0))
                         - 0.129 * np.sin(2.0 * np.pi / 355.0 * (jd - 8.0)) + 12.0 / np.pi * (meridian - west))
    h = st * np.pi / 12.0
    alt = np.arcsin(math.sin(lat) * np.sin(dec) - math.cos(lat) * np.cos(dec) * np.cos(h))
    sazi = -np.arctan2(np.cos(dec) * np.sin(h), -math.cos(lat) * np.sin(dec) - math.sin(lat) * np.cos(dec) * np.cos(h))
    return SolarPosition(np.degrees(alt), np.mod(np.degrees(sazi) + 180.0, 360.0), "gendaymtx")


# ---------------------------------------------------------------------------
# The matrix
# ---------------------------------------------------------------------------

@dataclass(frozen=True, eq=False)
class SkyMatrix:
    """Patch luminance per hour, and what it was made from.

    luminance : (patches, hours) [cd/m²], rows in :class:`SkyPatches` order (``np.asarray``
        of the matrix gives it)
    patches : the :class:`SkyPatches`;  weather : the :class:`HourlyWeather`
    sun : ``"patches"`` (the sun is in the matrix) or ``"separate"`` (it is not: see
        :attr:`sun_illuminance`)
    values, ground_reflectance, rotation, solar_position_method : as given to :func:`sky_matrix`
    daylight : (hours,) bool, the non-zero columns: sun above the horizon and light in the file
    sun_altitude, sun_azimuth : (hours,) [°] the sun of each row; the azimuth in the matrix's
        frame (after ``rotation``)
    clearness, brightness : (hours,) the Perez ε and Δ (NaN at night)
    diffuse_horizontal_illuminance, direct_normal_illuminance : (hours,) [lux] the hour's
        daylight the matrix is made of (0 at night)
    sun_illuminance : (hours,) [lux] direct normal illuminance of the sun *not* in the matrix:
        the direct normal illuminance with ``sun="separate"``, zero with ``sun="patches"``,
        so that E = D · S + (sun coefficient) · sun_illuminance counts the sun once either way
    """

    luminance: np.ndarray
    patches: SkyPatches
    weather: HourlyWeather
    sun: str
    values: str
    ground_reflectance: float
    rotation: float
    solar_position_method: str
    daylight: np.ndarray
    sun_altitude: np.ndarray
    sun_azimuth: np.ndarray
    clearness: np.ndarray
    brightness: np.ndarray
    diffuse_horizontal_illuminance: np.ndarray
    direct_normal_illuminance: np.ndarray
    sun_illuminance: np.ndarray

    def __array__(self, dtype=None, copy=None):
        return self.luminance if dtype is None else self.luminance.astype(dtype)

    @property
    def shape(self) -> tuple[int, int]:
        return self.luminance.shape

    @property
    def sun_direction(self) -> np.ndarray:
        """(hours, 3) unit vectors towards each row's sun, in the matrix's frame."""
        a, z = np.radians(self.sun_altitude), np.radians(self.sun_azimuth)
        return np.column_stack([np.cos(a) * np.sin(z), np.cos(a) * np.cos(z), np.sin(a)])

    def horizontal_illuminance(self) -> np.ndarray:
        """(hours,) Σ L_p cos Z_p Ω_p over the sky patches [lux]: what the matrix gives an
        unobstructed horizontal sensor (the ground apart), by patch centres."""
        p = self.patches
        w = p.directions[p.sky, 2] * p.solid_angles[p.sky]
        return w @ self.luminance[p.sky]


def _hour_values(weather: HourlyWeather, values: str) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(direct normal, diffuse horizontal) irradiance [W/m²] and the file's illuminance
    [lux] (NaN with ``values="irradiance"``), refusing a row without what is needed."""
    dn_w, dh_w = weather.direct_normal_irradiance, weather.diffuse_horizontal_irradiance
    need = [("direct normal irradiance", dn_w), ("diffuse horizontal irradiance", dh_w)]
    dn_lux, dh_lux = weather.direct_normal_illuminance, weather.diffuse_horizontal_illuminance
    if values == "illuminance":
        if np.isnan(dn_lux).all() and np.isnan(dh_lux).all():
            raise InputError(f"{weather.label}: the file gives no illuminance (a .{weather.format} file has none "
                             "unless it is an EPW with them): use values='irradiance'")
        need += [("direct normal illuminance", dn_lux), ("diffuse horizontal illuminance", dh_lux)]
    for name, v in need:
        missing = np.flatnonzero(np.isnan(v))
        if len(missing):
            raise InputError(f"{weather.where(missing[0])}: the {name} is missing (values='{values}' needs it "
                             "in every hour)")
    return dn_w, dh_w, dn_lux, dh_lux


def _argument(value, name: str, low: float = -math.inf, high: float = math.inf) -> float:
    """A finite number within [low, high] given to :func:`sky_matrix`, else ValueError."""
    try:
        number = float(value)
    except (TypeError, ValueError):
        number = math.nan
    if isinstance(value, (bool, str)) or not (math.isfinite(number) and low <= number <= high):
        raise ValueError(f"{name} must be a finite number within {low:g} and {high:g}, got {value!r}")
    return number


def _dew_points(weather: HourlyWeather, dew_point: float | None) -> np.ndarray:
    """Per row: ``dew_point`` when given; else, as ``gendaymtx`` (2025) reads an EPW, the
    mean of the row's dew point and the two rows' before (the first row standing in for
    those before it, a missing value replaced by the last one given); 11 °C where the file
    gives none."""
    n = len(weather)
    if dew_point is not None:
        return np.full(n, float(dew_point))
    d = weather.dew_point
    given = ~np.isnan(d)
    if not given.any():
        return np.full(n, GENDAYMTX_DEW_POINT)
    last = np.maximum.accumulate(np.where(given, np.arange(n), -1))
    d = np.where(last >= 0, d[np.maximum(last, 0)], GENDAYMTX_DEW_POINT)
    padded = np.concatenate([d[:1], d[:1], d])
    return (padded[:-2] + padded[1:-1] + padded[2:]) / 3.0


def _sun_positions(weather: HourlyWeather, method: str) -> SolarPosition:
    if method == "gendaymtx":
        return gendaymtx_solar_position(weather)
    if method not in SOLAR_POSITION_METHODS:
        raise ValueError(f"solar_position must be one of {(*SOLAR_POSITION_METHODS, 'gendaymtx')}, got {method!r}")
    return weather.solar_position(method)


def _directions(altitude: np.ndarray, azimuth: np.ndarray) -> np.ndarray:
    """(hours, 3) unit vectors of altitudes and azimuths [°] (arrays;
    :func:`~lbl_illum.daylight.sky.sun_vector` for one)."""
    a, z = np.radians(altitude), np.radians(azimuth)
    return np.column_stack([np.cos(a) * np.sin(z), np.cos(a) * np.cos(z), np.sin(a)])


def sky_matrix(weather: HourlyWeather | str | Path, mf: int = 1, sun: str = "patches", values: str = "irradiance",
               ground_reflectance: float = 0.2, rotation: float = 0.0, dew_point: float | None = None,
               solar_position: str = "auto") -> SkyMatrix:
    """The sky matrix of a weather file (module text): patch luminance [cd/m²] per hour.

    weather : an :class:`HourlyWeather` or the path of an ``.epw`` or ``.wea`` file
    mf : Reinhart subdivision (1: Tregenza, 146 rows; 2: 578; 4: 2306)
    sun : ``"patches"`` — the direct sun spread over the 4 nearest sky patches, as
        ``gendaymtx`` does; ``"separate"`` — sky and ground only (``gendaymtx -s``), the sun
        in :attr:`SkyMatrix.sun_illuminance` and :attr:`SkyMatrix.sun_direction`
    values : ``"irradiance"`` — the direct normal and diffuse horizontal irradiance [W/m²],
        turned into illuminance by the Perez (1990) efficacies (``gendaymtx``);
        ``"illuminance"`` — the file's direct normal and diffuse horizontal illuminance [lux]
        (an EPW's) set the sky's and sun's brightness, the irradiances still shaping the sky
        (ε and Δ are defined on them), as :func:`~lbl_illum.daylight.sky.perez_sky_from_weather`
    ground_reflectance : ρ_g of the ground patch, ρ_g (E_dh + E_dn sin γ_s) / π (with either
        ``sun``: the ground is lit by the sun whether or not the sun is in the matrix)
    rotation : [°] the sky turned counter-clockwise seen from above (towards west of
        north) about the zenith, ``gendaymtx -r``: the sun's azimuth in the matrix frame is
        its true azimuth − rotation (the matrix of a model turned clockwise by the angle)
    dew_point : [°C] for every hour; None: the file's (a 3-hour mean, as ``gendaymtx``),
        11 °C for a ``.wea``
    solar_position : ``"auto"``, ``"pvlib"``, ``"noaa"`` (:func:`~lbl_illum.daylight.solar.solar_position`)
        or ``"gendaymtx"`` (:func:`gendaymtx_solar_position`, to reproduce Radiance)

    Rows whose sun, at the row's time (module :mod:`~lbl_illum.daylight.weather`: mid-hour
    for an EPW), is at or below the horizon, or without light, are zero columns.  A year at
    MF 1 takes about 0.03 s, at MF 4 0.3 s (the result, 2306 × 8760 values, is 160 MB).
    """
    if not isinstance(weather, HourlyWeather):
        weather = read_weather(weather)
    if sun not in SUN_OPTIONS:
        raise ValueError(f"sun must be one of {SUN_OPTIONS}, got {sun!r}")
    if values not in VALUE_OPTIONS:
        raise ValueError(f"values must be one of {VALUE_OPTIONS}, got {values!r}")
    ground_reflectance = _argument(ground_reflectance, "ground_reflectance", 0.0, 1.0)
    rotation = _argument(rotation, "rotation")
    if dew_point is not None:
        dew_point = _argument(dew_point, "dew_point", -80.0, 40.0)
    patches = sky_patches(mf)
    position = _sun_positions(weather, solar_position)
    alt = np.asarray(position.altitude, dtype=np.float64).reshape(-1)
    az = np.mod(np.asarray(position.azimuth, dtype=np.float64).reshape(-1) - rotation, 360.0)
    dn_w, dh_w, dn_lux, dh_lux = _hour_values(weather, values)
    water = precipitable_water(_dew_points(weather, dew_point))
    perez = perez_hours(dn_w, dh_w, alt, weather.day_of_year, water)
    if values == "irradiance":
        dn_lux, dh_lux = dn_w * perez.direct_efficacy, dh_w * perez.diffuse_efficacy
    daylight = (alt > 0.0) & (dn_w + dh_w > 0.0) & (dn_lux + dh_lux > 0.0)
    dn_lux, dh_lux = np.where(daylight, dn_lux, 0.0), np.where(daylight, dh_lux, 0.0)

    n_hours = len(weather)
    luminance = np.zeros((len(patches), n_hours))
    sky = patches.directions[patches.sky]
    omega = patches.solid_angles[patches.sky]
    cos_weight = sky[:, 2] * omega
    band_cos, band = np.unique(sky[:, 2], return_inverse=True)     # the gradation depends on the band only
    model_sun = _directions(90.0 - perez.zenith, az)               # the sun that shapes the sky
    true_sun = _directions(alt, az)
    hours = np.flatnonzero(daylight)
    step = max(1, _CHUNK_ELEMENTS // len(sky))
    for start in range(0, len(hours), step):
        h = hours[start:start + step]
        a, b, c, d, e = perez.coefficients[:, h]
        cos_chi = np.clip(sky @ model_sun[h].T, -1.0, 1.0)           # (patches, hours)
        with np.errstate(over="ignore"):
            gradation = (1.0 + a * np.exp(b / band_cos[:, None]))[band]
            lv = gradation * (1.0 + c * np.exp(d * np.arccos(cos_chi)) + e * cos_chi ** 2)
        lv = np.maximum(lv, 0.0)
        norm = cos_weight @ lv
        flat = norm <= _TINY                                        # no shape left: a uniform sky
        if flat.any():
            lv[:, flat] = 1.0
            norm = np.where(flat, math.pi, norm)
        luminance[patches.sky, h] = lv * (dh_lux[h] / norm)
        if sun == "patches":
            _add_sun(luminance, h, true_sun[h] @ sky.T, dn_lux[h], omega)
    sin_alt = np.sin(np.radians(alt))
    luminance[patches.GROUND] = ground_reflectance * (dh_lux + dn_lux * np.maximum(sin_alt, 0.0)) / math.pi
    night = np.where(daylight, 1.0, np.nan)
    return SkyMatrix(luminance=luminance, patches=patches, weather=weather, sun=sun, values=values,
                     ground_reflectance=ground_reflectance, rotation=rotation,
                     solar_position_method=position.method, daylight=daylight, sun_altitude=alt, sun_azimuth=az,
                     clearness=perez.clearness * night, brightness=perez.brightness * night,
                     diffuse_horizontal_illuminance=dh_lux, direct_normal_illuminance=dn_lux,
                     sun_illuminance=dn_lux.copy() if sun == "separate" else np.zeros(n_hours))


def sun_patch_weights(cos_theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The :data:`SUN_PATCHES` sky patches nearest each sun and their shares of it:
    ``cos_theta`` (hours, sky patches) are the cosines of the angles between the suns and
    the sky patches' centres; returns ``(near, share)``, (hours, 4) indices among the sky
    patches (row − 1) and weights summing to 1, w ∝ 1 / (1.002 − cos θ) (``gendaymtx``,
    ``AddDirect``)."""
    near = np.argpartition(-cos_theta, SUN_PATCHES - 1, axis=1)[:, :SUN_PATCHES]   # (hours, 4)
    w = 1.0 / (SUN_WEIGHT_OFFSET - np.take_along_axis(cos_theta, near, axis=1))
    return near, w / w.sum(axis=1, keepdims=True)


def _add_sun(luminance: np.ndarray, hours: np.ndarray, cos_theta: np.ndarray, direct_normal: np.ndarray,
             omega: np.ndarray) -> None:
    """Spread each hour's direct normal illuminance over the sky patches nearest the sun
    (:func:`sun_patch_weights`; ``cos_theta``: (hours, sky patches)), luminance += w E_dn
    / Ω (``gendaymtx``, ``AddDirect``)."""
    near, share = sun_patch_weights(cos_theta)
    luminance[1 + near, hours[:, None]] += share * direct_normal[:, None] / omega[near]

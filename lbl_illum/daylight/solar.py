"""Where the sun is, and what a weather file says about an hour: site, time, solar position,
air mass, extraterrestrial irradiance and EPW weather files.

Frames and units (docs/design.md §2): altitude in degrees above the horizon, azimuth in degrees
clockwise from north (east = 90°), latitude in degrees north, longitude in degrees **east**
(west negative; Radiance's ``gensky`` and ``gendaylit`` take west positive), time zones in
hours east of UTC (US Pacific standard time is −8), irradiance in W/m², illuminance in lux.

Solar position
--------------
:func:`solar_position` uses pvlib's implementation of the NREL Solar Position Algorithm
(Reda & Andreas 2004, uncertainty ±0.0003°) when pvlib is installed (the optional extra
``solar``), and otherwise this module's own implementation of the NOAA solar calculator
(the low-accuracy solar coordinates of Meeus 1998, ch. 25, and the equation of time of
ch. 28), which agrees with the SPA within about 0.01° for the years 1900–2100 (measured
against pvlib in ``tests/test_solar.py``).  Both give the *apparent* (refracted) altitude,
with the refraction formula of the SPA (eq. 42) for the pressure of the site's elevation
and 12 °C; the NOAA path leaves out the topocentric parallax (at most 0.0024°).

Weather files
-------------
:func:`read_epw` reads an EnergyPlus weather file (EPW; EnergyPlus "Auxiliary programs",
§2.9): the ``LOCATION`` header line gives the site, each data line one hour, the values of
hour ``h`` being those of the hour *ending* at ``h``:00 local standard time.  The reader
is this module's own, not pvlib's ``read_epw``: it reads only the dozen fields a sky
needs and names the line and field of any fault, which the scene file's one-line error
messages require; ``tests/test_solar.py`` checks that both read the same values.

References
----------
1. I. Reda, A. Andreas, "Solar position algorithm for solar radiation applications",
   Solar Energy 76(5), 577–589 (2004); NREL/TP-560-34302, revised 2008.
2. J. Meeus, *Astronomical Algorithms*, 2nd ed., Willmann-Bell (1998), ch. 25 and 28.
3. NOAA Global Monitoring Laboratory, solar calculator spreadsheet (NOAA_Solar_Calculations_day.xls),
   after Meeus.
4. F. Kasten, "A new table and approximation formula for the relative optical air mass",
   Arch. Meteorol. Geophys. Bioklimatol. B 14, 206–223 (1966).
5. J. W. Spencer, "Fourier series representation of the position of the sun", Search 2(5),
   172 (1971).
6. R. Perez, P. Ineichen, R. Seals, J. Michalsky, R. Stewart, "Modeling daylight availability
   and irradiance components from direct and global irradiance", Solar Energy 44(5), 271–289
   (1990).
"""

from __future__ import annotations

import datetime as _dt
import math
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Mapping

import numpy as np

from ..errors import InputError, check_keys, get_number
from ..optional import available

__all__ = [
    "Site", "SolarPosition", "WeatherFile", "WeatherRecord", "SOLAR_CONSTANT", "SOLAR_POSITION_METHODS",
    "site_from_table", "parse_time", "to_utc", "julian_day", "day_of_year", "solar_position",
    "sun_equatorial_coordinates", "have_pvlib", "air_mass_kasten1966", "extraterrestrial_normal_irradiance",
    "precipitable_water", "pressure_at_elevation", "read_epw",
]

#: Solar constant [W/m²] of the Perez models (Perez et al. 1990; Radiance's gendaylit).
SOLAR_CONSTANT = 1367.0
#: ``method`` values of :func:`solar_position`.
SOLAR_POSITION_METHODS = ("auto", "pvlib", "noaa")
#: Refraction is applied above this true altitude [°]: the sun's radius (0.26667°) plus the
#: refraction at the horizon (0.5667°), as the SPA (eq. 42) and pvlib do.
_REFRACTION_LIMIT = -(0.26667 + 0.5667)
#: Default air temperature [°C] for refraction (pvlib's default).
_TEMPERATURE = 12.0
_J2000 = 2451545.0
_UNIX_EPOCH_JD = 2440587.5


# ---------------------------------------------------------------------------
# Site and time
# ---------------------------------------------------------------------------

@dataclass(frozen=True)
class Site:
    """A place on Earth.

    latitude : [°] north positive;  longitude : [°] east positive
    time_zone : [h] east of UTC of the local standard time (None: not known)
    elevation : [m] above sea level (sets the pressure used for refraction)
    name : for messages and reports
    """

    latitude: float
    longitude: float
    time_zone: float | None = None
    elevation: float = 0.0
    name: str = ""

    def meridian_warning(self, where: str) -> str | None:
        """A warning when the longitude is far (> 30°, two hours) from the time zone's
        meridian: usually a sign error (west longitudes are negative here)."""
        if self.time_zone is None:
            return None
        off = (self.longitude - 15.0 * self.time_zone + 180.0) % 360.0 - 180.0
        if abs(off) > 30.0:
            return (f"{where}: longitude {self.longitude:g}° is {abs(off):.0f}° from the meridian of time zone "
                    f"{self.time_zone:+g} h ({15 * self.time_zone:g}°): west longitudes are negative")
        return None


def site_from_table(table: Mapping[str, Any], where: str) -> Site:
    """``[site]``: ``latitude`` [°N], ``longitude`` [°E], ``time_zone`` [h east of UTC],
    ``elevation`` [m] (default 0), ``name`` (optional)."""
    check_keys(table, ("latitude", "longitude", "time_zone", "elevation", "name"), where,
               required=("latitude", "longitude"))
    name = table.get("name", "")
    if not isinstance(name, str):
        raise InputError(f"{where}: 'name' must be a string, got {name!r}")
    tz = get_number(table, "time_zone", where, minimum=-14.0, maximum=14.0) if "time_zone" in table else None
    return Site(latitude=get_number(table, "latitude", where, minimum=-90.0, maximum=90.0),
                longitude=get_number(table, "longitude", where, minimum=-180.0, maximum=180.0),
                time_zone=tz,
                elevation=get_number(table, "elevation", where, default=0.0, minimum=-500.0, maximum=9000.0),
                name=name)


_TIME_RE = re.compile(
    r"^\s*(\d{4})-(\d{1,2})-(\d{1,2})[ T](\d{1,2}):(\d{2})(?::(\d{2}(?:\.\d*)?))?\s*"
    r"(Z|UTC|[+-]\d{1,2}(?::?\d{2})?)?\s*$", re.IGNORECASE)


def parse_time(value: Any, where: str, key: str = "time") -> tuple[_dt.datetime, float | None]:
    """A date and time from a scene file: ``(naive datetime, UTC offset [h] or None)``.

    Strings ``"YYYY-MM-DD HH:MM[:SS]"`` (or with ``T``) are local standard time of the site
    (offset None); a suffix ``Z`` or ``UTC`` means UTC and ``+HH:MM`` / ``-HH:MM`` any other
    offset.  TOML date-times (``time = 2024-06-21T12:00:00``, with or without an offset)
    are taken the same way.
    """
    if isinstance(value, _dt.datetime):
        if value.tzinfo is None:
            return value, None
        off = value.utcoffset()
        return value.replace(tzinfo=None), (off.total_seconds() / 3600.0 if off is not None else None)
    if not isinstance(value, str):
        raise InputError(f"{where}: '{key}' must be a date and time such as \"2024-06-21 12:00\", got {value!r}")
    m = _TIME_RE.match(value)
    if not m:
        raise InputError(f"{where}: '{key}' must look like \"2024-06-21 12:00\" (local standard time) or "
                         f"\"2024-06-21 12:00Z\" (UTC), got {value!r}")
    y, mo, d, h, mi = (int(m[i]) for i in range(1, 6))
    sec = float(m[6]) if m[6] else 0.0
    try:
        t = _dt.datetime(y, mo, d, h, mi) + _dt.timedelta(seconds=sec)
    except ValueError as exc:
        raise InputError(f"{where}: '{key}' {value!r}: {exc}") from None
    zone = m[7]
    if zone is None:
        return t, None
    if zone.upper() in ("Z", "UTC"):
        return t, 0.0
    sign = -1.0 if zone[0] == "-" else 1.0
    digits = zone[1:].replace(":", "")
    hours, minutes = (int(digits[:-2]), int(digits[-2:])) if len(digits) > 2 else (int(digits), 0)
    return t, sign * (hours + minutes / 60.0)


def to_utc(local: _dt.datetime, offset_hours: float) -> _dt.datetime:
    """UTC of a naive ``local`` time that is ``offset_hours`` east of UTC."""
    return local - _dt.timedelta(hours=offset_hours)


def julian_day(utc) -> np.ndarray:
    """Julian day(s) of naive UTC ``datetime`` (or a sequence of them, or ``datetime64``)."""
    t = np.asarray(utc, dtype="datetime64[us]")
    seconds = (t - np.datetime64("1970-01-01T00:00:00", "us")) / np.timedelta64(1, "s")
    return _UNIX_EPOCH_JD + np.asarray(seconds, dtype=np.float64) / 86400.0


def day_of_year(t: _dt.datetime) -> int:
    """1 on 1 January."""
    return t.timetuple().tm_yday


# ---------------------------------------------------------------------------
# Solar position
# ---------------------------------------------------------------------------

@dataclass(frozen=True)
class SolarPosition:
    """Apparent altitude [°] (refracted), azimuth [°] clockwise from north, and the method used."""

    altitude: np.ndarray | float
    azimuth: np.ndarray | float
    method: str


def have_pvlib() -> bool:
    """Whether pvlib can be imported (without importing it)."""
    return available("pvlib")


def pressure_at_elevation(elevation: float) -> float:
    """Standard-atmosphere pressure [hPa] at ``elevation`` [m] (the formula of pvlib's
    ``alt2pres``): 1013.25 (1 − 2.25577e-5 h)^5.25588."""
    return 1013.25 * (1.0 - 2.25577e-5 * elevation) ** 5.25588


def sun_equatorial_coordinates(jd) -> dict[str, np.ndarray]:
    """Apparent solar coordinates at Julian day(s) ``jd`` by the NOAA calculator
    (Meeus 1998, ch. 25 low accuracy; equation of time ch. 28 after Smart).

    Returns ``declination`` and ``right_ascension`` [°], ``equation_of_time`` [min]
    and ``apparent_longitude`` [°].  Uses UT in place of dynamical time (the ~70 s between
    them move the sun by 0.0008°).
    """
    jc = (np.asarray(jd, dtype=np.float64) - _J2000) / 36525.0
    L0 = np.mod(280.46646 + jc * (36000.76983 + jc * 0.0003032), 360.0)   # geometric mean longitude
    M = 357.52911 + jc * (35999.05029 - 0.0001537 * jc)                    # mean anomaly
    ecc = 0.016708634 - jc * (0.000042037 + 0.0000001267 * jc)             # orbit eccentricity
    Mr = np.radians(M)
    C = (np.sin(Mr) * (1.914602 - jc * (0.004817 + 0.000014 * jc))
         + np.sin(2 * Mr) * (0.019993 - 0.000101 * jc) + np.sin(3 * Mr) * 0.000289)   # equation of centre
    omega = np.radians(125.04 - 1934.136 * jc)                              # longitude of the Moon's node
    lam = np.radians(L0 + C - 0.00569 - 0.00478 * np.sin(omega))           # apparent longitude
    eps0 = 23.0 + (26.0 + (21.448 - jc * (46.815 + jc * (0.00059 - jc * 0.001813))) / 60.0) / 60.0
    eps = np.radians(eps0 + 0.00256 * np.cos(omega))                        # corrected obliquity
    decl = np.arcsin(np.sin(eps) * np.sin(lam))
    ra = np.mod(np.degrees(np.arctan2(np.cos(eps) * np.sin(lam), np.cos(lam))), 360.0)
    y = np.tan(eps / 2.0) ** 2
    L0r = np.radians(L0)
    eot = 4.0 * np.degrees(y * np.sin(2 * L0r) - 2 * ecc * np.sin(Mr) + 4 * ecc * y * np.sin(Mr) * np.cos(2 * L0r)
                           - 0.5 * y * y * np.sin(4 * L0r) - 1.25 * ecc * ecc * np.sin(2 * Mr))
    return {"declination": np.degrees(decl), "right_ascension": ra, "equation_of_time": eot,
            "apparent_longitude": np.mod(np.degrees(lam), 360.0)}


def _refraction(true_altitude, pressure: float, temperature: float):
    """Atmospheric refraction [°] to add to the true altitude (SPA eq. 42, Bennett's formula
    scaled by pressure [hPa] and temperature [°C]); 0 below :data:`_REFRACTION_LIMIT`."""
    e0 = np.asarray(true_altitude, dtype=np.float64)
    with np.errstate(invalid="ignore", divide="ignore"):
        r = (pressure / 1010.0) * (283.0 / (273.0 + temperature)) * 1.02 / (
            60.0 * np.tan(np.radians(e0 + 10.3 / (e0 + 5.11))))
    return np.where(e0 >= _REFRACTION_LIMIT, r, 0.0)


def _solar_position_noaa(jd, latitude, longitude, pressure, temperature):
    sun = sun_equatorial_coordinates(jd)
    frac = np.mod(np.asarray(jd, dtype=np.float64) - 0.5, 1.0)       # UTC fraction of the day
    true_solar_minutes = np.mod(frac * 1440.0 + sun["equation_of_time"] + 4.0 * longitude, 1440.0)
    H = np.radians(true_solar_minutes / 4.0 - 180.0)                  # hour angle, west positive
    phi, dec = np.radians(latitude), np.radians(sun["declination"])
    sin_alt = np.sin(phi) * np.sin(dec) + np.cos(phi) * np.cos(dec) * np.cos(H)
    alt = np.degrees(np.arcsin(np.clip(sin_alt, -1.0, 1.0)))
    az = np.mod(np.degrees(np.arctan2(np.sin(H), np.cos(H) * np.sin(phi) - np.tan(dec) * np.cos(phi))) + 180.0,
                360.0)
    return alt + _refraction(alt, pressure, temperature), az


def _solar_position_pvlib(utc, latitude, longitude, elevation, pressure, temperature):
    import pandas as pd
    from pvlib import solarposition

    times = pd.DatetimeIndex(np.atleast_1d(np.asarray(utc, dtype="datetime64[ns]"))).tz_localize("UTC")
    sp = solarposition.get_solarposition(times, latitude, longitude, altitude=elevation, pressure=pressure * 100.0,
                                         method="nrel_numpy", temperature=temperature)
    return sp["apparent_elevation"].to_numpy(), sp["azimuth"].to_numpy()


def solar_position(utc, latitude: float, longitude: float, elevation: float = 0.0, method: str = "auto",
                   pressure: float | None = None, temperature: float = _TEMPERATURE) -> SolarPosition:
    """Apparent solar altitude and azimuth at naive UTC time(s) ``utc`` for a site.

    utc : a ``datetime`` (naive, UTC), a sequence of them or ``datetime64`` values
    latitude, longitude : [°] north and east positive;  elevation : [m]
    method : ``"pvlib"`` (NREL SPA through pvlib), ``"noaa"`` (this module) or
        ``"auto"`` (pvlib when installed)
    pressure : [hPa] for refraction (default: standard atmosphere at ``elevation``)
    temperature : [°C] for refraction

    Returns scalars for a scalar time, arrays otherwise.
    """
    if method not in SOLAR_POSITION_METHODS:
        raise ValueError(f"method must be one of {SOLAR_POSITION_METHODS}, got {method!r}")
    if method == "auto":
        method = "pvlib" if have_pvlib() else "noaa"
    if pressure is None:
        pressure = pressure_at_elevation(elevation)
    scalar = np.ndim(np.asarray(utc, dtype="datetime64[us]")) == 0
    if method == "pvlib":
        if not have_pvlib():
            raise ImportError("solar position method 'pvlib' needs pvlib (pip install 'lbl_illum[solar]')")
        alt, az = _solar_position_pvlib(utc, latitude, longitude, elevation, pressure, temperature)
    else:
        alt, az = _solar_position_noaa(julian_day(utc), latitude, longitude, pressure, temperature)
    alt, az = np.asarray(alt, dtype=np.float64), np.asarray(az, dtype=np.float64)
    if scalar:
        return SolarPosition(float(alt.reshape(-1)[0]), float(az.reshape(-1)[0]), method)
    return SolarPosition(alt, az, method)


# ---------------------------------------------------------------------------
# Radiometry
# ---------------------------------------------------------------------------

def air_mass_kasten1966(zenith):
    """Relative optical air mass at solar zenith angle(s) ``zenith`` [°] (Kasten 1966),
    m = 1 / (cos Z + 0.15 (93.885 − Z)^−1.253), the formula of the Perez models; Z is
    limited to 90°."""
    z = np.minimum(np.asarray(zenith, dtype=np.float64), 90.0)
    return 1.0 / (np.cos(np.radians(z)) + 0.15 * (93.885 - z) ** -1.253)


def extraterrestrial_normal_irradiance(day):
    """Extraterrestrial normal irradiance E_0 [W/m²] on day of year ``day`` (1 = 1 January):
    the solar constant 1367 W/m² times Spencer's (1971) eccentricity correction
    1.00011 + 0.034221 cos Γ + 0.00128 sin Γ + 0.000719 cos 2Γ + 0.000077 sin 2Γ, Γ = 2π (day − 1)/365.
    ``day=None`` gives the mean distance, 1367 W/m².  A float for a scalar day, an array for
    an array of days."""
    if day is None:
        return SOLAR_CONSTANT
    g = 2.0 * np.pi * (np.asarray(day, dtype=np.float64) - 1) / 365.0
    e0 = SOLAR_CONSTANT * (1.00011 + 0.034221 * np.cos(g) + 0.00128 * np.sin(g)
                           + 0.000719 * np.cos(2 * g) + 0.000077 * np.sin(2 * g))
    return float(e0) if e0.ndim == 0 else e0


def precipitable_water(dew_point):
    """Atmospheric precipitable water W [cm] from the surface dew point [°C]:
    W = exp(0.07 T_d − 0.075) (Perez et al. 1990, after Wright, Perez & Michalsky 1989).
    A float for a scalar, an array for an array."""
    w = np.exp(0.07 * np.asarray(dew_point, dtype=np.float64) - 0.075)
    return float(w) if w.ndim == 0 else w


# ---------------------------------------------------------------------------
# EPW weather files
# ---------------------------------------------------------------------------

#: EPW data fields read (0-based index, name, value that means "missing").
_EPW_FIELDS = {
    "year": (0, None), "month": (1, None), "day": (2, None), "hour": (3, None), "minute": (4, None),
    "dry_bulb": (6, 99.9), "dew_point": (7, 99.9),
    "global_horizontal_irradiance": (13, 9999.0), "direct_normal_irradiance": (14, 9999.0),
    "diffuse_horizontal_irradiance": (15, 9999.0),
    "global_horizontal_illuminance": (16, 999999.0), "direct_normal_illuminance": (17, 999900.0),
    "diffuse_horizontal_illuminance": (18, 999900.0),
}
_EPW_MIN_FIELDS = 19
_EPW_HEADER_LINES = 8


@dataclass(frozen=True)
class WeatherRecord:
    """One hour of a weather file.  ``line`` is its line number in the file; ``hour`` is the
    hour *ending* at ``hour``:00 local standard time (1…24).  Irradiance [W/m²],
    illuminance [lux], temperatures [°C]; NaN where the file marks a value missing."""

    line: int
    year: int
    month: int
    day: int
    hour: int
    minute: int
    dry_bulb: float
    dew_point: float
    global_horizontal_irradiance: float
    direct_normal_irradiance: float
    diffuse_horizontal_irradiance: float
    global_horizontal_illuminance: float
    direct_normal_illuminance: float
    diffuse_horizontal_illuminance: float


@dataclass
class WeatherFile:
    """An EPW file: its site (from the ``LOCATION`` line), its hourly records and its header
    lines (``LOCATION`` … ``DATA PERIODS``, as read)."""

    path: Path
    site: Site
    records: list[WeatherRecord]
    header: tuple[str, ...] = ()

    def record_at(self, time: Any, where: str, key: str = "time") -> tuple[WeatherRecord, _dt.datetime]:
        """The record of ``time`` (``"MM-DD HH:MM"``, local standard time) and that time as a
        naive local ``datetime`` in the record's year.

        A time t belongs to the record of the hour ending at the next full hour at or after
        t: ``"06-21 12:00"`` and ``"06-21 11:30"`` both select the hour 11:00–12:00 (EPW
        hour 12); ``"06-22 00:00"`` is hour 24 of 21 June.
        """
        if not isinstance(time, str) or not (m := re.match(r"^\s*(\d{1,2})-(\d{1,2})\s+(\d{1,2}):(\d{2})\s*$", time)):
            raise InputError(f"{where}: '{key}' must look like \"06-21 12:00\" (month-day hour:minute, local "
                             f"standard time) with a weather file, got {time!r}")
        month, day, hour, minute = (int(m[i]) for i in range(1, 5))
        if not (1 <= month <= 12 and 1 <= day <= 31 and 0 <= hour <= 24 and 0 <= minute < 60) or (
                hour == 24 and minute):
            raise InputError(f"{where}: '{key}' {time!r} is not a valid month-day hour:minute")
        ending = hour + (1 if minute else 0)           # hour-ending record 1..24, or 0
        key_day = (month, day)
        if ending == 0:                                # 00:00 ends hour 24 of the day before
            key_day, ending = None, 24
        for rec in self.records:
            if key_day is None:
                if rec.hour == 24 and _next_day(rec) == (month, day):
                    break
            elif (rec.month, rec.day, rec.hour) == (month, day, ending):
                break
        else:
            raise InputError(f"{where}: '{key}' {time!r}: no such hour in {self.path.name} "
                             f"({_span(self.records)})")
        try:
            local = _dt.datetime(rec.year, month, day) + _dt.timedelta(hours=hour, minutes=minute)
        except ValueError as exc:
            raise InputError(f"{where}: '{key}' {time!r}: {exc}") from None
        return rec, local


def _next_day(rec: WeatherRecord) -> tuple[int, int]:
    try:
        t = _dt.date(rec.year, rec.month, rec.day) + _dt.timedelta(days=1)
    except ValueError:
        return (0, 0)
    return (t.month, t.day)


def _span(records: list[WeatherRecord]) -> str:
    if not records:
        return "the file has no hours"
    a, b = records[0], records[-1]
    return f"the file runs from {a.month:02d}-{a.day:02d} hour {a.hour} to {b.month:02d}-{b.day:02d} hour {b.hour}"


def read_epw(path: str | Path, where: str | None = None) -> WeatherFile:
    """Read an EPW weather file.  Every fault is an :class:`InputError` naming the file and
    the line (and field): ``weather.epw: line 12: field 15 (direct_normal_irradiance) ...``.

    ``where`` prefixes messages (default: the file's name).
    """
    path = Path(path)
    label = where or path.name
    lines = _weather_file_lines(path, label)
    if not lines or not lines[0].upper().startswith("LOCATION"):
        raise InputError(f"{label}: line 1: an EPW file starts with a LOCATION line")
    site = _epw_site(lines[0], label)
    records = []
    for i, line in enumerate(lines[_EPW_HEADER_LINES:], start=_EPW_HEADER_LINES + 1):
        if not line.strip():
            continue
        records.append(_epw_record(line, i, label))
    if not records:
        raise InputError(f"{label}: no data lines after the {_EPW_HEADER_LINES} header lines")
    return WeatherFile(path=path, site=site, records=records, header=tuple(lines[:_EPW_HEADER_LINES]))


def _weather_file_lines(path: Path, label: str) -> list[str]:
    """The lines of a weather file (undecodable bytes replaced), or an :class:`InputError`
    naming it when it is missing or cannot be read."""
    try:
        text = path.read_bytes().decode("utf-8", errors="replace")
    except FileNotFoundError:
        raise InputError(f"{label}: no such weather file") from None
    except OSError as exc:
        raise InputError(f"{label}: cannot read ({exc.strerror or exc})") from None
    return text.splitlines()


def _epw_site(line: str, label: str) -> Site:
    """LOCATION,city,state,country,source,WMO,latitude,longitude,time zone,elevation."""
    f = [s.strip() for s in line.split(",")]
    if len(f) < 10:
        raise InputError(f"{label}: line 1: the LOCATION line needs 10 fields (LOCATION, city, state, country, "
                         f"source, WMO, latitude, longitude, time zone, elevation), got {len(f)}")
    values = []
    for k, name, lo, hi in ((6, "latitude", -90, 90), (7, "longitude", -180, 180), (8, "time zone", -14, 14),
                            (9, "elevation", -500, 9000)):
        try:
            v = float(f[k])
        except ValueError:
            raise InputError(f"{label}: line 1: LOCATION field {k + 1} ({name}) must be a number, "
                             f"got {f[k]!r}") from None
        if not (math.isfinite(v) and lo <= v <= hi):
            raise InputError(f"{label}: line 1: LOCATION field {k + 1} ({name}) must be within {lo}…{hi}, got {v:g}")
        values.append(v)
    name = ", ".join(s for s in f[1:4] if s and s != "-")
    return Site(latitude=values[0], longitude=values[1], time_zone=values[2], elevation=values[3], name=name)


def _epw_record(line: str, number: int, label: str) -> WeatherRecord:
    f = line.split(",")
    if len(f) < _EPW_MIN_FIELDS:
        raise InputError(f"{label}: line {number}: a data line needs at least {_EPW_MIN_FIELDS} "
                         f"comma-separated fields, got {len(f)}")
    out: dict[str, Any] = {"line": number}
    for name, (k, missing) in _EPW_FIELDS.items():
        text = f[k].strip()
        try:
            v = float(text)
        except ValueError:
            raise InputError(f"{label}: line {number}: field {k + 1} ({name}) must be a number, got {text!r}") from None
        if not math.isfinite(v):
            raise InputError(f"{label}: line {number}: field {k + 1} ({name}) must be finite, got {text!r}")
        if missing is None:
            if v != int(v):
                raise InputError(f"{label}: line {number}: field {k + 1} ({name}) must be a whole number, got {text!r}")
            out[name] = int(v)
        else:
            out[name] = math.nan if v >= missing else v
    for name, lo, hi in (("month", 1, 12), ("day", 1, 31), ("hour", 1, 24), ("minute", 0, 60)):
        if not lo <= out[name] <= hi:
            k = _EPW_FIELDS[name][0]
            raise InputError(f"{label}: line {number}: field {k + 1} ({name}) must be within {lo}…{hi}, "
                             f"got {out[name]}")
    for name in ("global_horizontal_irradiance", "direct_normal_irradiance", "diffuse_horizontal_irradiance",
                 "global_horizontal_illuminance", "direct_normal_illuminance", "diffuse_horizontal_illuminance"):
        if out[name] < 0:
            k = _EPW_FIELDS[name][0]
            raise InputError(f"{label}: line {number}: field {k + 1} ({name}) must be >= 0, got {out[name]:g}")
    return WeatherRecord(**out)

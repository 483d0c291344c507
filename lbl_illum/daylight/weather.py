"""The hours of a weather file as arrays, for annual daylight: EnergyPlus (EPW) and
Radiance/DAYSIM (``.wea``) files read into one :class:`HourlyWeather` table.

:func:`read_weather` reads either kind, by the file's extension, and returns per row
(hour) its date, the local standard time at which the sun is taken, the direct normal
and diffuse horizontal irradiance [W/m²], the direct normal and diffuse horizontal
illuminance [lux] and the dew point [°C] (NaN where the file has no such value), and
the site.  The sky matrix of :mod:`lbl_illum.daylight.skymatrix` is made from it.

Hour convention
---------------
An EPW row of hour H (1…24) holds the values of the hour *ending* at H:00 local standard
time (EnergyPlus "Auxiliary programs", §2.9); the sun of that row is taken at the middle
of the hour, H − 0.5 (``hour`` = 11.5 for the row of hour 12), as Radiance's ``gendaymtx``
does with an hourly EPW (``loadEPW.c``: hour − 1 + 0.5) and as ``epw2wea`` writes it
(``epw2wea.c``: hour − 0.5, e.g. ``1 1 0.500`` for the first row).  A ``.wea`` row carries
that decimal hour itself, which is taken as it is.  Times are local standard time (no
daylight saving) of the file's time zone.

The ``.wea`` format (DAYSIM; Radiance ``gendaymtx``, ``epw2wea``)
-----------------------------------------------------------------
::

    place Oakland Metropolitan Arpt_USA
    latitude 37.72
    longitude 122.22          <- degrees WEST of Greenwich (east negative)
    time_zone 120             <- degrees WEST of Greenwich of the standard meridian (15 per hour)
    site_elevation 2.0        <- metres
    weather_data_file_units 1 <- 1: direct normal and diffuse horizontal irradiance, W/m²
    1 1 0.500 0 0             <- month day hour direct_normal diffuse_horizontal
    ...

The signs are those of ``epw2wea`` (``longitude = −EPW longitude``, ``time_zone =
−15 × EPW time zone``) and of ``gendaymtx``'s reader (``loadEPW.c``: longitude × −1, time
zone × −1/15), so ``time_zone 120`` is UTC−8 (US Pacific) and ``longitude 122.22`` is
122.22° W.  :class:`HourlyWeather` holds the site in this package's convention (east
positive, time zone in hours east of UTC).  Data lines have 5 columns, or 7 as
``epw2wea -a`` writes them (aerosol optical depth and sky cover, not read).  Only units 1
are read: units 2 (direct horizontal) and 3 (photometric) are refused with a message.

Input checks
------------
Every fault is an :class:`~lbl_illum.errors.InputError` whose one-line message names the
file and the line, in the manner of :func:`~lbl_illum.daylight.solar.read_epw`
(``oak.wea: line 12: column 4 (direct_normal_irradiance) must be a number, got 'x'``): an
unknown extension, a missing file, a value that is not a number or out of range
(irradiance ≤ 1415 W/m² and illuminance ≤ 138 011 lx, what reaches the top of the
atmosphere at the Sun's nearest), a wrong number of columns, a missing or repeated header
line, rows out of time order, and an EPW whose rows do not run hour by hour through the
period its ``DATA PERIODS`` line names (a truncated or padded file).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import InputError
from .sky import MAX_EXTRATERRESTRIAL_ILLUMINANCE, MAX_EXTRATERRESTRIAL_IRRADIANCE
from .solar import SolarPosition, Site, WeatherFile, _weather_file_lines, read_epw, solar_position

__all__ = ["HourlyWeather", "read_weather", "read_wea", "weather_from_epw", "WEA_HEADER_KEYS",
           "REFERENCE_YEAR", "REFERENCE_LEAP_YEAR"]

#: Header keys of a ``.wea`` file, in the order DAYSIM and ``epw2wea`` write them.
WEA_HEADER_KEYS = ("place", "latitude", "longitude", "time_zone", "site_elevation", "weather_data_file_units")
#: The year whose calendar places the sun for a file without one year of its own (a typical
#: meteorological year mixes years, a ``.wea`` has none): a common year, or
#: :data:`REFERENCE_LEAP_YEAR` when the file has a 29 February.
REFERENCE_YEAR = 2023
REFERENCE_LEAP_YEAR = 2024

#: Days in each month of a leap year (29 February is a valid date; whether the year has it is
#: decided by the file).
_MONTH_DAYS = np.array([31, 29, 31, 30, 31, 30, 31, 31, 30, 31, 30, 31])
#: Day of a leap year before each month (index 0 = January).
_MONTH_START = np.concatenate([[0], np.cumsum(_MONTH_DAYS)[:-1]])
_WEA_COLUMNS = ("month", "day", "hour", "direct_normal_irradiance", "diffuse_horizontal_irradiance")


@dataclass(frozen=True, eq=False)
class HourlyWeather:
    """The rows of a weather file as arrays (one entry per row, ``len`` rows).

    path : the file;  format : ``"epw"`` or ``"wea"``
    site : latitude [°N], longitude [°E], time zone [h east of UTC], elevation [m]
    month, day : the row's date;  line : its line number in the file (for messages)
    hour : local standard time [h] at which the row's sun is taken: H − 0.5 for the EPW
        row of the hour ending at H:00, the decimal hour as written for a ``.wea`` row
    direct_normal_irradiance, diffuse_horizontal_irradiance : [W/m²]
    direct_normal_illuminance, diffuse_horizontal_illuminance : [lux] (NaN in a ``.wea``)
    dew_point : [°C] (NaN in a ``.wea``)
    year : the year whose calendar places the sun (the file's, when all its EPW rows give the
        same one; otherwise :data:`REFERENCE_YEAR`, or :data:`REFERENCE_LEAP_YEAR` when the
        file has a 29 February)

    NaN marks a value the file gives as missing.
    """

    path: Path
    format: str
    site: Site
    month: np.ndarray
    day: np.ndarray
    hour: np.ndarray
    direct_normal_irradiance: np.ndarray
    diffuse_horizontal_irradiance: np.ndarray
    direct_normal_illuminance: np.ndarray
    diffuse_horizontal_illuminance: np.ndarray
    dew_point: np.ndarray
    line: np.ndarray
    year: int

    def __post_init__(self):
        n = len(self.month)
        for name in ("month", "day", "line"):
            object.__setattr__(self, name, np.asarray(getattr(self, name), dtype=np.int64))
        for name in ("hour", "direct_normal_irradiance", "diffuse_horizontal_irradiance",
                     "direct_normal_illuminance", "diffuse_horizontal_illuminance", "dew_point"):
            object.__setattr__(self, name, np.asarray(getattr(self, name), dtype=np.float64))
        for name in ("day", "hour", "direct_normal_irradiance", "diffuse_horizontal_irradiance",
                     "direct_normal_illuminance", "diffuse_horizontal_illuminance", "dew_point", "line"):
            if len(getattr(self, name)) != n:
                raise ValueError(f"HourlyWeather: '{name}' has {len(getattr(self, name))} values, 'month' {n}")
        if self.site.time_zone is None:
            raise ValueError("HourlyWeather: the site needs a time zone (the rows are in local standard time)")

    def __len__(self) -> int:
        return len(self.month)

    @property
    def label(self) -> str:
        """The file's name, as messages name it."""
        return Path(self.path).name

    def where(self, row: int) -> str:
        """``"oak.wea: line 12"`` for row ``row`` (0-based), to start a message."""
        return f"{self.label}: line {int(self.line[row])}"

    @property
    def date(self) -> np.ndarray:
        """The rows' dates in :attr:`year` (``datetime64[D]``)."""
        months = np.datetime64(f"{self.year:04d}-01", "M") + (self.month - 1)
        return months.astype("datetime64[D]") + (self.day - 1)

    @property
    def day_of_year(self) -> np.ndarray:
        """1 on 1 January (of :attr:`year`: 1 March is day 61 in a leap year)."""
        return (self.date - np.datetime64(f"{self.year:04d}-01-01", "D")).astype(np.int64) + 1

    def local_time(self) -> np.ndarray:
        """Local standard time of each row's sun (``datetime64[ms]``)."""
        return self.date.astype("datetime64[ms]") + np.round(self.hour * 3.6e6).astype("timedelta64[ms]")

    def utc(self) -> np.ndarray:
        """UTC of each row's sun (``datetime64[ms]``): local standard time − time zone."""
        offset = np.timedelta64(int(round(self.site.time_zone * 3.6e6)), "ms")
        return self.local_time() - offset

    def solar_position(self, method: str = "auto") -> SolarPosition:
        """Apparent altitude and azimuth [°] of each row's sun
        (:func:`~lbl_illum.daylight.solar.solar_position`: NREL SPA through pvlib when
        installed, else the NOAA calculator; refracted for the site's elevation)."""
        s = self.site
        return solar_position(self.utc(), s.latitude, s.longitude, s.elevation, method=method)


# ---------------------------------------------------------------------------
# Dispatch
# ---------------------------------------------------------------------------

def read_weather(path: str | Path) -> HourlyWeather:
    """Read an hourly weather file by its extension: ``.epw`` (EnergyPlus,
    :func:`weather_from_epw`) or ``.wea`` (Radiance/DAYSIM, :func:`read_wea`).  Faults are
    :class:`~lbl_illum.errors.InputError` naming the file and line (module text)."""
    path = Path(path)
    kind = path.suffix.lower()
    if kind == ".epw":
        return weather_from_epw(read_epw(path), path.name)
    if kind == ".wea":
        return read_wea(path)
    raise InputError(f"{path.name}: unknown kind of weather file {kind or '(no extension)'!r}: "
                     "read_weather reads .epw (EnergyPlus) and .wea (Radiance/DAYSIM) files")


def _check_range(values: np.ndarray, top: float, where, name: str, unit: str) -> None:
    """Refuse the first value of ``values`` that is above ``top`` (NaN passes):
    ``where(i)`` starts the message of row i."""
    bad = np.flatnonzero(values > top)
    if len(bad):
        i = bad[0]
        raise InputError(f"{where(i)}: {name} {values[i]:g} {unit} is more than reaches the top of the atmosphere "
                         f"({top:.6g} {unit} at the Sun's nearest)")


def _check_dates(month: np.ndarray, day: np.ndarray, where, what: str) -> None:
    """Refuse a day beyond its month's length (29 February passes)."""
    bad = np.flatnonzero(day > _MONTH_DAYS[month - 1])
    if len(bad):
        i = bad[0]
        raise InputError(f"{where(i)}: {what} {month[i]:02d}-{day[i]:02d} is not a date "
                         f"(month {month[i]} has {_MONTH_DAYS[month[i] - 1]} days)")


def _year_for(month: np.ndarray, day: np.ndarray, years: set[int] | None = None) -> int:
    """The file's one year when it has one that fits its dates, else the reference year."""
    leap_day = bool(np.any((month == 2) & (day == 29)))
    if years is not None and len(years) == 1:
        year = next(iter(years))
        is_leap = year % 4 == 0 and (year % 100 != 0 or year % 400 == 0)
        if 1 <= year <= 9999 and (is_leap or not leap_day):
            return year
    return REFERENCE_LEAP_YEAR if leap_day else REFERENCE_YEAR


# ---------------------------------------------------------------------------
# EPW
# ---------------------------------------------------------------------------

def _epw_data_period(wf: WeatherFile, label: str) -> tuple[tuple[int, int], tuple[int, int]]:
    """(start (month, day), end (month, day)) of the ``DATA PERIODS`` header line (line 8),
    which must give one period of hourly records."""
    where = f"{label}: line 8"
    text = wf.header[7] if len(wf.header) >= 8 else ""
    f = [s.strip() for s in text.split(",")]
    if f[0].upper() != "DATA PERIODS" or len(f) < 7:
        raise InputError(f"{where}: an EPW file's line 8 is 'DATA PERIODS,1,1,name,weekday,start,end' "
                         f"(start and end as month/day), got {text[:40]!r}")
    if f[1] != "1":
        raise InputError(f"{where}: DATA PERIODS gives {f[1]!r} periods; one period is read")
    if f[2] != "1":
        raise InputError(f"{where}: DATA PERIODS gives {f[2]!r} records per hour; hourly files (1) are read")
    dates = []
    for k, text_date in ((5, f[5]), (6, f[6])):
        parts = [p.strip() for p in text_date.split("/")]
        try:
            month, day = int(parts[0]), int(parts[1])
            if len(parts) > 3 or not (1 <= month <= 12 and 1 <= day <= _MONTH_DAYS[month - 1]):
                raise ValueError
        except (ValueError, IndexError):
            raise InputError(f"{where}: DATA PERIODS field {k + 1} must be a date month/day, got {text_date!r}") \
                from None
        dates.append((month, day))
    return dates[0], dates[1]


def weather_from_epw(wf: WeatherFile, label: str | None = None) -> HourlyWeather:
    """The :class:`HourlyWeather` of an EPW file read by
    :func:`~lbl_illum.daylight.solar.read_epw`, after checking that its rows run hour by hour
    (1…24 each day, days in calendar order, 29 February optional) from the first to the last
    day of its ``DATA PERIODS`` line, and that no direct normal or diffuse horizontal value
    exceeds what reaches the top of the atmosphere."""
    label = label or wf.path.name
    recs = wf.records
    start, end = _epw_data_period(wf, label)
    line = np.array([r.line for r in recs])
    month = np.array([r.month for r in recs])
    day = np.array([r.day for r in recs])
    hour = np.array([r.hour for r in recs])

    def where(i):
        return f"{label}: line {line[i]}"

    _check_dates(month, day, where, "the date")
    # rows as hours of a leap-year calendar; each must follow the one before by one hour,
    # or by 25 over an absent 29 February, or wrap from 31 December hour 24 to 1 January hour 1
    t = (_MONTH_START[month - 1] + day - 1) * 24 + hour - 1
    step = np.diff(t)
    feb28_end = (month[:-1] == 2) & (day[:-1] == 28) & (hour[:-1] == 24)
    ok = (step == 1) | ((step == 25) & feb28_end) | ((step == 1 - 366 * 24) & (month[:-1] == 12))
    span = f"DATA PERIODS (line 8) gives {start[0]}/{start[1]} to {end[0]}/{end[1]}"
    if not ok.all():
        i = int(np.flatnonzero(~ok)[0]) + 1
        raise InputError(f"{where(i)}: {month[i]:02d}-{day[i]:02d} hour {hour[i]} follows {month[i - 1]:02d}-"
                         f"{day[i - 1]:02d} hour {hour[i - 1]}: an hourly EPW file has each hour of its data period "
                         "once, in order")
    if (month[0], day[0], hour[0]) != (*start, 1):
        raise InputError(f"{where(0)}: the data start at {month[0]:02d}-{day[0]:02d} hour {hour[0]}; {span}")
    if (month[-1], day[-1], hour[-1]) != (*end, 24):
        raise InputError(f"{where(len(recs) - 1)}: the data end at {month[-1]:02d}-{day[-1]:02d} hour {hour[-1]}; "
                         f"{span}")

    def column(name):
        return np.array([getattr(r, name) for r in recs], dtype=np.float64)

    values = {name: column(name) for name in ("direct_normal_irradiance", "diffuse_horizontal_irradiance",
                                              "direct_normal_illuminance", "diffuse_horizontal_illuminance",
                                              "dew_point")}
    for name, top, unit in (("direct_normal_irradiance", MAX_EXTRATERRESTRIAL_IRRADIANCE, "W/m2"),
                            ("diffuse_horizontal_irradiance", MAX_EXTRATERRESTRIAL_IRRADIANCE, "W/m2"),
                            ("direct_normal_illuminance", MAX_EXTRATERRESTRIAL_ILLUMINANCE, "lux"),
                            ("diffuse_horizontal_illuminance", MAX_EXTRATERRESTRIAL_ILLUMINANCE, "lux")):
        _check_range(values[name], top, where, name, unit)
    return HourlyWeather(path=wf.path, format="epw", site=wf.site, month=month, day=day, hour=hour - 0.5,
                         line=line, year=_year_for(month, day, {r.year for r in recs}), **values)


# ---------------------------------------------------------------------------
# .wea
# ---------------------------------------------------------------------------

#: (key, lowest, highest) of the numeric header values, in the file's units (degrees west).
_WEA_RANGES = {"latitude": (-90.0, 90.0), "longitude": (-180.0, 180.0), "time_zone": (-210.0, 210.0),
               "site_elevation": (-500.0, 9000.0)}


def _finite(word: str) -> bool:
    try:
        return math.isfinite(float(word))
    except ValueError:
        return False


def _numbers(words: list[str], where: str, names: list[str]) -> list[float]:
    """The numbers of a line's ``words``, or an :class:`InputError` naming the first that is
    not a finite number by its name in ``names``."""
    bad = next((k for k, word in enumerate(words) if not _finite(word)), None)
    if bad is not None:
        raise InputError(f"{where}: {names[bad]} must be a finite number, got {words[bad]!r}")
    return [float(word) for word in words]


def _wea_header(lines: list[str], label: str) -> tuple[dict[str, str], int]:
    """The header values by key and the index of the first data line."""
    header: dict[str, str] = {}
    i = 0
    for i, line in enumerate(lines):
        words = line.split(None, 1)
        if not words:
            continue
        key = words[0]
        try:
            float(key)
            break                               # the first data line
        except ValueError:
            pass
        if key not in WEA_HEADER_KEYS:
            raise InputError(f"{label}: line {i + 1}: unknown header line {key!r} (a .wea header has "
                             f"{', '.join(WEA_HEADER_KEYS)})")
        if key in header:
            raise InputError(f"{label}: line {i + 1}: a second {key!r} line")
        header[key] = words[1].strip() if len(words) > 1 else ""
    else:
        i = len(lines)
    for key in WEA_HEADER_KEYS:
        if key not in header:
            raise InputError(f"{label}: line {i + 1}: the header has no {key!r} line (a .wea header has "
                             f"{', '.join(WEA_HEADER_KEYS)})")
    return header, i


def read_wea(path: str | Path) -> HourlyWeather:
    """Read a Radiance/DAYSIM ``.wea`` weather file (module text): the header's site, with
    longitude and time zone turned from the file's degrees west into degrees east and hours
    east of UTC, and per data line month, day, decimal hour (local standard time of the
    row's sun, taken as written), direct normal and diffuse horizontal irradiance [W/m²]."""
    path = Path(path)
    label = path.name
    lines = _weather_file_lines(path, label)
    header, first = _wea_header(lines, label)
    number = {}
    for key, (lo, hi) in _WEA_RANGES.items():
        where = f"{label}: line {_header_line(lines, key)}"
        v, = _numbers([header[key]], where, [f"{key!r}"])
        if not lo <= v <= hi:
            raise InputError(f"{where}: {key!r} must be within {lo:g}…{hi:g}, got {v:g}")
        number[key] = v
    units = header["weather_data_file_units"]
    if units != "1":
        raise InputError(f"{label}: line {_header_line(lines, 'weather_data_file_units')}: weather_data_file_units "
                         f"{units!r} is not read; only 1 (direct normal and diffuse horizontal irradiance, W/m2)")
    rows, line_numbers = [], []
    for i in range(first, len(lines)):
        words = lines[i].split()
        if not words:
            continue
        where = f"{label}: line {i + 1}"
        if len(words) not in (5, 7):
            raise InputError(f"{where}: a data line has 5 columns (month day hour direct_normal_irradiance "
                             f"diffuse_horizontal_irradiance), or 7 as epw2wea -a writes them; got {len(words)}")
        rows.append(_numbers(words[:5], where, [f"column {k + 1} ({name})" for k, name in enumerate(_WEA_COLUMNS)]))
        line_numbers.append(i + 1)
    if not rows:
        raise InputError(f"{label}: no data lines after the header")
    data = np.array(rows)
    line = np.array(line_numbers)

    def where(i):
        return f"{label}: line {line[i]}"

    for k, (name, lo, hi) in enumerate((("month", 1, 12), ("day", 1, 31), ("hour", 0, 24))):
        bad = np.flatnonzero((data[:, k] < lo) | (data[:, k] > hi) | ((data[:, k] != np.round(data[:, k])) & (k < 2)))
        if len(bad):
            kind = "a whole number " if k < 2 else ""
            raise InputError(f"{where(bad[0])}: column {k + 1} ({name}) must be {kind}within {lo}…{hi}, "
                             f"got {data[bad[0], k]:g}")
    month, day, hour = data[:, 0].astype(np.int64), data[:, 1].astype(np.int64), data[:, 2]
    _check_dates(month, day, where, "the date")
    for k in (3, 4):
        bad = np.flatnonzero(data[:, k] < 0)
        if len(bad):
            raise InputError(f"{where(bad[0])}: column {k + 1} ({_WEA_COLUMNS[k]}) must be >= 0, "
                             f"got {data[bad[0], k]:g}")
        _check_range(data[:, k], MAX_EXTRATERRESTRIAL_IRRADIANCE, where, _WEA_COLUMNS[k], "W/m2")
    # time order: each row after the one before, except a new year (December → January)
    t = (_MONTH_START[month - 1] + day - 1) * 24.0 + hour
    back = np.flatnonzero((np.diff(t) <= 0) & ~((month[:-1] == 12) & (month[1:] == 1)))
    if len(back):
        i = back[0] + 1
        raise InputError(f"{where(i)}: {month[i]:02d}-{day[i]:02d} {hour[i]:g} h does not come after the line before "
                         f"({month[i - 1]:02d}-{day[i - 1]:02d} {hour[i - 1]:g} h): the rows are in time order")
    site = Site(latitude=number["latitude"], longitude=0.0 - number["longitude"],
                time_zone=0.0 - number["time_zone"] / 15.0, elevation=number["site_elevation"], name=header["place"])
    def missing():
        return np.full(len(rows), np.nan)

    return HourlyWeather(path=path, format="wea", site=site, month=month, day=day, hour=hour,
                         direct_normal_irradiance=data[:, 3], diffuse_horizontal_irradiance=data[:, 4],
                         direct_normal_illuminance=missing(), diffuse_horizontal_illuminance=missing(),
                         dew_point=missing(), line=line, year=_year_for(month, day))


def _header_line(lines: list[str], key: str) -> int:
    """Line number of a header key (present: :func:`_wea_header` checked it)."""
    return next(i + 1 for i, line in enumerate(lines) if line.split(None, 1)[:1] == [key])

"""Annual climate-based daylight metrics of a sensor grid: occupancy, DA, cDA, UDI, ASE,
sDA with operable shades (IES LM-83-12), LEED v4.1 points and EN 17037 daylight provision.

Nothing here computes light.  The input is hourly illuminance at P sensor points for the
T rows of a weather file (T = 8760 for a year), as (P, T) arrays [lux]:

* ``illuminance``: total illuminance with every shade open;
* ``direct_sun``: the illuminance of the sun's disk alone, through the glazing, with no
  reflection (for ASE and the shade rule);
* for each window group with operable shades, a :class:`WindowGroup`: the same two arrays
  with that group's shades closed and every other group's open.

Hours
-----
Row ``r`` of a year is hour ``r % 24 + 1`` of day ``r // 24 + 1`` (1 January is day 1; a
year has 365 days, 29 February is not a row, as in EPW and TMY files).  A row is named by
the hour *ending* it: row hour H (1…24) covers H − 1 … H local **standard** time, the
weather file's convention (EnergyPlus "Auxiliary programs", EPW data fields).

Occupancy
---------
Metrics are taken over the occupied hours, each row weighted by its occupancy
w_r ∈ [0, 1] (1 occupied, 0 empty, a fraction for a partly occupied hour).

* :func:`lm83_occupancy`, the default of IES LM-83-12 §2.2.1: 8:00 to 18:00 local clock
  time, every day of the year (no weekends or holidays), 10 hours a day, 3650 hours a
  year.  Without daylight-saving time (``dst=None``, the default) the occupied rows are
  those whose hour-ending H satisfies 8 < H ≤ 18 (H = 9…18, i.e. 8:00–18:00 standard
  time).  LM-83 speaks of local clock time; where clocks move in summer give
  ``dst="us"`` (second Sunday of March to the first Sunday of November, the rule since
  2007) or ``dst="eu"`` (last Sunday of March to the last Sunday of October) and the
  ``year`` whose calendar the weather file stands for: on those days the clock is one
  hour ahead, 8:00–18:00 clock time is 7:00–17:00 standard time, and the occupied rows
  are 7 < H ≤ 17.  The change happens at night (2:00 in the US, 1:00 UTC in the EU), so a
  change-over day's office hours are wholly on its new time.  Either way the year has
  3650 occupied rows.  Standard time is this module's default, as in Honeybee's LEED
  post-processing (honeybee-radiance-postprocess, ``occupancy_schedule_8_to_6``: rows
  8…17 of each day, no daylight-saving time).  Rows with night hours across midnight
  on summer days are not moved to the day before.
* :func:`read_schedule`: a schedule file, one occupancy per row (see there).

Per-point metrics (:func:`point_metrics`), over the occupied hours, w_r the weights and
W = Σ w_r the occupied hours [h]; E the illuminance [lux] of a point at row r:

====================  ============================================================  =========
metric                definition                                                    source
====================  ============================================================  =========
DA(t)                 100 · Σ w_r [E ≥ t] / W [%], default t = 300 lux              [1], [2]
cDA(t)                100 · Σ w_r min(1, E / t) / W [%]: partial credit below t     [3]
UDI fell short        100 · Σ w_r [E < 100] / W [%]                                 [4], [5]
UDI supplementary     100 · Σ w_r [100 ≤ E < 300] / W [%]                           [6]
UDI autonomous        100 · Σ w_r [300 ≤ E ≤ 3000] / W [%]                          [6]
UDI useful            supplementary + autonomous: 100 ≤ E ≤ 3000 [%]                [4], [6]
UDI exceeded          100 · Σ w_r [E > 3000] / W [%]                                [4], [6]
ASE hours             Σ w_r [E_sun ≥ 1000] [h], E_sun the direct sun                [1]
====================  ============================================================  =========

The UDI limits are those of Mardaljevic et al. 2012 [6] (100, 300, 3000 lux); the original
papers [4, 5] put the upper limit at 2000 lux (``udi_limits=(100, 300, 2000)``).

Spatial metrics (per area and overall, over the points as equal shares of the floor, as
the grids of :mod:`lbl_illum.workplane.grid` lay them; ``100 · k / n`` is computed from
the counts, so a boundary such as 11 of 20 points = 55 % is exact):

* sDA300/50% = percent of points with DA300 ≥ 50 % of the occupied hours, with the
  shades operated as LM-83 §2.2.6 has it when window groups are given (below) [1];
* ASE1000,250 = percent of points with **more than** 250 occupied hours of direct sun
  ≥ 1000 lux, always with the shades open [1] §3.

Operable shades (:func:`operate_shades`, LM-83-12 §2.2.6): each hour, the shades of a
window group close when more than 2 % of the points of an area receive direct sun of
1000 lux or more.  With G groups, each hour takes the *least shaded* combination of
closed groups that leaves at most 2 % of every area's points at ≥ 1000 lux of direct sun:

* G ≤ ``EXHAUSTIVE_GROUPS`` (4): every combination is tried; the fewest closed groups
  win, among as many the one that leaves the highest mean illuminance over the area's
  points, then the first in the order of :func:`itertools.combinations` over the groups
  as given;
* more groups: a greedy rule, one group closed at a time, each time the one that leaves
  the fewest points at ≥ 1000 lux (ties: the highest mean illuminance, then the earlier
  group), until the area complies;
* when no combination complies (sun through glazing without shades), every group
  closes and the hour is counted as *unresolved*;
* each area (each distinct area name; unnamed points form one area) is judged on its
  own points; a group is closed when any area needs it closed.

The arrays of a combination come from the per-group ones by superposition: the light of
each window group adds to the rest, so with the groups C closed,
X_C = X_open + Σ_{g∈C} (X_g − X_open), for X the illuminance and the direct sun (exact
when closing a shade changes only what passes its own windows; shades' reflections back
into the room are then part of X_g).

LEED v4.1 BD+C, EQ credit Daylight, Option 1 (:func:`leed_points`; credit language as
published by USGBC, Table 1): average sDA300/50% of the regularly occupied floor ≥ 40 % →
1 point, ≥ 55 % → 2 points, ≥ 75 % → 3 points; every regularly occupied space at
sDA300/50% ≥ 55 % → one more point when 2 were reached (3 at most), exemplary performance
when 3 were.  Healthcare: 1 point at 40 %, 2 at 55 %, and 75 % or every space at 55 % is
exemplary performance (2 points at most).  ASE1000,250 sets no point: a space above 10 %
must show how its design addresses glare (v4.1; LEED v4 required ASE ≤ 10 %).

EN 17037:2018 daylight provision, illuminance method (:func:`en17037_provision`, EN 17037
§5.1 and Table A.1): over the *daylight hours*, half of the year's hours (4380) with the
highest outdoor diffuse horizontal illuminance (:func:`en17037_daylight_hours`), a level is
reached when, for at least 50 % of the daylight hours each, the target illuminance E_T is
reached over at least 50 % of the points and the minimum target illuminance E_TM over at
least 95 % of them:

=========  ==============  =================
level      E_T (50 %)      E_TM (95 %)
=========  ==============  =================
minimum    300 lux         100 lux
medium     500 lux         300 lux
high       750 lux         500 lux
=========  ==============  =================

Each hour is judged over the plane first, then the hours are counted (as ClimateStudio
reads the standard); some tools take per-point DA first and then the share of points,
which can differ.  For spaces lit through horizontal or inclined roof openings the
standard asks E_T over 95 % of the plane (EN 17037 Table A.1, note, as we read it: check it
against your copy): ``target_percent=95``.

Thresholds are inclusive where the definitions say "at least" (E ≥ t, DA ≥ 50 %,
shares ≥ 50 % or 95 %, sDA ≥ 40 %) and strict where they say "more than" (ASE > 250 h,
more than 2 % of the points, UDI exceeded E > 3000 lux).

Arrays may be float32 (the engine's) or float64; every sum is taken in float64.

References
----------
1. IES LM-83-12, *Approved Method: IES Spatial Daylight Autonomy (sDA) and Annual
   Sunlight Exposure (ASE)*, Illuminating Engineering Society, New York, 2012.
2. C. F. Reinhart, O. Walkenhorst, "Validation of dynamic RADIANCE-based daylight
   simulations for a test office with external blinds", Energy and Buildings 33(7),
   683–697 (2001) (daylight autonomy).
3. Z. Rogers, *Daylighting Metric Development Using Daylight Autonomy Calculations in the
   Sensor Placement Optimization Tool*, Architectural Energy Corporation, Boulder CO
   (2006) (continuous daylight autonomy).
4. A. Nabil, J. Mardaljevic, "Useful daylight illuminance: a new paradigm for assessing
   daylight in buildings", Lighting Res. Technol. 37(1), 41–59 (2005).
5. A. Nabil, J. Mardaljevic, "Useful daylight illuminances: A replacement for daylight
   factors", Energy and Buildings 38(7), 905–913 (2006).
6. J. Mardaljevic, M. Andersen, N. Roy, J. Christoffersen, "Daylighting metrics: is
   there a relation between useful daylight illuminance and daylight glare
   probability?", Proc. BSO12, Loughborough (2012) (UDI 100–300–3000 lux).
7. USGBC, LEED v4.1 Building Design and Construction, EQ credit Daylight, Option 1,
   Table 1 (credit language as on leeduser.buildinggreen.com, e.g.
   /credit/Data-Centers-NC-v4.1/EQc7 and /credit/Healthcare-v4.1/EQc7).
8. EN 17037:2018, *Daylight in buildings*, CEN, §5.1 and Annex A (Table A.1).
9. ClimateStudio documentation, "EN 17037 Daylight Provision"
   (climatestudiodocs.com/docs/daylightEN17037.html): per-hour reading, daylight hours
   the 4380 of most diffuse horizontal illuminance.
"""

from __future__ import annotations

import datetime as _dt
import math
import os
from dataclasses import dataclass, field
from itertools import combinations
from pathlib import Path

import numpy as np

from ..errors import InputError, show
from ..io.files import atomic_write_text, read_text_file

__all__ = [
    "AnnualMetrics", "PointMetrics", "ShadeOperation", "WindowGroup", "annual_metrics", "annual_summary",
    "ase_percent", "dst_days", "en17037_daylight_hours", "en17037_provision", "leed_points", "lm83_occupancy",
    "operate_shades", "point_metrics", "read_schedule", "row_times", "spatial_da", "sun_hours",
    "write_point_table", "DST_RULES", "EN17037_LEVELS", "EXHAUSTIVE_GROUPS", "HOURS_PER_YEAR",
]

#: Rows of a year: 365 days of 24 hours.
HOURS_PER_YEAR = 8760
#: LM-83-12 §2.2.1: the analysis hours, 8:00 to 18:00 local clock time.
LM83_HOURS = (8, 18)
#: Daylight-saving rules of :func:`lm83_occupancy`.
DST_RULES = ("us", "eu")
#: Default DA and cDA threshold [lux] (sDA300/50%).
DA_THRESHOLD = 300.0
#: UDI limits [lux]: fell short below the first, supplementary up to the second, autonomous
#: up to and with the third, exceeded above it (Mardaljevic et al. 2012).
UDI_LIMITS = (100.0, 300.0, 3000.0)
#: Direct sun [lux] counted by ASE and by the shade rule (LM-83-12).
SUN_THRESHOLD = 1000.0
#: ASE1000,250: a point fails with more than this many occupied hours of direct sun.
ASE_HOURS = 250.0
#: sDA: a point passes with DA ≥ this percent of the occupied hours.
SDA_TIME_PERCENT = 50.0
#: The shades of a window group close when more than this percent of an area's points
#: get direct sun (LM-83-12 §2.2.6).
SHADE_TRIGGER_PERCENT = 2.0
#: Window groups up to which every combination of shades is tried.
EXHAUSTIVE_GROUPS = 4
#: LEED v4.1 Option 1, Table 1: (average sDA [%], points) for most rating systems ...
LEED_TIERS = ((40.0, 1), (55.0, 2), (75.0, 3))
#: ... and for Healthcare (75 % is exemplary performance there).
LEED_TIERS_HEALTHCARE = ((40.0, 1), (55.0, 2))
#: Every space at this sDA [%] adds a point (or exemplary performance).
LEED_EVERY_SPACE = 55.0
#: A space above this ASE1000,250 [%] must show how its design addresses glare.
LEED_ASE_GLARE = 10.0
#: EN 17037 Table A.1: level -> (E_T [lux] over 50 % of the plane, E_TM [lux] over 95 %).
EN17037_LEVELS = {"minimum": (300.0, 100.0), "medium": (500.0, 300.0), "high": (750.0, 500.0)}
#: EN 17037 shares: of the plane for E_T and E_TM, and of the daylight hours [%].
EN17037_TARGET_PERCENT, EN17037_MINIMUM_PERCENT, EN17037_HOURS_PERCENT = 50.0, 95.0, 50.0
#: Points per block when per-point metrics are summed (bounds the memory of the masks).
BLOCK_POINTS = 2048


# ---------------------------------------------------------------------------
# Hours and occupancy
# ---------------------------------------------------------------------------

def row_times(rows: int = HOURS_PER_YEAR) -> np.ndarray:
    """(rows, 3) int: month, day and hour-ending H (1…24, local standard time) of each row
    of a 365-day year (no 29 February)."""
    r = np.arange(rows)
    start = _dt.date(2001, 1, 1)                   # any year without 29 February
    dates = [start + _dt.timedelta(days=int(d)) for d in range(int(math.ceil(rows / 24)))]
    months = np.array([d.month for d in dates])
    days = np.array([d.day for d in dates])
    return np.column_stack([months[r // 24], days[r // 24], r % 24 + 1])


def _sunday(year: int, month: int, nth: int) -> _dt.date:
    """The ``nth`` Sunday of a month (``nth`` = -1: the last)."""
    if nth > 0:
        first = _dt.date(year, month, 1)
        return first + _dt.timedelta(days=(6 - first.weekday()) % 7 + 7 * (nth - 1))
    last = _dt.date(year + (month == 12), month % 12 + 1, 1) - _dt.timedelta(days=1)
    return last - _dt.timedelta(days=(last.weekday() + 1) % 7)


def dst_days(rule: str, year: int) -> tuple[_dt.date, _dt.date]:
    """(first, end): the days whose office hours are on summer time, ``first`` ≤ day < ``end``.

    ``"us"``: the second Sunday of March to the first Sunday of November (US Energy Policy
    Act of 2005, from 2007); ``"eu"``: the last Sunday of March to the last Sunday of
    October (Directive 2000/84/EC).
    """
    if rule == "us":
        return _sunday(year, 3, 2), _sunday(year, 11, 1)
    if rule == "eu":
        return _sunday(year, 3, -1), _sunday(year, 10, -1)
    raise ValueError(f"daylight-saving rule must be one of {', '.join(DST_RULES)}, got {rule!r}")


def lm83_occupancy(start: int = LM83_HOURS[0], end: int = LM83_HOURS[1], dst: str | None = None,
                   year: int | None = None) -> np.ndarray:
    """(8760,) float64 of 0 and 1: occupied from ``start`` to ``end`` o'clock local clock
    time every day (IES LM-83-12 §2.2.1: 8 to 18, 3650 hours).

    Without ``dst`` the rows of hour-ending H with start < H ≤ end (standard time) are
    occupied.  ``dst`` ``"us"`` or ``"eu"`` with the ``year`` of the calendar: on the days
    of :func:`dst_days` the clock runs one hour ahead of standard time, and the rows with
    start − 1 < H ≤ end − 1 are occupied instead.
    """
    if not (isinstance(start, (int, np.integer)) and isinstance(end, (int, np.integer)) and 0 <= start < end <= 24):
        raise ValueError(f"occupancy hours must be whole hours 0 <= start < end <= 24, got {start!r}, {end!r}")
    times = row_times()
    hour = times[:, 2].copy()
    if dst is not None:
        if year is None:
            raise ValueError("daylight-saving time needs the year of the calendar (its Sundays)")
        first, stop = dst_days(dst, int(year))
        ordinal = np.array([_dt.date(int(year), int(m), int(d)).toordinal() for m, d, _ in times[::24]])
        summer = (ordinal >= first.toordinal()) & (ordinal < stop.toordinal())
        hour = hour + summer[np.arange(HOURS_PER_YEAR) // 24]      # the clock hour ending the row
    return ((hour > start) & (hour <= end)).astype(np.float64)


def read_schedule(path: str | os.PathLike) -> np.ndarray:
    """An occupancy schedule file: (8760,) float64 within 0…1.

    Format: a text file (UTF-8), one value per row of the year, 8760 lines: line k is the
    hour ending at (k − 1) % 24 + 1 o'clock local standard time of day (k − 1) // 24 + 1,
    the weather file's rows (no 29 February).  A value is 0 (empty), 1 (occupied) or a
    fraction.  Blank lines and lines starting with ``#`` are skipped; a first line that
    is not a number (a spreadsheet's column name) is skipped too.  Any fault is an
    :class:`InputError` naming the file (and the line): a value that is not a number or not
    within 0…1, a count other than 8760, a schedule that occupies no hour.
    """
    path = Path(path)
    name = path.name or str(path)
    text = read_text_file(path, " schedule")
    values = []
    header_allowed = True                  # a first line that is not a number: a column name
    for number, line in enumerate(text.replace("\r\n", "\n").replace("\r", "\n").split("\n"), start=1):
        cell = line.strip()
        if not cell or cell.startswith("#"):
            continue
        try:
            v = float(cell)
        except ValueError:
            if header_allowed:
                header_allowed = False
                continue
            raise InputError(f"{name}: line {number}: expected one number per line (occupancy 0 to 1), "
                             f"got {show(cell)}") from None
        header_allowed = False
        if not math.isfinite(v) or not 0.0 <= v <= 1.0:
            raise InputError(f"{name}: line {number}: occupancy must be within 0 and 1, got {show(cell)}")
        values.append(v)
    if len(values) != HOURS_PER_YEAR:
        raise InputError(f"{name}: {len(values)} values, expected {HOURS_PER_YEAR} (one a line for each hour of "
                         "a 365-day year, the first the hour ending 1:00 on 1 January)")
    schedule = np.array(values)
    if not schedule.any():
        raise InputError(f"{name}: the schedule occupies no hour (all {HOURS_PER_YEAR} values are 0)")
    return schedule


# ---------------------------------------------------------------------------
# Checks
# ---------------------------------------------------------------------------

def _hourly(values, name: str, shape: tuple[int, int] | None = None) -> np.ndarray:
    """A (P, T) array of finite values ≥ 0, float32 or float64 kept as given."""
    a = np.asarray(values)
    if a.dtype not in (np.float32, np.float64):
        a = a.astype(np.float64)
    if a.ndim != 2 or 0 in a.shape:
        raise ValueError(f"{name} must be a (points, hours) array, got shape {a.shape}")
    if shape is not None and a.shape != shape:
        raise ValueError(f"{name} has shape {a.shape}, expected {shape}")
    if not np.isfinite(a).all():
        raise ValueError(f"{name}: {int((~np.isfinite(a)).sum())} values are not finite")
    if (a < 0).any():
        raise ValueError(f"{name}: {int((a < 0).sum())} values are below 0")
    return a


def _weights(occupancy, hours: int) -> np.ndarray:
    w = np.asarray(occupancy, dtype=np.float64).ravel()
    if w.shape != (hours,):
        raise ValueError(f"occupancy has {w.size} values for {hours} hours")
    if not np.isfinite(w).all() or (w < 0).any() or (w > 1).any():
        raise ValueError("occupancy values must be within 0 and 1")
    if not w.any():
        raise ValueError("the occupancy covers no hour")
    return w


def _area_names(areas, points: int) -> np.ndarray:
    if areas is None:
        return np.full(points, "", dtype=object)
    names = np.asarray(areas, dtype=object).ravel()
    if names.shape != (points,):
        raise ValueError(f"{names.size} area names for {points} points")
    return names


def _percent(count, total) -> float:
    """100 · count / total with the multiplication first (11 of 20 is exactly 55)."""
    return float(100.0 * count / total)


# ---------------------------------------------------------------------------
# Per-point metrics
# ---------------------------------------------------------------------------

@dataclass
class PointMetrics:
    """Per-point figures over the occupied hours (module docstring): each (P,) float64 in
    percent of the occupied hours, ``occupied_hours`` W = Σ w_r [h]."""

    threshold: float
    udi_limits: tuple[float, float, float]
    occupied_hours: float
    da: np.ndarray
    cda: np.ndarray
    udi_fell_short: np.ndarray
    udi_supplementary: np.ndarray
    udi_autonomous: np.ndarray
    udi_exceeded: np.ndarray

    @property
    def udi_useful(self) -> np.ndarray:
        """Share of the occupied hours with lower ≤ E ≤ upper UDI limit [%]."""
        return self.udi_supplementary + self.udi_autonomous


def point_metrics(illuminance, occupancy, threshold: float = DA_THRESHOLD,
                  udi_limits: tuple[float, float, float] = UDI_LIMITS) -> PointMetrics:
    """DA, cDA and UDI of each point (module docstring).

    illuminance : (P, T) [lux];  occupancy : (T,) weights within 0…1, not all 0;
    threshold : DA and cDA threshold t > 0 [lux];  udi_limits : (lower, split, upper) [lux],
    increasing.
    """
    E = _hourly(illuminance, "illuminance")
    w = _weights(occupancy, E.shape[1])
    low, mid, high = (float(x) for x in udi_limits)
    if not (0.0 < low <= mid <= high and math.isfinite(high)):
        raise ValueError(f"UDI limits must be increasing and above 0, got {udi_limits!r}")
    t = float(threshold)
    if not (t > 0.0 and math.isfinite(t)):
        raise ValueError(f"the DA threshold must be > 0, got {threshold!r}")
    cols = np.flatnonzero(w > 0.0)
    wt, total = w[cols], float(w[cols].sum())
    out = {k: np.empty(len(E)) for k in ("da", "cda", "fell", "sup", "aut", "exc")}
    for lo in range(0, len(E), BLOCK_POINTS):
        e = np.take(E[lo:lo + BLOCK_POINTS], cols, axis=1)     # C order (E[...][:, cols] is not: slow @)
        hi_ = lo + len(e)
        out["da"][lo:hi_] = (e >= t) @ wt
        out["cda"][lo:hi_] = np.minimum(e / t, 1.0) @ wt
        out["fell"][lo:hi_] = (e < low) @ wt
        out["sup"][lo:hi_] = ((e >= low) & (e < mid)) @ wt
        out["aut"][lo:hi_] = ((e >= mid) & (e <= high)) @ wt
        out["exc"][lo:hi_] = (e > high) @ wt
    pct = {k: 100.0 * v / total for k, v in out.items()}
    return PointMetrics(t, (low, mid, high), total, pct["da"], pct["cda"], pct["fell"], pct["sup"], pct["aut"],
                        pct["exc"])


def sun_hours(direct_sun, occupancy, threshold: float = SUN_THRESHOLD) -> np.ndarray:
    """(P,) occupied hours with direct sun ≥ ``threshold`` [h] (Σ w_r [E_sun ≥ 1000 lux])."""
    D = _hourly(direct_sun, "direct_sun")
    w = _weights(occupancy, D.shape[1])
    cols = np.flatnonzero(w > 0.0)
    hours = np.empty(len(D))
    for lo in range(0, len(D), BLOCK_POINTS):
        d = np.take(D[lo:lo + BLOCK_POINTS], cols, axis=1)
        hours[lo:lo + len(d)] = (d >= threshold) @ w[cols]
    return hours


def spatial_da(da: np.ndarray) -> float:
    """sDA [%]: percent of points with DA ≥ 50 % of the occupied hours."""
    da = np.asarray(da, dtype=np.float64)
    return _percent(int((da >= SDA_TIME_PERCENT).sum()), da.size)


def ase_percent(hours: np.ndarray, limit: float = ASE_HOURS) -> float:
    """ASE [%]: percent of points with more than ``limit`` occupied hours of direct sun."""
    hours = np.asarray(hours, dtype=np.float64)
    return _percent(int((hours > limit).sum()), hours.size)


# ---------------------------------------------------------------------------
# Operable shades (LM-83-12 §2.2.6)
# ---------------------------------------------------------------------------

@dataclass
class WindowGroup:
    """A window group with operable shades: ``illuminance`` and ``direct_sun`` (P, T) [lux]
    with this group's shades closed and every other group's open."""

    name: str
    illuminance: np.ndarray
    direct_sun: np.ndarray


@dataclass
class ShadeOperation:
    """The shades hour by hour: ``closed`` (G, T) bool per group (``names``), ``illuminance``
    (P, T) float32 with the shades so operated [lux], ``unresolved`` (T,) bool: hours when
    even all shades closed leave more than 2 % of an area's points in direct sun."""

    names: list[str]
    closed: np.ndarray
    illuminance: np.ndarray
    unresolved: np.ndarray

    def closed_hours(self, occupancy) -> dict[str, float]:
        """Occupied hours [h] each group's shades are closed."""
        w = _weights(occupancy, self.closed.shape[1])
        return {name: float(self.closed[g] @ w) for g, name in enumerate(self.names)}


def _sunlit(direct: np.ndarray) -> np.ndarray:
    """(hours,) number of points at ≥ 1000 lux of direct sun."""
    return (direct >= SUN_THRESHOLD).sum(axis=0)


def _complies(direct: np.ndarray) -> np.ndarray:
    """At most 2 % of the points at ≥ 1000 lux (100 · k ≤ 2 · n, in integers)."""
    return 100 * _sunlit(direct) <= SHADE_TRIGGER_PERCENT * direct.shape[0]


def _choose(d_open, e_open, d_delta, e_delta) -> tuple[np.ndarray, np.ndarray]:
    """The least shaded compliant combination for hours that do not comply open.

    d_open, e_open : (p, h) one area's points at those hours;  d_delta, e_delta : (G, p, h)
    the change when a group closes.  Returns closed (G, h) bool and unresolved (h,) bool.
    """
    G, _, h = d_delta.shape
    closed = np.zeros((G, h), bool)
    todo = np.ones(h, bool)
    if G <= EXHAUSTIVE_GROUPS:
        for k in range(1, G + 1):
            cols = np.flatnonzero(todo)
            if len(cols) == 0:
                break
            best, best_mean = np.full(len(cols), -1), np.full(len(cols), -np.inf)
            options = list(combinations(range(G), k))
            for i, combo in enumerate(options):
                idx = list(combo)
                d = d_open[:, cols] + d_delta[idx][:, :, cols].sum(axis=0)
                mean = (e_open[:, cols] + e_delta[idx][:, :, cols].sum(axis=0)).mean(axis=0)
                better = _complies(d) & (mean > best_mean)
                best[better], best_mean[better] = i, mean[better]
            for i, combo in enumerate(options):
                hit = cols[best == i]
                closed[np.ix_(list(combo), hit)] = True
            todo[cols[best >= 0]] = False
    else:
        for _ in range(G):
            cols = np.flatnonzero(todo)
            if len(cols) == 0:
                break
            state_d = d_open[:, cols] + np.einsum("gh,gph->ph", closed[:, cols], d_delta[:, :, cols])
            state_e = e_open[:, cols] + np.einsum("gh,gph->ph", closed[:, cols], e_delta[:, :, cols])
            count = np.stack([_sunlit(state_d + d_delta[g][:, cols]) for g in range(G)]).astype(float)
            mean = np.stack([(state_e + e_delta[g][:, cols]).mean(axis=0) for g in range(G)])
            count[closed[:, cols]] = np.inf                     # already closed
            fewest = count == count.min(axis=0)
            pick = np.argmax(np.where(fewest, mean, -np.inf), axis=0)
            closed[pick, cols] = True
            after = d_open[:, cols] + np.einsum("gh,gph->ph", closed[:, cols], d_delta[:, :, cols])
            todo[cols[_complies(after)]] = False
    closed[:, todo] = True                          # nothing complies: every shade closed
    return closed, todo


def operate_shades(illuminance, direct_sun, groups: list[WindowGroup], areas=None) -> ShadeOperation:
    """Operate the shades of ``groups`` hour by hour as IES LM-83-12 §2.2.6 (module docstring).

    illuminance, direct_sun : (P, T) [lux] with every shade open;  groups : one
    :class:`WindowGroup` each (at least one, names distinct);  areas : (P,) area names,
    each area judged on its own points (None: all points one area).
    """
    E = _hourly(illuminance, "illuminance")
    D = _hourly(direct_sun, "direct_sun", E.shape)
    if not groups:
        raise ValueError("no window group to operate")
    names = [str(g.name) for g in groups]
    if len(set(names)) != len(names):
        raise ValueError("window group names must differ")
    E_g = [_hourly(g.illuminance, f"window group {g.name!r}: illuminance", E.shape) for g in groups]
    D_g = [_hourly(g.direct_sun, f"window group {g.name!r}: direct_sun", E.shape) for g in groups]
    labels = _area_names(areas, len(E))
    G, T = len(groups), E.shape[1]
    closed = np.zeros((G, T), bool)
    unresolved = np.zeros(T, bool)
    for name in dict.fromkeys(labels.tolist()):
        rows = np.flatnonzero(labels == name)
        hours = np.flatnonzero(~_complies(D[rows]))
        if len(hours) == 0:
            continue
        sub = np.ix_(rows, hours)
        d_open, e_open = D[sub].astype(np.float64), E[sub].astype(np.float64)
        d_delta = np.stack([d[sub] - d_open for d in D_g])
        e_delta = np.stack([e[sub] - e_open for e in E_g])
        c, u = _choose(d_open, e_open, d_delta, e_delta)
        closed[:, hours] |= c
        unresolved[hours] |= u
    shaded = E.astype(np.float32, copy=True)
    for g in range(G):
        hours = np.flatnonzero(closed[g])
        if len(hours):
            shaded[:, hours] += (E_g[g][:, hours] - E[:, hours]).astype(np.float32)
    np.maximum(shaded, 0.0, out=shaded)             # superposition round-off
    return ShadeOperation(names, closed, shaded, unresolved)


# ---------------------------------------------------------------------------
# LEED v4.1 and EN 17037
# ---------------------------------------------------------------------------

def leed_points(sda: float, space_sda=None, healthcare: bool = False) -> dict:
    """LEED v4.1 BD+C EQ credit Daylight, Option 1 points (Table 1; module docstring).

    sda : the average sDA300/50% [%] of the regularly occupied floor;  space_sda : the
    sDA300/50% [%] of each regularly occupied space (None: the floor is one space);
    healthcare : the Healthcare column.  Returns ``{"points", "exemplary_performance",
    "every_space_55"}``.
    """
    sda = float(sda)
    spaces = [sda] if space_sda is None else [float(s) for s in space_sda]
    every = bool(spaces) and all(s >= LEED_EVERY_SPACE for s in spaces)
    tiers = LEED_TIERS_HEALTHCARE if healthcare else LEED_TIERS
    points = max([p for limit, p in tiers if sda >= limit], default=0)
    if healthcare:
        exemplary = sda >= LEED_TIERS[-1][0] or every
    else:
        exemplary = every and points == 3
        if every and points == 2:
            points = 3
    return {"points": points, "exemplary_performance": exemplary, "every_space_55": every}


def en17037_daylight_hours(diffuse_horizontal=None, sun_up=None) -> np.ndarray:
    """(T,) bool: the daylight hours of EN 17037:2018.

    diffuse_horizontal : (T,) outdoor diffuse horizontal illuminance [lux] of the weather
    file; the T // 2 rows (4380 of 8760) with the highest values are taken, among equal
    values the earlier rows; missing values (NaN) count as the lowest.  The diffuse
    horizontal irradiance [W/m²] ranks the hours nearly alike where the file has no
    illuminance (a .wea file).  sun_up : (T,) bool,
    used when no diffuse illuminance is given: the hours with the sun up (about half the
    year at any latitude).
    """
    if diffuse_horizontal is not None:
        v = np.asarray(diffuse_horizontal, dtype=np.float64).ravel()
        if v.size < 2:
            raise ValueError("the diffuse horizontal illuminance needs at least two hours")
        if np.isnan(v).all():
            raise ValueError("the diffuse horizontal illuminance is missing at every hour (a .wea file has none): "
                             "give the diffuse horizontal irradiance or the sun-up hours")
        chosen = np.argsort(-v, kind="stable")[: v.size // 2]      # numpy sorts NaN last
        mask = np.zeros(v.size, bool)
        mask[chosen] = True
        return mask
    if sun_up is None:
        raise ValueError("EN 17037 daylight hours need the diffuse horizontal illuminance or the sun-up hours")
    mask = np.asarray(sun_up, dtype=bool).ravel()
    if not mask.any():
        raise ValueError("no hour has the sun up")
    return mask


def en17037_provision(illuminance, daylight_hours, target_percent: float = EN17037_TARGET_PERCENT) -> dict:
    """The EN 17037:2018 daylight provision level of one space (module docstring).

    illuminance : (P, T) [lux] over the space's reference plane;  daylight_hours : (T,)
    bool (:func:`en17037_daylight_hours`);  target_percent : percent of the plane for E_T
    (50; 95 for roof openings).  Returns ``{"level": "none" | "minimum" | "medium" |
    "high", "daylight_hours": n, "levels": {level: {"target_lux", "target_hours",
    "minimum_lux", "minimum_hours", "met"}}}``, the ``*_hours`` in percent of the
    daylight hours meeting each criterion.
    """
    E = _hourly(illuminance, "illuminance")
    mask = np.asarray(daylight_hours, dtype=bool).ravel()
    if mask.shape != (E.shape[1],) or not mask.any():
        raise ValueError(f"daylight hours must be a (T,) mask with at least one hour, T = {E.shape[1]}")
    share = float(target_percent)
    if not 0.0 < share <= 100.0:
        raise ValueError(f"target_percent must be within 0 and 100, got {target_percent!r}")
    e = E[:, mask]
    n, hours = e.shape
    out = {"level": "none", "daylight_hours": int(hours), "target_percent": share, "levels": {}}
    for level, (target, minimum) in EN17037_LEVELS.items():
        # an hour passes when 100·k ≥ percent·n (k points at or above the illuminance)
        t_ok = 100 * (e >= target).sum(axis=0) >= share * n
        m_ok = 100 * (e >= minimum).sum(axis=0) >= EN17037_MINIMUM_PERCENT * n
        t_hours, m_hours = int(t_ok.sum()), int(m_ok.sum())
        met = (100 * t_hours >= EN17037_HOURS_PERCENT * hours) and (100 * m_hours >= EN17037_HOURS_PERCENT * hours)
        out["levels"][level] = {"target_lux": target, "target_hours": _percent(t_hours, hours),
                                "minimum_lux": minimum, "minimum_hours": _percent(m_hours, hours), "met": bool(met)}
        if met and out["level"] == _previous_level(level):
            out["level"] = level
    return out


def _previous_level(level: str) -> str:
    order = ["none"] + list(EN17037_LEVELS)
    return order[order.index(level) - 1]


def _lowest_level(levels) -> str:
    order = ["none"] + list(EN17037_LEVELS)
    return min(levels, key=order.index) if levels else "none"


# ---------------------------------------------------------------------------
# All of it, for a report
# ---------------------------------------------------------------------------

@dataclass
class AnnualMetrics:
    """The annual metrics of a grid (:func:`annual_metrics`).

    open : per-point metrics with the shades open;  shaded : the same with the shades
    operated (None without window groups);  ase_hours : (P,) occupied hours of direct sun
    ≥ 1000 lux, shades open (None without ``direct_sun``);  shades : the shade operation or
    None;  areas : (P,) names;  en17037 : area name (``""`` for all points) -> the result
    of :func:`en17037_provision`, empty without daylight hours.
    """

    occupancy: np.ndarray
    open: PointMetrics
    shaded: PointMetrics | None
    ase_hours: np.ndarray | None
    shades: ShadeOperation | None
    areas: np.ndarray
    healthcare: bool = False
    en17037: dict = field(default_factory=dict)

    @property
    def lm83(self) -> PointMetrics:
        """The metrics sDA is taken from: shades operated when given, else open."""
        return self.shaded if self.shaded is not None else self.open

    def area_names(self) -> list[str]:
        """Named areas in the order of first appearance (unnamed points belong to none)."""
        return [a for a in dict.fromkeys(self.areas.tolist()) if a]


def annual_metrics(illuminance, occupancy, *, direct_sun=None, groups: list[WindowGroup] | None = None,
                   areas=None, daylight_hours=None, threshold: float = DA_THRESHOLD,
                   udi_limits: tuple[float, float, float] = UDI_LIMITS, healthcare: bool = False,
                   en17037_target_percent: float = EN17037_TARGET_PERCENT) -> AnnualMetrics:
    """Every metric of this module for a grid.

    illuminance : (P, T) [lux], shades open;  occupancy : (T,) weights
    (:func:`lm83_occupancy`, :func:`read_schedule`);  direct_sun : (P, T) [lux], shades
    open (ASE; needed with ``groups``);  groups : window groups with operable shades
    (:func:`operate_shades`);  areas : (P,) area names;  daylight_hours : (T,) bool mask for
    EN 17037 (:func:`en17037_daylight_hours`; None: no EN 17037);  healthcare : LEED's
    Healthcare column.  EN 17037 is taken with the shades open (the provision of the
    openings; shading belongs to its glare and sunlight criteria).
    """
    E = _hourly(illuminance, "illuminance")
    w = _weights(occupancy, E.shape[1])
    names = _area_names(areas, len(E))
    open_ = point_metrics(E, w, threshold, udi_limits)
    D = _hourly(direct_sun, "direct_sun", E.shape) if direct_sun is not None else None
    ase = sun_hours(D, w) if D is not None else None
    shades = shaded = None
    if groups:
        if D is None:
            raise ValueError("operable shades need the direct sun (direct_sun) to be operated")
        shades = operate_shades(E, D, groups, names)
        shaded = point_metrics(shades.illuminance, w, threshold, udi_limits)
    en = {}
    if daylight_hours is not None:
        en[""] = en17037_provision(E, daylight_hours, en17037_target_percent)
        for name in dict.fromkeys(names.tolist()):
            if name:
                en[name] = en17037_provision(E[names == name], daylight_hours, en17037_target_percent)
    return AnnualMetrics(w, open_, shaded, ase, shades, names, healthcare, en)


def _area_figures(m: AnnualMetrics, sel: np.ndarray, en: dict | None, spaces=None) -> dict:
    o, s = m.open, m.lm83
    doc = {
        "points": int(sel.sum()),
        "da": float(o.da[sel].mean()),
        "cda": float(o.cda[sel].mean()),
        "udi": {"fell_short": float(o.udi_fell_short[sel].mean()),
                "supplementary": float(o.udi_supplementary[sel].mean()),
                "autonomous": float(o.udi_autonomous[sel].mean()),
                "useful": float(o.udi_useful[sel].mean()),
                "exceeded": float(o.udi_exceeded[sel].mean())},
        "sda": spatial_da(s.da[sel]),
    }
    if m.shaded is not None:
        doc["shaded"] = {"da": float(s.da[sel].mean()), "cda": float(s.cda[sel].mean()),
                         "udi_useful": float(s.udi_useful[sel].mean())}
        doc["sda_shades_open"] = spatial_da(o.da[sel])
    if m.ase_hours is not None:
        doc["ase"] = ase_percent(m.ase_hours[sel])
        doc["ase_hours_mean"] = float(m.ase_hours[sel].mean())
    doc["leed_points"] = leed_points(doc["sda"], spaces, m.healthcare)["points"]
    if en is not None:
        doc["en17037"] = en
    return doc


def annual_summary(m: AnnualMetrics) -> dict:
    """A JSON-ready dict of the figures, overall (all points) and per named area.

    Each of ``overall`` and ``areas[name]``: ``points``; mean ``da``, ``cda`` and ``udi``
    shares [% of occupied hours] with the shades open; ``sda`` [% of points] (LM-83: with
    the shades operated when window groups were given, then also ``sda_shades_open`` and
    the ``shaded`` means); ``ase`` [% of points] and ``ase_hours_mean`` [h] with direct
    sun; ``leed_points``: for an area as if it were the whole floor, overall those of the
    credit (the named areas its spaces); ``en17037`` with daylight hours.  ``leed`` holds the credit for the whole: the overall sDA and the named areas as
    its spaces; with direct sun the overall ``ase``, the areas above 10 % (``ase_over_10``)
    and ``glare_review``, whether a space (the whole floor without names) is above 10 %
    and must show how it addresses glare.  ``en17037_every_area``: the lowest level of the
    named areas.
    """
    names = m.area_names()
    everyone = np.ones(len(m.areas), bool)
    spaces = [spatial_da(m.lm83.da[m.areas == n]) for n in names] if names else None
    doc = {
        "occupied_hours": m.open.occupied_hours,
        "threshold": m.open.threshold,
        "udi_limits": list(m.open.udi_limits),
        "units": {"da": "% of occupied hours", "cda": "% of occupied hours", "udi": "% of occupied hours",
                  "sda": "% of points", "ase": "% of points", "ase_hours_mean": "h"},
        "overall": _area_figures(m, everyone, m.en17037.get(""), spaces),
        "areas": {n: _area_figures(m, m.areas == n, m.en17037.get(n)) for n in names},
    }
    if m.shades is not None:
        occupied = m.occupancy > 0
        doc["shades"] = {"groups": m.shades.closed_hours(m.occupancy),
                         "unresolved_hours": int((m.shades.unresolved & occupied).sum())}
    leed = leed_points(doc["overall"]["sda"], spaces, m.healthcare)
    leed.update({"version": "LEED v4.1 BD+C EQ credit Daylight, option 1", "healthcare": m.healthcare,
                 "sda": doc["overall"]["sda"], "shades_operated": m.shades is not None})
    if m.ase_hours is not None:
        leed["ase"] = doc["overall"]["ase"]
        over = [n for n in names if doc["areas"][n]["ase"] > LEED_ASE_GLARE]
        leed["ase_over_10"] = over
        leed["glare_review"] = bool(over) if names else leed["ase"] > LEED_ASE_GLARE
    doc["leed"] = leed
    if m.en17037 and names:
        doc["en17037_every_area"] = _lowest_level([m.en17037[n]["level"] for n in names])
    return doc


def write_point_table(path: str | os.PathLike, points, m: AnnualMetrics) -> None:
    """Write the per-point figures as CSV, atomically.

    Columns: ``x,y,z`` (as given), ``DA300``, ``cDA300``, ``UDI<100``, ``UDI100-300``,
    ``UDI300-3000``, ``UDI100-3000``, ``UDI>3000`` [% of occupied hours] with the shades
    open (names follow the threshold and UDI limits), ``ASE1000_hours`` [h] with direct
    sun, ``DA300_shaded``, ``cDA300_shaded``, ``UDI<100_shaded``, ``UDI100-3000_shaded``,
    ``UDI>3000_shaded`` with operated shades,
    and ``area`` last when any point has a name.  Values keep 6 significant digits.
    """
    xyz = np.asarray(points, dtype=np.float64)
    if xyz.ndim != 2 or xyz.shape[1] < 3 or len(xyz) != len(m.areas):
        raise ValueError(f"points must be (P, 3) with P = {len(m.areas)}, got shape {xyz.shape}")
    o = m.open
    low, mid, high = (f"{x:g}" for x in o.udi_limits)
    t = f"{o.threshold:g}"
    cols = {"x": xyz[:, 0], "y": xyz[:, 1], "z": xyz[:, 2], f"DA{t}": o.da, f"cDA{t}": o.cda,
            f"UDI<{low}": o.udi_fell_short, f"UDI{low}-{mid}": o.udi_supplementary,
            f"UDI{mid}-{high}": o.udi_autonomous, f"UDI{low}-{high}": o.udi_useful, f"UDI>{high}": o.udi_exceeded}
    if m.ase_hours is not None:
        cols[f"ASE{SUN_THRESHOLD:g}_hours"] = m.ase_hours
    if m.shaded is not None:
        s = m.shaded
        cols.update({f"DA{t}_shaded": s.da, f"cDA{t}_shaded": s.cda, f"UDI<{low}_shaded": s.udi_fell_short,
                     f"UDI{low}-{high}_shaded": s.udi_useful, f"UDI>{high}_shaded": s.udi_exceeded})
    named = any(m.areas)
    table = np.column_stack(list(cols.values()))
    lines = [",".join(list(cols) + (["area"] if named else []))]
    for i, row in enumerate(table):
        line = ",".join(f"{v:.6g}" for v in row)
        lines.append(f"{line},{m.areas[i]}" if named else line)
    atomic_write_text(path, "\n".join(lines) + "\n")

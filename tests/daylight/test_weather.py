"""The hourly weather reader: EPW and .wea files of one year give the same hours, site and
sun times, and every kind of bad input is refused in one line naming the file and line."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

from lbl_illum.errors import InputError
from lbl_illum.daylight.weather import REFERENCE_LEAP_YEAR, REFERENCE_YEAR, HourlyWeather, read_wea, read_weather

DATA = Path(__file__).resolve().parents[2] / "examples" / "weather"
EPW = DATA / "USA_CA_Oakland.Intl.AP.724930_TMY3.epw"
WEA = DATA / "oakland_tmy3.wea"


@pytest.fixture(scope="module")
def epw():
    return read_weather(EPW)


@pytest.fixture(scope="module")
def wea():
    return read_weather(WEA)


def test_epw_year_hours_and_site(epw):
    assert epw.format == "epw" and len(epw) == 8760
    s = epw.site
    assert (s.latitude, s.longitude, s.time_zone, s.elevation) == (37.72, -122.22, -8.0, 2.0)
    # the row of hour H is the hour ending at H:00; its sun is taken at H - 0.5
    assert epw.hour[:3].tolist() == [0.5, 1.5, 2.5] and epw.hour[23] == 23.5 and epw.hour[24] == 0.5
    assert (epw.month[-1], epw.day[-1], epw.hour[-1]) == (12, 31, 23.5)
    assert epw.line[0] == 9 and epw.line[-1] == 8768
    # line 20, 1 January hour 12: 1999,1,1,12,0,…,13.0,1.0 (dew point),…,442,655,129 (W/m2),45751,63645,15371 (lux)
    i = 11
    assert epw.dew_point[i] == 1.0
    assert (epw.direct_normal_irradiance[i], epw.diffuse_horizontal_irradiance[i]) == (655.0, 129.0)
    assert (epw.direct_normal_illuminance[i], epw.diffuse_horizontal_illuminance[i]) == (63645.0, 15371.0)
    assert epw.line[i] == 20
    assert epw.year == REFERENCE_YEAR                       # a TMY mixes years
    assert not np.isnan(epw.dew_point).any()


def test_wea_signs_and_same_hours_as_epw(epw, wea):
    """oakland_tmy3.wea is epw2wea's output of the EPW: longitude 122.22 and time_zone 120 are
    degrees west, i.e. −122.22° E and UTC−8, and every row holds the EPW row's values at the
    same sun time."""
    assert wea.format == "wea" and len(wea) == 8760
    for key in ("latitude", "longitude", "time_zone", "elevation"):
        assert getattr(wea.site, key) == getattr(epw.site, key)
    for key in ("month", "day", "hour", "direct_normal_irradiance", "diffuse_horizontal_irradiance"):
        np.testing.assert_array_equal(getattr(wea, key), getattr(epw, key))
    assert np.isnan(wea.direct_normal_illuminance).all() and np.isnan(wea.dew_point).all()
    assert wea.line[0] == 7 and wea.where(0) == "oakland_tmy3.wea: line 7"


def test_local_time_utc_and_day_of_year(epw):
    assert str(epw.local_time()[0]) == "2023-01-01T00:30:00.000"
    assert str(epw.utc()[0]) == "2023-01-01T08:30:00.000"
    assert epw.day_of_year[[0, 24, -1]].tolist() == [1, 2, 365]
    p = epw.solar_position("noaa")
    noon = 172 * 24 - 24 + 12                                # 21 June, hour ending 13:00, sun at 12:30
    assert (epw.month[noon], epw.day[noon], epw.hour[noon]) == (6, 21, 12.5)
    # sun due south near 12:30 PST at 122.2 W (solar noon about 12:11): 90 − 37.72 + 23.44 = 75.7°
    assert p.altitude[noon] == pytest.approx(75.0, abs=1.0) and p.azimuth[noon] == pytest.approx(200.0, abs=15.0)


def _wea_text(rows=("6 21 12.500 800 100", "6 21 13.500 700 110", "6 21 14.500 600 120"),
              header=("place Test_Site", "latitude 37.72", "longitude 122.22", "time_zone 120", "site_elevation 2.0",
                      "weather_data_file_units 1")):
    return "\n".join([*header, *rows]) + "\n"


def test_wea_with_epw2wea_a_columns_and_a_leap_day(tmp_path):
    """Seven columns (epw2wea -a adds aerosol optical depth and sky cover) are read; a 29
    February puts the sun in a leap year's calendar."""
    path = tmp_path / "leap.wea"
    path.write_text(_wea_text(rows=("2 28 12.5 800 100 0.120 0.3", "2 29 12.5 700 110 0.100 0.0",
                                    "3 1 12.5 600 120 0.100 0.0")))
    w = read_wea(path)
    assert len(w) == 3 and w.year == REFERENCE_LEAP_YEAR and w.day_of_year.tolist() == [59, 60, 61]
    assert w.site.longitude == -122.22 and w.site.time_zone == -8.0 and w.site.name == "Test_Site"


def _epw_day(tmp_path, change=None, period=" 1/ 1, 1/ 1", name="day.epw"):
    """The first day of the Oakland EPW as a file of its own (DATA PERIODS of that day);
    ``change(lines)`` edits the list of lines (0-based; data from index 8) first."""
    lines = EPW.read_text().splitlines()[:8 + 24]
    lines[7] = f"DATA PERIODS,1,1,Data,Sunday,{period}"
    if change is not None:
        change(lines)
    path = tmp_path / name
    path.write_text("\n".join(lines) + "\n")
    return path


def _set_field(index, field, value):
    def change(lines):
        f = lines[index].split(",")
        f[field] = value
        lines[index] = ",".join(f)
    return change


def test_an_epw_of_one_day_reads_in_its_own_year(tmp_path):
    w = read_weather(_epw_day(tmp_path))
    assert len(w) == 24 and w.hour[-1] == 23.5 and w.year == 1999     # one year throughout: the file's


WEA_FAULTS = [
    # (file name, text, message pattern)
    ("w.wea", _wea_text(rows=("6 21 12.5 abc 100",)),
     r"^w\.wea: line 7: column 4 \(direct_normal_irradiance\) must be a finite number, got 'abc'$"),
    ("w.wea", _wea_text(rows=("6 21 12.5 1500 100",)), r"^w\.wea: line 7: direct_normal_irradiance 1500 W/m2 is more "
                                                       r"than reaches the top of the atmosphere"),
    ("w.wea", _wea_text(rows=("6 21 12.5 800 -3",)), r"^w\.wea: line 7: column 5 \(diffuse_horizontal_irradiance\) "
                                                     r"must be >= 0, got -3$"),
    ("w.wea", _wea_text(rows=("13 21 12.5 800 100",)), r"^w\.wea: line 7: column 1 \(month\) must be a whole number "
                                                       r"within 1…12, got 13$"),
    ("w.wea", _wea_text(rows=("6 21 24.5 800 100",)), r"^w\.wea: line 7: column 3 \(hour\) must be within 0…24"),
    ("w.wea", _wea_text(rows=("6 21 12.5 800 100", "2 30 12.5 0 0")), r"^w\.wea: line 8: the date 02-30 is not a "
                                                                      r"date \(month 2 has 29 days\)$"),
    ("w.wea", _wea_text(rows=("6 21 12.5 800",)), r"^w\.wea: line 7: a data line has 5 columns .*; got 4$"),
    ("w.wea", _wea_text(rows=("6 21 12.5 800 100 0.1",)), r"^w\.wea: line 7: a data line has 5 columns .*; got 6$"),
    ("w.wea", _wea_text(rows=("6 21 13.5 800 100", "6 21 12.5 800 100")),
     r"^w\.wea: line 8: 06-21 12\.5 h does not come after the line before \(06-21 13\.5 h\)"),
    ("w.wea", _wea_text(header=("place X", "latitude 37.72", "longitude 122.22", "site_elevation 2",
                                "weather_data_file_units 1")),
     r"^w\.wea: line 6: the header has no 'time_zone' line \(a \.wea header has place, latitude"),
    ("w.wea", _wea_text(header=("place X", "latitude north", "longitude 122.22", "time_zone 120", "site_elevation 2",
                                "weather_data_file_units 1")), r"^w\.wea: line 2: 'latitude' must be a finite number, "
                                                               r"got 'north'$"),
    ("w.wea", _wea_text(header=("place X", "latitude 37.7", "longitude 122.22", "time_zone 400", "site_elevation 2",
                                "weather_data_file_units 1")), r"^w\.wea: line 4: 'time_zone' must be within "
                                                               r"-210…210, got 400$"),
    ("w.wea", _wea_text(header=("place X", "latitude 37.7", "longitude 122.22", "time_zone 120", "site_elevation 2",
                                "weather_data_file_units 2")), r"^w\.wea: line 6: weather_data_file_units '2' is not "
                                                               r"read; only 1"),
    ("w.wea", _wea_text(header=("place X", "latitude 37.7", "longitude 122.22", "time_zone 120", "site_elevation 2",
                                "weather_units 1")), r"^w\.wea: line 6: unknown header line 'weather_units'"),
    ("w.wea", _wea_text(rows=()), r"^w\.wea: no data lines after the header$"),
    ("w.csv", "1,2,3\n", r"^w\.csv: unknown kind of weather file '\.csv': read_weather reads \.epw"),
]


@pytest.mark.parametrize("name, text, pattern", WEA_FAULTS)
def test_bad_wea_and_unknown_kinds_are_refused_naming_file_and_line(tmp_path, name, text, pattern):
    path = tmp_path / name
    path.write_text(text)
    with pytest.raises(InputError) as info:
        read_weather(path)
    message = str(info.value)
    assert "\n" not in message and re.search(pattern, message), message


def _drop(index):
    def change(lines):
        del lines[index]
    return change


EPW_FAULTS = [
    # (change of the one-day EPW, DATA PERIODS, message pattern)
    (_drop(-1), " 1/ 1, 1/ 1", r"^day\.epw: line 31: the data end at 01-01 hour 23; DATA PERIODS \(line 8\) gives 1/1 "
                               r"to 1/1$"),
    (_drop(8 + 6), " 1/ 1, 1/ 1", r"^day\.epw: line 15: 01-01 hour 8 follows 01-01 hour 6: an hourly EPW file has each "
                                  r"hour of its data period once, in order$"),
    (None, " 1/ 1, 1/ 2", r"^day\.epw: line 32: the data end at 01-01 hour 24; DATA PERIODS \(line 8\) gives 1/1 to "
                          r"1/2$"),
    (_set_field(8 + 11, 14, "1500"), " 1/ 1, 1/ 1", r"^day\.epw: line 20: direct_normal_irradiance 1500 W/m2 is more "
                                                     r"than reaches the top"),
    (_set_field(8 + 11, 14, "lots"), " 1/ 1, 1/ 1", r"^day\.epw: line 20: field 15 \(direct_normal_irradiance\) must "
                                                     r"be a number, got 'lots'$"),
    (lambda lines: lines.__setitem__(12, ",".join(lines[12].split(",")[:10])), " 1/ 1, 1/ 1",
     r"^day\.epw: line 13: a data line needs at least 19 comma-separated fields, got 10$"),
    (lambda lines: lines.__setitem__(7, "DATA PERIODS,1,4,Data,Sunday, 1/ 1, 1/ 1"), " 1/ 1, 1/ 1",
     r"^day\.epw: line 8: DATA PERIODS gives '4' records per hour; hourly files \(1\) are read$"),
    (lambda lines: lines.__setitem__(7, "DATA PERIODS,1,1,Data,Sunday, 1/ 1,Dec 31"), " 1/ 1, 1/ 1",
     r"^day\.epw: line 8: DATA PERIODS field 7 must be a date month/day, got 'Dec 31'$"),
]


@pytest.mark.parametrize("change, period, pattern", EPW_FAULTS)
def test_bad_epw_is_refused_naming_file_and_line(tmp_path, change, period, pattern):
    with pytest.raises(InputError) as info:
        read_weather(_epw_day(tmp_path, change, period))
    message = str(info.value)
    assert "\n" not in message and re.search(pattern, message), message


@pytest.mark.parametrize("name", ["nope.epw", "nope.wea"])
def test_a_missing_file_is_named(tmp_path, name):
    with pytest.raises(InputError, match=rf"^{re.escape(name)}: no such weather file$"):
        read_weather(tmp_path / name)


def test_a_table_of_hours_checks_its_columns():
    from lbl_illum.daylight.solar import Site

    site = Site(37.72, -122.22, -8.0)
    one = np.ones(2)
    with pytest.raises(ValueError, match="'hour' has 1 values, 'month' 2"):
        HourlyWeather(path=Path("x"), format="wea", site=site, month=[6, 6], day=[21, 21], hour=[12.5], line=[1, 2],
                      direct_normal_irradiance=one, diffuse_horizontal_irradiance=one, direct_normal_illuminance=one,
                      diffuse_horizontal_illuminance=one, dew_point=one, year=2023)
    with pytest.raises(ValueError, match="time zone"):
        HourlyWeather(path=Path("x"), format="wea", site=Site(37.72, -122.22), month=[6, 6], day=[21, 21],
                      hour=[12.5, 13.5], line=[1, 2], direct_normal_irradiance=one, diffuse_horizontal_irradiance=one,
                      direct_normal_illuminance=one, diffuse_horizontal_illuminance=one, dew_point=one, year=2023)

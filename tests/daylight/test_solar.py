"""Solar position against published values, time and site parsing, and the EPW reader."""

from __future__ import annotations

import datetime as dt
import math
from pathlib import Path

import numpy as np
import pytest

from lbl_illum.errors import InputError
from lbl_illum.daylight.solar import (
    Site, air_mass_kasten1966, extraterrestrial_normal_irradiance, have_pvlib, julian_day, parse_time,
    precipitable_water, read_epw, site_from_table, solar_position, sun_equatorial_coordinates, to_utc,
)

DATA = Path(__file__).resolve().parents[1] / "data"
EPW = DATA / "berkeley_excerpt.epw"
needs_pvlib = pytest.mark.skipif(not have_pvlib(), reason="pvlib is not installed (optional extra 'solar')")


def direction(alt, az):
    a, z = np.radians(alt), np.radians(az)
    return np.stack([np.cos(a) * np.sin(z), np.cos(a) * np.cos(z), np.sin(a)], axis=-1)


# -- published values ------------------------------------------------------------------------
@pytest.mark.parametrize("method", ["noaa", pytest.param("pvlib", marks=needs_pvlib)])
def test_spa_paper_example(method):
    """Reda & Andreas, "Solar position algorithm for solar radiation applications" (NREL/TP-560-34302,
    2008), Table A5.1: Golden, Colorado, 17 October 2003 12:30:30 local time (UTC−7), latitude
    39.742476°, longitude −105.1786°, elevation 1830.14 m, 820 mbar, 11 °C: topocentric zenith
    angle 50.11162°, azimuth 194.34024°.  Ours (NOAA): 50.11159°, 194.34258° (measured)."""
    utc = to_utc(dt.datetime(2003, 10, 17, 12, 30, 30), -7.0)
    p = solar_position(utc, 39.742476, -105.1786, 1830.14, method=method, pressure=820.0, temperature=11.0)
    assert p.method == method
    assert 90.0 - p.altitude == pytest.approx(50.11162, abs=0.05)
    assert p.azimuth == pytest.approx(194.34024, abs=0.05)
    assert np.degrees(np.arccos(direction(p.altitude, p.azimuth) @ direction(90 - 50.11162, 194.34024))) < 0.01


def test_meeus_example_25a_and_equation_of_time():
    """Meeus, *Astronomical Algorithms* (2nd ed. 1998), Example 25.a, 1992 October 13.0 TD
    (JD 2448908.5): apparent longitude 199.90895°, right ascension 198.38083°, declination
    −7.78507°; Example 28.b: equation of time 13 min 42.7 s."""
    assert julian_day(dt.datetime(1992, 10, 13)) == pytest.approx(2448908.5)
    c = sun_equatorial_coordinates(2448908.5)
    assert c["apparent_longitude"] == pytest.approx(199.90895, abs=2e-4)
    assert c["right_ascension"] == pytest.approx(198.38083, abs=2e-4)
    assert c["declination"] == pytest.approx(-7.78507, abs=2e-4)
    assert c["equation_of_time"] == pytest.approx(13 + 42.7 / 60, abs=0.1 / 60)


def test_noon_altitude_at_the_equinox_and_solstice():
    """Independent geometry: at local solar noon the altitude is 90° − |φ − δ| (δ from Meeus,
    checked above); the sun stands due south north of the tropics."""
    lat = 37.87
    for day in (dt.datetime(2024, 3, 20), dt.datetime(2024, 6, 20)):
        jd = float(julian_day(day + dt.timedelta(hours=12)))
        c = sun_equatorial_coordinates(jd)
        noon_utc = day + dt.timedelta(minutes=720 - c["equation_of_time"])   # at longitude 0
        p = solar_position(noon_utc, lat, 0.0, method="noaa", pressure=0.0)
        assert p.altitude == pytest.approx(90 - abs(lat - c["declination"]), abs=0.01)
        assert p.azimuth == pytest.approx(180.0, abs=0.05)


@needs_pvlib
def test_noaa_agrees_with_pvlib_spa_over_two_centuries():
    """5000 random instants 1900–2100 at five latitudes: the NOAA fallback is within 0.02° of
    pvlib's NREL SPA (measured: largest 0.018°)."""
    rng = np.random.default_rng(3)
    t = np.datetime64("1900-01-01") + (rng.random(5000) * 200 * 365.25 * 86400).astype("timedelta64[s]")
    for lat in (-60.0, -10.0, 0.0, 37.87, 65.0):
        a = solar_position(t, lat, 20.0, 100.0, method="noaa")
        b = solar_position(t, lat, 20.0, 100.0, method="pvlib")
        up = b.altitude > -0.5
        cos = np.clip(np.sum(direction(a.altitude, a.azimuth) * direction(b.altitude, b.azimuth), axis=-1), -1, 1)
        assert np.degrees(np.arccos(cos))[up].max() < 0.02


def test_solar_position_vectorised_and_auto():
    times = [dt.datetime(2024, 6, 21, h) for h in range(24)]
    p = solar_position(times, 37.87, -122.27, method="noaa")
    assert p.altitude.shape == (24,) and p.azimuth.shape == (24,)
    one = solar_position(times[20], 37.87, -122.27, method="noaa")
    assert isinstance(one.altitude, float) and one.altitude == pytest.approx(p.altitude[20])
    assert solar_position(times[20], 37.87, -122.27).method == ("pvlib" if have_pvlib() else "noaa")
    with pytest.raises(ValueError):
        solar_position(times[0], 0, 0, method="spa")


# -- radiometry ------------------------------------------------------------------------------
def test_air_mass_extraterrestrial_and_water():
    assert air_mass_kasten1966(0.0) == pytest.approx(1.0, abs=1e-3)
    assert air_mass_kasten1966(60.0) == pytest.approx(2.0, rel=5e-3)          # ≈ 1/cos Z (plane-parallel)
    assert air_mass_kasten1966(90.0) == pytest.approx(36.5, rel=0.01)         # Kasten (1966): 36.5 at the horizon
    assert extraterrestrial_normal_irradiance(None) == 1367.0
    assert extraterrestrial_normal_irradiance(3) == pytest.approx(1367 * 1.0344, rel=1e-3)    # perihelion
    assert extraterrestrial_normal_irradiance(185) == pytest.approx(1367 * 0.9666, rel=1e-3)  # aphelion
    assert precipitable_water((math.log(2) + 0.075) / 0.07) == pytest.approx(2.0)


# -- time and site ---------------------------------------------------------------------------
def test_parse_time_forms():
    assert parse_time("2024-06-21 12:00", "s") == (dt.datetime(2024, 6, 21, 12), None)
    assert parse_time("2024-06-21T12:30:15", "s") == (dt.datetime(2024, 6, 21, 12, 30, 15), None)
    assert parse_time("2024-06-21 12:00Z", "s")[1] == 0.0
    assert parse_time("2024-06-21 12:00 UTC", "s")[1] == 0.0
    assert parse_time("2024-06-21 12:00-07:00", "s")[1] == -7.0
    assert parse_time("2024-06-21 12:00+0530", "s")[1] == 5.5
    toml_aware = dt.datetime(2024, 6, 21, 12, tzinfo=dt.timezone(dt.timedelta(hours=2)))
    assert parse_time(toml_aware, "s") == (dt.datetime(2024, 6, 21, 12), 2.0)
    assert to_utc(dt.datetime(2024, 6, 21, 12), -8.0) == dt.datetime(2024, 6, 21, 20)
    for bad in ("21/06/2024 12:00", "2024-06-31 12:00", 12):
        with pytest.raises(InputError, match=r"^s: 'time'"):
            parse_time(bad, "s")


def test_site_table():
    site = site_from_table({"latitude": 37.87, "longitude": -122.27, "time_zone": -8}, "s.toml: [site]")
    assert site == Site(37.87, -122.27, -8.0, 0.0, "")
    assert site.meridian_warning("w") is None
    assert "west longitudes are negative" in Site(37.87, 122.27, -8.0).meridian_warning("w")
    with pytest.raises(InputError, match=r"s.toml: \[site\]: missing key 'longitude'"):
        site_from_table({"latitude": 1}, "s.toml: [site]")
    with pytest.raises(InputError, match=r"'latitude' must be <= 90"):
        site_from_table({"latitude": 91, "longitude": 0}, "s.toml: [site]")


# -- EPW -------------------------------------------------------------------------------------
def test_epw_header_and_records():
    epw = read_epw(EPW)
    assert epw.site.latitude == 37.876 and epw.site.longitude == -122.247
    assert epw.site.time_zone == -8.0 and epw.site.elevation == 200.0
    assert len(epw.records) == 96 and epw.records[0].line == 9
    rec, local = epw.record_at("06-20 12:00", "w")
    assert (rec.month, rec.day, rec.hour, rec.line) == (6, 20, 12, 20)
    assert local == dt.datetime(1999, 6, 20, 12)
    assert rec.direct_normal_irradiance == 870 and rec.diffuse_horizontal_illuminance == 15442
    assert epw.record_at("06-20 11:30", "w")[0] is rec              # the hour ending at 12:00
    assert epw.record_at("06-20 11:00", "w")[0].hour == 11
    assert epw.record_at("06-21 00:00", "w")[0].line == rec.line + 12   # hour 24 of 20 June
    with pytest.raises(InputError, match=r"^w: 'time' '07-01 12:00': no such hour in berkeley_excerpt.epw"):
        epw.record_at("07-01 12:00", "w")
    with pytest.raises(InputError, match=r"^w: 'time' must look like \"06-21 12:00\""):
        epw.record_at("2024-06-20 12:00", "w")


@needs_pvlib
def test_epw_reader_agrees_with_pvlib():
    import pvlib

    data, meta = pvlib.iotools.read_epw(str(EPW))
    epw = read_epw(EPW)
    assert (meta["latitude"], meta["longitude"], meta["TZ"], meta["altitude"]) == (
        epw.site.latitude, epw.site.longitude, epw.site.time_zone, epw.site.elevation)
    assert len(data) == len(epw.records)
    for (_, row), rec in zip(data.iterrows(), epw.records):
        assert (row["month"], row["day"], row["hour"]) == (rec.month, rec.day, rec.hour)
        assert (row["dni"], row["dhi"], row["temp_dew"]) == (
            rec.direct_normal_irradiance, rec.diffuse_horizontal_irradiance, rec.dew_point)
        assert (row["direct_normal_illum"], row["diffuse_horizontal_illum"]) == (
            rec.direct_normal_illuminance, rec.diffuse_horizontal_illuminance)


def _broken(tmp_path, line_no, change):
    lines = EPW.read_text().splitlines()
    lines[line_no - 1] = change(lines[line_no - 1])
    path = tmp_path / "broken.epw"
    path.write_text("\n".join(lines) + "\n")
    return path


@pytest.mark.parametrize("line_no, change, message", [
    (20, lambda s: s.replace(",870,", ",lots,"), r"^broken.epw: line 20: field 15 \(direct_normal_irradiance\) "
                                                 r"must be a number, got 'lots'$"),
    (30, lambda s: ",".join(s.split(",")[:10]), r"^broken.epw: line 30: a data line needs at least 19"),
    (12, lambda s: s.replace("1999,6,20,4,", "1999,6,20,25,"), r"^broken.epw: line 12: field 4 \(hour\) must be "
                                                               r"within 1…24, got 25$"),
    (1, lambda s: s.replace("37.876", "north"), r"^broken.epw: line 1: LOCATION field 7 \(latitude\) must be"),
])
def test_epw_errors_name_line_and_field(tmp_path, line_no, change, message):
    with pytest.raises(InputError, match=message) as exc:
        read_epw(_broken(tmp_path, line_no, change))
    assert "\n" not in str(exc.value)


def test_epw_missing_file(tmp_path):
    with pytest.raises(InputError, match="nope.epw: no such weather file"):
        read_epw(tmp_path / "nope.epw")

"""The sun (lbl_illum.daylight.sun): frame, disk, and the [sun] table by angles or by site and time."""

from __future__ import annotations

import datetime as dt

import numpy as np
import pytest

from lbl_illum.errors import InputError
from lbl_illum.daylight.solar import Site, solar_position
from lbl_illum.daylight.sun import SUN_COS_HALF_ANGLE, SUN_SOLID_ANGLE, Sun, sun_from_table, sun_position_at

SITE = Site(37.876, -122.247, -8.0, 200.0)


def test_direction_frame_and_disk():
    """+x east, +y north, +z up; azimuth clockwise from north."""
    assert np.allclose(Sun(0, 90, 1).direction, [1, 0, 0], atol=1e-12)
    assert np.allclose(Sun(0, 0, 1).direction, [0, 1, 0], atol=1e-12)
    assert np.allclose(Sun(90, 17, 1).direction, [0, 0, 1], atol=1e-12)
    sun = Sun(35, 210, 1000)
    d = sun.sample_directions(np.random.default_rng(0).random(1000), np.random.default_rng(1).random(1000))
    assert np.allclose(np.linalg.norm(d, axis=1), 1) and sun.within_disk(d).all()
    assert 2 * np.pi * (1 - SUN_COS_HALF_ANGLE) == pytest.approx(SUN_SOLID_ANGLE)
    assert sun.luminance == pytest.approx(1000 / SUN_SOLID_ANGLE)


def test_zero_direct_normal_positions_without_light():
    sun = sun_from_table({"altitude": 30, "azimuth": 100, "direct_normal_illuminance": 0}, "s.toml: [sun]")
    assert not sun.is_up and sun.horizontal_illuminance == 0 and sun.warnings == ()
    assert Sun(30, 100, 5).is_up and not Sun(-1, 100, 5).is_up


def test_sun_by_time_matches_solar_position():
    sun = sun_from_table({"time": "2024-03-20 09:15", "direct_normal_illuminance": 50000}, "s.toml: [sun]", SITE)
    utc = dt.datetime(2024, 3, 20, 17, 15)
    p = solar_position(utc, SITE.latitude, SITE.longitude, SITE.elevation)
    assert (sun.altitude, sun.azimuth, sun.time) == (pytest.approx(p.altitude), pytest.approx(p.azimuth), utc)
    assert 90 < sun.azimuth < 180                                   # morning sun in the south-east
    alt, az, _ = sun_position_at("2024-03-20 17:15Z", Site(37.876, -122.247, elevation=200.0), "w")  # no time zone
    assert (alt, az) == (pytest.approx(sun.altitude), pytest.approx(sun.azimuth))


def test_sun_at_night_warns():
    sun = sun_from_table({"time": "2024-03-20 23:00", "direct_normal_illuminance": 50000}, "s.toml: [sun]", SITE)
    assert sun.altitude < 0 and not sun.is_up
    assert sun.warnings[0].startswith("s.toml: [sun]: the sun is below the horizon")


@pytest.mark.parametrize("table, site, message", [
    ({"time": "2024-03-20 09:15", "direct_normal_illuminance": 1}, None, r"'time' needs a \[site\] table"),
    ({"time": "2024-03-20 09:15", "direct_normal_illuminance": 1}, Site(1, 2), r"\[site\] needs 'time_zone'"),
    ({"altitude": 10, "azimuth": 0}, SITE, r"missing key 'direct_normal_illuminance'"),
    ({"azimuth": 0, "direct_normal_illuminance": 1}, SITE, r"missing key 'altitude' \(or give a 'time'"),
    ({"altitude": 91, "azimuth": 0, "direct_normal_illuminance": 1}, None, r"'altitude' must be <= 90"),
    ({"altitude": 10, "azimuth": 0, "direct_normal_iluminance": 1}, None, r"did you mean 'direct_normal_illuminance'"),
    # brighter than the sun above the atmosphere at perihelion (133 334 lx × 1.0351)
    ({"altitude": 10, "azimuth": 0, "direct_normal_illuminance": 1.4e5}, None,
     r"'direct_normal_illuminance' must be <= 1380\d\d, got 140000"),
])
def test_sun_table_errors(table, site, message):
    with pytest.raises(InputError, match=rf"^s.toml: \[sun\]: .*{message}") as exc:
        sun_from_table(table, "s.toml: [sun]", site)
    assert "\n" not in str(exc.value)


def test_brightest_possible_sun_is_accepted():
    sun = sun_from_table({"altitude": 60, "azimuth": 180, "direct_normal_illuminance": 1.38e5}, "s.toml: [sun]")
    assert sun.direct_normal_illuminance == 1.38e5


def test_default_direct_normal_from_the_sky():
    sun = sun_from_table({"altitude": 40, "azimuth": 180}, "s.toml: [sun]", default_direct_normal=65000.0)
    assert sun.direct_normal_illuminance == 65000.0

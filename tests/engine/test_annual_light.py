"""A year from the cache's daylight coefficients (lbl_illum.engine.annual) against
point-in-time runs of the engine under the same hours' Perez skies and suns."""

from __future__ import annotations

import numpy as np
import pytest

from lbl_illum.daylight.skymatrix import sky_matrix
from lbl_illum.daylight.weather import read_weather
from lbl_illum.engine.annual import annual_light, hour_scene, shaded_scene, sun_positions
from lbl_illum.engine.integrator import Integrator
from lbl_illum.options import Options

from conftest import EXAMPLES

EPW = EXAMPLES / "weather" / "USA_CA_Oakland.Intl.AP.724930_TMY3.epw"
OPTIONS = Options(accuracy=0.12, samples=64, bounces=3, point_samples=1024, interpolation="paper")



@pytest.fixture(scope="module")
def year(office_quarter):
    scene, points, normals = office_quarter
    weather = read_weather(EPW)
    return annual_light(scene, points, normals, weather, OPTIONS)


def test_outputs_are_a_year_of_float32(year, office_quarter):
    n = len(office_quarter[1])
    assert year.illuminance.shape == (n, 8760) and year.illuminance.dtype == np.float32
    assert year.direct_sun.shape == (n, 8760) and year.direct_sun.dtype == np.float32
    night = ~year.sky.daylight
    assert night.sum() > 4000
    assert not year.illuminance[:, night].any() and not year.direct_sun[:, night].any()
    assert (year.illuminance >= year.direct_sun).all()


def test_sun_shares_carry_each_hours_direct_normal_illuminance():
    matrix = sky_matrix(EPW, sun="separate")
    weather = matrix.weather
    suns, shares = sun_positions(matrix, weather.site.latitude)
    assert 40 < len(suns) < 200 and (suns[:, 2] > 0).all()
    np.testing.assert_allclose(np.linalg.norm(suns, axis=1), 1.0)
    np.testing.assert_allclose(shares.sum(axis=0), matrix.direct_normal_illuminance, rtol=1e-5)
    # bilinear weights reproduce the sun's own direction where no node is below the horizon
    hours = np.flatnonzero(shares.any(axis=0) & (matrix.sun_altitude > 20.0))
    mean = (suns.T @ shares[:, hours]) / matrix.direct_normal_illuminance[hours]
    cosine = np.einsum("ij,ji->i", matrix.sun_direction[hours], mean) / np.linalg.norm(mean, axis=0)
    assert np.degrees(np.arccos(np.minimum(cosine, 1.0))).max() < 0.3


@pytest.mark.parametrize("kind", ["overcast", "sun in the room", "sunny, sun behind the room"])
def test_hours_agree_with_point_in_time_runs(year, office_quarter, kind):
    """Per point within 6 %, the mean within 3 % (the sky in 145 patches, the
    interreflected sun from the 4 sun positions nearest the hour's, the direct sun by one
    ray to the disk's centre against the run's jittered rays over the disk)."""
    scene, points, normals = office_quarter
    m = year.sky
    day = m.daylight & (m.sun_altitude > 15.0)
    if kind == "overcast":
        pick = day & (m.clearness < 1.1)
    elif kind == "sun in the room":
        pick = day & (m.clearness > 5.0) & (year.direct_sun.max(axis=0) > 5000.0)
    else:
        pick = day & (m.clearness > 4.0) & (year.direct_sun.max(axis=0) == 0.0)       # no sun through the window
    hour = np.flatnonzero(pick)[len(np.flatnonzero(pick)) // 2]
    ref = Integrator(hour_scene(scene, m, hour), OPTIONS).compute(points, normals).illuminance
    rel = year.illuminance[:, hour] / ref - 1.0
    assert abs(rel.mean()) < 0.03, (hour, rel)
    assert np.abs(rel).max() < 0.06, (hour, rel)


def test_hour_scene_refuses_a_night_row(year, office_quarter):
    with pytest.raises(ValueError, match="no daylight"):
        hour_scene(office_quarter[0], year.sky, int(np.flatnonzero(~year.sky.daylight)[0]))


def test_closed_shades_scale_the_light_through_the_window(year, office_quarter):
    """The office's daylight all comes through its one window: with its glass's
    transmittance times 0.05 the year reads 0.05 times as much (paths through the pane
    twice, out and back in, are far below the tolerance).  The direct sun scales exactly;
    the rest within the two calculations' noise (glass is transmitted at random in
    proportion to τ, so the shaded one samples the window with other rays: over three
    seeds the sums' ratios ranged over −1.9…+1.2 % for the sky and −0.8…+4.3 % for the
    interreflected sun)."""
    scene, points, normals = office_quarter
    closed = shaded_scene(scene, ["glazing"], 0.05)
    shaded = annual_light(closed, points, normals, year.sky.weather, OPTIONS, matrix=year.sky)
    lit = year.illuminance > 50.0
    assert shaded.illuminance[lit].sum() / year.illuminance[lit].sum() == pytest.approx(0.05, rel=0.03)
    ratio = shaded.illuminance[lit] / year.illuminance[lit]
    assert np.percentile(np.abs(ratio / 0.05 - 1.0), 95) < 0.1
    np.testing.assert_allclose(shaded.direct_sun, 0.05 * year.direct_sun, rtol=1e-5, atol=1e-3)


def test_shaded_scene_refuses_what_is_not_glass(office_quarter):
    scene = office_quarter[0]
    with pytest.raises(ValueError, match="'wall' is not a glass or translucent material.*glazing"):
        shaded_scene(scene, ["wall"], 0.1)
    with pytest.raises(ValueError, match="within 0 and 1"):
        shaded_scene(scene, ["glazing"], 1.5)
    closed = shaded_scene(scene, ["glazing"], 0.1)
    glass = {m.name: m for m in closed.materials}["glazing"]
    assert glass.transmittance == pytest.approx(tuple(0.1 * t for t in {m.name: m for m in scene.materials}["glazing"]
                                                      .transmittance))

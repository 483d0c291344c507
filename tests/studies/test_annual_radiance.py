"""The Radiance reference of the annual calculation (validation/studies/annual_radiance.py):
the two-phase method (gendaymtx, rcontrib, dctimestep, rmtxop) and one gendaymtx sun per
hour (rcontrib -ab 0) on the office example, Oakland TMY3.

The helpers are checked without Radiance; the rest skips when Radiance's programs are not
installed (pip install pyradiance).  The runs use the module's QUICK settings (a year in
about 2 s on 2 cores, two bounces): the totals are then far from converged, and only what does not depend
on the ambient settings is checked closely: the hours, the night, the direct sun (exact at
any setting: -ab 0), the metrics' plumbing.  The comparison with lbl-illum annual is slow.
"""

from types import SimpleNamespace

import numpy as np
import pytest

from conftest import EXAMPLES, radiance_tool
from lbl_illum import load_scene, read_points
from lbl_illum.daylight.skymatrix import sky_matrix
from lbl_illum.daylight.weather import read_weather
from lbl_illum.engine.integrator import Integrator
from lbl_illum.engine.sun_hours import sun_visibility
from lbl_illum.io.radiance import export_radiance
from lbl_illum.workplane.annual import annual_metrics, annual_summary, lm83_occupancy
from lbl_illum_studies import annual_radiance as ar

SCENE = EXAMPLES / "office" / "scene.toml"
EPW = EXAMPLES / "weather" / "USA_CA_Oakland.Intl.AP.724930_TMY3.epw"
WEA = EXAMPLES / "weather" / "oakland_tmy3.wea"
NEEDED = ("oconv", "rcontrib", "gendaymtx", "dctimestep", "rmtxop")
MISSING = [name for name in NEEDED if radiance_tool(name) is None]
needs_radiance = pytest.mark.skipif(bool(MISSING),
                                    reason=f"needs Radiance's {', '.join(MISSING)} (pip install pyradiance)")

#: Direct sun against direct_sun_matrix with the same suns, on the point-hours both light:
#: gendaymtx prints each sun's radiance with 4 significant digits (5e-4 relative), the
#: rest is float32.  Measured on the office: 4.4e-4 at most, 6.7e-5 on average.
DIRECT_RTOL = 1e-3
#: Point-hours lit by one calculation only (a point on a shadow's edge, where the two
#: ray tracers round differently): 1 of 26,657 lit point-hours measured.
DIRECT_EDGE_SHARE = 5e-4


@pytest.fixture(scope="module")
def office():
    scene = load_scene(SCENE)
    points, normals = read_points(EXAMPLES / "office" / "grid.pts", scene.unit_scale)
    return scene, points, normals


@pytest.fixture(scope="module")
def weather():
    return read_weather(EPW)


@pytest.fixture(scope="module")
def quick(office):
    _, points, normals = office
    return ar.two_phase(SCENE, points, normals, EPW, **ar.QUICK)


def _direct_reference(office, matrix):
    """lbl_illum's shadow ray per point and hour to the sun's centre (``sun_visibility``
    without the disk), as ``rcontrib -ab 0 -dj 0`` traces each hour's sun source:
    ``direct_sun_matrix`` averages the disk where a penumbra falls, which rtrace does not."""
    scene, points, normals = office
    integrator = Integrator(scene, scene.options)
    s, e_dn = matrix.sun_direction, matrix.direct_normal_illuminance
    up = (s[:, 2] > 0.0) & (e_dn > 0.0)
    out = np.zeros((len(points), len(s)), np.float32)
    out[:, up] = sun_visibility(integrator.direct, integrator.tracer, points, normals, s[up]) * e_dn[up].astype(
        np.float32)
    return out


# -- helpers, without Radiance ------------------------------------------------------------------
def _header(rows, cols, comps, fmt, big=False):
    text = f"#?RADIANCE\nsome program\nNROWS={rows}\nNCOLS={cols}\nNCOMP={comps}\n"
    if fmt != "ascii":
        text += f"BigEndian={int(big)}\n"
    return (text + f"FORMAT={fmt}\n\n").encode()


@pytest.mark.parametrize("fmt, dtype", [("float", "<f4"), ("double", "<f8"), ("float", ">f4"), ("ascii", None)])
def test_read_matrix_reads_every_format(fmt, dtype):
    values = np.arange(2 * 3 * 3, dtype=np.float64).reshape(2, 3, 3) / 4.0
    if dtype is None:
        body = "\n".join(" ".join(f"{v:g}" for v in row) for row in values.reshape(-1, 3)).encode()
    else:
        body = values.astype(dtype).tobytes()
    data = _header(2, 3, 3, fmt, big=dtype is not None and dtype.startswith(">")) + body
    np.testing.assert_array_equal(ar.read_matrix(data), values)
    with pytest.raises(ValueError, match="holds"):
        ar.read_matrix(_header(2, 4, 3, fmt) + body)


def test_solar_minutes_name_the_rows_as_gendaymtx_does(weather):
    """gendaymtx -D names the sun of a row solar<1440 (J - 1) + round(60 hour)>: the EPW's
    first row (hour 1, sun at 0:30) is minute 30; the .wea written from it gives the same."""
    minutes = ar.solar_minutes(weather)
    assert len(minutes) == 8760 and len(np.unique(minutes)) == 8760
    assert minutes[:3].tolist() == [30, 90, 150]
    assert minutes[-1] == 1440 * 364 + 23 * 60 + 30
    np.testing.assert_array_equal(ar.solar_minutes(read_weather(WEA)), minutes)
    leap = SimpleNamespace(month=np.array([2, 2, 3]), day=np.array([28, 29, 1]), hour=np.array([0.5, 0.5, 0.5]))
    assert ar.solar_minutes(leap).tolist() == [1440 * 58 + 30, 1440 * 59 + 30, 1440 * 60 + 30]
    assert ar.sun_columns(weather, ["solar30", "solar750"]).tolist() == [0, 12]
    with pytest.raises(ValueError, match="matches no row"):
        ar.sun_columns(weather, ["solar31"])


def test_black_materials_keep_the_glass_and_the_export_names(office, tmp_path):
    scene, points, normals = office
    ex = export_radiance(scene, tmp_path / "scene", points, normals)
    exported = (tmp_path / "scene" / "materials.rad").read_text()
    black = ar.black_materials(scene)
    names = lambda text: [line.split()[2] for line in text.splitlines() if line.startswith("void ")]
    assert names(black) == names(exported)
    assert "void BRTDfunc glazing" in black and black.count("5 0 0 0 0 0") == len(scene.materials) - 1
    assert "sky.rad" in ex.scene_files          # what two_phase leaves out


# -- with Radiance ----------------------------------------------------------------------------------
@needs_radiance
def test_one_column_per_row_of_the_weather_file(quick):
    for key in ("illuminance", "direct_sun", "illuminance_exact_sun"):
        E = quick[key]
        assert E.shape == (77, 8760) and E.dtype == np.float32
        assert np.isfinite(E).all() and (E >= 0).all()
    assert quick["rows"] == 8760
    assert quick["sun_sources"] > 4000
    assert len(quick["commands"]) == 12 and quick["commands"][0].startswith("gendaymtx -m 1 -of ")
    assert quick["seconds"] > 0


@needs_radiance
def test_zero_at_night_and_light_in_every_daylight_hour(quick, weather):
    """Rows without light are zero columns; every row lbl_illum calls daylight (its sun above
    the horizon, with gendaymtx's solar position) lights every sensor.  gendaymtx also
    lights the few rows whose mid-hour sun is just below the horizon but whose file gives
    light (docs/annual-sky.md: 83 in this year)."""
    dark = (weather.direct_normal_irradiance + weather.diffuse_horizontal_irradiance) <= 0
    assert dark.sum() > 4000
    for key in ("illuminance", "direct_sun", "illuminance_exact_sun"):
        assert not quick[key][:, dark].any()
    ours = sky_matrix(weather, sun="separate", solar_position="gendaymtx").daylight
    assert (quick["illuminance"][:, ours] > 0).all()
    lit = quick["illuminance"].any(axis=0)
    assert not (ours & ~lit).any()
    assert lit.sum() <= quick["daylight_columns"] <= ours.sum() + 100
    assert 0 < (lit & ~ours).sum() <= 100


@needs_radiance
def test_direct_sun_is_part_of_the_total(quick):
    """The total with the exact sun holds the direct sun in every point-hour (up to the noise
    of the patch sun's direct view it replaces).  The classic two-phase total, with the sun
    in 4 patches, holds it over the year at every point but not in every hour: near the
    edge of the sunlit patch the patches miss the window where the sun does not."""
    D, E, X = quick["direct_sun"], quick["illuminance"], quick["illuminance_exact_sun"]
    lit = D > 0
    assert quick["below_direct_exact_sun"] == (X < D * (1 - 1e-4)).sum() <= 1e-3 * lit.sum()
    assert (X[lit] >= 0.95 * D[lit]).all()
    assert (E.sum(axis=1) > D.sum(axis=1)).all()
    assert 0.1 * lit.sum() < quick["below_direct"] < 0.4 * lit.sum()


@needs_radiance
def test_direct_sun_agrees_with_direct_sun_matrix(quick, office, weather):
    """The same suns (lbl_illum's sky matrix with gendaymtx's solar position, which
    reproduces gendaymtx's sun and E_dn) through lbl_illum's shadow rays: within the 4
    digits gendaymtx prints the suns' radiance with, on the point-hours both light."""
    matrix = sky_matrix(weather, sun="separate", solar_position="gendaymtx")
    ours = _direct_reference(office, matrix)
    radiance = quick["direct_sun"]
    both = (ours > 0) & (radiance > 0)
    one = (ours > 0) ^ (radiance > 0)
    assert both.sum() > 20000
    assert one.sum() <= DIRECT_EDGE_SHARE * both.sum()
    rel = np.abs(radiance[both].astype(np.float64) / ours[both] - 1.0)
    assert rel.max() < DIRECT_RTOL and rel.mean() < DIRECT_RTOL / 5
    assert radiance.sum(dtype=np.float64) / ours.sum(dtype=np.float64) == pytest.approx(1.0, abs=DIRECT_RTOL)


@needs_radiance
def test_lbl_illum_suns_give_lbl_illums_direct_sun(office, weather):
    """sun="lbl_illum": one source per hour at lbl_illum's own sun (default solar position),
    radiance E_dn / (179 Ω) with 9 digits: the same direct sun as direct_sun_matrix to
    float precision, the same lit point-hours."""
    _, points, normals = office
    result = ar.two_phase(SCENE, points, normals, EPW, sun="lbl_illum", exact_sun=False, **ar.QUICK)
    assert result["illuminance_exact_sun"] is None
    ours = _direct_reference(office, sky_matrix(weather, sun="separate"))
    radiance = result["direct_sun"]
    np.testing.assert_array_equal(radiance > 0, ours > 0)
    np.testing.assert_allclose(radiance, ours, rtol=1e-5, atol=1e-3)


@needs_radiance
def test_the_wea_gives_the_same_hours_and_suns(office, quick):
    """gendaymtx reads the .wea epw2wea wrote from the EPW: the same suns light the same
    point-hours; their brightness differs by the dew point (a .wea has none: 11 °C)."""
    _, points, normals = office
    result = ar.two_phase(SCENE, points, normals, WEA, exact_sun=False, **ar.QUICK)
    np.testing.assert_array_equal(result["direct_sun"] > 0, quick["direct_sun"] > 0)
    ratio = result["direct_sun"].sum(dtype=np.float64) / quick["direct_sun"].sum(dtype=np.float64)
    assert ratio == pytest.approx(1.0, abs=0.03)


@needs_radiance
def test_sda_and_ase_from_the_arrays(quick, office, weather):
    """How to get sDA300/50 % and ASE1000,250 from the two arrays: lbl_illum.workplane.annual
    with LM-83's occupancy.  ASE counts direct-sun hours only, so it is the same as from
    lbl_illum's own direct sun with the same suns."""
    E, D = quick["illuminance"], quick["direct_sun"]
    summary = annual_summary(annual_metrics(E, lm83_occupancy(), direct_sun=D))["overall"]
    assert 0 <= summary["sda"] <= 100 and 0 < summary["ase"] < 100
    figures = ar.metrics(E, D)
    assert figures["sda"] == summary["sda"] and figures["ase"] == summary["ase"]
    assert figures["illuminance_sum"] == pytest.approx(E.sum(dtype=np.float64))
    ours = _direct_reference(office, sky_matrix(weather, sun="separate", solar_position="gendaymtx"))
    own = annual_summary(annual_metrics(E, lm83_occupancy(), direct_sun=ours))["overall"]
    assert own["ase"] == summary["ase"]


@needs_radiance
def test_seed_shuffles_the_points_and_puts_the_rows_back(office, quick):
    """rcontrib seeds from the clock; seed feeds the points in another order: the direct sun
    (no random numbers: -ab 0, -dj 0) comes back identical row by row, the total with other
    noise (up to 15 % on a point's year at the back of the room, lit by one noisy bounce)."""
    _, points, normals = office
    shuffled = ar.two_phase(SCENE, points, normals, EPW, seed=3, exact_sun=False, **ar.QUICK)
    np.testing.assert_array_equal(shuffled["direct_sun"], quick["direct_sun"])
    assert not np.array_equal(shuffled["illuminance"], quick["illuminance"])
    a = quick["illuminance"].sum(axis=1, dtype=np.float64)
    b = shuffled["illuminance"].sum(axis=1, dtype=np.float64)
    assert np.abs(b / a - 1).max() < 0.3
    assert np.corrcoef(a, b)[0, 1] > 0.99           # the rows are the same points


@needs_radiance
@pytest.mark.slow
def test_against_lbl_illum_annual(office, weather):
    """A short two-phase run (-ab 11 -ad 16384 -lw 1e-5: 1.1 % noise on a point's year)
    against lbl-illum annual at draft: the year's total with the exact sun within 2 %
    (measured with the converged reference: +0.8 %, the direct sun +1.1 % of it from
    gendaymtx's solar position; the points' years −0.8 … +3.6 %), every point's within
    10 %, sDA and ASE the same on this office."""
    from lbl_illum.engine.annual import annual_light

    scene, points, normals = office
    radiance = ar.two_phase(SCENE, points, normals, EPW, ab=11, ad=16384, lw=1e-5, lr=-24)
    ours = annual_light(scene, points, normals, weather, scene.options.with_preset("draft"))
    X, E = radiance["illuminance_exact_sun"].astype(np.float64), ours.illuminance.astype(np.float64)
    assert X.sum() / E.sum() == pytest.approx(1.0, abs=0.02)
    assert np.abs(X.sum(axis=1) / E.sum(axis=1) - 1).max() < 0.10
    a, b = ar.metrics(X, radiance["direct_sun"]), ar.metrics(E, ours.direct_sun)
    assert a["sda"] == b["sda"] and a["ase"] == b["ase"]

"""The extremes study: every setting and input at its limit gives finite, bounded,
correct illuminance.

The quick version runs once per module (about 10 s).  Each test states the bound it
checks; the report states the same bounds (tolerance column)."""

import math

import numpy as np
import pytest

from lbl_illum import Options
from lbl_illum.engine.integrator import RunStats
from lbl_illum_studies import extremes as ex
from lbl_illum_studies.report import StudyContext
from lbl_illum.daylight.sun import SUN_SOLID_ANGLE, Sun


@pytest.fixture(scope="module")
def results():
    return ex.run(StudyContext(quick=True)).results


def case(results, name, settings=""):
    found = [c for c in results["cases"] if c["case"] == name and c["settings"].startswith(settings)]
    assert found, name
    return found[0]


# -- the helpers against independent computations -----------------------------------------------
def test_opening_closed_form_matches_a_numerical_integral():
    """E = L ∫ cos θ cos θ' / d² dA over the opening, L = E_h/π, both cosines h/d."""
    P, _ = ex.workplane()
    W, L, H = ex.ROOM
    k = 400
    s = (np.arange(k) + 0.5) / k * ex.HOLE
    X, Y = np.meshgrid((W - ex.HOLE) / 2 + s, (L - ex.HOLE) / 2 + s)
    dA = (ex.HOLE / k) ** 2
    for p, closed in zip(P, ex.opening_illuminance(P)):
        h = H - p[2]
        d2 = (X - p[0]) ** 2 + (Y - p[1]) ** 2 + h * h
        numeric = ex.E_H / math.pi * np.sum(h * h / (d2 * d2)) * dA
        assert closed == pytest.approx(numeric, rel=1e-4)


def test_grazing_sun_closed_form_matches_sampling_the_disk():
    """The small-angle closed form against E_dn · mean max(0, sin altitude) over
    directions drawn uniformly on the true spherical cap (the engine's sampler)."""
    rng = np.random.default_rng(3)
    delta = ex.sun_disk_radius()
    assert 2 * math.pi * (1 - math.cos(delta)) == pytest.approx(SUN_SOLID_ANGLE)
    n = 2_000_000
    for alt in (0.1, 0.2):
        d = Sun(alt, 0.0, ex.E_DN).sample_directions(rng.random(n), rng.random(n))
        sampled = ex.E_DN * np.mean(np.maximum(d[:, 2], 0.0))
        exact, centre = ex.grazing_sun_illuminance(alt)
        assert exact == pytest.approx(sampled, rel=3e-3)
        assert centre < exact


def test_bounds_and_record_rule():
    assert ex.upper_bound(ex.E_H / math.pi, 0.7) == pytest.approx(ex.E_H)
    assert ex.upper_bound(0.0, 0.5, 1000.0) == pytest.approx(2000.0)
    opts = Options(samples=32, bounces=2)           # 3 × 11 = 33 rays per record, then 2 × 8 = 16
    ok = RunStats(new_records=[4, 10, 50], queries=[4, 4 * 33, 10 * 16])
    assert ex.records_bounded(ok, opts, 4)
    assert not ex.records_bounded(RunStats(new_records=[4, 10, 50], queries=[4, 4 * 33, 10 * 16 + 1]), opts, 4)
    assert not ex.records_bounded(RunStats(new_records=[5, 0, 0], queries=[4, 0, 0]), opts, 4)


def test_wall_fills_the_view_of_a_sensor_one_millimetre_from_it():
    assert 1 - 1e-9 < ex.wall_view_factor(1e-3) < 1.0
    assert ex.wall_view_factor(50.0) < 0.8


# -- the quick study ------------------------------------------------------------------------------
def test_every_case_finishes_plausible_and_within_its_tolerance(results):
    """Finite, ≥ 0, ≤ E_max, records within the placement bound, and the value within the
    tolerance of the table (4 standard errors + stated bias, or exact)."""
    assert results["failed"] == []
    for c in results["cases"]:
        assert c["plausible"], (c["case"], c.get("why"))


def test_closed_box_is_exactly_dark_at_every_sensor(results):
    for c in results["cases"]:
        if c["case"] == "closed box under sun and sky":
            assert set(c["per_sensor"].values()) == {0.0}, c["per_sensor"]
    dark = case(results, "closed box, no light")
    assert dark["result"] == 0.0 and dark["rays"] == 0 and dark["records"] == 0


def test_black_room_has_no_indirect_light_and_matches_the_closed_form(results):
    c = case(results, "reflectance 0")
    assert c["deeper_records"] == 0 and c["same_as_bounces_0"]
    assert abs(c["difference"]) <= 4 * c["se"]


def test_units_and_sizes_do_not_change_the_result(results):
    """Same seed: ≤ 1e-6 relative between mm, m and km, and between spheres of radius
    1e-4 m and 1e4 m; each sphere within 3 % of the §4 closed form at every sensor."""
    c = case(results, "room in mm and km")
    assert c["mm_vs_m"] <= 1e-6 and c["km_vs_m"] <= 1e-6
    assert case(results, "sphere r = 0.0001 m vs 10000 m")["difference"] <= 1e-6
    for r in ("0.0001", "10000"):
        assert case(results, f"sphere r = {r} m")["difference"] <= 0.03


def test_extreme_settings_stay_bounded(results):
    """a = 1 and 10, 1 and 4 samples with interpolation: bounds only (finite, 0 ≤ E ≤ 10,000 lux)."""
    for name in ("a = 1", "a = 10", "samples = 1, a = 0.1", "samples = 4, a = 0.1"):
        c = case(results, name)
        assert c["plausible"] and 0.0 <= c["result"] <= ex.E_H
    for name in ("samples = 1, a = 0", "samples = 4, a = 0", "a = 0.001", "samples = 65536", "bounces = 0",
                 "bounces = 50, a = 0"):
        c = case(results, name)
        assert abs(c["difference"]) <= 4 * c["se"] + c["bias_allowed"], name


def test_sensors_near_surfaces_and_extreme_suns(results):
    """1 mm from a wall: within 0.5 % of ρ E_wall; grazing sun and the zenith sun's sliver on
    vertical sensors: within 4 SE of their closed forms; zenith sun on horizontal sensors:
    E_dn + E_h to 1e-9."""
    assert abs(case(results, "facing a wall at 1 mm")["difference"]) <= 0.005
    for name in ("grazing sun, 0.1°", "zenith sun, vertical sensor", "sensor on a surface (z = 0)"):
        c = case(results, name)
        assert abs(c["difference"]) <= 4 * c["se"] + c["bias_allowed"], name
    assert case(results, "sun at the zenith")["difference"] <= 1e-9


def test_degenerate_triangles_are_counted_and_dropped(results):
    c = case(results, "zero-area and duplicate triangles, non-manifold edge")
    assert c["counted"] == c["injected"] == {"zero-area": 2, "duplicate": 3}
    assert c["identical"] and c["non_manifold_edges"] == 1 and c["clean_warnings"] == []
    for name in ("file with a NaN corner", "file with only zero-area triangles"):
        msg = case(results, name)["message"]
        assert msg and "\n" not in msg


def test_out_of_range_options_are_refused_with_one_line(results):
    for r in results["options_refused"]:
        assert r["message"] and "\n" not in r["message"] and r["key"] in r["message"], r

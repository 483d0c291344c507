"""The scene-requires study: records and rays only where the queries need them.

The quick version runs once per module (about 10 s); each test checks one property
with the bound the report states.
"""

import json
import math

import numpy as np
import pytest

from lbl_illum import read_points
from lbl_illum.engine.cache import LevelRecords
from lbl_illum.errors import InputError
from lbl_illum_studies import scene_requires as sr
from lbl_illum_studies.report import StudyContext

from conftest import EXAMPLES


@pytest.fixture(scope="module")
def study():
    ctx = StudyContext(quick=True)
    report = sr.run(ctx)
    return report, ctx


@pytest.fixture(scope="module")
def results(study):
    return study[0].results


# -- helpers ---------------------------------------------------------------------------
def test_interior_tells_room_faces_from_outer_faces_and_ground():
    P = np.array([[1.0, 1.0, 0.0],     # floor, facing up: inside
                  [2.0, 0.0, 1.0],     # south wall, inner face: inside
                  [2.0, 0.0, 1.0],     # south wall, outer face: outside
                  [2.0, 3.0, 3.0],     # ceiling from below: inside
                  [2.0, 3.0, 3.0],     # roof from above: outside
                  [5.0, -3.0, 0.0],    # ground
                  [1.0, 2.0, 0.8]])    # a sensor
    N = np.array([[0, 0, 1], [0, 1, 0], [0, -1, 0], [0, 0, -1], [0, 0, 1], [0, 0, 1], [0, 0, 1]], float)
    assert sr.interior(P, N).tolist() == [True, True, False, True, False, False, True]
    assert sr.on_floor(P, N).tolist() == [True, False, False, False, False, False, False]
    assert sr.regions(P, N) == {"west": 2, "east": 2, "outside": 3}     # x < 2 m is west


def test_growth_exponent_of_a_power_law_is_its_power():
    n = np.array([10.0, 40.0, 160.0])
    assert sr.growth_exponents(n, 3.0 * n ** 0.25) == pytest.approx([0.25, 0.25], abs=1e-12)
    assert sr.growth_exponents(n, n) == pytest.approx([1.0, 1.0], abs=1e-12)
    assert math.isnan(sr.growth_exponents([1, 2], [0, 5])[0])


def test_uncovered_by_applies_eq5_to_the_first_records_only():
    level = LevelRecords(0.5, np.zeros(3), 10.0)
    up = np.array([[0.0, 0.0, 1.0]])
    level.add(np.zeros((1, 3)), up, np.array([1.0]))          # covers |P| < a R = 0.5 on its plane
    level.add(np.array([[3.0, 0.0, 0.0]]), up, np.array([1.0]))
    P = np.array([[0.3, 0.0, 0.0], [0.7, 0.0, 0.0], [3.0, 0.0, 0.0]])
    N = np.tile(up, (3, 1))
    assert sr.uncovered_by(level, 1, P, N).tolist() == [False, True, True]
    assert sr.uncovered_by(level, 2, P, N).tolist() == [False, True, False]
    assert sr.uncovered_by(level, 0, P, N).tolist() == [True, True, True]


def test_workplane_grid_at_half_a_metre_is_the_example_grid():
    points, normals = sr.workplane_grid(0.5)
    ref_p, ref_n = read_points(EXAMPLES / "office" / "grid.pts")
    assert np.array_equal(points, ref_p) and np.array_equal(normals, ref_n)
    assert len(sr.workplane_grid(0.125)[0]) == 25 * 41


def test_without_a_checkout_the_study_says_so_in_one_line(monkeypatch):
    monkeypatch.setattr(sr, "repository_root", lambda: None)
    with pytest.raises(InputError, match="examples/") as err:
        sr.run(StudyContext(quick=True))
    assert "\n" not in str(err.value)


# -- the quick study ---------------------------------------------------------------------
def test_half_grid_level0_records_lie_in_the_half(results):
    half = results["half"]
    # records of level 0 are made at the half's own sensors (x = 0.5, 1, 1.5 m) only
    assert half["level0_outside_sensor_box"] == 0
    assert half["level0_max_x"] < sr.HALF_X
    assert half["regions"]["east"][0] == 0 and half["regions"]["outside"][0] == 0
    assert half["records"][0] <= half["points"] == 33


def test_half_grid_costs_less_but_deeper_levels_reach_the_far_half(results):
    half, full = results["half"], results["full"]
    assert half["records_fraction"] < 1.0 and half["rays_fraction"] < 1.0
    # light bounces: deeper records in the east half, fewer than the full grid's there at level 1
    assert half["regions"]["east"][1] > 0
    assert half["regions"]["east"][1] < full["regions"]["east"][1]


def test_black_floor_gets_no_deeper_record(results):
    B = results["settings"]["bounces"]
    assert results["black_floor"]["floor_records"][1:] == [0] * B
    # the same count finds floor records when the floor reflects (the check can fail)
    assert sum(results["full"]["floor_records"][1:]) > 0
    assert results["black_floor"]["total_records"] < results["full"]["total_records"]


def test_no_light_no_records_no_rays(results):
    dark = results["dark"]
    assert dark["total_records"] == 0 and dark["rays"] == 0 and dark["max_illuminance"] == 0.0


def test_sun_without_sky_skips_only_the_bounce_limit_level(results):
    B = results["settings"]["bounces"]
    records = results["sun_only"]["records"]
    assert records[B] == 0
    assert all(c > 0 for c in records[:B])


def test_second_grid_pays_only_for_what_the_first_left_uncovered(results):
    ov = results["overlap"]
    new, alone = ov["B_after_A"]["new_records"], ov["B_alone"]["records"]
    assert all(n <= a for n, a in zip(new, alone))
    assert sum(new) < sum(alone)
    assert ov["B_after_A"]["rays"] < ov["B_alone"]["rays"]
    # every new record lies outside the domains of A's records of its level
    assert sum(ov["new_records_covered_by_A"]) == 0
    # the shared rows (y 2.5-3.5 m) are answered by A: new level-0 records only beyond them
    assert ov["new_level0_min_y"] > sr.A_MAX_Y
    assert ov["B_after_A"]["new_records"][0] <= ov["points_B"] - ov["points_shared"]


def test_records_level_off_as_points_get_dense(results):
    den = results["density"]
    exps = den["exponents"]
    assert den["points"] == sorted(den["points"])
    # coarse grids: about one level-0 record per point
    assert exps["level 0"][0] >= sr.COARSE_EXPONENT_MIN
    # dense grids: the count levels off (the bound the report states)
    assert exps["level 0"][-1] <= sr.DENSE_EXPONENT_MAX
    assert exps["all"][-1] <= sr.DENSE_EXPONENT_MAX
    assert den["records"][0][-1] < den["points"][-1] / 2


def test_every_check_held_and_the_report_writes(study, tmp_path):
    report, ctx = study
    assert all(report.results["checks"].values()), report.results["checks"]
    assert ctx.runs == ctx.planned
    assert ctx.rays > 0 and ctx.records > 0
    folder = report.write(tmp_path / "scene-requires", {"quick": True})
    text = (folder / "report.md").read_text()
    assert "did NOT hold" not in text
    for name in ("plan_full_half", "section_black_floor", "plan_overlap", "records_vs_points"):
        assert (folder / f"{name}.png").stat().st_size > 0
    doc = json.loads((folder / "results.json").read_text())
    assert doc["results"]["dark"]["rays"] == 0
    # the probe the dark run skipped does trace rays when called: the zero is not vacuous
    assert doc["results"]["dark"]["spacing_probe_rays"] > 0

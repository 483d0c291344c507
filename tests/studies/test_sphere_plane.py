"""The sphere-plane study (the paper's §4): its reference and its quick version.

The reference is checked against exact special cases and an independent brute-force
ray count; the quick version (a = 0.1, 1024 samples, a quarter of the sphere at the
full version's point density) runs once per module and must meet the bounds its
report states: mean relative error ≤ 2 % and max ≤ 6 % with the default interpolation,
mean ≤ 2 % and max ≤ twice the split-sphere estimate 1.4a with the paper's Eq. 5.
"""

import json
import math

import numpy as np
import pytest

from lbl_illum import Integrator, Options
from lbl_illum_studies import sphere_plane as sp
from lbl_illum_studies import sphere_plane_reference as ref
from lbl_illum_studies.report import StudyContext


# -- the reference ---------------------------------------------------------------------------
@pytest.mark.parametrize("h", [0.3, 1.0, 2.5])
def test_contour_integral_of_a_disc_seen_from_above_is_exact(h):
    # a disc of radius 1 seen from height h on its axis, facing it: Φ = π sin²α = π / (1 + h²)
    phi = ref.segment_projected_solid_angle([[0.0, 0.0, h]], [[0.0, 0.0, -1.0]])
    assert phi[0] == pytest.approx(math.pi / (1.0 + h * h), rel=1e-12)


def test_contour_integral_of_a_growing_disc_tends_to_the_whole_visible_plane():
    # a point 1 m above the plane, its normal tilted 45° below the horizontal, sees the plane
    # where x > −1; a disc of radius W around the origin tends to that half-plane, whose
    # projected solid angle is π(1 − n_z)/2, with a deficit falling as 1/W
    n = np.array([[math.sqrt(0.5), 0.0, -math.sqrt(0.5)]])
    P = np.array([[0.0, 0.0, 1.0]])
    big = ref.segment_projected_solid_angle(P, n, radius=1e6)
    assert big[0] == pytest.approx(math.pi * (1.0 + math.sqrt(0.5)) / 2.0, rel=1e-5)


def test_upper_half_is_the_closed_form_and_continuous_at_the_equator():
    g = np.radians([0.0, 20.0, 45.0, 90.0])
    expected = ref.E0 * np.sin(g) + ref.RHO * ref.E0 * (1.0 - np.sin(g)) / 2.0
    assert ref.illuminance(g) == pytest.approx(expected, rel=1e-14)
    just_below = ref.illuminance(np.radians([-1e-7]))[0]
    assert just_below == pytest.approx(ref.RHO * ref.E0 / 2.0, rel=1e-8)


def test_lower_half_quadrature_converges_to_1e_minus_6_and_vanishes_at_contact():
    g = np.radians(np.linspace(-85.0, -0.01, 120))
    assert ref.quadrature_error(g).max() < 1e-6
    assert ref.illuminance(np.radians([-89.9]))[0] < 1e-5 * ref.E0


def test_reference_agrees_with_brute_force_ray_counting():
    # independent of the contour formula: cosine-distributed rays, counted where they reach
    # the plane outside the shadow disc; 5 standard errors at each elevation
    g = np.radians([-60.0, -45.0, -30.0, -15.0, -5.0, 10.0, 40.0])
    est, se = ref.monte_carlo_illuminance(g, 200_000, np.random.default_rng(5))
    assert np.all(np.abs(est - ref.illuminance(g)) <= 5.0 * se + 1e-9)


def test_plane_truncation_falls_as_one_over_the_half_width():
    g = np.radians(np.linspace(-50.0, 80.0, 27))
    d1 = ref.truncation_deficit(g, 2000.0)
    d2 = ref.truncation_deficit(g, 4000.0)
    assert np.all(d2 < d1)
    assert d2.max() / d1.max() == pytest.approx(0.5, rel=0.02)
    # the study's plane: below 0.1 % of E at every point it uses
    gamma = sp.elevation(sp.sphere_points(2000)[1])
    frac = ref.truncation_deficit(np.radians(gamma), sp.HALF_WIDTH) / ref.illuminance(np.radians(gamma))
    assert frac.max() < 1e-3


def test_points_cover_the_band_uniformly_by_area():
    P, N = sp.sphere_points(4000)
    assert np.allclose(np.linalg.norm(P - [0.0, 0.0, 1.0], axis=1), 1.0)
    assert np.allclose(P - [0.0, 0.0, 1.0], N)
    gamma = sp.elevation(N)
    assert gamma.min() >= sp.GAMMA_MIN and gamma.max() <= 90.0
    dens = np.array(sp.band_density(gamma, sp.band_edges()))
    assert dens.max() / dens.min() < 1.05


def test_fit_line_recovers_a_line():
    f = sp.fit_line([0.1, 0.2, 0.4], [0.01 + 0.3 * x for x in (0.1, 0.2, 0.4)])
    assert f["intercept"] == pytest.approx(0.01) and f["slope"] == pytest.approx(0.3) and f["r2"] == pytest.approx(1.0)


# -- the engine pieces of the study ----------------------------------------------------------------
def test_paper_answer_of_a_run_equals_a_run_with_the_paper_rule():
    # the study answers one record set both ways; a separate run with interpolation="paper"
    # must give the same illuminance (placement does not depend on the rule)
    scene = sp.build_scene()
    P, N = sp.sphere_points(2000)
    both = sp.engine_run(scene, P, N, 0.4, samples=256)
    paper = Integrator(scene, Options(accuracy=0.4, bounces=1, samples=256, interpolation="paper")).compute(P, N)
    assert both["records"] == paper.stats.records[0] < 1000
    assert both["paper"] == pytest.approx(paper.illuminance, rel=1e-6)
    assert not np.allclose(both["paper"], both["gradients"])


def test_rows_order_goes_top_down_and_is_a_permutation():
    P, N = sp.sphere_points(500)
    order = sp.query_order(P, N, "rows")
    assert sorted(order.tolist()) == list(range(500))
    z = P[order, 2]
    assert z[0] > 1.9 and z[-1] < 0.5
    assert sorted(sp.query_order(P, N, "random").tolist()) == list(range(500))


# -- the quick version ----------------------------------------------------------------------------
@pytest.fixture(scope="module")
def study():
    ctx = StudyContext(quick=True)
    report = sp.run(ctx)
    return report, ctx


@pytest.fixture(scope="module")
def results(study):
    return study[0].results


def _ladder(results, a):
    return next(row for row in results["ladder"] if row["accuracy"] == a)


def test_quick_default_interpolation_meets_its_bounds(results):
    row = _ladder(results, 0.1)
    assert row["gradients"]["mean"] <= sp.QUICK_BOUNDS["mean"]
    assert row["gradients"]["max"] <= sp.QUICK_BOUNDS["max"]


def test_quick_paper_rule_meets_the_paper_statement(results):
    row = _ladder(results, 0.1)
    assert row["paper"]["mean"] <= sp.QUICK_BOUNDS["mean"]
    assert row["paper"]["max"] <= 2.0 * sp.SPLIT_SPHERE_FACTOR * 0.1


def test_quick_run_interpolates(results):
    # fewer records than points, or the test would measure Monte Carlo noise only
    assert _ladder(results, 0.1)["records_per_query"] < 0.5


def test_pure_monte_carlo_is_unbiased_against_the_reference(results):
    mc = results["monte_carlo"]
    assert mc["records"] == mc["points"]
    # standard error of the mean signed error ≈ rms / √n ≈ 0.03 %; truncation and tessellation < 0.03 %
    assert abs(mc["bias"]) <= 4.0 * mc["rms"] / math.sqrt(mc["points"]) + 3e-4
    assert mc["mean"] < 0.01


def test_quick_sequential_order_answers_within_bounds(results):
    (row,) = [r for r in results["sequential"] if r["accuracy"] == 0.1]
    assert 0 < row["records"] < results["settings"]["points"]
    assert row["final_gradients"]["mean"] <= sp.QUICK_BOUNDS["mean"]
    assert row["sequential_paper"]["mean"] <= sp.QUICK_BOUNDS["mean"]


def test_quick_report_states_its_bounds_and_skips_radiance(study, tmp_path):
    report, ctx = study
    assert report.results["radiance"] is None
    assert ctx.runs == 4
    folder = report.write(tmp_path / "sphere-plane", {"quick": True})
    text = (folder / "report.md").read_text()
    assert "mean ≤ 2 % and max ≤ 6 % with the default interpolation" in text
    assert "Radiance was not run" in text
    data = json.loads((folder / "results.json").read_text())
    assert data["results"]["reference"]["quadrature_max_relative_change"] < 1e-6
    assert data["results"]["reference"]["truncation_max_fraction"]["5000"] < 1e-3


# -- Radiance (optional) -------------------------------------------------------------------------
def test_radiance_scene_gives_e0_at_the_top_and_the_reference_with_matched_ar(tmp_path):
    pytest.importorskip("pyradiance")
    programs = sp.radiance_programs()
    if programs is None:
        pytest.skip("pyradiance has no Radiance programs")
    P, N = sp.sphere_points(400, gamma_min=0.0)
    rad = sp.Radiance(programs, tmp_path, P, N)
    direct = rad.run(0.0, None, samples=1)
    # near the top the sphere sees almost no plane: E0 sin γ, which checks the sun's units
    top = np.argmax(N[:, 2])
    assert direct["illuminance"][top] == pytest.approx(ref.illuminance(np.radians(sp.elevation(N[top:top + 1])))[0],
                                                       rel=2e-3)
    r = rad.run(0.2, int(round(rad.cube_size / 0.1)))
    E = ref.illuminance(np.radians(sp.elevation(N)))
    assert r["records"] > 0
    assert np.mean(np.abs(r["illuminance"] / E - 1.0)) < 0.02

"""The integrating-sphere study, quick version: closed-form interreflection over many
bounces (validation/studies/integrating_sphere.py), the ambient value at the bounce
limit, and a closed box of reflectance 0.999 against its flux balance.

The exact values are recomputed here from the study's scene constants (ideal sphere:
E_0 = π L (r/R)², f = (r/R)², q = ρ (1 − f)), not taken from the study's own results;
the icosphere emitter differs from the ideal sphere by 7.5e-5, far below every bound.
"""

import math

import numpy as np
import pytest

from lbl_illum_studies import integrating_sphere as study
from lbl_illum_studies.report import StudyContext


@pytest.fixture(scope="module")
def report():
    return study.run(StudyContext(quick=True))


def ideal(rho):
    """(E_0 [lux], q) of the integrating sphere with the study's R, r and L."""
    f = (study.LAMP_RADIUS / study.WALL_RADIUS) ** 2
    return math.pi * study.LAMP_LUMINANCE * f, rho * (1.0 - f)


def runs_by_bounces(report, rho):
    return {x["bounces"]: x for x in report.results["ladders"][f"{rho:g}"]["runs"]}


def test_polygon_illuminance_of_a_square_matches_the_closed_form():
    """Centred square of half side a at height h above the point (Lambert's corner formula,
    four corners): E = 2 L [X/√(1+X²) atan(X/√(1+X²))] · 2 with X = a/h."""
    a, h, L = 1.0, 1.0, 100.0
    sq = np.array([[-a, -a, h], [a, -a, h], [a, a, h], [-a, a, h]])
    tri = np.array([[sq[0], sq[2], sq[1]], [sq[0], sq[3], sq[2]]])     # normals facing down, to the point
    X = a / h
    corner = 0.5 * L * 2 * X / math.sqrt(1 + X * X) * math.atan(X / math.sqrt(1 + X * X))
    E = study.polygon_illuminance(np.zeros((1, 3)), np.array([[0, 0, 1.0]]), tri, L)
    assert E[0] == pytest.approx(4 * corner, rel=1e-9)


@pytest.mark.slow
def test_direct_step_is_the_true_spheres_closed_form_at_every_sensor(report):
    """Nothing hides the emitter from the wall: every sensor's direct light is
    π L (r/d)², to 1e-6 (emitters.py; before: 40 % at the worst sensor)."""
    assert report.results["direct"]["max_sensor_error"] <= study.DIRECT_BOUND == 1e-6


@pytest.mark.slow
def test_emitter_facets_give_the_ideal_sphere_within_1e4(report):
    em = report.results["emitter"]
    E0, _ = ideal(0.5)
    assert em["E0_facets_lux"] == pytest.approx(E0, rel=1e-4)


@pytest.mark.slow
def test_converged_bounces_within_two_percent_of_infinite_bounce_value(report):
    """ρ = 0.9, 46 bounces (truncation q^47 < 0.5 %): mean wall illuminance within 2 % of
    E_∞ = E_0 / (1 − q)."""
    E0, q = ideal(study.CONVERGED_RHO)
    N = study.CONVERGED_BOUNCES
    assert q ** (N + 1) < 0.005
    mean = runs_by_bounces(report, study.CONVERGED_RHO)[N]["mean"]
    assert mean == pytest.approx(E0 / (1 - q), rel=study.CONVERGED_BOUND)
    assert study.CONVERGED_BOUND == 0.02


@pytest.mark.slow
@pytest.mark.parametrize("k", [1, 2, 3])
def test_first_bounces_match_the_partial_sums(report, k):
    """Interreflected part after k bounces within 4 % of E_0 Σ_{j=1..k} q^j."""
    E0, q = ideal(study.CONVERGED_RHO)
    run = runs_by_bounces(report, study.CONVERGED_RHO)[k]
    exact = E0 * sum(q ** j for j in range(1, k + 1))
    assert run["indirect"] == pytest.approx(exact, rel=study.PER_BOUNCE_BOUND)
    assert study.PER_BOUNCE_BOUND == 0.04


@pytest.mark.slow
def test_ambient_equal_to_the_infinite_value_gives_it_after_few_bounces(report):
    setup = report.results["ambient_setup"]
    E0, q = ideal(setup["rho"])
    by_factor = {x["factor"]: x for x in report.results["ambient"]}
    assert by_factor[1.0]["mean"] == pytest.approx(E0 / (1 - q), rel=study.AMBIENT_BOUND)
    # without ambient the same run is short by the truncation q^(N+1)
    N = setup["bounces"]
    assert by_factor[0.0]["mean"] == pytest.approx(E0 * (1 - q ** (N + 1)) / (1 - q), rel=study.AMBIENT_BOUND)


@pytest.mark.slow
def test_every_diffuse_level_holds_its_remaining_bounces(report):
    """Level k of the 46-bounce run: mean record value within 5 % of
    E_0 Σ_{j=1..46−k} q^j (the direct light at the records' hits is exact), and nothing
    blows up at depth."""
    E0, q = ideal(study.CONVERGED_RHO)
    profile = report.results["ladders"][f"{study.CONVERGED_RHO:g}"]["profile"]
    assert len(profile) == study.CONVERGED_BOUNCES
    for level in profile:
        n = level["remaining"]
        exact = E0 * q * (1 - q ** n) / (1 - q)
        assert np.isfinite(level["mean"])
        assert abs(level["mean"] / exact - 1) <= level["bound"] == study.LEVEL_BOUND == 0.05, level


@pytest.mark.slow
def test_closed_box_reflectance_0999_fifty_bounces_matches_flux_balance(report):
    """ρ = 0.999, 50 bounces: the pure Monte Carlo wall mean within 2 % of the flux-balance
    partial sum, every value finite.  The reference itself: its first bounce needs only
    f_0, and its infinite limit lies within 0.1 % of the uniform-exitance balance
    Ē_0 / (1 − ρ (1 − A_e/A_w))."""
    box = report.results["box"]
    ref = box["reference"]
    rho = study.BOX_REFLECTANCE
    assert ref["infinite"] == pytest.approx(ref["E0"] / (1 - rho * (1 - ref["f_uniform"])), rel=1e-3)
    run = [x for x in box["runs"] if x["accuracy"] == 0.0 and x["bounces"] == 50][0]
    assert run["finite"] and run["min_sensor"] > 0
    assert run["mean"] == pytest.approx(run["exact"], rel=study.BOX_MC_BOUND)
    assert run["exact"] < ref["infinite"]


@pytest.mark.slow
def test_report_states_every_check_and_all_held(report, tmp_path):
    assert report.results["checks"] and all(c["held"] for c in report.results["checks"])
    folder = report.write(tmp_path / "integrating-sphere", {"quick": True})
    text = (folder / "report.md").read_text()
    assert "Bounds asserted by the test suite" in text and "| 0.02 |" in text
    assert (folder / "convergence.png").stat().st_size > 0

"""The glare study, quick version (validation/studies/glare.py, ``lbl-illum validate glare
--quick``): pixel solid angles, a source evaluated by hand, the bundled office against
evalglare (when installed) and E_v against the illuminance at the eye; about 12 s."""

import math

import pytest

from lbl_illum_studies import glare as study
from lbl_illum_studies.report import StudyContext

pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def report():
    if study.unavailable() is not None:
        pytest.skip(study.unavailable())
    return study.run(StudyContext(quick=True))


def test_every_bound_held(report):
    failed = [c for c in report.results["checks"] if not c["held"]]
    assert not failed, failed


def test_the_pixels_hold_the_hemisphere(report):
    for row in report.results["solid_angles"]:
        assert abs(row["all_omega_error"]) < 1e-9 and abs(row["all_projected_error"]) < 1e-9
        assert -0.01 < row["valid_projected_share"] <= 0.0


def test_dgp_against_evalglare_and_the_hand(report):
    for row in report.results["synthetic"]:
        assert row["ours"]["dgp"] == pytest.approx(row["hand"]["dgp"], abs=study.HAND_DGP_BOUND)
    if report.results["evalglare"] is None:
        pytest.skip("Radiance's evalglare is not installed (pip install pyradiance)")
    office = report.results["office"]
    assert len(office) == len(study.OFFICE)
    for row in office:
        assert abs(row["ours"]["dgp"] - row["evalglare"]["dgp"]) <= study.DGP_BOUND
        assert row["ours"]["sources"] == len(row["evalglare"]["sources"])


def test_ev_at_the_eye(report):
    for row in report.results["office"]:
        error = row.get("ev_error_without_sun", row["ev_error"])
        assert abs(error) <= study.EV_EYE_BOUND, row["name"]
    sun = [r for r in report.results["office"] if "sun in view" in r["name"]]
    assert sun and sun[0]["eye_direct"] > 0 and sun[0]["ev_sun"] > 0


def test_report_names_the_differences(report):
    md = report.markdown()
    assert "Where we differ from evalglare" in md and "2π" in md and "{" not in md.split("## Pixel")[1][:200]
    assert math.isfinite(report.results["office"][0]["eye_illuminance"])

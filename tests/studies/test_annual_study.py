"""The annual study, quick version (validation/studies/annual.py, ``lbl-illum validate
annual --quick``): the year through the cache's daylight coefficients against
point-in-time runs at an overcast hour, a sunny hour with the sun in the room and one with
the sun behind the building; hourly means within 3 %, the direct sun within 1 %."""

from __future__ import annotations

import json

import pytest

from lbl_illum_studies import run_study, unavailable
from lbl_illum_studies.report import StudyContext


@pytest.fixture(scope="module")
def report(tmp_path_factory):
    if unavailable("annual"):
        pytest.skip(unavailable("annual"))
    folder = run_study("annual", StudyContext(quick=True), tmp_path_factory.mktemp("reports"))
    return json.loads((folder / "results.json").read_text()), folder


def test_every_bound_holds(report):
    doc, _ = report
    checks = doc["results"]["checks"]
    assert len(checks) >= 4
    failed = [c for c in checks if not c["held"]]
    assert not failed, failed


def test_the_three_kinds_of_hour_are_there(report):
    doc, folder = report
    kinds = {r["kind"] for r in doc["results"]["hours"]}
    assert kinds == {"overcast", "sun in the room", "sun behind the building"}
    sunny = [r for r in doc["results"]["hours"] if r["kind"] == "sun in the room"][0]
    assert sunny["direct_mean"] > 1000.0
    assert (folder / "report.md").is_file() and (folder / "year.png").is_file()


def test_annual_glare_against_a_rendered_fisheye(report):
    doc, _ = report
    rows = doc["results"]["glare"]
    assert rows and all(0.0 < r["dgp"] <= 1.0 and 0.0 < r["image_dgp"] <= 1.0 for r in rows)

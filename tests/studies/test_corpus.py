"""The corpus study (validation/studies/corpus.py) and its scenes: the quick version runs
two presets on the deep room as whole commands against its committed reference (about
10 s); the scene files of every case load and match their references' points."""

import json

import numpy as np
import pytest

from lbl_illum import load_scene, read_points
from lbl_illum_studies import corpus, corpus_scenes
from lbl_illum_studies.report import StudyContext

pytestmark = pytest.mark.skipif(corpus.unavailable() is not None, reason=str(corpus.unavailable()))


@pytest.fixture(scope="module")
def quick():
    ctx = StudyContext(quick=True)
    return ctx, corpus.run(ctx)


def test_quick_study_runs_whole_commands_within_the_bias_target(quick):
    ctx, report = quick
    runs = report.results["runs"]
    assert [r["preset"] for r in runs] == list(corpus.QUICK_PRESETS)
    assert ctx.runs == ctx.planned
    for r in runs:
        assert abs(r["bias"]) <= corpus.BIAS_TARGET, r
        assert r["records"] > 0 and r["rays"] > 0
        assert r["seconds"] > r["compute_seconds"] > 0        # the whole command includes its start-up
    assert report.results["targets"]["bias_missed"] == []
    assert "Every preset on every case" in report.markdown()


@pytest.mark.parametrize("scene, sky", [(s, sky) for s, sky in corpus_scenes.cases() if s.name != "furnished-office"],
                         ids=lambda v: getattr(v, "name", v))
def test_every_case_loads_and_fits_its_reference(scene, sky):
    files, points = corpus_scenes.prepare(scene)
    loaded = load_scene(files[sky])
    P, N = read_points(points, loaded.unit_scale)
    assert len(P) > 20 and np.allclose(np.linalg.norm(N, axis=1), 1.0)
    path = corpus_scenes.reference_path(scene, sky)
    if path.is_file():
        ref = json.loads(path.read_text())
        assert len(ref["illuminance"]) == len(P)
        assert np.all(np.asarray(ref["illuminance"]) > 0)


def test_cases_without_a_reference_are_named_not_measured():
    row = {"scene": "office", "sky": "overcast", "role": "choose", "preset": "high", "seconds": 5.0,
           "compute_seconds": 2.0, "records": 10, "rays": 100, "points": 3, "bias": 0.002, "mean_error": 0.004,
           "max_error": 0.01, "reference_rse": 0.003}
    report = corpus._report([row], {}, ("high",), False, ["cabin-sunny"])
    text = report.markdown()
    assert "**Not measured** (no converged reference yet): cabin-sunny" in text
    assert report.results["targets"]["unmeasured"] == ["cabin-sunny"]
    assert report.results["targets"]["bias_missed"] == []


def test_seed_summary_means_the_seeds_and_states_the_spread():
    runs = [{"seconds": s, "compute_seconds": s - 1, "records": 10 * s, "rays": 100 * s, "bias": b,
             "mean": abs(b) + 0.01, "max": 0.05 + b} for s, b in ((2.0, 0.02), (4.0, -0.01), (6.0, 0.002))]
    got = corpus.seed_summary(runs)
    assert got["seeds"] == 3 and got["seconds"] == pytest.approx(4.0) and got["records"] == 40
    assert got["bias"] == pytest.approx(0.004, abs=1e-15)
    sd = np.sqrt(((0.016 ** 2) + (0.014 ** 2) + (0.002 ** 2)) / 2)          # sample standard deviation
    assert got["bias_spread"] == pytest.approx(sd, rel=1e-12)
    assert got["bias_standard_error"] == pytest.approx(sd / np.sqrt(3), rel=1e-12)
    assert got["max_error"] == pytest.approx(0.07) and got["mean_error"] == pytest.approx(0.01 + 0.032 / 3)
    one = corpus.seed_summary(runs[:1])
    assert one["bias"] == 0.02 and one["bias_spread"] == 0.0 and one["seeds"] == 1

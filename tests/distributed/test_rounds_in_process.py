"""Runs cut into rounds of chunks, in this process (``--workers 0``; no Dask needed): the
same bits every time, an interrupted run resumed from its cache file to the bits of an
uninterrupted one, and the integrator's split into solving and answering exact."""

from pathlib import Path

import numpy as np
import pytest

from lbl_illum.distributed.cluster import InProcess
from lbl_illum.distributed.plan import Decomposition
from lbl_illum.distributed.rounds import solve_points
from lbl_illum.distributed.worker import SceneRecipe
from lbl_illum.engine.integrator import Integrator
from lbl_illum.io.points import read_points
from lbl_illum.scene.scenefile import load_scene

OFFICE = Path(__file__).resolve().parents[2] / "examples" / "office"
PLAN = Decomposition(chunk=12, most=2)


def office_job(point_samples=0):
    """The office example at a small setting (cache from the sensors on: level 0 interpolates)."""
    scene = load_scene(OFFICE / "scene.toml")
    points, normals = read_points(OFFICE / "grid.pts", scene.unit_scale)
    options = scene.options.with_preset("draft").replace(bounces=2, samples=32, accuracy=0.2)
    if point_samples == 0:
        import dataclasses
        options = dataclasses.replace(options, point_samples=None)
    else:
        options = options.replace(point_samples=point_samples)
    return scene, points[:48], normals[:48], options, SceneRecipe(str((OFFICE / "scene.toml").resolve()))


def in_process(scene, options, recipe, points, normals, plan=PLAN, **kw):
    integ = Integrator(scene, options)
    cluster = InProcess()
    cluster.prepare(recipe, options, integ.fingerprint, scene, integ.context)
    return solve_points(cluster, recipe, integ, points, normals, plan=plan, **kw)


def test_in_process_rounds_repeat_bit_for_bit():
    scene, P, N, options, recipe = office_job()
    a, costs, _ = in_process(scene, options, recipe, P, N)
    b, _, _ = in_process(scene, options, recipe, P, N)
    assert np.array_equal(a.rgb, b.rgb) and a.stats.records == b.stats.records
    assert [c.chunks for c in costs.rounds] == [1, 2, 1]          # 4 chunks of 12: rounds of 1, 2, 1
    assert a.stats.records[0] > 0 and np.all(a.illuminance > 0)


def test_point_samples_rounds_repeat_bit_for_bit():
    scene, P, N, options, recipe = office_job(point_samples=64)
    a, _, _ = in_process(scene, options, recipe, P, N)
    b, _, _ = in_process(scene, options, recipe, P, N)
    assert np.array_equal(a.rgb, b.rgb) and a.stats.records[0] == len(P)     # each sensor its own record


class _StopAt:
    """A progress display that presses Ctrl-C when round ``n`` begins."""

    def __init__(self, n):
        self.n = n

    def describe(self, text):
        if text.startswith(f"round {self.n} "):
            raise KeyboardInterrupt

    def update(self, rays):
        pass


def test_interrupted_run_keeps_merged_rounds_and_resumes_to_the_same_bits(tmp_path):
    scene, P, N, options, recipe = office_job()
    whole, _, _ = in_process(scene, options, recipe, P, N)
    cache = tmp_path / "run.cache"
    with pytest.raises(KeyboardInterrupt) as info:
        in_process(scene, options, recipe, P, N, cache_file=cache, progress=_StopAt(3))
    assert info.value.saved_cache == str(cache) and sum(info.value.saved_records) > 0
    assert cache.is_file()
    resumed, costs, _ = in_process(scene, options, recipe, P, N, cache_file=cache)
    assert costs.rounds[0].new == 0 and costs.rounds[1].new == 0       # the finished rounds add nothing
    assert np.array_equal(resumed.rgb, whole.rgb)


def test_solving_then_answering_is_compute():
    """compute(solve_only=True) then answer() gives compute()'s bits (one run, one stream)."""
    scene, P, N, options, _ = office_job()
    whole = Integrator(scene, options).compute(P, N)
    split = Integrator(scene, options)
    solved = split.compute(P, N, solve_only=True)
    direct, indirect = split.answer(P, N)
    assert np.all(solved.direct == 0.0) and np.all(solved.indirect == 0.0)
    assert np.array_equal(direct, whole.direct) and np.array_equal(indirect, whole.indirect)


def test_a_year_by_rounds_has_the_ordinary_direct_sun_and_close_light():
    """The direct sun by sensor chunks x hour batches is the ordinary run's, bit for bit (no
    random numbers); the year's light by rounds is within 1 % of it on the mean."""
    from lbl_illum.daylight.weather import read_weather
    from lbl_illum.distributed.annual import annual_solver
    from lbl_illum.engine.annual import annual_light

    scene, P, N, options, recipe = office_job(point_samples=32)
    weather = read_weather(OFFICE.parent / "weather" / "USA_CA_Oakland.Intl.AP.724930_TMY3.epw")
    ordinary = annual_light(scene, P, N, weather, options)
    rounds = annual_light(scene, P, N, weather, options, solve=annual_solver(InProcess(), recipe.path, PLAN))
    assert np.array_equal(rounds.direct_sun, ordinary.direct_sun)
    assert abs(rounds.illuminance.mean() / ordinary.illuminance.mean() - 1) < 0.01

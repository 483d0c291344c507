"""Cache files: reuse gives identical results without new primary evaluations; wrong caches are refused."""

import numpy as np
import pytest

from lbl_illum import InputError, IrradianceCache, Options, load_scene, read_points
from lbl_illum.integrator import Integrator

from conftest import EXAMPLES


@pytest.fixture(scope="module")
def office():
    scene = load_scene(EXAMPLES / "office" / "scene.toml")
    points, normals = read_points(EXAMPLES / "office" / "grid.pts", scene.unit_scale)
    return scene, points[::4], normals[::4]


OPTS = Options(accuracy=0.2, bounces=2, samples=128)


@pytest.mark.parametrize("opts", [OPTS, OPTS.replace(interpolation="hessian")], ids=["round", "elliptical"])
def test_second_run_from_file_is_identical_and_computes_no_record(office, tmp_path, opts):
    scene, points, normals = office
    first = Integrator(scene, opts)
    r1 = first.compute(points, normals)
    assert r1.stats.primary_evaluations > 0
    path = tmp_path / "office.lblcache"
    first.cache.save(path)
    second = Integrator(scene, opts)
    second.cache = IrradianceCache.load(path, second.fingerprint)
    assert second.cache.record_counts == first.cache.record_counts
    r2 = second.compute(points, normals)
    assert r2.stats.primary_evaluations == 0
    assert np.array_equal(r1.illuminance, r2.illuminance)
    assert r2.stats.rays < r1.stats.rays / 5
    if opts.interpolation == "hessian":      # the domains' shapes and leak sectors came back
        for a, b in zip(first.cache.levels, second.cache.levels):
            n = a.count
            assert b.anisotropic and np.array_equal(a.W[:n], b.W[:n]) and np.array_equal(a.leak[:n], b.leak[:n])
        assert any(lv.leak[:lv.count].any() for lv in second.cache.levels)


def test_cache_of_other_settings_or_scene_is_refused(office, tmp_path):
    scene, points, normals = office
    integ = Integrator(scene, OPTS)
    integ.compute(points[:2], normals[:2])
    path = tmp_path / "c.lblcache"
    integ.cache.save(path)
    other = Integrator(scene, OPTS.replace(bounces=3))
    with pytest.raises(InputError, match="another scene or other settings"):
        IrradianceCache.load(path, other.fingerprint)


def test_damaged_cache_is_refused(office, tmp_path):
    scene, points, normals = office
    integ = Integrator(scene, OPTS)
    integ.compute(points[:2], normals[:2])
    path = tmp_path / "c.lblcache"
    integ.cache.save(path)
    data = bytearray(path.read_bytes())
    path.write_bytes(bytes(data[: len(data) // 2]))
    with pytest.raises(InputError, match="c.lblcache"):
        IrradianceCache.load(path, integ.fingerprint)

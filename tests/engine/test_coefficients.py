"""Daylight coefficients carried by the cache's records (lbl_illum.engine.coefficients):
the same calculation as the irradiance, linear in the sky and the sun.

The checks are exact where the coefficients and a point-in-time run make the same
calculation: under a uniform sky (constant over every patch) with the paper's
interpolation (no gradient terms), D · L must equal the run's indirect illuminance at
each sensor to float32 round-off; with the sun at a sun position and every hit traced,
the sun's coefficient must equal the run's interreflected sun within the sampling of
the sun's disk.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from lbl_illum.daylight.sky import NoSky, UniformSky
from lbl_illum.daylight.skymatrix import sky_patches
from lbl_illum.daylight.sun import Sun
from lbl_illum.engine import coefficients
from lbl_illum.engine.coefficients import CoefficientRecords, grey_scene
from lbl_illum.engine.integrator import Integrator
from lbl_illum.options import Options
from lbl_illum.photometry import luminance

from conftest import EXAMPLES

#: Small but complete: point samples at the sensors, three cached levels, portals.
OPTIONS = Options(accuracy=0.15, samples=32, bounces=3, point_samples=256, interpolation="paper")


def _run(scene, points, normals, options=OPTIONS, suns=None):
    integ = Integrator(scene, options)
    dc = CoefficientRecords(integ, 1, suns)
    result = integ.compute(points, normals)
    vectors = dc.at_points(points, normals, np.arange(len(points)))
    return result, dc, vectors


def _copy(folder, text, tmp_path):
    """The scene file ``text`` written beside a copy of ``folder``'s other files."""
    import shutil

    for f in folder.iterdir():
        if f.is_file():
            shutil.copy(f, tmp_path / f.name)
    (tmp_path / "scene.toml").write_text(text)
    return tmp_path / "scene.toml"


def _uniform(scene, ground_reflectance=0.2):
    return dataclasses.replace(scene, sky=UniformSky(horizontal_illuminance=10000.0,
                                                     ground_reflectance=ground_reflectance), sun=None)


def test_uniform_sky_through_the_coefficients_is_the_run_itself(office_quarter):
    scene, points, normals = office_quarter
    scene = _uniform(scene)
    plain = Integrator(scene, OPTIONS).compute(points, normals)
    result, dc, vectors = _run(scene, points, normals)
    # carrying the coefficients changes nothing of the irradiance
    np.testing.assert_array_equal(result.rgb, plain.rgb)
    L = np.full(len(sky_patches(1)), 10000.0 / np.pi)
    L[0] = 0.2 * 10000.0 / np.pi
    E = dc.photometric(vectors) @ L
    np.testing.assert_allclose(E, luminance(plain.indirect), rtol=2e-5)
    assert dc.grey and dc.channels == 1


def test_coloured_surfaces_keep_three_channels(office_quarter, tmp_path):
    from lbl_illum import load_scene

    _, points, normals = office_quarter
    office = EXAMPLES / "office"
    text = (office / "scene.toml").read_text().replace("reflectance = 0.5", "reflectance = [0.6, 0.5, 0.3]", 1)
    scene = _uniform(load_scene(_copy(office, text, tmp_path)))
    result, dc, vectors = _run(scene, points, normals)
    assert not dc.grey and dc.channels == 3
    L = np.full(len(sky_patches(1)), 10000.0 / np.pi)
    L[0] = 0.2 * 10000.0 / np.pi
    per_channel = vectors @ L                                         # (n, 3) lux
    np.testing.assert_allclose(per_channel, result.indirect, rtol=2e-5)


def test_grey_scene(office_quarter):
    scene, *_ = office_quarter
    integ = Integrator(scene, OPTIONS)
    assert grey_scene(integ.context)


@pytest.fixture
def exact_sun(monkeypatch):
    """Every hit traced towards every sun (no systematic sampling of the hits)."""
    monkeypatch.setattr(coefficients, "SUN_HITS", 0)
    monkeypatch.setattr(coefficients, "DEEP_SUN_HITS", 0)
    monkeypatch.setattr(coefficients, "SENSOR_SUN_BUDGET", 10**9)


def test_sun_coefficient_is_the_interreflected_sun(office_quarter, exact_sun):
    scene, points, normals = office_quarter
    sun = Sun(altitude=35.0, azimuth=160.0, direct_normal_illuminance=50000.0)
    scene = dataclasses.replace(scene, sky=NoSky(horizontal_illuminance=0.0, ground_reflectance=0.2), sun=sun)
    plain = Integrator(scene, OPTIONS).compute(points, normals)
    result, dc, vectors = _run(scene, points, normals, suns=sun.direction[None])
    E = dc.photometric(vectors)[:, -1] * sun.direct_normal_illuminance
    ref = luminance(plain.indirect)
    assert ref.min() > 100.0
    # the run samples the sun's disk (jittered shadow rays), the coefficient its centre
    rel = E / ref - 1.0
    assert abs(rel.mean()) < 0.01
    assert np.abs(rel).max() < 0.04


def test_sampled_hits_keep_the_sun_unbiased(office_quarter, exact_sun, monkeypatch):
    """Below the sensors, SUN_HITS (DEEP_SUN_HITS below level 2) of each record's hits
    traced towards the sun, weighted by their inverse chance: over three seeds the mean
    agrees with every hit traced."""
    scene, points, normals = office_quarter
    sun = Sun(altitude=35.0, azimuth=160.0, direct_normal_illuminance=50000.0)
    scene = dataclasses.replace(scene, sky=NoSky(horizontal_illuminance=0.0, ground_reflectance=0.2), sun=sun)
    exact, sampled = [], []
    for seed in range(3):
        options = dataclasses.replace(OPTIONS, seed=seed)
        monkeypatch.setattr(coefficients, "SUN_HITS", 0)
        monkeypatch.setattr(coefficients, "DEEP_SUN_HITS", 0)
        exact.append(_run(scene, points, normals, options, sun.direction[None])[2][:, 0, -1])
        monkeypatch.setattr(coefficients, "SUN_HITS", 8)
        monkeypatch.setattr(coefficients, "DEEP_SUN_HITS", 4)
        sampled.append(_run(scene, points, normals, options, sun.direction[None])[2][:, 0, -1])
    exact, sampled = np.array(exact), np.array(sampled)
    assert sampled.mean() == pytest.approx(exact.mean(), rel=0.02)
    assert np.abs(sampled / exact - 1.0).max() < 0.15


def test_portal_filter_changes_no_sun(office_quarter):
    """The shadow rays of the inside limited to the portals' directions give what every
    ray gives: sun_at with the filter equals sun_at with every point treated as outside."""
    scene, points, normals = office_quarter
    integ = Integrator(scene, OPTIONS)
    patches = sky_patches(1)
    suns = patches.directions[1:][patches.directions[1:, 2] > 0.1][::3]
    dc = CoefficientRecords(integ, 1, suns)
    rng = np.random.default_rng(3)
    # points on the floor, the walls' inner faces and the ground outside (by the window and beside the room)
    P = np.vstack([np.column_stack([rng.uniform(0.1, 3.9, 300), rng.uniform(0.1, 5.9, 300), np.zeros(300)]),
                   np.column_stack([np.full(100, 4.0), rng.uniform(0.1, 5.9, 100), rng.uniform(0.1, 2.9, 100)]),
                   np.column_stack([rng.uniform(-3, 7, 200), rng.uniform(-3, 9, 200), np.zeros(200)])])
    N = np.vstack([np.tile([0, 0, 1.0], (300, 1)), np.tile([-1.0, 0, 0], (100, 1)), np.tile([0, 0, 1.0], (200, 1))])
    outside = (P[:, 0] < 0) | (P[:, 0] > 4) | (P[:, 1] < 0) | (P[:, 1] > 6)
    origins = integ.tracer.offset(P, N)
    filtered = dc.sun_at(P, N, origins)
    everything = dc.sun_at(P, N, origins, inside=np.zeros(len(P), bool))
    np.testing.assert_array_equal(filtered, everything)
    assert (filtered[:300] > 0).any() and (filtered[outside] > 0).any()


def test_lookup_weights_interpolate_like_the_lookup(office_quarter):
    scene, points, normals = office_quarter
    integ = Integrator(scene, OPTIONS)
    integ.compute(points, normals)
    lv = integ.cache.levels[1]
    rng = np.random.default_rng(0)
    n = lv.count
    P = lv.P[:n] + rng.normal(scale=0.05, size=(n, 3)) * (np.abs(lv.N[:n]) < 0.5)
    E, _, count = lv.lookup(P, lv.N[:n], zone=integ.context.zone(P))
    record, weight = lv.lookup_weights(P, lv.N[:n], zone=integ.context.zone(P))
    assert ((record >= 0).sum(axis=1) == np.minimum(count, coefficients.PAIRS)).all()
    E2 = (np.where(record[..., None] >= 0, lv.E[np.maximum(record, 0)], 0.0) * weight[..., None]).sum(axis=1)
    full = count <= coefficients.PAIRS
    np.testing.assert_allclose(E2[full], E[full], rtol=1e-5)


def test_hessian_domains_carry_the_coefficients(office_quarter):
    """With elliptical (Hessian) record domains the coefficients are interpolated over the
    same domains: under a uniform sky within 1.5 % of the run at every sensor (1.1 % at
    most, measured), the run's reflections reading the records with their gradients."""
    scene, points, normals = office_quarter
    scene = _uniform(scene)
    options = dataclasses.replace(OPTIONS, interpolation="hessian")
    result, dc, vectors = _run(scene, points, normals, options)
    L = np.full(len(sky_patches(1)), 10000.0 / np.pi)
    L[0] = 0.2 * 10000.0 / np.pi
    E = dc.photometric(vectors) @ L
    np.testing.assert_allclose(E, luminance(result.indirect), rtol=0.015)

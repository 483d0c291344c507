"""The irradiance cache end to end: the paper's §4 scene, level bookkeeping, order independence."""

import numpy as np
import pytest

from lbl_illum import Options, compute_illuminance, load_scene, read_points
from lbl_illum.integrator import Integrator

from conftest import EXAMPLES, GROUND, make_scene

SPHERE = EXAMPLES / "sphere_on_plane"


@pytest.fixture(scope="module")
def sphere_scene():
    scene = load_scene(SPHERE / "scene.toml")
    points, normals = read_points(SPHERE / "points.pts", scene.unit_scale)
    return scene, points, normals


def upper_half_reference(normals, E0=1000.0, rho=0.7):
    """§4, upper half: E = E0 sin γ + ρ E0 (1 − sin γ)/2 (direct + first bounce)."""
    s = normals[:, 2]
    return E0 * s + rho * E0 * (1.0 - s) / 2.0


def test_sphere_on_plane_upper_half_within_three_percent(sphere_scene):
    scene, points, normals = sphere_scene
    result = compute_illuminance(scene, points, normals, Options(accuracy=0.1, bounces=1))
    up = normals[:, 2] >= 0.0
    ref = upper_half_reference(normals[up])
    err = np.abs(result.illuminance[up] / ref - 1.0)
    assert err.max() < 0.03, err.max()
    # with no sky and no ambient the bounce limit is dark: no level-1 records at all
    assert result.stats.records[1] == 0


def test_pure_monte_carlo_makes_a_record_per_query(sphere_scene):
    scene, points, normals = sphere_scene
    result = compute_illuminance(scene, points[:20], normals[:20], Options(accuracy=0, bounces=1, samples=256))
    assert result.stats.new_records[0] == 20


def test_result_does_not_depend_on_query_order(sphere_scene):
    scene, points, normals = sphere_scene
    opts = Options(accuracy=0.2, bounces=1, samples=256)
    a = compute_illuminance(scene, points, normals, opts)
    # the same records answer every query: a second, permuted lookup against the same
    # cache gives the same values point for point
    integ = Integrator(scene, opts, cache=None)
    first = integ.compute(points, normals)
    perm = np.random.default_rng(0).permutation(len(points))
    again = integ.compute(points[perm], normals[perm])
    assert again.stats.primary_evaluations == 0
    assert np.allclose(again.indirect, first.indirect[perm], rtol=0, atol=0)
    assert np.allclose(a.illuminance, first.illuminance, rtol=0, atol=0)


def test_same_seed_same_result_other_seed_other_noise(sphere_scene):
    scene, points, normals = sphere_scene
    opts = Options(accuracy=0.1, bounces=1, samples=128, seed=3)
    a = compute_illuminance(scene, points, normals, opts).illuminance
    b = compute_illuminance(scene, points, normals, opts).illuminance
    c = compute_illuminance(scene, points, normals, opts.replace(seed=4)).illuminance
    assert np.array_equal(a, b)
    assert not np.array_equal(a, c)


def closed_box(reflectance, size=2.0):
    mats = {"wall": {"type": "diffuse", "reflectance": reflectance},
            "lamp": {"type": "light", "luminance": 1000.0}}
    geo = [{"shape": "box", "center": [0, 0, size / 2], "size": [size, size, size], "material": "wall"},
           {"shape": "rectangle", "origin": [-0.1, -0.1, size - 0.01], "u": [0.2, 0, 0], "v": [0, 0.2, 0],
            "material": "lamp"}]
    return make_scene(geo, mats)


def test_black_room_has_no_indirect_light_and_no_deeper_records():
    scene = closed_box(0.0)
    pts = np.array([[0.0, 0.0, 1.0], [0.5, 0.5, 0.5]])
    nrm = np.array([[0, 0, 1.0], [0, 0, 1.0]])
    result = compute_illuminance(scene, pts, nrm, Options(bounces=3, samples=64))
    assert np.all(result.indirect == 0.0)
    assert result.stats.records[1:] == [0, 0, 0]


def test_no_light_at_all_computes_nothing_indirect():
    scene = make_scene([GROUND], {"ground": {"type": "diffuse", "reflectance": 0.5}})
    result = compute_illuminance(scene, np.zeros((3, 3)), np.tile([0, 0, 1.0], (3, 1)), Options(bounces=4))
    assert np.all(result.illuminance == 0.0)
    assert sum(result.stats.records) == 0


def test_more_bounces_add_light_and_converge_in_a_closed_box():
    """Light-box: each bounce adds less; the series is bounded (ρ = 0.5)."""
    scene = closed_box(0.5)
    pts = np.array([[0.0, 0.0, 1.0]])
    nrm = np.array([[0, 0, 1.0]])
    E = [compute_illuminance(scene, pts, nrm, Options(bounces=b, samples=256)).indirect[0, 0] for b in (1, 2, 6)]
    assert 0 < E[0] < E[1] < E[2]
    assert E[2] - E[1] < E[1] - E[0]


def test_same_room_in_millimetres_and_kilometres_gives_the_same_illuminance():
    """Units are converted on reading; the engine's offsets scale with the geometry."""
    def room(factor, units):
        geo = [{"shape": "box", "center": [0, 0, 1.5 * factor], "size": [4 * factor, 6 * factor, 3 * factor],
                "material": "wall"},
               {"shape": "rectangle", "origin": [-2 * factor, -1 * factor, 2.999 * factor],
                "u": [4 * factor, 0, 0], "v": [0, 2 * factor, 0], "material": "sky-light"}]
        mats = {"wall": {"type": "diffuse", "reflectance": 0.5}, "sky-light": {"type": "light", "luminance": 500}}
        return make_scene(geo, mats, units=units)
    pts = np.array([[0.0, 0.0, 0.8], [1.5, 2.5, 0.8]])
    nrm = np.array([[0, 0, 1.0], [0, 0, 1.0]])
    opts = Options(bounces=2, samples=128)
    E_mm = compute_illuminance(room(1000.0, "mm"), pts, nrm, opts).illuminance
    E_km = compute_illuminance(room(0.001, "km"), pts, nrm, opts).illuminance
    assert np.allclose(E_mm, E_km, rtol=1e-6)


def test_records_and_results_do_not_depend_on_the_order_of_the_points():
    """A shuffled sensor file makes the same records and the same value at every point."""
    scene = load_scene(EXAMPLES / "office" / "scene.toml")
    points, normals = read_points(EXAMPLES / "office" / "grid.pts", scene.unit_scale)
    opts = Options(accuracy=0.2, bounces=2, samples=64)
    a = compute_illuminance(scene, points, normals, opts)
    perm = np.random.default_rng(5).permutation(len(points))
    b = compute_illuminance(scene, points[perm], normals[perm], opts)
    assert a.stats.records == b.stats.records
    assert np.allclose(b.illuminance, a.illuminance[perm], rtol=1e-9)


def test_bounce_scaling_of_accuracy_is_capped_at_twice_the_first_level():
    opts = Options(accuracy=0.1)
    a = [opts.level_accuracy(k) for k in range(12)]
    assert a[0] == 0.1 and a[1] == pytest.approx(0.14) and a[2] == pytest.approx(0.196)
    assert max(a) == pytest.approx(0.2) and a[-1] == pytest.approx(0.2)
    assert Options(accuracy=0.1, bounce_scaling=False).level_accuracy(7) == 0.1


def test_point_samples_evaluate_every_point_and_start_the_cache_one_level_down():
    opts = Options(accuracy=0.1, samples=512, point_samples=4096)
    assert opts.level_accuracy(0) == 0.0 and opts.level_samples(0) == 4096
    assert opts.level_accuracy(1) == 0.1 and opts.level_samples(1) == 512
    assert opts.level_accuracy(2) == pytest.approx(0.14) and opts.level_samples(2) == 256
    scene = closed_box(0.5)
    pts = np.array([[0.0, 0.0, 1.0], [0.01, 0.0, 1.0]])       # close enough to share a record
    nrm = np.array([[0, 0, 1.0], [0, 0, 1.0]])
    shared = compute_illuminance(scene, pts, nrm, Options(bounces=2, samples=256))
    own = compute_illuminance(scene, pts, nrm, Options(bounces=2, samples=256, point_samples=256))
    assert shared.stats.new_records[0] == 1 and own.stats.new_records[0] == 2
    assert np.all(np.isfinite(own.illuminance)) and np.all(own.indirect > 0)

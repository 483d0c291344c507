"""The irradiance cache end to end: the paper's §4 scene, level bookkeeping, order independence."""

import math

import numpy as np
import pytest

from lbl_illum import Options, compute_illuminance, load_scene, read_points
from lbl_illum.engine.integrator import Integrator

from conftest import DOWN, EXAMPLES, GROUND, PLASTIC_FLOOR, UNIFORM_SKY, make_scene, plastic_floor_reference

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


@pytest.mark.parametrize("interpolation", ["gradients", "hessian"])
def test_sphere_on_plane_upper_half_within_three_percent(sphere_scene, interpolation):
    scene, points, normals = sphere_scene
    result = compute_illuminance(scene, points, normals, Options(accuracy=0.1, bounces=1, interpolation=interpolation))
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
    # nothing can be lit, so not even the spacing probe is traced
    assert result.stats.rays == 0


def test_rays_count_this_run_only_and_a_covered_rerun_traces_none():
    """A second compute on the same Integrator reports its own rays, not the total;
    with the spacing limits given, all queries covered and no sun or light surface,
    it traces nothing at all."""
    scene = make_scene([GROUND], {"ground": {"type": "diffuse", "reflectance": 0.5}},
                       sky={"type": "uniform", "horizontal_illuminance": 1000.0})
    points, normals = np.zeros((4, 3)), np.tile([0, 0, 1.0], (4, 1))
    points[:, 0] = np.linspace(-1.0, 1.0, 4)
    integ = Integrator(scene, Options(bounces=1, samples=64, min_spacing=0.5, max_spacing=4.0))
    first = integ.compute(points, normals)
    again = integ.compute(points, normals)
    assert first.stats.rays > 0
    assert again.stats.primary_evaluations == 0
    assert again.stats.rays == 0


def test_more_bounces_add_light_and_converge_in_a_closed_box():
    """Light-box: each bounce adds less; the series is bounded (ρ = 0.5)."""
    scene = closed_box(0.5)
    pts = np.array([[0.0, 0.0, 1.0]])
    nrm = np.array([[0, 0, 1.0]])
    E = [compute_illuminance(scene, pts, nrm, Options(bounces=b, samples=256)).indirect[0, 0] for b in (1, 2, 6)]
    assert 0 < E[0] < E[1] < E[2]
    assert E[2] - E[1] < E[1] - E[0]


def test_path_roulette_keeps_the_light_of_deep_bounces_and_cuts_their_rays(monkeypatch):
    """Pure Monte Carlo in a closed box of ρ = 0.5 over 10 bounces, where the paths'
    throughput falls below the limit from the fourth bounce on: the Russian roulette of weak one-ray paths
    (integrator._path_roulette) gives, per point, the illuminance of the same estimator
    without it (limit 0) within 4 standard errors of the difference (8 seeds each), with
    fewer rays."""
    from lbl_illum.engine import integrator

    scene = closed_box(0.5)
    pts = np.array([[0.0, 0.0, 0.3], [0.6, -0.5, 1.0], [-0.7, 0.4, 1.6]])
    nrm = np.array([[0, 0, 1.0], [1.0, 0, 0], [0, 0, -1.0]])

    def runs(limit):
        monkeypatch.setattr(integrator, "PATH_ROULETTE_LIMIT", limit)
        out = [compute_illuminance(scene, pts, nrm, Options(accuracy=0.0, samples=4, point_samples=128, bounces=10,
                                                            seed=seed)) for seed in range(8)]
        return np.array([r.indirect[:, 0] for r in out]), sum(r.stats.rays for r in out)

    with_roulette, rays = runs(0.1)
    without, rays_without = runs(0.0)
    diff = with_roulette.mean(axis=0) - without.mean(axis=0)
    err = np.sqrt(with_roulette.var(axis=0, ddof=1) / 8 + without.var(axis=0, ddof=1) / 8)
    assert np.all(np.abs(diff) < 4 * err), (diff, err)
    assert rays < 0.8 * rays_without


def test_paths_trapped_among_specular_plastic_do_not_multiply():
    """Inside a closed box of plastic with a specular part of 0.95, every hit is both a
    diffuse hit (a one-ray path below the first level) and a continuation (up to 9 hits a
    ray): without the roulette of weak paths each level would hold about 9 times the
    records of the one above.  With it the deep levels hold fewer than the second."""
    mats = {"wall": {"type": "plastic", "reflectance": 0.6, "specularity": 0.95, "roughness": 0.0},
            "lamp": {"type": "light", "luminance": 1000.0}}
    geo = [{"shape": "box", "center": [0, 0, 1.0], "size": [2.0, 2.0, 2.0], "material": "wall"},
           {"shape": "rectangle", "origin": [-0.1, -0.1, 1.99], "u": [0.2, 0, 0], "v": [0, 0.2, 0], "material": "lamp"}]
    scene = make_scene(geo, mats)
    result = compute_illuminance(scene, np.array([[0.0, 0.0, 0.5]]), np.array([[0, 0, 1.0]]),
                                 Options(accuracy=0.0, samples=4, point_samples=64, bounces=8, seed=3))
    records = result.stats.records
    assert max(records[3:]) < records[2], records
    assert np.isfinite(result.illuminance).all() and result.indirect[0, 0] > 0


@pytest.mark.parametrize("interpolation", ["gradients", "hessian"])
def test_same_room_in_millimetres_and_kilometres_gives_the_same_illuminance(interpolation):
    """Units are converted on reading; the engine's offsets (and the Hessian's record
    domains) scale with the geometry."""
    def room(factor, units):
        geo = [{"shape": "box", "center": [0, 0, 1.5 * factor], "size": [4 * factor, 6 * factor, 3 * factor],
                "material": "wall"},
               {"shape": "rectangle", "origin": [-2 * factor, -1 * factor, 2.999 * factor],
                "u": [4 * factor, 0, 0], "v": [0, 2 * factor, 0], "material": "sky-light"}]
        mats = {"wall": {"type": "diffuse", "reflectance": 0.5}, "sky-light": {"type": "light", "luminance": 500}}
        return make_scene(geo, mats, units=units)
    pts = np.array([[0.0, 0.0, 0.8], [1.5, 2.5, 0.8]])
    nrm = np.array([[0, 0, 1.0], [0, 0, 1.0]])
    opts = Options(bounces=2, samples=128, interpolation=interpolation)
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
    # growth stops at 0.4; a larger a given by the user is kept as it is
    assert [Options(accuracy=0.3).level_accuracy(k) for k in (0, 1, 5)] == [0.3, 0.4, 0.4]
    assert Options(accuracy=0.5).level_accuracy(3) == 0.5


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


def test_sensors_in_corners_and_on_edges_of_a_closed_room_see_no_daylight():
    """A closed room under sun and sky is dark inside: E = 0 exactly, also for sensors
    in its corners and on its edges (their ray origins once lay in the plane of the
    adjacent wall, and rays slipped out through the edge)."""
    scene = make_scene([{"shape": "box", "center": [2, 3, 1.5], "size": [4, 6, 3], "material": "wall"}],
                       {"wall": {"type": "diffuse", "reflectance": 0.7}},
                       sky={"type": "uniform", "horizontal_illuminance": 10000.0},
                       sun={"altitude": 30, "azimuth": 200, "direct_normal_illuminance": 50000.0})
    P = np.array([[0, 0, 0], [0, 0, 0], [0, 0, 0], [4, 6, 3], [2, 0, 0], [0, 3, 3], [4, 0, 1.5]], float)
    N = np.array([[0, 0, 1], [1, 0, 0], [1, 1, 1], [-1, -1, -1], [0, 1, 1], [1, 0, 0], [-1, 1, 0]], float)
    result = compute_illuminance(scene, P, N, Options(accuracy=0, bounces=1, samples=256))
    assert np.all(result.illuminance == 0.0)


def test_sensor_one_millimetre_from_a_large_wall_sees_the_wall():
    """ε is 3 mm beside a 200 m wall: a sensor 1 mm in front of it, facing it, must see
    the wall's luminance ρ E_wall / π over its whole hemisphere, not the sky behind.
    E_wall = E_dn cos i + E_h / 2 + ρ_g E_gh / 2 (sun, half the uniform sky, half the
    ground glow), so E = ρ E_wall up to the sliver of sky past the wall's edges."""
    scene = make_scene([{"shape": "rectangle", "origin": [-100, 0, 0], "u": [200, 0, 0], "v": [0, 0, 100],
                         "material": "wall"}], {"wall": {"type": "diffuse", "reflectance": 0.5}},
                       sky={"type": "uniform", "horizontal_illuminance": 10000.0, "ground_reflectance": 0.2},
                       sun={"altitude": 30, "azimuth": 180, "direct_normal_illuminance": 50000.0})
    E_gh = 10000.0 + 50000.0 * np.sin(np.radians(30))
    E_wall = 50000.0 * np.cos(np.radians(30)) + 10000.0 / 2 + 0.2 * E_gh / 2
    result = compute_illuminance(scene, np.array([[0.0, -1e-3, 50.0]]), np.array([[0.0, 1.0, 0.0]]),
                                 Options(bounces=1, samples=256))
    assert result.illuminance[0] == pytest.approx(0.5 * E_wall, rel=2e-3)


def test_records_traced_in_blocks_give_the_same_records_and_comparable_values(sphere_scene, monkeypatch):
    """Large passes are traced in blocks of at most MAX_BATCH_RAYS rays (bounding the
    temporary memory).  Where the records go does not depend on it; their values differ
    only by Monte Carlo noise (other random streams per block), and a rerun with the same
    blocks is identical."""
    import lbl_illum.engine.integrator as integrator

    scene, points, normals = sphere_scene
    opts = Options(accuracy=0.1, bounces=1, samples=256)
    whole = compute_illuminance(scene, points, normals, opts)
    monkeypatch.setattr(integrator, "MAX_BATCH_RAYS", 1000)     # 3 records a block
    blocks = compute_illuminance(scene, points, normals, opts)
    again = compute_illuminance(scene, points, normals, opts)
    assert blocks.stats.records == whole.stats.records
    assert np.array_equal(blocks.illuminance, again.illuminance)
    up = normals[:, 2] >= 0.0
    ref = upper_half_reference(normals[up])
    for run in (whole, blocks):
        assert np.abs(run.illuminance[up] / ref - 1.0).mean() < 0.01


def test_light_seen_in_a_mirror_counts_at_the_bounce_limit_without_a_sky():
    """A 1 m square light 1 m above a sensor's height, beside a mirror (ρ = 0.9) that the
    sensor faces; no sky, bounces = 0.  The light's mirror image gives
    E = ρ L ∫ cos θ_r cos θ_l / d² dA, integrated here by the midpoint rule."""
    light = {"shape": "polygon", "material": "lamp",
             "vertices": [[-0.5, -0.5, 2], [0.5, -0.5, 2], [0.5, 0.5, 2], [-0.5, 0.5, 2]]}
    mirror = {"shape": "polygon", "material": "mirror",
              "vertices": [[1, -5, -5], [1, 5, -5], [1, 5, 5], [1, -5, 5]]}
    scene = make_scene([light, mirror], {"lamp": {"type": "light", "luminance": 1000.0},
                                         "mirror": {"type": "mirror", "reflectance": 0.9}},
                       sky={"type": "none"}, settings={"bounces": 0, "samples": 16384})
    P, N = np.array([[0.5, 0.0, 1.0]]), np.array([[1.0, 0.0, 0.0]])
    n = 400
    c = (np.arange(n) + 0.5) / n - 0.5
    X, Y = np.meshgrid(2.0 + c, c)                       # the image lies at 1.5 < x < 2.5
    dx, dy, dz = X - 0.5, Y, 1.0
    d2 = dx * dx + dy * dy + dz * dz
    exact = 0.9 * 1000.0 * np.sum(dx * dz / d2 ** 2) / n ** 2
    result = compute_illuminance(scene, P, N)
    assert result.direct[0, 0] == 0.0                    # the light itself faces away
    assert result.indirect[0, 0] == pytest.approx(exact, rel=0.05)


# -- plastic ------------------------------------------------------------------------------
# A sensor 1 m above a 2 km plastic floor, facing down, under a uniform sky of luminance
# L = E_h/π (nothing else).  The floor's own irradiance is E_h wherever the sensor sees it
# (a point blocks nothing), so the floor's radiance toward the sensor at incidence θ is
# ρ_d(θ) E_h/π from its diffuse part plus ρ_s · A(θ) · L from its specular part, A the
# lobe's albedo (:func:`test_materials.lobe_albedo`; 1 for polished plastic, whose ρ_s(θ)
# carries Radiance's Fresnel estimate instead).  Integrated over the sensor's hemisphere
# (θ there is the incidence angle on the floor): E = E_h ∫₀¹ [ρ_d(μ) + ρ_s(μ) A(μ)] 2μ dμ,
# by 16-point Gauss–Legendre (A on a 200 × 128 grid: within 3e-5 of 48 points on
# 400 × 256).  The floor's edge, 88.9° from the sensor's axis, hides 4e-6 of the
# cosine-weighted hemisphere.




@pytest.mark.parametrize("s, alpha", [(0.05, 0.0), (0.1, 0.1), (0.05, 0.05), (0.1, 0.002)])
def test_plastic_floor_under_a_uniform_sky(s, alpha):
    """E at the downward sensor against the integral above (1024 samples, one record),
    within 0.6 %; the specular part is 2.5–5 % of E.  Measured over seeds 0–3: within
    ±0.33 % in every case — polished s = 0.05 with the Fresnel estimate (a stratified
    estimate of a function rising steeply at grazing), s = 0.1 with α = 0.1, s = 0.05
    with α = 0.05 (its specular branches play Russian roulette, s < PLASTIC_BRANCH_LIMIT),
    and the nearly polished α = 0.002, which is a mirror of reflectance s over a diffuse
    part (1 − s) C."""
    C = 0.5
    scene = make_scene([PLASTIC_FLOOR], {"floor": {"type": "plastic", "reflectance": C, "specularity": s,
                                                   "roughness": alpha}}, UNIFORM_SKY)
    E = compute_illuminance(scene, *DOWN, Options(accuracy=0.1, samples=1024, bounces=1)).illuminance[0]
    ref = plastic_floor_reference(C, s, alpha)
    assert E == pytest.approx(ref, rel=0.006)
    # the specular part is seen: a diffuse floor of reflectance C gives E_h C
    assert ref - 10000.0 * C > 10000.0 * s * (1 - C) * 0.8


@pytest.mark.parametrize("s, alpha", [(0.8, 0.0), (0.6, 0.1)])
def test_metal_floor_under_a_uniform_sky(s, alpha):
    """Radiance's metal of colour C = (0.9, 0.6, 0.2) (brass-like): the same integral with
    the specular part coloured per channel (polished: F + s C (1 − F); rough: s C A(μ)),
    within 0.6 % photometrically as for plastic; and apart from plastic of the same
    arguments by far (plastic reads 34–42 % higher here: its specular part is white)."""
    C = [0.9, 0.6, 0.2]
    scene = make_scene([PLASTIC_FLOOR], {"floor": {"type": "metal", "reflectance": C, "specularity": s,
                                                   "roughness": alpha}}, UNIFORM_SKY)
    E = compute_illuminance(scene, *DOWN, Options(accuracy=0.1, samples=1024, bounces=1)).illuminance[0]
    ref = plastic_floor_reference(C, s, alpha, metal=True)
    assert E == pytest.approx(ref, rel=0.006)
    assert plastic_floor_reference(C, s, alpha) / ref - 1 > 0.3


def test_plastic_without_specularity_is_a_diffuse_surface():
    """s = 0: a plastic of colour C gives results bit-identical to a diffuse surface of
    reflectance C (same rays, same random numbers), whatever its roughness."""
    wall = {"shape": "rectangle", "origin": [2, -3, 0], "u": [0, 6, 0], "v": [0, 0, 3], "material": "floor"}
    P = np.array([[0.0, 0.0, 0.0], [1.0, 1.0, 0.0], [1.99, 0.0, 1.0]])
    N = np.array([[0.0, 0.0, 1.0], [0.0, 0.0, 1.0], [-1.0, 0.0, 0.0]])
    sun = {"altitude": 35.0, "azimuth": 250.0, "direct_normal_illuminance": 60000.0}
    runs = []
    for floor in ({"type": "diffuse", "reflectance": [0.3, 0.4, 0.5]},
                  {"type": "plastic", "reflectance": [0.3, 0.4, 0.5], "specularity": 0.0, "roughness": 0.1},
                  {"type": "plastic", "reflectance": [0.3, 0.4, 0.5], "specularity": 0.0, "roughness": 0.0}):
        scene = make_scene([PLASTIC_FLOOR, wall], {"floor": floor}, UNIFORM_SKY, sun)
        runs.append(compute_illuminance(scene, P, N, Options(accuracy=0.2, samples=64, bounces=2)))
    for run in runs[1:]:
        assert np.array_equal(run.rgb, runs[0].rgb) and run.stats.records == runs[0].stats.records


@pytest.mark.parametrize("alpha", [0.2, 0.0])
def test_plastic_floor_reflects_the_sun(alpha):
    """No sky; the sun at 60° altitude over an infinite plastic floor (C = 0.5, s = 0.05),
    a downward sensor, bounces = 1.  Closed form: the floor's diffuse part gives
    E_h ∫ ρ_d(θ) 2 cos θ d(cos θ) (ρ_d = (1 − s) C when rough, (1 − ρ_s(θ)) C when polished,
    by :func:`plastic_floor_reference`'s quadrature); its specular part E_h s A(30°, α) when
    rough (A the lobe's albedo at the sun's incidence, by reciprocity), which hemisphere
    rays find as the sun's highlight, and E_h ρ_s(30°) when polished: the sun's image,
    counted as direct light.  So level-1 records are made for the rough floor only (a
    diffuse floor needs none either).  Within 0.5 %; measured over seeds 0–3: within 0.14 %."""
    from lbl_illum.scene.materials import plastic_fresnel
    from conftest import lobe_albedo

    C, s, E_dn = 0.5, 0.05, 50000.0
    sun = {"altitude": 60.0, "azimuth": 180.0, "direct_normal_illuminance": E_dn}
    E_h = E_dn * math.sin(math.radians(60.0))
    floor = {"type": "plastic", "reflectance": C, "specularity": s, "roughness": alpha}
    scene = make_scene([PLASTIC_FLOOR], {"floor": floor}, {"type": "none"}, sun)
    result = compute_illuminance(scene, *DOWN, Options(accuracy=0.2, samples=1024, bounces=1))
    x, w = np.polynomial.legendre.leggauss(16)
    mu, w = 0.5 * (x + 1.0), 0.5 * w
    if alpha > 0:
        diffuse, specular = (1 - s) * C, s * lobe_albedo(math.radians(30.0), alpha)
    else:
        diffuse = float(np.sum(w * (1 - (s + plastic_fresnel(mu) * (1 - s))) * C * 2 * mu))
        specular = s + float(plastic_fresnel(math.cos(math.radians(30.0)))) * (1 - s)
    assert result.illuminance[0] == pytest.approx(E_h * (diffuse + specular), rel=0.005)
    assert specular > 0.04
    assert (result.stats.records[1] > 0) == (alpha > 0)
    diffuse_floor = make_scene([PLASTIC_FLOOR], {"floor": {"type": "diffuse", "reflectance": C}}, {"type": "none"}, sun)
    assert compute_illuminance(diffuse_floor, *DOWN, Options(accuracy=0.2, samples=256, bounces=1)).stats.records[1] == 0


def test_cache_fingerprint_tells_plastics_apart():
    """Records made for one plastic are not reused for another: specularity and roughness
    enter the fingerprint that cache files are checked against."""
    from lbl_illum.engine.integrator import scene_fingerprint
    prints = set()
    for s, alpha in ((0.05, 0.1), (0.07, 0.1), (0.05, 0.2)):
        scene = make_scene([PLASTIC_FLOOR], {"floor": {"type": "plastic", "reflectance": 0.5, "specularity": s,
                                                       "roughness": alpha}}, UNIFORM_SKY)
        prints.add(scene_fingerprint(scene, Options()))
    assert len(prints) == 3

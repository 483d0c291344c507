"""Luminance images: analytic pixel values, the cache shared with illuminance runs (the command:
tests/cli/test_render_command.py).

Reference values and tolerances.
* A diffuse plane under a uniform sky and a sun, open to the whole upper hemisphere:
  E = E_h + E_dn sin(altitude) exactly, so L = ρ E/π.  The stratified estimate of a
  uniform sky is exact (π/S Σ L_sky = E_h) and the gradients of a constant are 0, so
  the only error is float32 storage: rtol 1e-5.
* Sky, sun disk, light surfaces seen directly, in a mirror (× ρ) or through a pane
  (× τ, + ρ × the reflected sky): exact, rtol 1e-6.
* Plastic (Radiance's ``plastic``): a camera ray meeting a plastic floor under a uniform
  sky carries ρ_d(θ) E/π + ρ_s(θ) L (polished: exact per ray, rtol 1e-6 along given rays,
  5e-3 over a 0.5° image whose θ varies by ±0.25°) or ρ_d E/π + s A(θ) L on average
  (rough: A the lobe's albedo by quadrature, test_materials.lobe_albedo; 4 standard errors).
  The sun's highlight on rough plastic is ρ_s f_s(v, s) cos θ_s E_dn on every ray, within
  0.5 % (the lobe's change across the 0.27° disk), and the sun disk is not counted again
  by the sampled reflections (one in ~1200 of them meets it, and would add ~10³ times the
  highlight).
* An integrating sphere (Modest, *Radiative Heat Transfer*, 2013, ch. 4; see
  validation/studies/integrating_sphere.py): wall luminance ρ/π · E_0 (1 − q^{N+1})/(1 − q)
  with E_0 = π L (r/R)², q = ρ (1 − (r/R)²).  The image mean over the wall pixels is
  within 4 % (direct step noise over ~1000 pixels ≈ 0.6 %, cache bias at a = 0.2 ≈ 2 %).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from lbl_illum import Options
from lbl_illum.engine.integrator import Integrator
from lbl_illum.scene.materials import plastic_fresnel, thin_pane_reflectance, ward_brdf
from lbl_illum.engine.render import (EDGE_SAMPLES, WEIGHT_LIMIT, edge_pixels, first_hit_sources, image_options,
                                     render_image, trace_view_paths, view_spacing)
from lbl_illum.daylight.sun import SUN_SOLID_ANGLE
from lbl_illum.scene.scenefile import scene_from_dict
from lbl_illum.scene.views import View, view_from_string

from conftest import ies_text, make_scene

E_H = 10000.0          # sky's horizontal illuminance [lux]
E_DN = 50000.0         # sun's direct normal illuminance [lux]
SUN_ALT, SUN_AZ = 40.0, 180.0
QUICK = Options(accuracy=0.2, samples=64, bounces=2)

PLANE = {"shape": "polygon", "material": "plane",
         "vertices": [[-50, -50, 0], [50, -50, 0], [50, 50, 0], [-50, 50, 0]]}


def uniform_sky(E=E_H):
    return {"type": "uniform", "horizontal_illuminance": E, "ground_reflectance": 0.2}


def overcast_sky(E=E_H):
    return {"type": "cie-overcast", "horizontal_illuminance": E, "ground_reflectance": 0.2}


def sun():
    return {"altitude": SUN_ALT, "azimuth": SUN_AZ, "direct_normal_illuminance": E_DN}


def plane_scene(kind="diffuse", reflectance=0.5, sky=None, with_sun=True):
    mats = {"plane": {"type": kind, "reflectance": reflectance}}
    return make_scene([PLANE], mats, sky or uniform_sky(), sun() if with_sun else None)


def pane_scene(reflectance=None, tau=0.6, sky=None, model="constant"):
    """A 40 m × 40 m vertical pane in the plane y = 2, nothing else.  ``model`` "constant"
    (τ, ρ at every angle; ρ by default the thin pane's at normal incidence) or "fresnel"."""
    glass = {"type": "glass", "transmittance": tau, "model": model}
    if reflectance is not None:
        glass["reflectance"] = reflectance
    geo = [{"shape": "rectangle", "origin": [-20, 2, -20], "u": [40, 0, 0], "v": [0, 0, 40], "material": "glass"}]
    return make_scene(geo, {"glass": glass}, sky or uniform_sky())


def sun_direction():
    alt, az = np.radians(SUN_ALT), np.radians(SUN_AZ)
    return np.array([np.cos(alt) * np.sin(az), np.cos(alt) * np.cos(az), np.sin(alt)])


# -- analytic pixels ---------------------------------------------------------------------

def test_diffuse_plane_under_sky_and_sun_is_rho_E_over_pi():
    scene = plane_scene(reflectance=0.5)
    view = view_from_string("-vtv -vp 0 0 1.5 -vd 0 1 -0.6 -vh 60 -vv 40")
    result = render_image(scene, view, 24, 16, QUICK, pixel_samples=2)
    E = E_H + E_DN * math.sin(math.radians(SUN_ALT))
    assert result.rgb.shape == (16, 24, 3) and result.rgb.dtype == np.float32
    assert result.valid.all()
    np.testing.assert_allclose(result.rgb, 0.5 * E / np.pi, rtol=1e-5)
    np.testing.assert_allclose(result.luminance, 0.5 * E / np.pi, rtol=1e-5)
    # every diffuse hit was a cache query; the plane needs no deeper level (its rays escape)
    s = result.stats
    assert s.diffuse_hits == 24 * 16 * 2 and s.queries[0] == s.diffuse_hits
    assert s.records[0] == s.new_records[0] > 0 and s.records[1] == 0
    assert s.rays >= s.camera_rays == 24 * 16 * 2


def test_sky_seen_directly_and_sun_disk_luminance():
    scene = plane_scene()
    up = render_image(scene, view_from_string("-vtv -vp 0 0 1.5 -vd 0 0 1 -vu 0 1 0 -vh 60 -vv 60"), 8, 8, QUICK)
    np.testing.assert_allclose(up.rgb, E_H / np.pi, rtol=1e-6)
    assert up.stats.diffuse_hits == 0 and up.stats.new_records in ([], [0, 0, 0])
    # a 0.2° view centred on the sun lies inside its 0.53° disk: sky + E_dn/Ω everywhere
    s = sun_direction()
    at_sun = View("v", (0, 0, 1.5), tuple(s), (0, 0, 1), 0.2, 0.2)
    result = render_image(scene, at_sun, 6, 6, QUICK, pixel_samples=3)
    np.testing.assert_allclose(result.rgb, E_H / np.pi + E_DN / SUN_SOLID_ANGLE, rtol=1e-6)


@pytest.mark.parametrize("rho", [1.0, 0.8])
def test_mirror_shows_the_sky_times_its_reflectance(rho):
    scene = plane_scene("mirror", rho, with_sun=False)
    view = view_from_string("-vtv -vp 0 0 1.5 -vd 0 1 -0.8 -vh 40 -vv 30")
    result = render_image(scene, view, 16, 12, QUICK)
    np.testing.assert_allclose(result.rgb, rho * E_H / np.pi, rtol=1e-6)
    assert result.stats.diffuse_hits == 0


def test_mirror_under_an_overcast_sky_and_the_sun_in_it():
    """Along given rays: ρ L_sky(reflected direction), and ρ L_sun where it reflects the sun."""
    scene = plane_scene("mirror", 0.8, sky=overcast_sky())
    integ = Integrator(scene, QUICK)
    s = sun_direction()
    d = np.array([[0.0, 0.6, -0.8], [0.3, 0.8, -0.52], s * [1, 1, -1]])
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    o = np.tile([0.0, 0.0, 1.5], (3, 1))
    radiance, hits, rays = trace_view_paths(integ, o, d, np.random.default_rng(0))
    reflected = d * [1, 1, -1]
    expected = 0.8 * scene.sky.luminance(reflected)
    expected[2] += 0.8 * E_DN / SUN_SOLID_ANGLE
    np.testing.assert_allclose(radiance, expected, rtol=1e-6)
    assert rays == 6 and len(hits["ray"]) == 0


@pytest.mark.parametrize("reflectance", [0.0, None])
def test_sky_through_a_constant_pane(reflectance):
    """Through a pane: τ L; with the pane's reflection also ρ L of the sky behind the eye."""
    tau = 0.6
    scene = pane_scene(reflectance, tau)
    rho = thin_pane_reflectance(tau) if reflectance is None else 0.0
    view = view_from_string("-vtv -vp 0 0 1.5 -vd 0 1 0.4 -vh 40 -vv 30")
    result = render_image(scene, view, 16, 12, QUICK)
    np.testing.assert_allclose(result.rgb, (tau + rho) * E_H / np.pi, rtol=1e-6)
    # overcast sky along given rays: the reflected direction has the same altitude
    scene = pane_scene(reflectance, tau, overcast_sky())
    integ = Integrator(scene, QUICK)
    d = np.array([[0.0, 1.0, 0.2], [0.5, 1.0, 0.7]])
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    radiance, _, rays = trace_view_paths(integ, np.zeros((2, 3)), d, np.random.default_rng(0))
    np.testing.assert_allclose(radiance, (tau + rho) * scene.sky.luminance(d), rtol=1e-6)
    assert rays == (6 if rho > 0 else 4)


def test_sky_through_a_fresnel_pane_at_the_rays_angle():
    """Fresnel glazing: τ(θ) + ρ(θ) at each ray's own angle of incidence θ; at normal
    incidence τ is the stated τ_n; towards grazing less comes through."""
    from lbl_illum.scene.materials import glazing_optics, pane_transmissivity

    tau_n = 0.6
    scene = pane_scene(None, tau_n, overcast_sky(), model="fresnel")
    integ = Integrator(scene, QUICK)
    d = np.array([[0.0, 1.0, 0.0], [0.0, 1.0, 0.3], [1.5, 1.0, 0.2], [4.0, 1.0, 0.1]])
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    radiance, _, _ = trace_view_paths(integ, np.tile([0.0, 0.0, 1.5], (4, 1)), d, np.random.default_rng(0))
    tau, rho = glazing_optics(d[:, 1], pane_transmissivity(np.full(3, tau_n)))
    np.testing.assert_allclose(radiance, (tau + rho) * scene.sky.luminance(d), rtol=1e-6)
    np.testing.assert_allclose(tau[0], tau_n, rtol=1e-6)
    transmitted = radiance[:, 1] / scene.sky.luminance(d)[:, 1] - rho[:, 1]
    assert np.all(np.diff(transmitted[[0, 2, 3]]) < 0)


def test_weak_branches_play_russian_roulette_without_bias():
    """A pane reflecting 1e-3 (< WEIGHT_LIMIT): the reflected branch survives about
    1e-3 / WEIGHT_LIMIT of the time with weight WEIGHT_LIMIT: the mean stays τ + ρ."""
    tau, rho = 0.5, 1e-3
    assert rho < WEIGHT_LIMIT
    scene = pane_scene(rho, tau)
    integ = Integrator(scene, QUICK)
    n = 20000
    d = np.tile([0.0, 1.0, 0.3], (n, 1)) / np.linalg.norm([0.0, 1.0, 0.3])
    radiance, _, rays = trace_view_paths(integ, np.zeros((n, 3)), d, np.random.default_rng(1))
    L = E_H / np.pi
    values = np.unique(np.round(radiance[:, 1] / L, 9))
    np.testing.assert_allclose(values, [tau, tau + WEIGHT_LIMIT])
    survivors = (rays - 2 * n) / n                       # reflected branches traced
    assert abs(survivors - rho / WEIGHT_LIMIT) < 4 * math.sqrt(0.25 / n)
    np.testing.assert_allclose(radiance[:, 1].mean() / L, tau + rho, rtol=4 * math.sqrt(0.25 / n) * 2e-3)


def test_light_surface_seen_directly_and_edge_pixels_are_sample_means():
    """A parallel 8 m × 8 m view (1 m pixels) of a light covering x > 0.5 on black:
    16 stratified samples per pixel put exactly 8 in each half of the edge column, and the
    EDGE_SAMPLES added there (stratified too) 4 of 8.  With one sample per pixel the edge
    column has 1 + 8 samples: 4 or 5 of 9 on the light, never all or none, which is what
    made a speckled line of an edge."""
    geo = [{"shape": "rectangle", "origin": [0.5, -10, 0], "u": [20, 0, 0], "v": [0, 20, 0], "material": "lamp"}]
    scene = make_scene(geo, {"lamp": {"type": "light", "luminance": 1000.0}}, {"type": "none"})
    view = view_from_string("-vtl -vp 0 0 5 -vd 0 0 -1 -vu 0 1 0 -vh 8 -vv 8")
    result = render_image(scene, view, 8, 8, QUICK, pixel_samples=16)
    lum = result.luminance
    np.testing.assert_allclose(lum[:, :4], 0.0)
    np.testing.assert_allclose(lum[:, 4], 500.0, rtol=1e-6)
    np.testing.assert_allclose(lum[:, 5:], 1000.0, rtol=1e-6)
    # column 4 (its rays differ), and the neighbour its first ray differs from
    assert EDGE_SAMPLES == 8 and result.stats.edge_pixels == 8 * 2
    one = render_image(scene, view, 8, 8, QUICK, pixel_samples=1)
    edge = one.luminance[:, 4] / 1000.0
    assert np.all(np.isclose(edge, 4 / 9, rtol=1e-6) | np.isclose(edge, 5 / 9, rtol=1e-6))
    np.testing.assert_allclose(one.luminance[:, :4], 0.0)
    np.testing.assert_allclose(one.luminance[:, 5:], 1000.0, rtol=1e-6)


def _keys(material, normal, offset, distance=None):
    """(1, k, 1) surface keys of a row of k pixels, one ray each."""
    material = np.asarray(material)[None, :, None]
    normal = np.asarray(normal, float)[None, :, None, :]
    offset = np.asarray(offset, float)[None, :, None]
    distance = np.full(offset.shape, 3.0) if distance is None else np.asarray(distance, float)[None, :, None]
    return material, normal, offset, distance


def test_edges_are_between_surfaces_not_between_triangles_of_one_surface():
    """Pixels 0-1: two triangles of one wall (same material, plane and offset to round-off);
    1-2: a partition 5 cm before the wall, same finish; 3-4: the floor meeting the wall at
    90 degrees; 5-6: the sky beside the wall.  Both pixels of each differing pair are edges."""
    wall, floor = [0.0, -1.0, 0.0], [0.0, 0.0, 1.0]
    edge = edge_pixels(*_keys([1, 1, 1, 1, 2, 1, -1],
                              [wall, wall, wall, wall, floor, wall, [0, 0, 0]],
                              [3.0, 3.0 + 1e-9, 2.95, 2.95, 0.0, 3.0, 0.0]))
    assert edge[0].tolist() == [False, True, True, True, True, True, True]
    one_surface = edge_pixels(*_keys([1, 1, 1], [wall, wall, wall], [3.0, 3.0 + 1e-9, 3.0 - 1e-9]))
    assert not one_surface.any()
    turned = np.array([0.0, -np.cos(np.radians(12.0)), np.sin(np.radians(12.0))])
    assert edge_pixels(*_keys([1, 1], [wall, turned], [3.0, 3.0]))[0].all()
    slightly = np.array([0.0, -np.cos(np.radians(5.0)), np.sin(np.radians(5.0))])
    assert not edge_pixels(*_keys([1, 1], [wall, slightly], [3.0, 3.0])).any()


def test_fisheye_corners_are_invalid_and_zero():
    """A hemispherical fisheye (-vth 180) fills the inscribed circle; the corners see nothing.
    (A 180° angular fisheye's corners are valid rays looking behind, as in rpict.)"""
    scene = plane_scene(with_sun=False)
    view = view_from_string("-vth -vp 0 0 1.5 -vd 0 0 1 -vu 0 1 0 -vh 180 -vv 180")
    result = render_image(scene, view, 16, 16, QUICK, pixel_samples=4)
    assert not result.valid[0, 0] and not result.valid[-1, -1] and result.valid[8, 8]
    assert np.all(result.rgb[~result.valid] == 0.0)
    # every valid sample looks at the sky (above the horizon): pixel = mean of valid samples
    np.testing.assert_allclose(result.rgb[result.valid], E_H / np.pi, rtol=1e-6)
    # valid: every pixel wholly inside the circle, none wholly outside it (rim pixels, which
    # get edge rays, may be either)
    lo = np.arange(16.0)
    near = np.hypot(np.clip(8.0, lo, lo + 1)[:, None] - 8.0, np.clip(8.0, lo, lo + 1)[None, :] - 8.0)
    far = np.hypot(np.maximum(np.abs(lo - 8.0), np.abs(lo + 1 - 8.0))[:, None],
                   np.maximum(np.abs(lo - 8.0), np.abs(lo + 1 - 8.0))[None, :])
    assert result.valid[far < 8.0 - 1e-9].all() and not result.valid[near > 8.0 + 1e-9].any()


def test_aft_clipping_is_black_beyond_the_plane():
    scene = plane_scene(with_sun=False)
    view = view_from_string("-vtv -vp 0 0 1.5 -vd 0 1 -0.6 -vh 40 -vv 20 -va 0.5")
    result = render_image(scene, view, 8, 4, QUICK)
    assert np.all(result.rgb == 0.0) and result.stats.diffuse_hits == 0


@pytest.mark.parametrize("rho", [0.5])
def test_integrating_sphere_walls_match_the_closed_form(rho):
    R, r, L = 1.0, 0.1, 1000.0
    geo = [{"shape": "sphere", "center": [0, 0, 0], "radius": R, "material": "wall"},
           {"shape": "sphere", "center": [0, 0, 0], "radius": r, "material": "lamp"}]
    scene = make_scene(geo, {"wall": {"type": "diffuse", "reflectance": rho},
                             "lamp": {"type": "light", "luminance": L}}, {"type": "none"})
    bounces = 8
    opts = Options(accuracy=0.2, samples=128, bounces=bounces)
    f = (r / R) ** 2
    q = rho * (1 - f)
    E = math.pi * L * f * (1 - q ** (bounces + 1)) / (1 - q)
    walls = render_image(scene, view_from_string("-vtv -vp 0 0 0.5 -vd 1 0 0.2 -vh 60 -vv 60"), 32, 32, opts)
    assert walls.stats.diffuse_hits == 32 * 32
    mean = float(walls.luminance.mean())
    assert abs(mean / (rho * E / math.pi) - 1) < 0.04, (mean, rho * E / math.pi)
    lamp = render_image(scene, view_from_string("-vtv -vp 0 0 0.5 -vd 0 0 -1 -vu 0 1 0 -vh 5 -vv 5"), 4, 4, opts,
                  cache=walls.cache)
    np.testing.assert_allclose(lamp.rgb, L, rtol=1e-6)


# -- plastic ------------------------------------------------------------------------------

def plastic_scene(s, alpha, C=(0.2, 0.5, 0.8), sky=None, with_sun=False, kind="plastic"):
    mats = {"plane": {"type": kind, "reflectance": list(C), "specularity": s, "roughness": alpha}}
    return make_scene([PLANE], mats, sky or uniform_sky(), sun() if with_sun else None)


def rays_at(incidence_deg, n):
    """n camera rays from 1.5 m above the plane, meeting it at the given incidence."""
    t = math.radians(incidence_deg)
    d = np.tile([0.0, math.sin(t), -math.cos(t)], (n, 1))
    return np.tile([0.0, 0.0, 1.5], (n, 1)), d


@pytest.mark.parametrize("deg", [20.0, 60.0, 85.0])
def test_polished_plastic_reflects_the_sky_with_radiance_fresnel_estimate(deg):
    """Along given rays: known radiance ρ_s(θ) L_sky, one diffuse hit of weight
    ρ_d(θ)/π = (1 − ρ_s(θ)) C/π, ρ_s(θ) = s + F(cos θ)(1 − s) (normal.c)."""
    s, C = 0.05, np.array([0.2, 0.5, 0.8])
    integ = Integrator(plastic_scene(s, 0.0), QUICK)
    o, d = rays_at(deg, 4)
    radiance, hits, rays = trace_view_paths(integ, o, d, np.random.default_rng(0))
    F = math.exp(-5.85 * math.cos(math.radians(deg))) - 0.00202943064
    rho_s = s + F * (1 - s)
    np.testing.assert_allclose(radiance, rho_s * E_H / np.pi, rtol=1e-6)
    np.testing.assert_allclose(hits["weight"], np.tile((1 - rho_s) * C / np.pi, (4, 1)), rtol=1e-12)
    assert rays == 8 and list(hits["ray"]) == [0, 1, 2, 3]


@pytest.mark.parametrize("alpha, deg", [(0.05, 30.0), (0.2, 75.0)])
def test_rough_plastic_reflects_the_sky_by_its_lobe_albedo(alpha, deg):
    from conftest import lobe_albedo

    s, C = 0.1, np.array([0.2, 0.5, 0.8])
    integ = Integrator(plastic_scene(s, alpha), QUICK)
    n = 20000
    o, d = rays_at(deg, n)
    radiance, hits, _ = trace_view_paths(integ, o, d, np.random.default_rng(2))
    L = radiance[:, 1] / (E_H / np.pi)                 # specular part, in units of L_sky
    expected = s * lobe_albedo(math.radians(deg), alpha)
    assert abs(L.mean() - expected) < 4 * L.std() / math.sqrt(n) + 1e-6, (L.mean(), expected)
    np.testing.assert_allclose(radiance[:, 0], radiance[:, 2])            # a white highlight
    np.testing.assert_allclose(hits["weight"], np.tile((1 - s) * C / np.pi, (n, 1)), rtol=1e-12)


def test_rough_plastic_sun_highlight_is_counted_once():
    """No sky; the sun at 40° altitude.  Rays meeting a rough plastic plane (α = 0.1)
    where it mirrors the sun carry ρ_s f_s(v, s) cos θ_s E_dn each (the disk's centre: at
    the lobe's peak it changes by < 0.5 % across the disk); rays tilted 0.15 rad away, on
    the lobe's flank (±4 % across the disk), on average, within 0.3 %, and none above
    1.1 times it.  Polished plastic shows the sun's disk in the mirror direction instead."""
    s, alpha = 0.05, 0.1
    integ = Integrator(plastic_scene(s, alpha, sky={"type": "none"}, with_sun=True), QUICK)
    sd = sun_direction()
    n = 30000
    rng = np.random.default_rng(5)
    for tilt in (0.0, 0.15):
        d = sd * [1, 1, -1] + [tilt, 0.0, 0.0]
        d = np.tile(d / np.linalg.norm(d), (n, 1))
        o = np.tile([0.0, 0.0, 1.5], (n, 1))
        radiance, hits, _ = trace_view_paths(integ, o, d, rng)
        N = np.tile([0.0, 0.0, 1.0], (n, 1))
        expected = s * ward_brdf(N[:1], d[:1], sd[None, :], alpha)[0] * sd[2] * E_DN
        assert len(hits["ray"]) == n and np.allclose(radiance[:, 0], radiance[:, 2])
        if tilt == 0.0:
            assert expected > 0.5 * E_DN
            np.testing.assert_allclose(radiance, expected, rtol=5e-3)      # every ray: no disk counted twice
        else:
            assert expected > 0.1 * E_DN
            L = radiance[:, 1]
            assert L.max() < 1.1 * expected and abs(L.mean() / expected - 1) < 3e-3
    polished = Integrator(plastic_scene(s, 0.0, sky={"type": "none"}, with_sun=True), QUICK)
    d = sd * [1, 1, -1]
    radiance, _, _ = trace_view_paths(polished, np.array([[0.0, 0.0, 1.5]]), d[None, :], rng)
    rho_s = s + float(plastic_fresnel(sd[2])) * (1 - s)
    np.testing.assert_allclose(radiance[0], rho_s * E_DN / SUN_SOLID_ANGLE, rtol=1e-6)


@pytest.mark.parametrize("deg", [20.0, 85.0])
def test_polished_metal_reflects_the_sky_in_its_colour(deg):
    """Radiance's metal (normal.c): specular reflectance F + s C (1 − F) per channel,
    F = FRESNE(cos θ), so the reflection is coloured at normal incidence and turns white
    toward grazing; the diffuse hit keeps (1 − ρ_s(θ)) C with the plastic's scalar ρ_s."""
    s, C = 0.8, np.array([0.9, 0.6, 0.2])
    integ = Integrator(plastic_scene(s, 0.0, C, kind="metal"), QUICK)
    o, d = rays_at(deg, 4)
    radiance, hits, _ = trace_view_paths(integ, o, d, np.random.default_rng(0))
    F = math.exp(-5.85 * math.cos(math.radians(deg))) - 0.00202943064
    np.testing.assert_allclose(radiance, np.tile((F + s * C * (1 - F)) * E_H / np.pi, (4, 1)), rtol=1e-6)
    rho_s = s + F * (1 - s)
    np.testing.assert_allclose(hits["weight"], np.tile((1 - rho_s) * C / np.pi, (4, 1)), rtol=1e-12)


def test_rough_metal_sun_highlight_has_its_colour():
    """The sun's highlight on rough metal is the plastic's times C per channel: the same
    rays and random numbers give s C f_s cos θ_s E_dn (Radiance's metal) where plastic
    gives the white s f_s cos θ_s E_dn."""
    s, alpha, C = 0.6, 0.1, np.array([0.9, 0.6, 0.2])
    sd = sun_direction()
    d = np.tile(sd * [1, 1, -1], (64, 1))
    o = np.tile([0.0, 0.0, 1.5], (64, 1))
    out = {}
    for kind in ("plastic", "metal"):
        integ = Integrator(plastic_scene(s, alpha, C, sky={"type": "none"}, with_sun=True, kind=kind), QUICK)
        out[kind] = trace_view_paths(integ, o, d, np.random.default_rng(3))[0]
    assert out["plastic"][:, 0].min() > 0.5 * E_DN
    np.testing.assert_allclose(out["metal"], out["plastic"] * C, rtol=1e-12)


def test_polished_plastic_image_under_a_uniform_sky():
    """A 0.5° view of the plane at 60° incidence: every pixel (ρ_d(θ) E + ρ_s(θ) E)/π with
    E = E_h (the plane's illuminance through the cache, exact for a uniform sky): the
    diffuse part goes through the cache like a diffuse surface's."""
    s, C = 0.05, np.array([0.2, 0.5, 0.8])
    view = view_from_string("-vtv -vp 0 0 1.5 -vd 0 0.8660254 -0.5 -vh 0.5 -vv 0.5")
    result = render_image(plastic_scene(s, 0.0), view, 8, 8, QUICK)
    rho_s = s + (math.exp(-5.85 * 0.5) - 0.00202943064) * (1 - s)
    expected = ((1 - rho_s) * C + rho_s) * E_H / np.pi
    # ρ_s(θ) changes by ±0.0012 across the ±0.25° of the view: ±0.4 % of the red channel
    np.testing.assert_allclose(result.rgb.reshape(-1, 3), np.tile(expected, (64, 1)), rtol=5e-3)
    np.testing.assert_allclose(result.rgb.reshape(-1, 3).mean(axis=0), expected, rtol=1e-3)
    assert result.stats.diffuse_hits == 64


# -- the cache ------------------------------------------------------------------------

def two_rooms():
    """Two closed 3 m rooms 10 m apart, each with a lamp in the ceiling."""
    geo, mats = [], {"wall": {"type": "diffuse", "reflectance": 0.5}, "lamp": {"type": "light", "luminance": 2000.0}}
    for x in (0.0, 10.0):
        geo.append({"shape": "box", "center": [x, 0, 1.5], "size": [3, 3, 3], "material": "wall"})
        geo.append({"shape": "rectangle", "origin": [x - 0.3, -0.3, 2.99], "u": [0.6, 0, 0], "v": [0, 0.6, 0],
                    "material": "lamp"})
    return make_scene(geo, mats, {"type": "none"})


ROOM_VIEW = "-vtv -vp -1.2 -1.2 1.6 -vd 1 1 0.3 -vh 70 -vv 70"
FLOOR = np.column_stack([np.repeat(np.linspace(-1.2, 1.2, 7), 7), np.tile(np.linspace(-1.2, 1.2, 7), 7),
                         np.full(49, 0.8)])
UP = np.tile([0.0, 0.0, 1.0], (49, 1))


def test_records_go_only_where_the_view_needs_them():
    scene = two_rooms()
    result = render_image(scene, view_from_string(ROOM_VIEW), 24, 20, QUICK)
    assert result.stats.records_made == sum(result.stats.records) > 0
    for lv in result.cache.levels:
        P = lv.P[:lv.count]
        assert np.all(np.abs(P[:, 0]) <= 1.5 + 1e-6), "a record in the room the camera is not in"
    # the lamp in the ceiling is seen directly
    assert result.luminance.max() == pytest.approx(2000.0)


def test_a_render_and_an_illuminance_run_share_records_both_ways():
    scene = two_rooms()
    opts = image_options(QUICK)
    view = view_from_string(ROOM_VIEW)
    fresh_grid = Integrator(scene, opts).compute(FLOOR, UP).stats
    fresh_image = render_image(scene, view, 24, 20, opts).stats
    # render first, then the grid on its cache: the grid makes fewer records
    image = render_image(scene, view, 24, 20, opts)
    grid = Integrator(scene, opts, cache=image.cache).compute(FLOOR, UP).stats
    assert grid.cache_hits > 0 and grid.primary_evaluations < fresh_grid.primary_evaluations
    # the grid first, then the image on its cache
    integ = Integrator(scene, opts)
    integ.compute(FLOOR, UP)
    before = sum(integ.cache.record_counts)
    again = render_image(scene, view, 24, 20, opts, cache=integ.cache)
    assert again.stats.cache_hits > 0 and again.stats.records_made < fresh_image.records_made
    assert sum(again.stats.records) == before + again.stats.records_made
    # a rerun on its own cache makes nothing and gives the same picture
    rerun = render_image(scene, view, 24, 20, opts, cache=again.cache)
    assert rerun.stats.records_made == 0
    np.testing.assert_array_equal(rerun.rgb, again.rgb)


def test_point_samples_are_not_used_for_images():
    opts = Options(accuracy=0.2, samples=64, bounces=2, point_samples=512)
    assert image_options(opts).point_samples is None
    scene = two_rooms()
    result = render_image(scene, view_from_string(ROOM_VIEW), 8, 6, opts)
    assert result.options.point_samples is None
    assert result.stats.new_records[0] < result.stats.diffuse_hits


def test_view_spacing_ignores_far_outliers():
    rng = np.random.default_rng(0)
    room = rng.uniform([0, 0, 0], [4, 6, 3], (1000, 3))
    far = rng.uniform([-100, -100, 0], [100, -50, 0], (30, 3))     # ground seen through a window
    lo, hi = view_spacing(np.vstack([room, far]))
    assert hi == pytest.approx(lo * 16)
    assert 2.5 < hi < 4.5                                        # D/2 of the room's 7.8 m diagonal, trimmed
    assert view_spacing(np.zeros((5, 3))) is None


# -- light sources seen directly (the false colour's default scale) -----------------------

def rect(origin, u, v, material):
    return {"shape": "rectangle", "origin": origin, "u": u, "v": v, "material": material}


#: The south wall's openings and panels at y = -2 (x from, x to, z from, z to) [m].
GLAZED, HOLE, PANEL, MIRROR = (-1.6, -0.4, 1.0, 2.0), (0.4, 1.6, 1.0, 2.0), (-1.6, -0.4, 0.2, 0.8), (0.4, 1.6, 0.2, 0.8)


def windowed_room(tmp_path):
    """A 4 × 4 × 3 m room (x, y from -2 to 2) under a uniform sky: in its south wall a
    glazed window and an unglazed hole (both x 1.2 m × z 1 m), below them a light panel and
    a mirror 2 cm in front of the wall, and a luminaire (a 0.6 m × 0.4 m opening) at the
    ceiling's centre."""
    (tmp_path / "lum.ies").write_text(ies_text(lambda v, h: np.full(np.shape(v), 500.0), np.array([0.0]),
                                               dims=(0.6, 0.4, 0.0)))
    geo = [rect([-2, -2, 0], [4, 0, 0], [0, 4, 0], "wall"), rect([-2, -2, 3], [4, 0, 0], [0, 4, 0], "wall"),
           rect([-2, 2, 0], [4, 0, 0], [0, 0, 3], "wall"), rect([-2, -2, 0], [0, 4, 0], [0, 0, 3], "wall"),
           rect([2, -2, 0], [0, 4, 0], [0, 0, 3], "wall"),
           # the south wall around the two openings
           rect([-2, -2, 0], [4, 0, 0], [0, 0, 1], "wall"), rect([-2, -2, 2], [4, 0, 0], [0, 0, 1], "wall"),
           rect([-2, -2, 1], [0.4, 0, 0], [0, 0, 1], "wall"), rect([-0.4, -2, 1], [0.8, 0, 0], [0, 0, 1], "wall"),
           rect([1.6, -2, 1], [0.4, 0, 0], [0, 0, 1], "wall"),
           rect([-1.6, -2, 1], [1.2, 0, 0], [0, 0, 1], "glass"),
           rect([-1.6, -1.98, 0.2], [1.2, 0, 0], [0, 0, 0.6], "lamp"),
           rect([0.4, -1.98, 0.2], [1.2, 0, 0], [0, 0, 0.6], "mirror")]
    mats = {"wall": {"type": "diffuse", "reflectance": 0.5}, "mirror": {"type": "mirror", "reflectance": 0.9},
            "glass": {"type": "glass", "transmittance": 0.7, "model": "constant"},
            "lamp": {"type": "light", "luminance": 2000.0}}
    data = {"units": "m", "geometry": geo, "materials": mats, "sky": uniform_sky(),
            "luminaires": [{"file": "lum.ies", "position": [0.0, 0.0, 2.9]}]}
    return scene_from_dict(data, tmp_path, "test.toml")


def inside(x, z, box, margin):
    return (box[0] + margin < x) & (x < box[1] - margin) & (box[2] + margin < z) & (z < box[3] - margin)


def test_source_pixels_are_the_window_the_hole_and_the_lamp_not_the_walls(tmp_path):
    """A parallel view of the south wall, 0.1 m pixels: every pixel wholly inside the glazed
    window, the hole or the light panel is a source pixel; every one wholly on the walls
    or on the mirror (which shows the room behind the camera) is not."""
    scene = windowed_room(tmp_path)
    view = view_from_string("-vtl -vp 0 1.5 1.5 -vd 0 -1 0 -vu 0 0 1 -vh 4 -vv 3")
    result = render_image(scene, view, 40, 30, QUICK, pixel_samples=2)
    assert result.source.shape == result.valid.shape == (30, 40) and result.source.dtype == bool
    o, d, _ = view.rays(40, 30)                                  # pixel centres, row 0 on top
    x, z = (o[:, 0] + d[:, 0] * (o[:, 1] + 2) / -d[:, 1]).reshape(30, 40), o[:, 2].reshape(30, 40)
    margin = 0.06                                                # over half a pixel: the whole pixel
    sources = [inside(x, z, box, margin) for box in (GLAZED, HOLE, PANEL)]
    mirror = inside(x, z, MIRROR, margin)
    wall = ~np.any([inside(x, z, box, -margin) for box in (GLAZED, HOLE, PANEL, MIRROR)], axis=0)
    for part in sources:
        assert part.sum() >= 30 and result.source[part].all()
    assert mirror.sum() >= 30 and not result.source[mirror].any()
    assert wall.sum() >= 400 and not result.source[wall].any()
    # the sky through the window is far brighter than the room: the false colour's default
    # scale comes from the room
    lum = result.luminance
    assert lum[sources[0]].min() > 5 * np.percentile(lum[wall], 99)


def test_first_hit_sources_along_given_rays(tmp_path):
    """From the room's centre: the luminaire's opening, the window, the hole and the panel
    are sources; the ceiling beside the luminaire, the mirror and the floor are not, nor
    is the window beyond the aft clipping distance."""
    integ = Integrator(windowed_room(tmp_path), QUICK)
    centre = np.array([0.0, 0.0, 1.5])
    targets = np.array([[0.0, 0.0, 2.9], [1.0, 1.0, 3.0], [-1.0, -2.0, 1.5], [1.0, -2.0, 1.5], [-1.0, -1.98, 0.5],
                        [1.0, -1.98, 0.5], [0.5, 0.5, 0.0], [-1.0, -2.0, 1.5]])
    d = targets - centre
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    o = np.tile(centre, (len(d), 1))
    tmax = np.r_[np.full(7, np.inf), 1.0]
    np.testing.assert_array_equal(first_hit_sources(integ.context, o, d, tmax),
                                  [True, False, True, True, True, False, False, False])
    assert first_hit_sources(integ.context, o[:1], d[:1])[0]


# -- the paper's Figure 5 (validation/studies/figure5.py, quick version) ---------------

@pytest.mark.slow
def test_figure5_quick_study_holds_the_papers_claims():
    """At equal rays (within 10 %) pure Monte Carlo's pixel noise in flat regions is at
    least twice the cached image's, and level-0 records are denser near the blocks."""
    pytest.importorskip("matplotlib")
    from lbl_illum_studies import figure5
    from lbl_illum_studies.report import StudyContext

    report = figure5.run(StudyContext(quick=True))
    res = report.results
    assert all(res["checks"].values()), res["checks"]
    assert res["noise"]["flat_pixels"] > 1000

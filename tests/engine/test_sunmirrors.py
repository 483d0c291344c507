"""The sun reflected by flat mirrors, panes and polished plastic (lbl_illum.engine.sunmirrors): closed forms per
point, shade on either leg, and hemisphere paths that no longer find the sun's image."""

import numpy as np
import pytest

from lbl_illum import Options, compute_illuminance
from lbl_illum.scene.materials import thin_pane_reflectance

from conftest import make_scene

SUN = {"altitude": 35.0, "azimuth": 120.0, "direct_normal_illuminance": 80000.0}
DIRECT_ONLY = Options(bounces=0)
MATS = {"mirror": {"type": "mirror", "reflectance": 0.8},
        "pane": {"type": "glass", "transmittance": 0.6, "model": "constant"},
        "block": {"type": "diffuse", "reflectance": 0.5},
        "floor": {"type": "diffuse", "reflectance": 0.4}}


def _sun():
    alt, az = np.radians(SUN["altitude"]), np.radians(SUN["azimuth"])
    return np.array([np.cos(alt) * np.sin(az), np.cos(alt) * np.cos(az), np.sin(alt)])


def _floor_mirror(size=40.0):
    return {"shape": "rectangle", "origin": [-size / 2, -size / 2, 0.0], "u": [size, 0, 0], "v": [0, size, 0],
            "material": "mirror"}


def _down(points):
    points = np.asarray(points, np.float64)
    return points, np.tile([0.0, 0.0, -1.0], (len(points), 1))


def test_downward_sensors_over_a_mirror_get_the_suns_image():
    """E = E_dn ρ (N·u), u the sun's direction mirrored in the floor: N = −z gives sin(altitude)."""
    scene = make_scene([_floor_mirror()], MATS, sun=SUN)
    P, N = _down([[x, y, 1.0] for x in (-3.0, 0.0, 2.5) for y in (-1.0, 4.0)])
    E = compute_illuminance(scene, P, N, DIRECT_ONLY).illuminance
    assert np.allclose(E, 80000.0 * 0.8 * np.sin(np.radians(35.0)), rtol=1e-4)
    tilted = np.array([[0.0, 0.6, -0.8]])
    u = _sun() * [1, 1, -1]
    E = compute_illuminance(scene, np.array([[0, 0, 1.0]]), tilted, DIRECT_ONLY).illuminance
    assert E[0] == pytest.approx(80000.0 * 0.8 * max(0.0, tilted[0] @ u), rel=1e-4)


def test_polished_plastic_shows_the_suns_image_rough_plastic_its_highlight():
    """A polished plastic floor (s = 0.05, α = 0): E = E_dn ρ_s(θ) sin(altitude) at downward
    sensors, ρ_s(θ) = s + F(cos θ)(1 − s) at the sun's incidence θ = 55° (Radiance's
    Fresnel estimate, :func:`plastic_fresnel`), to 1e-4.  Rough plastic (α = 0.1) has no
    image in the direct light; the sensors' hemisphere rays see its sun highlight,
    E_h s A(55°, α) (A the lobe's albedo, by reciprocity), within 1.5 % with 16,384 samples
    per sensor (measured over seeds 0–2: within 0.62 %)."""
    from lbl_illum.engine.direct import DirectLight
    from lbl_illum.engine.integrator import Integrator
    from lbl_illum.scene.materials import plastic_fresnel
    from conftest import lobe_albedo

    s, E_h = 0.05, 80000.0 * np.sin(np.radians(35.0))
    rho_s = s + float(plastic_fresnel(np.sin(np.radians(35.0)))) * (1 - s)
    P, N = _down([[x, 2.0, 1.0] for x in (-3.0, 0.0, 2.5)])
    for alpha, expected in ((0.0, E_h * rho_s), (0.1, E_h * s * lobe_albedo(np.radians(55.0), 0.1))):
        mats = dict(MATS, mirror={"type": "plastic", "reflectance": 0.0, "specularity": s, "roughness": alpha})
        scene = make_scene([_floor_mirror()], mats, sun=SUN)
        E = compute_illuminance(scene, P, N, Options(bounces=0, point_samples=16384)).illuminance
        np.testing.assert_allclose(E, expected, rtol=1e-4 if alpha == 0 else 0.015)
        integ = Integrator(scene, DIRECT_ONLY)
        direct = DirectLight(integ.tracer, integ.materials, integ.sun).illuminance(P, N, N, np.random.default_rng(1))
        assert np.all(direct == 0.0) == (alpha > 0)


def test_shade_on_either_leg_removes_the_image():
    s, u = _sun(), _sun() * [1, 1, -1]
    P = np.array([0.0, 0.0, 1.0])
    X = P + (P[2] / s[2]) * u                                     # where P sees the mirrored sun
    block_mirror_side = {"shape": "box", "center": list(P + 0.5 * (X - P)), "size": [0.3, 0.3, 0.3],
                         "material": "block"}
    block_sun_side = {"shape": "box", "center": list(X + 3.0 * s), "size": [0.5, 0.5, 0.5], "material": "block"}
    for block in (block_mirror_side, block_sun_side):
        scene = make_scene([_floor_mirror(), block], MATS, sun=SUN)
        E = compute_illuminance(scene, *_down([P]), DIRECT_ONLY).illuminance
        assert E[0] == 0.0
    # the far side of a mirror sees no sun in it; a sensor off the mirror's extent neither
    scene = make_scene([_floor_mirror(size=1.0)], MATS, sun=SUN)
    E = compute_illuminance(scene, *_down([[0.0, 0.0, -1.0], [30.0, 0.0, 1.0]]), DIRECT_ONLY).illuminance
    assert np.all(E == 0.0)


def test_a_pane_reflects_its_constant_reflectance():
    """A vertical pane facing the sun's azimuth: a sensor in front of it, facing it."""
    s = _sun()
    h = np.array([s[0], s[1], 0.0]) / np.hypot(s[0], s[1])     # horizontal, towards the sun
    side = np.cross([0, 0, 1.0], h)
    pane = {"shape": "rectangle", "origin": list(-3 * side - 0.0 * h), "u": list(6 * side), "v": [0, 0, 6.0],
            "material": "pane"}
    P = 2.0 * h + [0, 0, 2.0]
    normal = -h[None, :]
    E = compute_illuminance(make_scene([pane], MATS, sun=SUN), P[None, :], normal, DIRECT_ONLY).illuminance
    u = s - 2.0 * (s @ h) * h
    assert E[0] == pytest.approx(80000.0 * thin_pane_reflectance(0.6) * (normal[0] @ u), rel=1e-4)


def test_hemisphere_rays_do_not_count_the_suns_image_again():
    """A path ray aimed at the sun's image in a mirror brings the mirrored sky only: the
    image is the direct light's (virtual sun), and a ray finding it as well counted it twice."""
    from lbl_illum.engine.integrator import Integrator

    scene = make_scene([_floor_mirror()], MATS, sun=SUN, sky={"type": "uniform", "zenith_luminance": 1000.0})
    integ = Integrator(scene, Options())
    u = _sun() * [1, 1, -1]
    _, radiance, _, _ = integ.trace_paths(np.array([[0.0, 0.0, 1.0]]), u[None, :], np.random.default_rng(1))
    assert radiance[0] == pytest.approx([800.0] * 3, rel=1e-6)


def test_the_image_seen_through_a_pane_is_dimmed_by_it():
    """A mirror seen through a pane (a light shelf outside a window, seen from the ceiling):
    E = E_dn sin(altitude) (ρ_m τ + ρ_p) at a downward sensor above a 0.6 m pane of constant
    τ = 0.6 that the reflected ray crosses on its way to the floor mirror — the mirror's
    image through the pane plus the pane's own reflection — to 1e-4.  The pane stays off
    the mirror's far leg to the sun (1.4 m away)."""
    s, u = _sun(), _sun() * [1, 1, -1]
    P = np.array([0.0, 0.0, 1.0])
    crossing = P + (0.5 / s[2]) * u                               # where the ray meets z = 0.5
    pane = {"shape": "rectangle", "origin": list(crossing - [0.3, 0.3, 0.0]), "u": [0.6, 0, 0], "v": [0, 0.6, 0],
            "material": "pane"}
    scene = make_scene([_floor_mirror(), pane], MATS, sun=SUN)
    E = compute_illuminance(scene, *_down([P]), DIRECT_ONLY).illuminance
    expected = 80000.0 * np.sin(np.radians(35.0)) * (0.8 * 0.6 + thin_pane_reflectance(0.6))
    assert E[0] == pytest.approx(expected, rel=1e-4)
    # an opaque block in place of the pane still hides the mirror (and shows no image itself)
    block = dict(pane, material="block")
    E = compute_illuminance(make_scene([_floor_mirror(), block], MATS, sun=SUN), *_down([P]), DIRECT_ONLY).illuminance
    assert E[0] == 0.0

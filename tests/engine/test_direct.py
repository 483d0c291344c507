"""Direct light: the sun disk and light surfaces, by shadow rays."""

import numpy as np
import pytest

from lbl_illum import Options, compute_illuminance
from lbl_illum.photometry import luminance

from conftest import GROUND, horizontal, make_scene

MATS = {"ground": {"type": "diffuse", "reflectance": 0.3},
        "block": {"type": "diffuse", "reflectance": 0.5},
        "pane": {"type": "glass", "transmittance": 0.6}}
SUN = {"altitude": 35.0, "azimuth": 120.0, "direct_normal_illuminance": 80000.0}
DIRECT_ONLY = Options(bounces=0)


def _sun_vector():
    alt, az = np.radians(SUN["altitude"]), np.radians(SUN["azimuth"])
    return np.array([np.cos(alt) * np.sin(az), np.cos(alt) * np.cos(az), np.sin(alt)])


def test_sun_on_unobstructed_horizontal_sensor():
    scene = make_scene([GROUND], MATS, sun=SUN)
    pts, nrm = horizontal(4)
    E = compute_illuminance(scene, pts, nrm, DIRECT_ONLY).illuminance
    expected = 80000.0 * np.sin(np.radians(35.0))
    # the cosine over the disk (radius 0.27°) averages to the centre's within 1e-5
    assert np.allclose(E, expected, rtol=1e-4)


def test_sun_on_tilted_sensor_is_cosine_weighted():
    scene = make_scene([GROUND], MATS, sun=SUN)
    normal = np.array([[0.0, 1.0, 1.0]]) / np.sqrt(2)
    E = compute_illuminance(scene, np.array([[0, 0, 0.5]]), normal, DIRECT_ONLY).illuminance
    assert E[0] == pytest.approx(80000.0 * max(0.0, normal[0] @ _sun_vector()), rel=1e-4)


def test_sensor_in_shadow_gets_no_sun():
    s = _sun_vector()
    box = {"shape": "box", "center": list(2.0 * s), "size": [1, 1, 1], "material": "block"}
    scene = make_scene([GROUND, box], MATS, sun=SUN)
    E = compute_illuminance(scene, np.array([[0, 0, 0.0]]), np.array([[0, 0, 1.0]]), DIRECT_ONLY).illuminance
    assert E[0] == 0.0


def test_sun_behind_glass_is_multiplied_by_transmittance():
    s = _sun_vector()
    c = 2.0 * s
    u = np.cross(s, [0, 0, 1.0])
    u /= np.linalg.norm(u)
    v = np.cross(s, u)
    pane = {"shape": "rectangle", "origin": list(c - u - v), "u": list(2 * u), "v": list(2 * v), "material": "pane"}
    scene = make_scene([GROUND, pane], MATS, sun=SUN)
    E = compute_illuminance(scene, np.array([[0, 0, 0.0]]), np.array([[0, 0, 1.0]]), DIRECT_ONLY).illuminance
    assert E[0] == pytest.approx(0.6 * 80000.0 * np.sin(np.radians(35.0)), rel=1e-4)


def test_two_panes_multiply():
    s = _sun_vector()
    u = np.cross(s, [0, 0, 1.0])
    u /= np.linalg.norm(u)
    v = np.cross(s, u)
    panes = [{"shape": "rectangle", "origin": list(d * s - u - v), "u": list(2 * u), "v": list(2 * v),
              "material": "pane"} for d in (1.5, 2.5)]
    scene = make_scene([GROUND] + panes, MATS, sun=SUN)
    E = compute_illuminance(scene, np.array([[0, 0, 0.0]]), np.array([[0, 0, 1.0]]), DIRECT_ONLY).illuminance
    assert E[0] == pytest.approx(0.36 * 80000.0 * np.sin(np.radians(35.0)), rel=1e-4)


def test_sun_below_horizon_gives_nothing_and_a_warning():
    scene = make_scene([GROUND], MATS, sun={**SUN, "altitude": -5.0})
    assert any("below the horizon" in w for w in scene.warnings)
    E = compute_illuminance(scene, *horizontal(1), DIRECT_ONLY).illuminance
    assert E[0] == 0.0


def test_light_surface_matches_the_disk_formula():
    """A Lambertian disk-like square light of luminance L, side 2a, at height h above the
    sensor: E = L ∫∫ h² / (x² + y² + h²)² dx dy over the square (numerical reference)."""
    h, a, L = 1.0, 0.5, 1000.0
    light = {"shape": "rectangle", "origin": [-a, -a, h], "u": [2 * a, 0, 0], "v": [0, 2 * a, 0],
             "material": "lamp"}
    mats = {"ground": {"type": "diffuse", "reflectance": 0.0}, "lamp": {"type": "light", "luminance": L}}
    scene = make_scene([GROUND, light], mats)
    n = 2000
    x = (np.arange(n) + 0.5) / n * 2 * a - a
    X, Y = np.meshgrid(x, x)
    reference = L * np.sum(h * h / (X ** 2 + Y ** 2 + h * h) ** 2) * (2 * a / n) ** 2
    pts = np.zeros((400, 3))
    nrm = np.tile([0, 0, 1.0], (400, 1))
    E = compute_illuminance(scene, pts, nrm, DIRECT_ONLY).illuminance
    # 16 area samples per point, 400 points: the mean is within 1 % of the integral
    assert E.mean() == pytest.approx(reference, rel=0.01)


def test_grazing_sun_cut_by_the_horizon_counts_only_the_part_above_it():
    """Sun at 0.1°: the horizon of a horizontal sensor cuts the 0.27° disk.  Exact for a
    uniform disk of radius δ whose centre is α above the plane (small angles):
    E = E_dn/(π δ²) · [α A + (2/3)(δ² − α²)^{3/2}], A the disk's area above the plane;
    the centre's cosine times the visible fraction gave 102 lux instead of 165."""
    from lbl_illum.daylight.sun import SUN_SOLID_ANGLE
    scene = make_scene([GROUND], MATS, sun={"altitude": 0.1, "azimuth": 0.0, "direct_normal_illuminance": 80000.0})
    delta, alpha = np.arccos(1.0 - SUN_SOLID_ANGLE / (2 * np.pi)), np.radians(0.1)
    area = np.pi * delta**2 - (delta**2 * np.arccos(alpha / delta) - alpha * np.sqrt(delta**2 - alpha**2))
    exact = 80000.0 / (np.pi * delta**2) * (alpha * area + 2.0 / 3.0 * (delta**2 - alpha**2) ** 1.5)
    n = 400
    pts = np.column_stack([np.random.default_rng(0).uniform(-5, 5, (n, 2)), np.zeros(n)])
    E = compute_illuminance(scene, pts, np.tile([0, 0, 1.0], (n, 1)), DIRECT_ONLY).illuminance
    sem = E.std() / np.sqrt(n)
    assert sem < 0.02 * exact
    assert abs(E.mean() - exact) < 4 * sem


def _fresnel_pane(theta, tau_n, n=1.52):
    """Transmittance of Radiance's thin glass at incidence θ for normal transmittance τ_n,
    written with the angles (Snell and Fresnel): the check of lbl_illum.scene.materials."""
    r0 = ((n - 1) / (n + 1)) ** 2
    tn = (np.sqrt((1 - r0) ** 4 + 4 * r0 * r0 * tau_n ** 2) - (1 - r0) ** 2) / (2 * r0 * r0 * tau_n)
    tt = np.arcsin(np.sin(theta) / n)
    rs = (np.sin(theta - tt) / np.sin(theta + tt)) ** 2
    rp = (np.tan(theta - tt) / np.tan(theta + tt)) ** 2
    d = tn ** (1 / np.cos(tt))
    return 0.5 * sum((1 - r) ** 2 * d / (1 - (r * d) ** 2) for r in (rs, rp))


def test_sun_through_fresnel_glass_at_oblique_incidence():
    """A horizontal Fresnel pane above the sensor, sun at 35°: incidence 55°, so the sun
    passes τ(55°) = 0.524, not τ_n = 0.6; the constant model passes 0.6 at any angle."""
    pane = {"shape": "rectangle", "origin": [-20, -20, 1], "u": [40, 0, 0], "v": [0, 40, 0], "material": "pane"}
    expected = 80000.0 * np.sin(np.radians(35.0))
    tau = _fresnel_pane(np.radians(55.0), 0.6)
    for model, factor in (("fresnel", tau), ("constant", 0.6)):
        scene = make_scene([pane], {"pane": {"type": "glass", "transmittance": 0.6, "model": model}}, sun=SUN)
        E = compute_illuminance(scene, np.array([[0, 0, 0.0]]), np.array([[0, 0, 1.0]]), DIRECT_ONLY).illuminance
        # (τ averaged over the sun's 0.27° disk: 2e-4 above τ at its centre here)
        assert E[0] == pytest.approx(factor * expected, rel=5e-4), model
    assert tau == pytest.approx(0.524, abs=1e-3)


def test_light_surface_through_fresnel_glass():
    """A 1 m square light 1 m above the sensor behind a horizontal pane at 0.5 m:
    E = L ∫∫ τ(θ) h² / (x² + y² + h²)² dx dy, τ at each point's own incidence angle."""
    h, a, L = 1.0, 0.5, 1000.0
    geo = [{"shape": "rectangle", "origin": [-a, -a, h], "u": [2 * a, 0, 0], "v": [0, 2 * a, 0], "material": "lamp"},
           {"shape": "rectangle", "origin": [-5, -5, 0.5], "u": [10, 0, 0], "v": [0, 10, 0], "material": "pane"}]
    mats = {"lamp": {"type": "light", "luminance": L}, "pane": {"type": "glass", "transmittance": 0.6}}
    scene = make_scene(geo, mats)
    n = 1000
    x = (np.arange(n) + 0.5) / n * 2 * a - a
    X, Y = np.meshgrid(x, x)
    r2 = X ** 2 + Y ** 2 + h * h
    tau = _fresnel_pane(np.arccos(h / np.sqrt(r2)), 0.6)
    reference = L * np.sum(tau * h * h / r2 ** 2) * (2 * a / n) ** 2
    pts = np.zeros((400, 3))
    # (the pane reflects, so the indirect step runs: kept cheap, it finds nothing here)
    result = compute_illuminance(scene, pts, np.tile([0, 0, 1.0], (400, 1)),
                                 Options(bounces=0, samples=16, point_samples=0))
    E = luminance(result.direct)
    assert E.mean() == pytest.approx(reference, rel=0.01)
    assert reference / 752.2747 < 0.595               # less than τ_n = 0.6 times the bare light (752.27 lux)


def test_penumbra_of_a_straight_edge_per_point():
    """Sensors across the shadow edge of a wide plate 1 m above them, sun at the zenith: the
    visible part of the disk is a circular segment, f(t) = (acos(-t) + t sqrt(1 - t²)) / π
    with t the sensor's angular offset from the edge over the disk's angular radius.  Every
    sensor within 1 % of E_dn (16 random rays per sensor were off by up to 17 %)."""
    E_dn = 80000.0
    plate = {"shape": "polygon", "material": "block", "vertices": [[-20, -20, 1], [0, -20, 1], [0, 20, 1], [-20, 20, 1]]}
    scene = make_scene([GROUND, plate], MATS, sun={"altitude": 90.0, "azimuth": 0.0, "direct_normal_illuminance": E_dn})
    delta = np.arccos(1.0 - 6.8e-5 / (2.0 * np.pi))         # the disk's angular radius
    x = np.tan(np.linspace(-1.2, 1.2, 41) * delta)            # 1 m below the edge
    pts = np.column_stack([x, np.zeros_like(x), np.full_like(x, 1e-3)])
    nrm = np.tile([0.0, 0.0, 1.0], (len(x), 1))
    E = compute_illuminance(scene, pts, nrm, DIRECT_ONLY).illuminance
    t = np.clip(np.arctan(x) / delta, -1.0, 1.0)
    expected = E_dn * (np.arccos(-t) + t * np.sqrt(1.0 - t * t)) / np.pi
    assert np.max(np.abs(E - expected)) < 0.01 * E_dn, np.max(np.abs(E - expected)) / E_dn

"""Direct light: the sun disk and light surfaces, by shadow rays."""

import numpy as np
import pytest

from lbl_illum import Options, compute_illuminance

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
    from lbl_illum.sun import SUN_SOLID_ANGLE
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

"""Luminaires from photometric files: per-sensor direct light against I(θ, φ) cos θ / d²,
in every orientation, their shadows, and their light through the cache.

The reference intensities come from the analytic distribution the test file was written
from, and the luminaire's frame from explicit rotation matrices, not from the engine's
frame construction.  Tolerance 1 % per sensor (the table's bilinear interpolation on 5° ×
2.5° steps is below 0.3 % for this distribution).
"""

import math

import numpy as np
import pytest

from lbl_illum import Options, compute_illuminance
from lbl_illum.errors import InputError
from lbl_illum.scene import scene_from_dict

from conftest import ies_text

DIRECT_ONLY = Options(bounces=0)
BLACK_FLOOR = {"shape": "rectangle", "origin": [-50, -50, 0], "u": [100, 0, 0], "v": [0, 100, 0],
               "material": "black"}
MATS = {"black": {"type": "diffuse", "reflectance": 0.0}}


def distribution(gamma, c):
    """An asymmetric distribution [cd] (γ from the nadir, C counter-clockwise from C0)."""
    g, cc = np.radians(gamma), np.radians(c)
    return 1000.0 * (1.1 + np.cos(g)) * (1.0 + 0.5 * np.cos(cc) + 0.3 * np.sin(2 * cc)) / 2.1


def write_ies(path):
    path.write_text(ies_text(distribution, np.arange(0, 360.1, 5)))
    return path


def rot_z(deg):
    a = math.radians(deg)
    return np.array([[math.cos(a), -math.sin(a), 0], [math.sin(a), math.cos(a), 0], [0, 0, 1.0]])


def rot_y(deg):
    a = math.radians(deg)
    return np.array([[math.cos(a), 0, math.sin(a)], [0, 1.0, 0], [-math.sin(a), 0, math.cos(a)]])


def reference(points, normals, position, to_world):
    """E [lux] = I(γ, C) cos θ / d², (γ, C) of the emission direction in the luminaire's
    frame, ``to_world`` the matrix taking that frame's vectors to the scene's."""
    w = points - position
    d = np.linalg.norm(w, axis=1)
    e = w / d[:, None]
    local = e @ to_world                     # to_world.T @ e for each row
    gamma = np.degrees(np.arccos(np.clip(-local[:, 2], -1, 1)))
    c = np.degrees(np.arctan2(local[:, 1], local[:, 0])) % 360
    cos = np.maximum(0.0, -np.einsum("ij,ij->i", normals, e))
    return distribution(gamma, c) * cos / d ** 2


def floor_sensors(n=9, half=2.5):
    g = np.linspace(-half, half, n)
    X, Y = np.meshgrid(g, g)
    return np.column_stack([X.ravel(), Y.ravel(), np.zeros(X.size)]), np.tile([0, 0, 1.0], (X.size, 1))


def _scene(tmp_path, entry, geometry=(BLACK_FLOOR,), materials=MATS):
    """A scene of ``geometry`` with one luminaire ``entry`` (lum.ies written beside it), no sky."""
    write_ies(tmp_path / "lum.ies")
    data = {"units": "m", "geometry": list(geometry), "materials": dict(materials), "sky": {"type": "none"},
            "luminaires": [entry]}
    return scene_from_dict(data, tmp_path, "test.toml")


@pytest.mark.parametrize("rotation", [0.0, 30.0, 90.0, 217.0])
def test_downlight_every_floor_sensor_in_every_rotation(tmp_path, rotation):
    """Aimed straight down at 2.8 m: C0 turned by ``rotation`` counter-clockwise from +x."""
    pos = np.array([0.3, -0.2, 2.8])
    scene = _scene(tmp_path, {"file": "lum.ies", "position": pos.tolist(), "rotation": rotation})
    pts, nrm = floor_sensors()
    E = compute_illuminance(scene, pts, nrm, DIRECT_ONLY).illuminance
    ref = reference(pts, nrm, pos, rot_z(rotation))
    assert np.abs(E / ref - 1).max() < 0.01


@pytest.mark.parametrize("rotation", [0.0, 45.0, 150.0])
def test_tilted_luminaire_on_floor_and_wall_sensors(tmp_path, rotation):
    """Aimed 35° from the nadir towards +x, then turned about its aim: the frame is the
    rotation about y that takes −z to the aim, times the turn about the aim.  Sensors on
    the floor and on a wall facing −x (its cosines differ from the floor's)."""
    pos = np.array([0.0, 0.0, 2.5])
    aim = [math.sin(math.radians(35)), 0.0, -math.cos(math.radians(35))]
    scene = _scene(tmp_path, {"file": "lum.ies", "position": pos.tolist(), "aim": aim, "rotation": rotation})
    to_world = rot_y(-35.0) @ rot_z(rotation)
    assert np.allclose(to_world @ [0, 0, -1.0], aim)
    pts, nrm = floor_sensors()
    wall = np.column_stack([np.full(25, 3.0), np.repeat(np.linspace(-2, 2, 5), 5), np.tile(np.linspace(0.2, 2.2, 5), 5)])
    wall_n = np.tile([-1.0, 0, 0], (25, 1))
    P, N = np.vstack([pts, wall]), np.vstack([nrm, wall_n])
    E = compute_illuminance(scene, P, N, DIRECT_ONLY).illuminance
    ref = reference(P, N, pos, to_world)
    assert np.abs(E / ref - 1).max() < 0.01


def test_uplight_has_c90_along_minus_y(tmp_path):
    """Aimed straight up: half a turn about x, so C0 stays along +x and C90 is along −y;
    sensors on a ceiling above it."""
    pos = np.array([0.0, 0.0, 1.0])
    scene = _scene(tmp_path, {"file": "lum.ies", "position": pos.tolist(), "aim": [0, 0, 1]})
    pts, _ = floor_sensors()
    pts[:, 2] = 3.0
    nrm = np.tile([0, 0, -1.0], (len(pts), 1))
    E = compute_illuminance(scene, pts, nrm, DIRECT_ONLY).illuminance
    ref = reference(pts, nrm, pos, np.diag([1.0, -1.0, -1.0]))
    assert np.abs(E / ref - 1).max() < 0.01


def test_multiplier_and_shadow_of_a_plate(tmp_path):
    """A plate at 1 m hides the luminaire from the sensors under it (0 lux, sharp: a point
    source); the others get multiplier × I cos θ / d²."""
    pos = np.array([0.0, 0.0, 2.0])
    plate = {"shape": "rectangle", "origin": [-0.5, -0.5, 1.0], "u": [1, 0, 0], "v": [0, 1, 0], "material": "black"}
    scene = _scene(tmp_path, {"file": "lum.ies", "position": pos.tolist(), "multiplier": 0.8}, [BLACK_FLOOR, plate])
    pts, nrm = floor_sensors()
    E = compute_illuminance(scene, pts, nrm, DIRECT_ONLY).illuminance
    ref = 0.8 * reference(pts, nrm, pos, np.eye(3))
    hidden = (np.abs(pts[:, 0]) < 0.5 * 2 - 1e-9) & (np.abs(pts[:, 1]) < 0.5 * 2 - 1e-9)   # plate's shadow: 1 m half-width
    assert hidden.sum() > 0 and np.all(E[hidden] == 0.0)
    assert np.abs(E[~hidden] / ref[~hidden] - 1).max() < 0.01


def test_light_of_a_luminaire_feeds_the_cache_in_a_sphere_room(tmp_path):
    """An isotropic 100 cd point at the centre of a hollow sphere R = 1 m, reflectance 0.5:
    the walls get I/R² directly and ρ times as much again at each bounce (uniform
    exitance, nothing absorbs inside), E = (I/R²)(1 − ρ^{N+1})/(1 − ρ) after N = 3 bounces.
    Every wall sensor within 1 %."""
    lines = ["IESNA:LM-63-2002", "TILT=NONE", "1 -1 1 2 1 1 2 0 0 0", "1 1 10", "0 180", "0", "100 100"]
    (tmp_path / "iso.ies").write_text("\n".join(lines) + "\n")
    R, rho, N = 1.0, 0.5, 3
    wall = {"shape": "sphere", "center": [0, 0, 0], "radius": R, "material": "wall"}
    scene = _scene(tmp_path, {"file": "iso.ies", "position": [0, 0, 0]}, [wall],
                   {"wall": {"type": "diffuse", "reflectance": rho}})
    k = np.arange(40) + 0.5
    z = 1 - 2 * k / 40
    phi = np.pi * (1 + 5 ** 0.5) * k
    u = np.column_stack([np.sqrt(1 - z * z) * np.cos(phi), np.sqrt(1 - z * z) * np.sin(phi), z])
    pts = (1 - 5e-4) * R * u
    result = compute_illuminance(scene, pts, -u, Options(accuracy=0.2, samples=128, bounces=N))
    E0 = 100.0 / np.sum(pts ** 2, axis=1)
    assert np.allclose(result.direct[:, 1], E0, rtol=1e-9)
    ref = E0 * (1 - rho ** (N + 1)) / (1 - rho)
    assert np.abs(result.illuminance / ref - 1).max() < 0.01


@pytest.mark.parametrize("entry,message", [
    ({"file": "lum.ies"}, "luminaires[0]: missing key 'position'"),
    ({"file": "lum.ies", "position": [0, 0, 2], "aimm": [0, 0, -1]}, "unknown key 'aimm' (did you mean 'aim'?)"),
    ({"file": "lum.ies", "position": [0, 0, 2], "multiplier": 0}, "'multiplier' must be > 0"),
    ({"file": "lum.ies", "position": [0, 0, 2], "aim": [0, 0, 0]}, "'aim' must be a non-zero direction"),
    ({"file": "other.ies", "position": [0, 0, 2]}, "other.ies: no such file"),
])
def test_bad_luminaire_entries(tmp_path, entry, message):
    with pytest.raises(InputError) as err:
        _scene(tmp_path, entry)
    assert message in str(err.value)


def test_a_luminaire_inside_a_wall_is_reported(tmp_path):
    """A wall luminaire placed 5 cm inside a 0.3 m thick wall, aimed out of it: most of its
    light meets the wall's face within 0.25 m, and the run says so; a downlight 1 cm under
    a ceiling gets no such note."""
    from lbl_illum import Integrator
    wall = {"shape": "box", "center": [-0.15, 0, 1.5], "size": [0.3, 4, 3], "material": "black"}
    entry = {"file": "lum.ies", "position": [-0.05, 0, 2.0], "aim": [1, 0, 0], "name": "W1"}
    notes = Integrator(_scene(tmp_path, entry, [BLACK_FLOOR, wall]), DIRECT_ONLY).portal_notes()
    assert any("luminaire 'W1' (lum.ies) at (-0.05, 0, 2) m:" in n and "of its light meets a surface within 0.25 m"
               in n for n in notes), notes
    ceiling = {"shape": "rectangle", "origin": [-3, -3, 2.8], "u": [6, 0, 0], "v": [0, 6, 0], "material": "black"}
    under = _scene(tmp_path, {"file": "lum.ies", "position": [0, 0, 2.79]}, [BLACK_FLOOR, ceiling])
    assert not any("luminaire" in n for n in Integrator(under, DIRECT_ONLY).portal_notes())


def test_cache_fingerprint_tells_luminous_openings_apart(tmp_path):
    """Two files that differ only in the luminous opening light a room differently (near
    field, images), so a cache file made with one is not reused with the other."""
    from lbl_illum.engine.fingerprint import scene_fingerprint

    prints = set()
    for dims in ((0, 0, 0), (0.6, 0.6, 0), (0.6, 1.2, 0), (-0.4, -0.4, 0)):
        folder = tmp_path / "x".join(f"{d:g}" for d in dims)
        folder.mkdir()
        (folder / "lum.ies").write_text(ies_text(distribution, np.arange(0, 360.1, 5), dims=dims))
        data = {"units": "m", "geometry": [BLACK_FLOOR], "materials": MATS, "sky": {"type": "none"},
                "luminaires": [{"file": "lum.ies", "position": [0, 0, 2.0]}]}
        prints.add(scene_fingerprint(scene_from_dict(data, folder, "test.toml"), Options()))
    assert len(prints) == 4

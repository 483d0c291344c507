"""Window portals (paper §5): the sky seen through a window sampled by area, combined
with hemisphere sampling by multiple importance sampling — unbiased and less noisy."""

import numpy as np
import pytest

from lbl_illum import Options, compute_illuminance

from conftest import make_scene

TAU = 0.8


def roof_light_room(portal: bool, opening=1.0):
    """A closed black 4 × 4 × 3 m room with a glass roof opening, under a uniform sky."""
    h = opening / 2
    walls = [
        {"shape": "rectangle", "origin": [-2, -2, 0], "u": [4, 0, 0], "v": [0, 4, 0], "material": "black"},
        {"shape": "rectangle", "origin": [-2, -2, 0], "u": [4, 0, 0], "v": [0, 0, 3], "material": "black"},
        {"shape": "rectangle", "origin": [-2, 2, 0], "u": [4, 0, 0], "v": [0, 0, 3], "material": "black"},
        {"shape": "rectangle", "origin": [-2, -2, 0], "u": [0, 4, 0], "v": [0, 0, 3], "material": "black"},
        {"shape": "rectangle", "origin": [2, -2, 0], "u": [0, 4, 0], "v": [0, 0, 3], "material": "black"},
        # roof around the opening
        {"shape": "rectangle", "origin": [-2, -2, 3], "u": [4, 0, 0], "v": [0, 2 - h, 0], "material": "black"},
        {"shape": "rectangle", "origin": [-2, h, 3], "u": [4, 0, 0], "v": [0, 2 - h, 0], "material": "black"},
        {"shape": "rectangle", "origin": [-2, -h, 3], "u": [2 - h, 0, 0], "v": [0, 2 * h, 0], "material": "black"},
        {"shape": "rectangle", "origin": [h, -h, 3], "u": [2 - h, 0, 0], "v": [0, 2 * h, 0], "material": "black"},
        {"shape": "rectangle", "origin": [-h, -h, 3], "u": [2 * h, 0, 0], "v": [0, 2 * h, 0], "material": "pane"},
    ]
    mats = {"black": {"type": "diffuse", "reflectance": 0.0},
            "pane": {"type": "glass", "transmittance": TAU, "reflectance": 0.0, "portal": portal}}
    return make_scene(walls, mats, sky={"type": "uniform", "horizontal_illuminance": 10000})


def sky_through_opening(points, opening=1.0, n=600):
    """Independent reference: τ L ∫ cos θ_r cos θ_p / d² dA over the opening (midpoint rule)."""
    L = 10000 / np.pi
    s = (np.arange(n) + 0.5) / n * opening - opening / 2
    X, Y = np.meshgrid(s, s)
    out = []
    for p in points:
        dx, dy, dz = X - p[0], Y - p[1], 3.0 - p[2]
        d2 = dx * dx + dy * dy + dz * dz
        out.append(TAU * L * np.sum(dz * dz / d2 ** 2) * (opening / n) ** 2)
    return np.array(out)


POINTS = np.array([[0.0, 0.0, 0.0], [1.2, 0.3, 0.0], [1.9, 1.9, 0.0], [0.0, 0.0, 2.5], [-1.5, 0.2, 1.0]])
UP = np.tile([0.0, 0.0, 1.0], (len(POINTS), 1))


def test_portal_matches_the_integral_over_the_opening():
    ref = sky_through_opening(POINTS)
    E = compute_illuminance(roof_light_room(True), POINTS, UP, Options(accuracy=0, samples=1024, bounces=0)).illuminance
    assert np.allclose(E, ref, rtol=0.01), (E, ref)


def test_portal_and_plain_sampling_agree_and_portal_is_less_noisy():
    opts = [Options(accuracy=0, samples=256, bounces=0, seed=s) for s in range(6)]
    runs = {p: np.array([compute_illuminance(roof_light_room(p), POINTS, UP, o).illuminance for o in opts])
            for p in (False, True)}
    ref = sky_through_opening(POINTS)
    spread = {p: np.mean(runs[p].std(axis=0) / ref) for p in runs}
    assert spread[True] < spread[False] / 3, spread
    # both unbiased: their means over seeds agree with the integral within their noise
    for p in runs:
        err = np.abs(runs[p].mean(axis=0) / ref - 1)
        assert np.all(err < 4 * runs[p].std(axis=0) / ref / np.sqrt(len(opts)) + 1e-3), (p, err)


def test_portal_through_the_cache_levels():
    """With interpolation and a bounce the portal still gives the sky component (black room)."""
    ref = sky_through_opening(POINTS[:3])
    E = compute_illuminance(roof_light_room(True), POINTS[:3], UP[:3],
                            Options(accuracy=0.1, samples=1024, bounces=1)).illuminance
    assert np.allclose(E, ref, rtol=0.02)


def test_portal_key_must_be_boolean():
    from lbl_illum import InputError
    from lbl_illum.materials import material_from_table

    with pytest.raises(InputError, match="portal"):
        material_from_table("g", {"type": "glass", "transmittance": 0.5, "portal": "yes"}, "s.toml: [materials.g]")


def test_known_light_gradient_limits_record_radius_near_a_window():
    """Under the roof light the floor's sky component falls off fast; the split sphere
    (R_0 from distances only) does not see it, the E/|∇E| limit of the known light does."""
    from lbl_illum.integrator import Integrator

    scene = roof_light_room(True)
    pts = np.array([[0.8, 0.0, 2.0]])                  # 1 m below the roof, beside the opening
    radii = {}
    for limit in (False, True):
        integ = Integrator(scene, Options(accuracy=0.1, samples=1024, bounces=0))
        integ.gradient_limit = limit
        integ.compute(pts, UP[:1])
        radii[limit] = float(integ.cache.levels[0].R[0])
    assert radii[True] < 0.7 * radii[False], radii
    # the limit: E / |dE/dx| of the integral over the opening, by central differences
    h = 0.01
    E = sky_through_opening(np.array([[0.8, 0, 2], [0.8 + h, 0, 2], [0.8 - h, 0, 2]]))
    expected = E[0] / abs((E[1] - E[2]) / (2 * h))         # 0.618 m; split sphere alone: 1.39 m
    assert radii[True] == pytest.approx(expected, rel=0.1)

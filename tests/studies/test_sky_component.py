"""The sky-component study: the tool's sky component through roof and façade openings
against an independent integral over the opening (the project's criterion: within 5 % at every sensor).

The reference integral is checked first against a closed form: for a sky of uniform
luminance L the illuminance through a polygonal opening is L times the projected solid
angle of the polygon, which Lambert's contour formula gives exactly.  The quick version
(two skies, two openings, five sensors each; about 5 s) runs once per module.
"""

import math

import numpy as np
import pytest

from lbl_illum.daylight.sky import UniformSky
from lbl_illum_studies import sky_component as sc
from lbl_illum_studies.report import StudyContext


def projected_solid_angle(point, normal, polygon) -> float:
    """Projected solid angle [sr] of a planar ``polygon`` (k, 3) seen from ``point`` by a
    surface of unit ``normal`` lying wholly in front of it: Lambert's contour formula,
    (1/2) |Σ_i θ_i n · (v_i × v_{i+1}) / |v_i × v_{i+1}||, v_i the vertices relative to the
    point and θ_i the angle between consecutive ones (Lambert 1760; e.g. Arvo 1995, Eq. 6)."""
    v = np.asarray(polygon, float) - np.asarray(point, float)
    v = v / np.linalg.norm(v, axis=1, keepdims=True)
    total = 0.0
    for a, b in zip(v, np.roll(v, -1, axis=0)):
        cross = np.cross(a, b)
        theta = math.atan2(np.linalg.norm(cross), float(a @ b))
        total += theta * float(np.asarray(normal) @ cross) / np.linalg.norm(cross)
    return abs(total) / 2.0


def corners(kind):
    o, u, v = sc.opening(kind)
    return np.array([o, o + u, o + u + v, o + v])


# -- the reference against closed forms ----------------------------------------------------------
def test_gauss_legendre_rule_has_the_area_and_integrates_polynomials():
    nodes, weights = sc.gauss_legendre_rectangle([1.0, 2.0, 3.0], [2.0, 0.0, 0.0], [0.0, 0.0, 1.5], 8)
    assert weights.sum() == pytest.approx(3.0, rel=1e-14)
    # ∫ x^5 z^7 over x ∈ [1, 3], z ∈ [3, 4.5]: degree 15 is exact with 8 nodes
    exact = (3 ** 6 - 1) / 6 * (4.5 ** 8 - 3 ** 8) / 8
    assert np.sum(weights * nodes[:, 0] ** 5 * nodes[:, 2] ** 7) == pytest.approx(exact, rel=1e-12)


@pytest.mark.parametrize("kind", ["roof 1 m", "roof 4 m", "façade"])
def test_reference_integral_of_a_uniform_sky_is_lamberts_contour_formula(kind):
    """Every sensor of the study, a uniform sky: E = L · projected solid angle within 1e-9."""
    sky = UniformSky(horizontal_illuminance=math.pi * 1000.0, ground_reflectance=0.0)   # L = 1000 cd/m²
    P, N, _ = sc.sensors(kind)
    o, u, v = sc.opening(kind)
    E = sc.opening_illuminance(sky, P, N, o, u, v, 64)
    exact = [1000.0 * projected_solid_angle(p, n, corners(kind)) for p, n in zip(P, N)]
    assert E == pytest.approx(exact, rel=1e-9)


def test_reference_below_a_corner_is_the_parallel_rectangle_view_factor():
    """A point 3 m below the corner of a 2 × 1 m horizontal rectangle: E = π L F with
    F = (1/2π) [X/√(1+X²) atan(Y/√(1+X²)) + Y/√(1+Y²) atan(X/√(1+Y²))], X = a/c, Y = b/c
    (Howell's catalogue, B-2)."""
    sky = UniformSky(horizontal_illuminance=math.pi, ground_reflectance=0.0)        # L = 1
    X, Y = 2.0 / 3.0, 1.0 / 3.0
    F = (X / math.sqrt(1 + X * X) * math.atan(Y / math.sqrt(1 + X * X))
         + Y / math.sqrt(1 + Y * Y) * math.atan(X / math.sqrt(1 + Y * Y))) / (2 * math.pi)
    E = sc.opening_illuminance(sky, np.zeros((1, 3)), np.array([[0.0, 0, 1]]), [0, 0, 3.0], [2.0, 0, 0],
                               [0, 1.0, 0], 32)
    assert E[0] == pytest.approx(math.pi * F, rel=1e-10)


@pytest.mark.parametrize("sky", ["cie-overcast", 1, 12, 15])
def test_midpoint_rule_gives_the_skys_horizontal_illuminance(sky):
    scene = sc.room("roof 1 m", sky)
    assert sc.horizontal_illuminance(scene.sky) == pytest.approx(sc.E_H, rel=2e-5)


def test_rooms_are_black_and_portals_cover_the_openings():
    for kind in ("roof 1 m", "roof 4 m", "façade"):
        scene = sc.room(kind, 12)
        assert all(m.kind == "diffuse" and np.all(np.asarray(m.reflectance) == 0.0) for m in scene.materials)
        assert scene.sky.ground_luminance == 0.0
        assert scene.sun.direct_normal_illuminance == 0.0
        assert (scene.sun.altitude, scene.sun.azimuth) == pytest.approx(sc.SUN)
        o, u, v = sc.opening(kind)
        area = np.linalg.norm(np.cross(u, v))
        portal_area = sum(np.linalg.norm(np.cross(t[1] - t[0], t[2] - t[0])) / 2 for t in scene.portals)
        assert portal_area == pytest.approx(area, rel=1e-12)
        assert len(sc.room(kind, 12, portal=False).portals) == 0


# -- the quick study ------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def results():
    return sc.run(StudyContext(quick=True)).results


def test_quick_study_within_five_percent_at_every_sensor(results):
    assert len(results["runs"]) == 4
    for run in results["runs"]:
        err = np.asarray(run["error"])
        assert np.all(np.abs(err) <= sc.TOLERANCE), (run["opening"], run["label"], err)
        assert run["max_error"] == pytest.approx(float(np.max(np.abs(err))))
    assert results["passed"]


def test_quick_study_includes_sensors_beside_the_edges_and_outside_the_projection(results):
    labels = {s for run in results["runs"] for s in run["sensors"]}
    assert {"5 cm inside the east edge", "5 cm outside the east edge",
            "5 cm outside the west jamb's plane, 1 m in"} <= labels
    roof = next(r for r in results["runs"] if r["opening"] == "roof 1 m")
    o, u, v = sc.opening("roof 1 m")
    P = np.asarray(roof["points"])
    outside = (P[:, 0] < o[0]) | (P[:, 0] > o[0] + u[0]) | (P[:, 1] < o[1]) | (P[:, 1] > o[1] + v[1])
    assert outside.sum() >= 2


def test_quick_study_reference_is_converged(results):
    assert results["reference"]["quadrature_error_max"] < 1e-6
    assert results["reference"]["e_h_midpoint_error_max"] < 2e-5

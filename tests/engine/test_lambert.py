"""Lambert's formula for window portals (lbl_illum.engine.lambert): irradiance, gradient and Hessian
in closed form against a quadrature of the window and central differences of it."""

from __future__ import annotations

import numpy as np
import pytest

from lbl_illum.engine.hemisphere import orthonormal_basis
from lbl_illum.engine.lambert import portal_irradiance

# a 1.2 x 0.8 m window in the plane y = 0 (its outward normal -y: the sky lies at y < 0)
X0, X1, Z0, Z1 = -0.6, 0.6, 0.4, 1.2
WINDOW = np.array([[[X0, 0, Z0], [X1, 0, Z0], [X1, 0, Z1]], [[X0, 0, Z0], [X1, 0, Z1], [X0, 0, Z1]]], float)
OUT = np.array([[0.0, -1.0, 0.0]] * 2)


def quadrature(point, normal, n=500):
    """Irradiance [lux] from the window at luminance 1 by the midpoint rule over its area,
    with cos at the receiver clipped at 0 (the part below its horizon gives nothing)."""
    x = X0 + (np.arange(n) + 0.5) / n * (X1 - X0)
    z = Z0 + (np.arange(n) + 0.5) / n * (Z1 - Z0)
    X, Z = np.meshgrid(x, z)
    d = np.stack([X - point[0], -point[1] * np.ones_like(X), Z - point[2]], -1)
    r = np.linalg.norm(d, axis=-1)
    cos_r = np.maximum(d @ normal / r, 0.0)
    cos_w = np.abs(d[..., 1]) / r
    return float((cos_r * cos_w / r ** 2).sum() * (X1 - X0) * (Z1 - Z0) / n / n)


RECEIVERS = [
    ([0.2, 1.5, 0.0], [0, 0, 1]),            # a floor point, the window wholly above its horizon
    ([0.9, 0.8, 0.8], [0, 0, 1]),            # a desk at sill height: the window half below its horizon
    ([-1.5, 2.0, 1.0], [1, 0, 0]),           # a side wall facing the room
    ([0.1, 3.0, 2.2], [0, -0.6, -0.8]),      # a tilted ceiling point looking down at the window
]


def terms(point, normal):
    p = np.array([point], float)
    n = np.array([normal], float)
    n /= np.linalg.norm(n)
    return portal_irradiance(p, n, orthonormal_basis(n), WINDOW, np.ones(2), OUT)[0], n[0]


@pytest.mark.parametrize("point, normal", RECEIVERS)
def test_irradiance_matches_the_quadrature(point, normal):
    t, n = terms(point, normal)
    assert t[0] == pytest.approx(quadrature(np.array(point, float), n), rel=2e-4)


@pytest.mark.parametrize("point, normal", RECEIVERS)
def test_gradient_and_hessian_match_central_differences(point, normal):
    t, n = terms(point, normal)
    tan, bit = (v[0] for v in orthonormal_basis(n[None]))
    h = 1e-3
    p = np.array(point, float)

    def E(q):
        return terms(q, n)[0][0]

    grad = [(E(p + h * u) - E(p - h * u)) / (2 * h) for u in (tan, bit)]
    assert t[1:3] == pytest.approx(grad, rel=1e-4, abs=1e-6 * abs(t[0]))
    hess_tt = (E(p + h * tan) - 2 * E(p) + E(p - h * tan)) / h ** 2
    hess_bb = (E(p + h * bit) - 2 * E(p) + E(p - h * bit)) / h ** 2
    hess_tb = (E(p + h * (tan + bit)) - E(p + h * (tan - bit)) - E(p - h * (tan - bit)) + E(p - h * (tan + bit))) / (4 * h * h)
    assert [t[3], t[4], t[5]] == pytest.approx([hess_tt, hess_tb, hess_bb], rel=2e-3, abs=1e-4 * abs(t[0]))


def test_points_in_front_of_a_window_get_nothing_from_it():
    """Outside, on the sky side, the window is no source: E and its derivatives are 0."""
    t, _ = terms([0.0, -2.0, 0.5], [0, 1, 0])
    assert np.all(t == 0.0)
    inside, _ = terms([0.0, 2.0, 0.5], [0, -1, 0])
    assert inside[0] > 0.0


def test_luminance_scales_each_triangle():
    p, n = np.array([[0.2, 1.5, 0.0]]), np.array([[0.0, 0.0, 1.0]])
    one = portal_irradiance(p, n, orthonormal_basis(n), WINDOW, np.array([1.0, 0.0]), OUT)[0]
    two = portal_irradiance(p, n, orthonormal_basis(n), WINDOW, np.array([0.0, 3.0]), OUT)[0]
    both = portal_irradiance(p, n, orthonormal_basis(n), WINDOW, np.array([1.0, 3.0]), OUT)[0]
    assert both == pytest.approx(one + two, rel=1e-12)

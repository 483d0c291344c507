"""Eq. 2: stratified sampling of the projected hemisphere."""

import numpy as np
import pytest

from lbl_illum.hemisphere import cell_counts, orthonormal_basis, stratified_directions


def test_basis_is_orthonormal_for_every_normal_including_poles():
    rng = np.random.default_rng(1)
    n = rng.normal(size=(500, 3))
    n = np.vstack([n, [[0, 0, 1], [0, 0, -1], [1, 0, 0], [0, -1e-12, -1]]])
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    t, s = orthonormal_basis(n)
    for a, b in ((t, s), (t, n), (s, n)):
        assert np.abs(np.einsum("ij,ij->i", a, b)).max() < 1e-12
    for a in (t, s):
        assert np.allclose(np.linalg.norm(a, axis=1), 1.0)
    assert np.allclose(np.einsum("ij,ij->i", np.cross(t, s), n), 1.0)


@pytest.mark.parametrize("samples, expected", [(1, (1, 1)), (4, (1, 4)), (1024, (18, 57)), (65536, (144, 455))])
def test_cell_counts_make_roughly_square_cells(samples, expected):
    m, n = cell_counts(samples)
    assert (m, n) == expected
    assert abs(m * n - samples) / samples < 0.1


def test_every_cell_gets_one_direction_in_the_upper_hemisphere():
    rng = np.random.default_rng(2)
    normal = np.array([[0.3, -0.4, 0.866]])
    normal /= np.linalg.norm(normal)
    m, n = 6, 19
    d = stratified_directions(normal, m, n, rng)[0]
    assert d.shape == (m * n, 3)
    assert np.allclose(np.linalg.norm(d, axis=1), 1.0)
    cos = d @ normal[0]
    assert cos.min() > 0.0
    # cell j holds sin²θ in ((j-1)/m, j/m]: equal projected solid angle per row
    sin2 = 1.0 - cos ** 2
    rows = np.ceil(sin2 * m).astype(int).reshape(m, n)
    assert np.all(rows == np.arange(1, m + 1)[:, None])


def test_estimator_integrates_cosine_power_exactly_enough():
    """∫ cos^k θ dE-measure: π/(M N) Σ cos^k → 2π/(k+2) (analytic), k = 2."""
    rng = np.random.default_rng(3)
    d = stratified_directions(np.array([[0.0, 0.0, 1.0]]), 18, 57, rng)[0]
    estimate = np.pi / len(d) * np.sum(d[:, 2] ** 2)
    assert estimate == pytest.approx(2 * np.pi / 4, rel=2e-3)

"""Record sizing (lbl_illum.engine.sizing): the light limit of the records' radii."""

import numpy as np
import pytest

from lbl_illum.engine.hemisphere import stratified_directions
from lbl_illum.engine.sizing import known_gradient_limit


def test_known_gradient_limit_skips_unlit_records_and_keeps_the_lit_ones():
    """Records whose rays found no light at trace time get no limit (∞) without their
    gradients being computed; a lit record's limit does not depend on the unlit ones
    traced with it."""
    m, n = 4, 12
    rng = np.random.default_rng(3)
    normals = np.array([[0.0, 0.0, 1.0], [0.0, 0.6, 0.8], [1.0, 0.0, 0.0]])
    dirs = stratified_directions(normals, m, n, rng).reshape(-1, 3)
    t = rng.uniform(0.5, 5.0, len(dirs))
    radiance = np.repeat(rng.uniform(0.0, 100.0, (len(dirs), 1)), 3, axis=1)
    radiance[m * n: 2 * m * n] = 0.0                      # the second record saw nothing
    both = known_gradient_limit(normals, dirs, radiance, t, m, n)
    assert np.isinf(both[1]) and np.all(np.isfinite(both[[0, 2]]))
    for i in (0, 2):
        alone = known_gradient_limit(normals[i:i + 1], dirs[i * m * n:(i + 1) * m * n],
                                     radiance[i * m * n:(i + 1) * m * n], t[i * m * n:(i + 1) * m * n], m, n)
        assert alone[0] == pytest.approx(both[i], rel=1e-12)
    dark = known_gradient_limit(normals, dirs, np.zeros_like(radiance), t, m, n)
    assert np.all(np.isinf(dark))

"""The path follower's policies (lbl_illum.engine.paths): where grids and images differ.

A ray straight through a pane of τ = 0.6 (constant, ρ = thin_pane_reflectance(0.6)) onto
a light surface of luminance 100 cd/m² behind it, under a black sky:

* camera rays split at the pane and see the light through it: L = 100 τ exactly;
* hemisphere rays choose a branch and leave a light met through glass to the direct
  step (§5): L = 0 whichever branch they take;
* a light met after a reflection counts for both.
"""

import numpy as np
import pytest

from lbl_illum.engine.context import LightingContext
from lbl_illum.engine.paths import CAMERA, HEMISPHERE, follow_paths
from lbl_illum.scene.materials import thin_pane_reflectance

from conftest import make_scene

MATS = {"pane": {"type": "glass", "transmittance": 0.6, "model": "constant"},
        "lamp": {"type": "light", "luminance": 100.0},
        "mirror": {"type": "mirror", "reflectance": 0.5}}


def _scene(front):
    pane = {"shape": "rectangle", "origin": [-5, -5, 1.0], "u": [10, 0, 0], "v": [0, 10, 0], "material": front}
    lamp = {"shape": "rectangle", "origin": [-5, -5, 2.0], "u": [10, 0, 0], "v": [0, 10, 0], "material": "lamp"}
    under = {"shape": "rectangle", "origin": [-5, -5, -1.0], "u": [10, 0, 0], "v": [0, 10, 0], "material": "lamp"}
    return LightingContext.of(make_scene([pane, lamp, under], MATS, sky={"type": "uniform", "zenith_luminance": 0.0}))


def test_camera_rays_split_at_glass_and_see_emitters_through_it():
    context = _scene("pane")
    n = 64
    o, d = np.zeros((n, 3)), np.tile([0.0, 0.0, 1.0], (n, 1))
    cam = follow_paths(context, o, d, np.random.default_rng(1), CAMERA)
    # reflected branch goes down to the lamp below: 100 ρ; transmitted: 100 τ
    np.testing.assert_allclose(cam.radiance, 100.0 * (0.6 + thin_pane_reflectance(0.6)), rtol=1e-12)
    assert cam.rays == 3 * n                                      # camera rays, then both branches
    hemi = follow_paths(context, o, d, np.random.default_rng(1), HEMISPHERE)
    assert hemi.rays == 2 * n                                     # one branch each
    # transmitted branches see nothing (the direct step's light); reflected ones see the
    # lamp below after a reflection, weighted (p_t + p_r)/p_r · ρ = ρ + τ
    reflected = hemi.radiance[:, 0] > 0
    assert 0 < reflected.sum() < n
    np.testing.assert_allclose(hemi.radiance[reflected], 100.0 * (0.6 + thin_pane_reflectance(0.6)), rtol=1e-12)


def test_emitters_after_a_mirror_count_for_both_policies():
    context = _scene("mirror")
    o, d = np.zeros((4, 3)), np.tile([0.0, 0.0, 1.0], (4, 1))
    for policy in (CAMERA, HEMISPHERE):
        paths = follow_paths(context, o, d, np.random.default_rng(2), policy)
        np.testing.assert_allclose(paths.radiance, 50.0, rtol=1e-12)
        assert paths.first_t == pytest.approx([1.0] * 4)

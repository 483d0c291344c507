"""Annual glare (lbl_illum.glare.annual): the DGP of every hour with the sun and the bright
sky patches as sources, against the formula evaluated source by source, and the sky
patches' solid angles seen from an eye against their exact values."""

from __future__ import annotations

import math

import numpy as np
import pytest

from lbl_illum.daylight.skymatrix import sky_patches
from lbl_illum.daylight.sun import SUN_SOLID_ANGLE
from lbl_illum.engine.integrator import Integrator
from lbl_illum.glare.annual import (AnnualGlare, PatchVisibility, annual_glare, patch_visibility,
                                    simplified_dgp)
from lbl_illum.glare.metrics import _view_angles, daylight_glare_probability, position_index
from lbl_illum.options import Options
from lbl_illum.scene.views import view_from_string

from conftest import make_scene, GROUND


def test_simplified_dgp():
    assert simplified_dgp([0.0, 1000.0, 20000.0]) == pytest.approx([0.184, 0.24620, 1.0])


def _hour_by_hand(ev, L, visibility, sun=None):
    """DGP of one hour from the formula, source by source."""
    lum, omega, pos = [], [], []
    for p in range(len(L)):
        if L[p] * visibility.transmittance[p] >= 2000.0 and visibility.solid_angle[p] > 0:
            lum.append(L[p] * visibility.transmittance[p])
            omega.append(visibility.solid_angle[p])
            pos.append(visibility.position[p])
    if sun is not None:
        lum.append(sun[0])
        omega.append(SUN_SOLID_ANGLE)
        pos.append(sun[1])
    return daylight_glare_probability(ev, lum, omega, pos)


def test_dgp_of_every_hour_is_the_formula_source_by_source():
    rng = np.random.default_rng(2)
    view = view_from_string("-vta -vp 0 0 1.2 -vd 0 -1 0 -vu 0 0 1 -vh 180 -vv 180")
    P, H = 146, 40
    visibility = PatchVisibility(solid_angle=np.where(rng.random(P) < 0.3, rng.uniform(0.001, 0.04, P), 0.0),
                                 transmittance=rng.uniform(0.4, 0.7, P), position=rng.uniform(1.0, 8.0, P))
    L = rng.uniform(0.0, 9000.0, (P, H))
    ev = rng.uniform(200.0, 8000.0, H)
    sun = np.tile([0.0, -0.8, 0.6], (H, 1))
    sun /= np.linalg.norm(sun, axis=1, keepdims=True)
    e_dn = np.full(H, 60000.0)
    at_eye = np.where(np.arange(H) % 3 == 0, 30000.0, 0.0)          # the sun seen in every third hour
    g = annual_glare(ev, L, sun, e_dn, at_eye, view, visibility)
    cos = float(sun[0] @ view.unit_direction)
    sigma, tau, above = _view_angles(sun[:1], view)
    p_sun = float(position_index(sigma, tau, above)[0])
    for h in range(H):
        seen = (at_eye[h] / (cos * SUN_SOLID_ANGLE), p_sun) if at_eye[h] > 0 else None
        assert g.dgp[h] == pytest.approx(_hour_by_hand(ev[h], L[:, h], visibility, seen), rel=1e-9)
        assert g.sun_in_view[h] == (at_eye[h] > 0)
    assert g.dgps == pytest.approx(simplified_dgp(ev))


def test_summary_shares_and_en17037():
    g = AnnualGlare(ev=np.ones(100), dgp=np.r_[np.full(90, 0.3), np.full(5, 0.38), np.full(5, 0.5)],
                    dgps=np.full(100, 0.2), sun_in_view=np.zeros(100, bool), sources=np.zeros(100, int))
    s = g.summary(np.ones(100))
    assert s["dgp"]["classes"] == {"imperceptible": 90.0, "perceptible": 5.0, "disturbing": 0.0, "intolerable": 5.0}
    assert s["dgp"]["glare_autonomy"] == 95.0
    assert s["dgp"]["dgp_exceeded_in_5_percent"] == pytest.approx(0.38) and s["dgp"]["en17037"] == "medium"
    assert s["dgps"]["en17037"] == "high"


def test_patch_solid_angles_from_an_open_eye():
    """Over an open ground, an eye looking up sees every sky patch whole (Σ = 2π) and the
    ground glow not at all; looking north it sees the half of the sky in front of it."""
    scene = make_scene([GROUND], {"ground": {"type": "diffuse", "reflectance": 0.2}},
                       sky={"type": "uniform", "horizontal_illuminance": 10000.0})
    integ = Integrator(scene, Options(bounces=0))
    patches = sky_patches(1)
    eye = np.array([0.0, 0.0, 1.5])
    up = patch_visibility(integ.direct, integ.tracer, eye, view_from_string("-vta -vd 0 0 1 -vu 0 1 0"), patches)
    np.testing.assert_allclose(up.solid_angle[1:], patches.solid_angles[1:], rtol=1e-12)
    assert up.solid_angle[0] == 0.0
    np.testing.assert_allclose(up.transmittance[1:], 1.0, rtol=1e-12)
    north = patch_visibility(integ.direct, integ.tracer, eye, view_from_string("-vta -vd 0 1 0"), patches)
    assert north.solid_angle[1:].sum() == pytest.approx(math.pi, rel=0.02)
    assert north.solid_angle[0] == 0.0             # the ground plane hides the ground glow

"""Direct sun at sensors for every hour: the closed form in the open, and the point-in-time
direct step (which samples the sun's disk) behind the office's window."""

import numpy as np

from lbl_illum import load_scene, read_points
from lbl_illum.engine.integrator import Integrator
from lbl_illum.engine.sun_hours import direct_sun_matrix
from lbl_illum.options import Options
from lbl_illum.photometry import luminance

from conftest import ROOT, horizontal


def _suns(altitude_deg, azimuth_deg):
    alt, az = np.radians(altitude_deg), np.radians(azimuth_deg)
    return np.column_stack([np.cos(alt) * np.sin(az), np.cos(alt) * np.cos(az), np.sin(alt)])


def test_open_ground_gets_the_closed_form_and_night_and_backs_get_nothing(open_ground):
    """Horizontal sensors on an open ground: E_dn sin(altitude) exactly; the sun below the
    horizon, an hour without direct light and sensors facing down: 0."""
    integ = Integrator(open_ground(), Options(accuracy=0.2, samples=16, bounces=1))
    points, normals = horizontal(5, z=0.0)
    normals[4] = [0.0, 0.0, -1.0]
    alt = np.array([5.0, 30.0, 60.0, 89.0, -3.0, 40.0])
    e_dn = np.array([20000.0, 60000.0, 80000.0, 90000.0, 50000.0, 0.0])
    E = direct_sun_matrix(integ.direct, integ.tracer, points, normals, _suns(alt, [90, 135, 180, 225, 180, 200]), e_dn)
    assert E.shape == (5, 6) and E.dtype == np.float32
    expect = e_dn[:4] * np.sin(np.radians(alt[:4]))
    np.testing.assert_allclose(E[:4, :4], np.tile(expect, (4, 1)), rtol=1e-6)
    assert not E[:, 4:].any() and not E[4].any()


def test_behind_the_window_it_matches_the_point_in_time_direct_step():
    """The office under its clear sky and sun: at every grid point the point-in-time direct
    sun (16 jittered rays over the disk, 1,024 in penumbrae; τ(θ) of the glass) equals
    E_dn cos θ T(s) within 0.2 % where the disk is wholly seen or wholly hidden; the few
    penumbra points lie between 0 and the unshaded value."""
    scene = load_scene(ROOT / "examples" / "office" / "office_clear_sky.toml")
    points, normals = read_points(ROOT / "examples" / "office" / "grid.pts", scene.unit_scale)
    integ = Integrator(scene, Options(accuracy=0.2, samples=16, bounces=1))
    sun = scene.sun
    E = direct_sun_matrix(integ.direct, integ.tracer, points, normals, sun.direction[None], [sun.direct_normal_illuminance])[:, 0]
    lit = integ.direct
    saved, lit.mirrors = lit.mirrors, None            # the sun's images are not direct sun
    try:
        ref = luminance(lit.illuminance(points, normals, normals, np.random.default_rng(1), light_samples=16,
                                        origins=integ.tracer.sensor_origins(points, normals)))
    finally:
        lit.mirrors = saved
    full = sun.direct_normal_illuminance * np.clip(normals @ sun.direction, 0, None)
    inside = E > 0
    assert 5 < inside.sum() < len(E)                  # some sensors in the sun patch, some not
    penumbra = (ref > 1e-3 * full) & (ref < 0.999 * E.max())
    whole = ~penumbra
    np.testing.assert_allclose(E[whole], ref[whole], rtol=2e-3, atol=1e-3)
    assert penumbra.sum() <= 0.15 * len(E)
    assert np.all(ref[penumbra] <= full[penumbra] + 1e-6)

"""Sky models (DESIGN.md §2) and the Eq. 2 sampler under them, through the engine."""

import numpy as np
import pytest

from lbl_illum import Options, compute_illuminance
from lbl_illum.sky import CIEOvercastSky, NoSky, UniformSky, sky_from_table
from lbl_illum.errors import InputError

from conftest import horizontal


def _integrate_horizontal(sky, n=400):
    """Independent midpoint-rule ∫ L cos θ dω over the upper hemisphere."""
    alt = (np.arange(n) + 0.5) * (np.pi / 2) / n
    d = np.column_stack([np.cos(alt), np.zeros(n), np.sin(alt)])
    L = sky.luminance(d)[:, 0]
    return float(np.sum(L * np.sin(alt) * np.cos(alt)) * (np.pi / 2 / n) * 2 * np.pi)


@pytest.mark.parametrize("cls", [UniformSky, CIEOvercastSky])
def test_sky_models_integrate_to_their_horizontal_illuminance(cls):
    sky = cls(horizontal_illuminance=12345.0)
    assert _integrate_horizontal(sky) == pytest.approx(12345.0, rel=1e-4)


def test_cie_overcast_zenith_is_three_times_the_horizon():
    sky = CIEOvercastSky(horizontal_illuminance=10000.0)
    zen, hor = sky.luminance(np.array([[0, 0, 1.0], [1, 0, 0.0]]))[:, 0]
    assert zen == pytest.approx(3 * hor)
    assert zen == pytest.approx(9 * 10000 / (7 * np.pi))


def test_ground_glow_follows_gensky_convention():
    sky = UniformSky(horizontal_illuminance=10000.0, ground_reflectance=0.2, sun_horizontal_illuminance=5000.0)
    L = sky.luminance(np.array([[0, 0, -1.0]]))
    assert np.allclose(L, 0.2 * 15000 / np.pi)
    assert NoSky().is_dark


def test_sky_table_rejects_unknown_type_and_keys():
    with pytest.raises(InputError, match="cie-overcast"):
        sky_from_table({"type": "cie-overcst"}, "s.toml: [sky]")
    with pytest.raises(InputError, match="did you mean 'horizontal_illuminance'"):
        sky_from_table({"type": "uniform", "horizontal_iluminance": 1}, "s.toml: [sky]")


def test_uniform_sky_gives_pi_L_on_an_unobstructed_sensor(open_ground):
    scene = open_ground(sky={"type": "uniform", "horizontal_illuminance": 10000})
    pts, nrm = horizontal(3)
    E = compute_illuminance(scene, pts, nrm, Options(bounces=0)).illuminance
    assert np.allclose(E, 10000.0, rtol=1e-9)


@pytest.mark.parametrize("samples", [64, 1024])
def test_cie_overcast_unobstructed_horizontal_illuminance_within_one_percent(open_ground, samples):
    scene = open_ground(sky={"type": "cie-overcast", "horizontal_illuminance": 8000})
    pts, nrm = horizontal(5)
    E = compute_illuminance(scene, pts, nrm, Options(bounces=0, samples=samples, accuracy=0)).illuminance
    assert np.abs(E / 8000.0 - 1.0).max() < 0.01

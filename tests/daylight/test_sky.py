"""Sky models (docs/design.md §2) and the Eq. 2 sampler under them, through the engine."""

import numpy as np
import pytest

from lbl_illum import Options, compute_illuminance
from lbl_illum.daylight.sky import CIEOvercastSky, NoSky, UniformSky, sky_from_table
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


# -- CIE standard general sky, Perez all-weather sky ------------------------------------------
import math

from lbl_illum.daylight.sky import (
    CIE_GENERAL_SKY_TYPES, HEMISPHERE_RULE, SKY_ALIASES, CIEGeneralSky, PerezSky, hemisphere_integral,
    perez_coefficients, perez_from_illuminance, perez_from_irradiance, perez_sky, sun_vector,
)

SUNS = [(3.0, 80.0), (35.0, 200.0), (75.0, 135.0)]


def independent_horizontal(sky, n_alt=240, n_az=480):
    """∫ L cos Z dω by the midpoint rule in altitude and azimuth (not the model's own rule)."""
    alt = (np.arange(n_alt) + 0.5) * (np.pi / 2 / n_alt)
    az = (np.arange(n_az) + 0.5) * (2 * np.pi / n_az)
    A, Z = np.meshgrid(alt, az, indexing="ij")
    d = np.stack([np.cos(A) * np.sin(Z), np.cos(A) * np.cos(Z), np.sin(A)], axis=-1).reshape(-1, 3)
    L = sky.luminance(d)[:, 0].reshape(n_alt, n_az)
    return float(np.sum(L * np.sin(A) * np.cos(A)) * (np.pi / 2 / n_alt) * (2 * np.pi / n_az))


def expint_e3(x):
    """E_3(x) = (e^−x (1 − x) + x² E_1(x)) / 2 with the series E_1(x) = −γ − ln x − Σ (−x)^k / (k k!)."""
    e1 = -0.5772156649015329 - math.log(x) - sum((-x) ** k / (k * math.factorial(k)) for k in range(1, 40))
    return 0.5 * (math.exp(-x) * (1 - x) + x * x * e1)


@pytest.mark.parametrize("sky_type", sorted(CIE_GENERAL_SKY_TYPES))
def test_cie_general_skies_integrate_to_their_horizontal_illuminance(sky_type):
    """All 15 types, three suns: an independent midpoint rule finds E_h within 0.1 %
    (measured: largest 2.7e-5)."""
    for alt, az in SUNS:
        sky = CIEGeneralSky(horizontal_illuminance=25000.0, sky_type=sky_type, sun_altitude=alt, sun_azimuth=az)
        assert independent_horizontal(sky) == pytest.approx(25000.0, rel=1e-3)
        # the model's own rule against one four times finer: well under 0.1 %
        finer = (4 * HEMISPHERE_RULE[0], 4 * HEMISPHERE_RULE[1])
        assert hemisphere_integral(sky.sky_luminance, finer) == pytest.approx(25000.0, rel=1e-4)


@pytest.mark.parametrize("sky_type", [1, 3, 5])
def test_azimuthally_uniform_types_against_the_closed_form(sky_type):
    """Types 1, 3, 5 (c = e = 0): E_h / L_z = 2π (1/2 + a E_3(−b)) / (1 + a e^b), since
    ∫_0^1 μ exp(b/μ) dμ = E_3(−b) (substitute t = 1/μ).  No sun is needed."""
    a, b = CIE_GENERAL_SKY_TYPES[sky_type][:2]
    exact = 2 * math.pi * (0.5 + a * expint_e3(-b)) / (1 + a * math.exp(b))
    sky = CIEGeneralSky.from_zenith_luminance(1000.0, sky_type=sky_type)
    assert sky.horizontal_illuminance == pytest.approx(1000.0 * exact, rel=1e-6)
    assert sky.luminance(np.array([[0, 0, 1.0]]))[0, 0] == pytest.approx(1000.0, rel=1e-12)
    if sky_type == 5:
        assert exact == pytest.approx(math.pi)
    if sky_type == 1:
        # CIE type 1 is close to the traditional overcast sky: horizon/zenith ≈ 1/3, E_h/L_z ≈ 7π/9
        horizon = sky.luminance(np.array([[1.0, 0, 0]]))[0, 0]
        assert horizon / 1000.0 == pytest.approx(1 / 3, rel=0.01)
        assert exact == pytest.approx(7 * math.pi / 9, rel=0.01)


def test_cie_general_gradation_indicatrix_and_horizon():
    """φ(90°) = 1 exactly; φ falls from zenith to horizon for a > 0 (overcast types), is flat for
    a = 0 and rises for a < 0 (clear types); f falls from the sun to 90° away from it."""
    cz = np.cos(np.radians(np.linspace(0, 90, 181)))
    chi = np.cos(np.radians(np.linspace(0, 90, 181)))
    for t, (a, b, c, d, e, _) in CIE_GENERAL_SKY_TYPES.items():
        sky = CIEGeneralSky(horizontal_illuminance=1.0, sky_type=t, sun_altitude=30.0, sun_azimuth=0.0)
        phi = sky.gradation(cz)
        assert phi[-1] == 1.0
        steps = np.diff(phi)
        strict = steps[:150]                     # Z < 75°: below that exp(b / cos Z) underflows towards 0
        if a > 0:
            assert np.all(strict < 0) and np.all(steps <= 0)
        elif a == 0:
            assert np.all(steps == 0)
        else:
            assert np.all(strict > 0) and np.all(steps >= 0)
        assert np.all(np.diff(sky.indicatrix(chi)) <= 1e-15)
        # the exported luminance is exactly this product, scaled
        d_ = np.array([[np.sin(0.3), 0.0, np.cos(0.3)]])
        expect = sky.luminance_scale * sky.gradation(d_[:, 2]) * sky.indicatrix(d_ @ sun_vector(30.0, 0.0))
        assert sky.luminance(d_)[0, 0] == pytest.approx(expect[0], rel=1e-12)


@pytest.mark.parametrize("model", ["cie", "perez"])
def test_symmetric_about_the_solar_meridian(model):
    """L(α_s + δ) = L(α_s − δ) at every altitude, and the circumsolar sky is brighter than the
    anti-solar sky for the clear types."""
    az_s = 137.0
    if model == "cie":
        sky = CIEGeneralSky(horizontal_illuminance=10000.0, sky_type=12, sun_altitude=40.0, sun_azimuth=az_s)
    else:
        sky = perez_sky(700.0, 100.0, (40.0, az_s), irradiance=True)
    rng = np.random.default_rng(5)
    alt, delta = rng.uniform(0, 90, 500), rng.uniform(0, 180, 500)
    left = sky.luminance(np.stack([sun_vector(a, az_s - d) for a, d in zip(alt, delta)]))
    right = sky.luminance(np.stack([sun_vector(a, az_s + d) for a, d in zip(alt, delta)]))
    assert np.allclose(left, right, rtol=1e-12)
    near, far = sky.luminance(np.stack([sun_vector(40.0, az_s + 10.0), sun_vector(40.0, az_s + 180.0)]))[:, 0]
    assert near > 2 * far


def test_aliases_and_table():
    for name, t in SKY_ALIASES.items():
        sky = sky_from_table({"type": name, "horizontal_illuminance": 5000}, "s.toml: [sky]", sun_position=(30, 90))
        assert isinstance(sky, CIEGeneralSky) and sky.sky_type == t and sky.horizontal_illuminance == 5000
    assert SKY_ALIASES == {"cie-clear": 12, "cie-intermediate": 7}
    sky = sky_from_table({"type": "cie-general", "sky_type": 13, "zenith_luminance": 4000}, "s.toml: [sky]",
                         sun_position=(50, 180))
    assert sky.zenith_luminance == pytest.approx(4000.0) and sky.luminance(np.array([[0, 0, 1.0]]))[0, 0] == \
        pytest.approx(4000.0)
    assert sky_from_table({"type": "cie-overcast", "zenith_luminance": 900}, "w").horizontal_illuminance == \
        pytest.approx(700 * math.pi)
    assert sky_from_table({"type": "uniform", "zenith_luminance": 900}, "w").horizontal_illuminance == \
        pytest.approx(900 * math.pi)
    # types 1, 3, 5 need no sun; the others do
    assert sky_from_table({"type": "cie-general", "sky_type": 3}, "w").sun_direction is None


@pytest.mark.parametrize("table, message", [
    ({"type": "cie-general", "sky_type": 16}, r"^s.toml: \[sky\]: 'sky_type' must be a whole number 1…15, got 16$"),
    ({"type": "cie-general", "sky_type": 2.5}, r"'sky_type' must be a whole number"),
    ({"type": "cie-general", "sky_type": True}, r"'sky_type' must be a whole number"),
    ({"type": "cie-general"}, r"^s.toml: \[sky\]: type 'cie-general' needs 'sky_type'"),
    ({"type": "cie-clear", "sky_type": 12}, r"unknown key 'sky_type'"),
    ({"type": "cie-general", "sky_type": 12, "horizontal_illuminance": 1, "zenith_luminance": 1}, r"not both"),
    ({"type": "perez", "direct_normal_illuminance": 1}, r"needs 'direct_normal_illuminance' and "
                                                        r"'diffuse_horizontal_illuminance' \(missing key"),
    ({"type": "perez", "direct_normal_illuminance": 1, "diffuse_horizontal_irradiance": 1}, r"not both"),
    ({"type": "perez", "direct_normal_irradiance": 500, "diffuse_horizontal_irradiance": 0}, r"must be > 0"),
])
def test_sky_table_errors(table, message):
    with pytest.raises(InputError, match=message) as exc:
        sky_from_table(table, "s.toml: [sky]", sun_position=(30, 180))
    assert "\n" not in str(exc.value)


def test_sun_dependent_sky_without_sun_is_an_error():
    with pytest.raises(InputError, match=r"type 12 needs the sun's position"):
        sky_from_table({"type": "cie-clear"}, "s.toml: [sky]")
    with pytest.raises(InputError, match=r"'perez' needs the sun's position"):
        sky_from_table({"type": "perez", "direct_normal_illuminance": 1, "diffuse_horizontal_illuminance": 1}, "w")


NAN, INF = float("nan"), float("inf")
PEREZ_W = {"type": "perez", "direct_normal_irradiance": 600, "diffuse_horizontal_irradiance": 120}
PEREZ_LUX = {"type": "perez", "direct_normal_illuminance": 60000, "diffuse_horizontal_illuminance": 15000}


@pytest.mark.parametrize("table, message", [
    # non-finite values, each refused naming its key
    ({"type": "cie-general", "sky_type": NAN}, r"'sky_type' must be a whole number 1…15, got nan$"),
    ({"type": "cie-general", "sky_type": -INF}, r"'sky_type' must be a whole number 1…15, got -inf$"),
    ({"type": "cie-overcast", "horizontal_illuminance": NAN}, r"'horizontal_illuminance' must be finite, got nan$"),
    ({"type": "uniform", "zenith_luminance": INF}, r"'zenith_luminance' must be finite, got inf$"),
    ({"type": "cie-overcast", "ground_reflectance": NAN}, r"'ground_reflectance' must be finite"),
    ({**PEREZ_W, "direct_normal_irradiance": NAN}, r"'direct_normal_irradiance' must be finite, got nan$"),
    ({**PEREZ_W, "diffuse_horizontal_irradiance": INF}, r"'diffuse_horizontal_irradiance' must be finite"),
    ({**PEREZ_LUX, "diffuse_horizontal_illuminance": -INF}, r"'diffuse_horizontal_illuminance' must be finite"),
    ({**PEREZ_W, "dew_point": NAN}, r"'dew_point' must be finite, got nan$"),
    # out of range
    ({"type": "cie-overcast", "horizontal_illuminance": -1}, r"'horizontal_illuminance' must be >= 0, got -1$"),
    ({"type": "cie-overcast", "ground_reflectance": 1.5}, r"'ground_reflectance' must be <= 1, got 1.5$"),
    ({"type": "cie-general", "sky_type": 0}, r"'sky_type' must be a whole number 1…15, got 0$"),
    ({**PEREZ_W, "direct_normal_irradiance": -5}, r"'direct_normal_irradiance' must be >= 0, got -5$"),
    ({**PEREZ_W, "dew_point": 60}, r"'dew_point' must be <= 40, got 60$"),
    # more than reaches the top of the atmosphere (1367 W/m2 and 133 334 lx times 1.0351)
    ({**PEREZ_W, "direct_normal_irradiance": 1416},
     r"'direct_normal_irradiance' 1416 W/m2 is more than reaches the top of the atmosphere \(1414.98 W/m2 at the "
     r"Sun's nearest\)$"),
    ({**PEREZ_W, "diffuse_horizontal_irradiance": 2000}, r"'diffuse_horizontal_irradiance' 2000 W/m2 is more than"),
    ({**PEREZ_LUX, "direct_normal_illuminance": 140000}, r"'direct_normal_illuminance' 140000 lux is more than "
                                                         r"reaches the top of the atmosphere \(138014 lux"),
    ({**PEREZ_LUX, "diffuse_horizontal_illuminance": 1e300}, r"'diffuse_horizontal_illuminance' 1e\+300 lux is more"),
    # values the model cannot take, refused naming the keys
    ({**PEREZ_W, "diffuse_horizontal_irradiance": 5e-324},
     r"clearness must be a finite number, got inf; from 'direct_normal_irradiance' 600 and "
     r"'diffuse_horizontal_irradiance' 4.94066e-324$"),
    ({**PEREZ_LUX, "diffuse_horizontal_illuminance": 5e-324},
     r"no Perez sky \(ZeroDivisionError\); from 'direct_normal_illuminance' 60000"),
    # finite values whose sky would not be
    ({"type": "uniform", "zenith_luminance": 1e308}, r"'zenith_luminance' 1e\+308 is too large"),
    ({"type": "cie-clear", "zenith_luminance": 1e308}, r"'zenith_luminance' 1e\+308 is too large"),
])
def test_sky_values_must_be_finite_and_in_range(table, message):
    with pytest.raises(InputError, match=r"^s.toml: \[sky\]: .*" + message) as exc:
        sky_from_table(table, "s.toml: [sky]", sun_position=(30, 180))
    assert "\n" not in str(exc.value)


def test_perez_values_up_to_the_extraterrestrial_ones_are_accepted():
    """The bounds are those of sunlight above the atmosphere, not tighter: 1414 W/m² and
    138 000 lx direct normal (a clear sky at high altitude reaches about 1100 W/m²) pass."""
    from lbl_illum.daylight.sky import MAX_EXTRATERRESTRIAL_ILLUMINANCE, MAX_EXTRATERRESTRIAL_IRRADIANCE

    assert MAX_EXTRATERRESTRIAL_IRRADIANCE == pytest.approx(1367 * 1.0351)
    assert MAX_EXTRATERRESTRIAL_ILLUMINANCE == pytest.approx(133334 * 1.0351)
    sky = sky_from_table({**PEREZ_W, "direct_normal_irradiance": 1414}, "w", sun_position=(60, 180))
    assert sky.direct_normal_illuminance > 0 and sky.horizontal_illuminance > 0
    sky = sky_from_table({**PEREZ_LUX, "direct_normal_illuminance": 138000}, "w", sun_position=(60, 180))
    assert sky.direct_normal_illuminance == pytest.approx(138000, rel=1e-6)


@pytest.mark.parametrize("position, message", [
    ((NAN, 180), r"the sun's altitude and azimuth must be finite, got nan, 180$"),
    ((30, INF), r"the sun's altitude and azimuth must be finite, got 30, inf$"),
    ((91, 0), r"the sun's altitude must be within -90 and 90 degrees, got 91$"),
    (("high", 0), r"the sun's position must be \(altitude, azimuth\) in degrees"),
])
def test_sky_refuses_a_sun_position_that_is_not_one(position, message):
    with pytest.raises(InputError, match=r"^s.toml: \[sky\]: " + message):
        sky_from_table({"type": "cie-clear"}, "s.toml: [sky]", sun_position=position)


@pytest.mark.parametrize("make, message", [
    (lambda: UniformSky(horizontal_illuminance=NAN), r"horizontal_illuminance must be a finite number, got nan"),
    (lambda: CIEOvercastSky(horizontal_illuminance=-1.0), r"horizontal_illuminance must be >= 0, got -1"),
    (lambda: UniformSky(ground_reflectance=1.2), r"ground_reflectance must be within 0 and 1, got 1.2"),
    (lambda: UniformSky(sun_horizontal_illuminance=INF), r"sun_horizontal_illuminance must be a finite number"),
    (lambda: CIEGeneralSky(horizontal_illuminance=1e4, sky_type=12, sun_altitude=NAN, sun_azimuth=0.0),
     r"sun_altitude must be a finite number, got nan"),
    (lambda: CIEGeneralSky(horizontal_illuminance=1e4, sky_type=12, sun_altitude=30.0, sun_azimuth=INF),
     r"sun_azimuth must be a finite number, got inf"),
    (lambda: PerezSky(horizontal_illuminance=1e4, clearness=INF), r"clearness must be a finite number, got inf"),
    (lambda: PerezSky(horizontal_illuminance=1e4, clearness=0.5), r"clearness must be >= 1, got 0.5"),
    (lambda: PerezSky(horizontal_illuminance=1e4, brightness=NAN), r"brightness must be a finite number, got nan"),
    (lambda: PerezSky(horizontal_illuminance=1e4, sun_altitude=120.0), r"sun_altitude must be within -90 and 90"),
    (lambda: PerezSky(horizontal_illuminance=1e4, direct_normal_illuminance=-1.0),
     r"direct_normal_illuminance must be >= 0, got -1"),
])
def test_sky_objects_refuse_values_out_of_range(make, message):
    """The models made directly (library use, weather files) check their fields too."""
    with pytest.raises(ValueError, match=message):
        make()


# Radiance 6.0a ``gendaylit`` (version 2.5, 2018/04/18), the reference implementation of the Perez
# (1993) sky: ``gendaylit -ang ALT 0 -P EPSILON DELTA`` prints a…e as the 3rd–7th real arguments
# of ``skyfunc``.  One case per clearness bin (two in bin 2: the Δ ≥ 0.2 floor of bins 2–5).
GENDAYLIT_P = [
    # altitude, ε, Δ, a, b, c, d, e
    (30, 1.03, 0.12, 0.869933, -0.628953, 0.395438, -0.347678, -0.038612),
    (50, 1.1, 0.1, -1.324783, -0.834497, 8.371089, -2.275681, 0.205685),
    (50, 1.1, 0.3, -1.106397, -1.161856, 9.007209, -2.446261, 0.153870),
    (20, 1.4, 0.25, -1.178700, -0.708806, 9.957633, -2.960401, 0.114604),
    (60, 1.8, 0.3, -0.865169, -0.893514, 13.262453, -3.138170, 0.261874),
    (45, 2.5, 0.15, -1.014863, -0.514322, 14.077688, -3.278168, 0.029915),
    (35, 3.5, 0.2, -0.896575, -0.345998, 13.060946, -3.417024, 0.285650),
    (70, 5.0, 0.15, -0.944063, -0.213000, 17.341265, -3.919707, 0.623558),
    (40, 7.5, 0.12, -0.936066, -0.130486, 18.673943, -5.210489, 1.221014),
    (10, 10, 0.08, -0.935467, -0.101065, 13.312944, -5.528079, 0.814228),
]


@pytest.mark.parametrize("row", GENDAYLIT_P)
def test_perez_coefficients_against_gendaylit(row):
    """Perez, Seals & Michalsky (1993) Table 1 as evaluated by gendaylit (printed to 6 decimals;
    gendaylit keeps the table in single precision)."""
    alt, eps, delta, *coef = row
    assert perez_coefficients(eps, delta, 90.0 - alt) == pytest.approx(coef, abs=3e-6)


def test_perez_clearness_brightness_and_efficacy_against_gendaylit():
    """``gendaylit 3 1 12 -a 40 -o 105 -m 105 -W 500 150`` (1 March, W = 2 cm): sun at
    z = 0.664175, ε = 3.0491, Δ = 0.1618; its -O 2 / -O 1 outputs give the direct normal
    efficacy 7.289e8 cd/m² · 2π(1 − cos 0.2665°) / 500 W/m² = 99.08 lm/W and the diffuse one
    7.114e3 / 4.990e1 = 142.6 lm/W."""
    zenith = 90.0 - math.degrees(math.asin(0.664175))
    dew = (math.log(2.0) + 0.075) / 0.07                       # W = 2 cm, gendaylit's default
    p = perez_from_irradiance(500.0, 150.0, zenith, day=60, dew_point=dew)
    assert p.clearness == pytest.approx(3.0491, abs=1e-4)
    assert p.brightness == pytest.approx(0.1618, abs=1e-4)
    k_dir = 7.289e8 * 2 * math.pi * (1 - math.cos(math.radians(0.2665))) / 500.0
    assert p.direct_normal_illuminance / 500.0 == pytest.approx(k_dir, rel=1e-3)
    assert p.diffuse_horizontal_illuminance / 150.0 == pytest.approx(7.114e3 / 4.990e1, rel=2e-3)
    # from those illuminances back to the same ε and Δ
    q = perez_from_illuminance(p.direct_normal_illuminance, p.diffuse_horizontal_illuminance, zenith, day=60,
                               dew_point=dew)
    assert (q.clearness, q.brightness) == pytest.approx((p.clearness, p.brightness), rel=1e-6)
    assert (q.direct_normal_irradiance, q.diffuse_horizontal_irradiance) == pytest.approx((500.0, 150.0), rel=1e-6)


@pytest.mark.parametrize("alt, eps, delta", [(5, 1.02, 0.3), (30, 1.2, 0.1), (45, 1.7, 0.3), (60, 2.2, 0.25),
                                             (20, 3.0, 0.2), (70, 5.0, 0.15), (35, 8.0, 0.12), (80, 12.0, 0.1)])
def test_perez_skies_integrate_to_the_diffuse_illuminance(alt, eps, delta):
    """One case per clearness bin; the independent rule agrees within 0.1 % (measured 1.7e-5)."""
    sky = PerezSky(horizontal_illuminance=18000.0, sun_altitude=alt, sun_azimuth=250.0, clearness=eps,
                   brightness=delta)
    assert independent_horizontal(sky) == pytest.approx(18000.0, rel=1e-3)
    assert np.all(sky.luminance(np.array([[0, 0, 1.0], [1, 0, 0], [0.6, 0, 0.8]])) >= 0)


def test_perez_out_of_range_is_a_clear_error():
    with pytest.raises(InputError, match=r"^s.toml: \[sky\]: the Perez distribution .* negative everywhere"):
        sky_from_table({"type": "perez", "direct_normal_irradiance": 170, "diffuse_horizontal_irradiance": 68},
                       "s.toml: [sky]", sun_position=(89.5, 180))     # ε = 3.5, Δ = 0.05: outside the fit


@pytest.mark.parametrize("sky", [
    {"type": "cie-clear", "horizontal_illuminance": 20000},
    {"type": "cie-general", "sky_type": 9, "horizontal_illuminance": 20000},
    {"type": "perez", "direct_normal_illuminance": 60000, "diffuse_horizontal_illuminance": 20000},
])
def test_engine_sees_the_new_skies_horizontal_illuminance(open_ground, sky):
    """Through the integrator (Eq. 2 sampler, no bounces): E_h within 1 % on open ground,
    the sun's E_dn = 0 so the sky alone is measured (measured: 0.12 %, 0.04 %, 0.17 %)."""
    scene = open_ground(sky=sky, sun={"altitude": 40, "azimuth": 160, "direct_normal_illuminance": 0})
    pts, nrm = horizontal(5)
    E = compute_illuminance(scene, pts, nrm, Options(bounces=0, samples=2048, accuracy=0)).illuminance
    assert np.abs(E / scene.sky.horizontal_illuminance - 1.0).max() < 0.01


# -- a clear sky and sun from the sun's altitude and the turbidity, as gensky computes them --

def _clear_scene(sky, sun=None):
    from lbl_illum.scene import scene_from_dict

    data = {"geometry": [{"shape": "rectangle", "origin": [0, 0, 0], "u": [1, 0, 0], "v": [0, 1, 0],
                          "material": "m"}], "materials": {"m": {"type": "diffuse", "reflectance": 0.5}},
            "sky": sky, "sun": sun or {"altitude": 45, "azimuth": 180}}
    return scene_from_dict(data, ".", "s.toml")


def test_clear_sky_without_brightness_takes_gensky_s():
    """cie-clear with neither horizontal_illuminance nor zenith_luminance: gensky's zenith
    luminance 1000 [(1.376 T − 1.81) tan h + 0.38] cd/m² as Radiance renders it (× 179/203),
    and a [sun] without direct_normal_illuminance gensky's sun (× 179/208 over 0.5°)."""
    import math

    scene = _clear_scene({"type": "cie-clear"})
    formula = 1000.0 * ((1.376 * 2.45 - 1.81) * math.tan(math.radians(45)) + 0.38)        # 1941.2 cd/m²
    assert scene.sky.zenith_luminance == pytest.approx(formula * 179 / 203, rel=1e-12)
    omega = 2 * math.pi * (1 - math.cos(math.radians(0.25)))
    sun = 1.5e9 * (1.147 - 0.147 / math.sin(math.radians(45))) * 179 / 208
    assert scene.sun.direct_normal_illuminance == pytest.approx(sun * omega, rel=1e-12)
    hazy = _clear_scene({"type": "cie-clear", "turbidity": 6.0})
    assert hazy.sky.zenith_luminance > 2 * scene.sky.zenith_luminance
    given = _clear_scene({"type": "cie-clear", "horizontal_illuminance": 12000},
                         {"altitude": 45, "azimuth": 180, "direct_normal_illuminance": 70000})
    assert given.sky.horizontal_illuminance == 12000 and given.sun.direct_normal_illuminance == 70000


@pytest.mark.parametrize("sky, message", [
    ({"type": "cie-clear", "horizontal_illuminance": 9000, "turbidity": 3}, "'turbidity' sets the brightness"),
    ({"type": "cie-overcast", "turbidity": 3}, "'turbidity' sets the brightness"),
    ({"type": "cie-clear", "turbidity": 0.5}, "'turbidity'"),
])
def test_turbidity_only_where_it_sets_the_brightness(sky, message):
    with pytest.raises(InputError, match=message):
        _clear_scene(sky, {"altitude": 45, "azimuth": 180, "direct_normal_illuminance": 0})


def test_clear_sky_and_sun_match_radiance_gensky():
    """Radiance's own gensky at five altitudes and two turbidities: the zenith and solar
    radiance it writes (× 179 = what rtrace renders) within its four printed digits, and
    the sky's horizontal illuminance within 1.5 % (gensky's polynomial for it) plus the
    rounding of its printed ground level (one decimal)."""
    import math
    import subprocess

    from conftest import radiance_tool

    gensky = radiance_tool("gensky")
    if gensky is None:
        pytest.skip("Radiance (pyradiance) is not installed")
    for turbidity in (2.45, 4.0):
        for alt in (10.0, 30.0, 45.0, 60.0, 80.0):
            out = subprocess.run([gensky, "-ang", str(alt), "0", "+s", "-t", str(turbidity), "-g", "1"],
                                 capture_output=True, text=True, check=True).stdout.splitlines()
            solar = float(next(l for l in out if l.startswith("3 ")).split()[1])
            sky_args = next(l for l in out if l.startswith("7 ")).split()
            zenith = float(sky_args[2])
            ground = float(next(l for l in out if "Ground ambient level" in l).split()[-1])
            scene = _clear_scene({"type": "cie-clear", "turbidity": turbidity}, {"altitude": alt, "azimuth": 180})
            assert scene.sky.zenith_luminance / 179 == pytest.approx(zenith, rel=2e-3)
            omega = 2 * math.pi * (1 - math.cos(math.radians(0.25)))
            assert scene.sun.direct_normal_illuminance / omega / 179 == pytest.approx(solar, rel=2e-3)
            # the ground level gensky prints is zenith · normfactor, before the sun and ρ_g: E_h / (179 π)
            assert scene.sky.horizontal_illuminance == pytest.approx(179 * math.pi * ground,
                                                                     rel=0.015 + 0.05 / ground)

"""Photometric files (IES LM-63, EULUMDAT): tables, symmetries, units and bad input.

The files are written here from analytic intensity distributions, so every value read
back is checked against the function that made it, not against the reader's own table:
within 1 % (or 2 cd, 0.2 % of the peak, where a distribution falls to zero), the
bilinear interpolation's error on 5° × 2.5° steps.
"""

import math

import numpy as np
import pytest

from lbl_illum.errors import InputError
from lbl_illum.scene.photometric import FEET, read_photometry

from conftest import ies_text


def symmetric(gamma, c):
    """A distribution symmetric about both the C0–C180 and the C90–C270 planes [cd]."""
    return 800.0 * np.cos(np.radians(gamma) / 2) ** 2 * (1.0 + 0.4 * np.cos(np.radians(2 * c)))


def asymmetric(gamma, c):
    """No symmetry at all [cd]: stronger towards C0 and C60 than elsewhere."""
    g, cc = np.radians(gamma), np.radians(c)
    return 1000.0 * (1.1 + np.cos(g)) * (1.0 + 0.5 * np.cos(cc) + 0.3 * np.sin(2 * cc)) / 2.1


def write(tmp_path, name, text):
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


def directions(n=2000, seed=3):
    u = np.random.default_rng(seed).normal(size=(n, 3))
    return u / np.linalg.norm(u, axis=1, keepdims=True)


def angles_of(d):
    """(γ, C) [deg] of emission directions in the luminaire's frame (nadir −z, C0 +x, C90 +y)."""
    return np.degrees(np.arccos(-d[:, 2])), np.degrees(np.arctan2(d[:, 1], d[:, 0])) % 360


@pytest.mark.parametrize("horizontal", [np.arange(0, 90.1, 5), np.arange(0, 180.1, 5), np.arange(90, 270.1, 5),
                                        np.arange(0, 360.1, 5), np.arange(0, 355.1, 5)])
def test_ies_type_c_tables_and_their_symmetries_give_the_distribution(tmp_path, horizontal):
    """A quadrant, either half, the whole circle (closed at 360° or not): the same
    distribution (1 %: the bilinear interpolation of 5° × 2.5° steps)."""
    p = read_photometry(write(tmp_path, "a.ies", ies_text(symmetric, horizontal)))
    d = directions()
    g, c = angles_of(d)
    assert np.allclose(p.intensity(d), symmetric(g, c), rtol=0.01, atol=2.0)


def test_ies_full_table_of_an_asymmetric_luminaire_and_grid_values_exactly(tmp_path):
    p = read_photometry(write(tmp_path, "a.ies", ies_text(asymmetric, np.arange(0, 360.1, 5))))
    d = directions()
    g, c = angles_of(d)
    assert np.allclose(p.intensity(d), asymmetric(g, c), rtol=0.01, atol=2.0)
    # on the table's own angles the values are the file's
    G, C = np.radians([30.0, 90.0, 135.0]), np.radians([60.0, 185.0, 300.0])
    grid = np.column_stack([np.sin(G) * np.cos(C), np.sin(G) * np.sin(C), -np.cos(G)])
    assert np.allclose(p.intensity(grid), asymmetric(np.degrees(G), np.degrees(C)), rtol=1e-5)


def test_ies_rotationally_symmetric_downlight_is_dark_above_its_table(tmp_path):
    """One horizontal angle; vertical angles 0..90: nothing above the horizontal."""
    p = read_photometry(write(tmp_path, "a.ies", ies_text(symmetric, np.array([0.0]), np.arange(0, 90.1, 5))))
    d = directions()
    g, _ = angles_of(d)
    I = p.intensity(d)
    assert np.all(I[g > 90.0 + 1e-9] == 0.0)
    below = g < 90
    assert np.allclose(I[below], symmetric(g[below], 0.0), rtol=0.01, atol=2.0)
    assert p.symmetry == "axial"


def test_ies_multiplier_ballast_factor_and_feet(tmp_path):
    """I = candela × multiplier × ballast factor; luminous opening sizes in feet become metres."""
    text = ies_text(symmetric, np.array([0.0]), multiplier=2.5, ballast=0.9, units=1, dims=(2, 4, 0))
    p = read_photometry(write(tmp_path, "a.ies", text))
    down = np.array([[0.0, 0.0, -1.0]])
    assert p.intensity(down)[0] == pytest.approx(2.5 * 0.9 * symmetric(0.0, 0.0), rel=1e-9)
    assert p.opening.shape == "rectangle"
    assert (p.opening.width, p.opening.length) == pytest.approx((2 * FEET, 4 * FEET))


@pytest.mark.parametrize("dims,shape", [((0, 0, 0), "point"), ((0.6, 1.2, 0), "rectangle"), ((0.6, 1.2, 0.1), "box"),
                                        ((-0.2, -0.2, 0), "disk"), ((-0.2, 0, 0), "disk"),
                                        ((-0.2, -0.2, 0.3), "cylinder"), ((-0.2, -0.2, -0.2), "sphere")])
def test_ies_luminous_opening_shapes(tmp_path, dims, shape):
    p = read_photometry(write(tmp_path, "a.ies", ies_text(symmetric, np.array([0.0]), dims=dims)))
    assert p.opening.shape == shape


def test_flux_of_an_isotropic_source_is_four_pi_times_its_intensity(tmp_path):
    p = read_photometry(write(tmp_path, "a.ies", ies_text(lambda g, c: 100.0 + 0 * g, np.array([0.0]))))
    assert p.flux() == pytest.approx(400 * math.pi, rel=1e-4)


def test_ies_type_b_angles(tmp_path):
    """Type B: I(H, V) with H the plane's angle about x (atan2(−e_y, −e_z)) and V the angle
    in the plane (asin e_x), both −90..90; laterally symmetric when H starts at 0."""
    fn = lambda v, h: 500.0 * (1.5 + np.sin(np.radians(v))) * (1.2 + np.sin(np.radians(h)) / 2)   # noqa: E731
    H = np.arange(-90, 90.1, 5)
    V = np.arange(-90, 90.1, 2.5)
    p = read_photometry(write(tmp_path, "b.ies", ies_text(fn, H, V, ptype=2)))
    d = directions()
    front = d[:, 2] < -0.05
    d = d[front]
    h = np.degrees(np.arctan2(-d[:, 1], -d[:, 2]))
    v = np.degrees(np.arcsin(d[:, 0]))
    assert np.allclose(p.intensity(d), fn(v, h), rtol=0.01, atol=2.0)
    # lateral symmetry
    lateral = lambda v, h: fn(v, np.abs(h))           # noqa: E731
    q = read_photometry(write(tmp_path, "c.ies", ies_text(lateral, np.arange(0, 90.1, 5), V, ptype=2)))
    assert np.allclose(q.intensity(d), lateral(v, h), rtol=0.01, atol=2.0)


def test_ies_1995_latin1_and_commas(tmp_path):
    """An LM-63-1995 file with a Latin-1 degree sign in a keyword line and commas between numbers."""
    text = ies_text(symmetric, np.array([0.0]), version="IESNA:LM-63-1995").replace(
        "[MANUFAC] none", "[MANUFAC] 90\u00b0 optic")
    text = text.replace(" ", ",", 0)
    lines = text.splitlines()
    lines[6] = lines[6].replace(" ", ", ")
    path = tmp_path / "old.ies"
    path.write_bytes("\n".join(lines).encode("latin-1"))
    p = read_photometry(path)
    assert p.intensity(np.array([[0.0, 0.0, -1.0]]))[0] == pytest.approx(symmetric(0.0, 0.0))


def test_tilt_include_with_unit_factors_is_read(tmp_path):
    text = ies_text(symmetric, np.array([0.0]), tilt="TILT=INCLUDE\n1\n3\n0 45 90\n1 1 1")
    assert read_photometry(write(tmp_path, "a.ies", text)).symmetry == "axial"


@pytest.mark.parametrize("change,message", [
    (lambda t: t.replace("TILT=NONE", "TILT=lamp.tlt"), "line 4: TILT=lamp.tlt: a separate tilt file is not supported"),
    (lambda t: t.replace("TILT=NONE", "TILT=INCLUDE\n1\n2\n0 90\n1 0.8"), "line 8: TILT=INCLUDE with factors other than 1"),
    (lambda t: t.replace(" 1 2 0 0 0\n", " 3 2 0 0 0\n"), "line 5: photometric type 3 (type A) is not supported"),
    (lambda t: t.replace(" 1 2 0 0 0\n", " 1 5 0 0 0\n"), "line 5: units type must be 1 (feet) or 2 (metres)"),
    (lambda t: t.rsplit("\n", 2)[0] + "\n", "the file ends before a candela value"),
    (lambda t: t + "12\n", "unexpected '12' after the"),
    (lambda t: t.replace("TILT=NONE\n", ""), "no 'TILT=' line"),
    (lambda t: t.replace("TILT=NONE\n1 -1 ", "TILT=NONE\n1 0 "),
     "line 5: the lumens per lamp must be > 0, or -1 for absolute photometry, got 0"),
])
def test_ies_bad_files_name_the_file_and_line(tmp_path, change, message):
    text = change(ies_text(symmetric, np.array([0.0]), np.arange(0, 90.1, 10)))
    with pytest.raises(InputError, match="^bad.ies: ") as err:
        read_photometry(write(tmp_path, "bad.ies", text))
    assert message in str(err.value) and "\n" not in str(err.value)


def test_ies_negative_candela_names_its_line(tmp_path):
    text = ies_text(symmetric, np.array([0.0]), np.arange(0, 90.1, 10))
    lines = text.splitlines()
    lines[-1] = "-5 " + lines[-1].split(" ", 1)[1]
    with pytest.raises(InputError, match=rf"^bad.ies: line {len(lines)}: negative candela value -5"):
        read_photometry(write(tmp_path, "bad.ies", "\n".join(lines)))


def test_all_zero_table_is_refused(tmp_path):
    with pytest.raises(InputError, match="every intensity is zero"):
        read_photometry(write(tmp_path, "z.ies", ies_text(lambda g, c: 0 * g, np.array([0.0]))))


def test_missing_file(tmp_path):
    with pytest.raises(InputError, match="^none.ies: no such file"):
        read_photometry(tmp_path / "none.ies")


# -- EULUMDAT ---------------------------------------------------------------------------

def ldt_text(fn, isym, mc=24, ng=37, flux=2000.0, factor=1.0, lum=(600, 0, 0)):
    """An EULUMDAT file of ``fn`` (cd) at ``flux`` lm: intensities written in cd/klm."""
    c = np.arange(mc) * 360.0 / mc
    g = np.linspace(0, 180, ng)
    stored = {0: c, 1: c[:1], 2: c[: mc // 2 + 1], 3: c[mc // 4: mc // 4 + mc // 2 + 1], 4: c[: mc // 4 + 1]}[isym]
    lines = ["lbl_illum test", "1", str(isym), str(mc), f"{360 / mc:g}", str(ng), f"{180 / (ng - 1):g}", "report",
             "test luminaire", "T1", "t.ldt", "2026-12-04", "600", "0", "50", str(lum[0]), str(lum[1]), str(lum[2]),
             str(lum[2]), str(lum[2]), str(lum[2]), "100", "80", str(factor), "0", "1",
             "1", "LED", str(flux), "3000", "80", "20"]
    lines += ["0.5"] * 10
    lines += [f"{x:g}" for x in c] + [f"{x:g}" for x in g]
    for cc in stored:
        lines += [f"{v:.6g}" for v in fn(g, cc) * 1000.0 / flux / factor]
    return "\n".join(lines) + "\n"


@pytest.mark.parametrize("isym", [0, 1, 2, 3, 4])
def test_eulumdat_symmetries_give_the_distribution(tmp_path, isym):
    """Isym 0 (none), 1 (axial), 2 (C0–C180), 3 (C90–C270), 4 (both): each from a
    distribution with that symmetry, cd/klm × the lamps' flux / 1000, within 1 %."""
    fn = {0: asymmetric, 1: lambda g, c: symmetric(g, 0.0 * c),
          2: lambda g, c: symmetric(g, c) * (1 + 0.3 * np.cos(np.radians(c))),
          3: lambda g, c: symmetric(g, c) * (1 + 0.3 * np.sin(np.radians(c))), 4: symmetric}[isym]
    p = read_photometry(write(tmp_path, "a.ldt", ldt_text(fn, isym, mc=72, ng=73, factor=1.3)))
    d = directions()
    g, c = angles_of(d)
    assert np.allclose(p.intensity(d), fn(g, c), rtol=0.012, atol=2.0)


def test_eulumdat_luminous_area_in_mm_and_flux(tmp_path):
    p = read_photometry(write(tmp_path, "a.ldt", ldt_text(symmetric, 4, lum=(600, 300, 0))))
    assert (p.opening.shape, p.opening.length, p.opening.width) == ("rectangle", 0.6, 0.3)
    assert p.lamp_lumens == 2000.0
    assert read_photometry(write(tmp_path, "b.ldt", ldt_text(symmetric, 4, lum=(200, 0, 0)))).opening.shape == "disk"


@pytest.mark.parametrize("line,value,message", [
    (3, "7", "line 3: the symmetry indicator Isym must be 0..4, got 7"),
    (29, "0", "line 29: the lamps' flux must be > 0"),
    (24, "x", "line 24: the conversion factor must be a number, got 'x'"),
    (110, "-3", "line 110: negative intensity -3"),
])
def test_eulumdat_bad_files_name_the_line(tmp_path, line, value, message):
    lines = ldt_text(symmetric, 4).splitlines()
    lines[line - 1] = value
    with pytest.raises(InputError, match="^bad.ldt: ") as err:
        read_photometry(write(tmp_path, "bad.ldt", "\n".join(lines)))
    assert message in str(err.value)


def test_eulumdat_truncated(tmp_path):
    text = "\n".join(ldt_text(symmetric, 4).splitlines()[:60])
    with pytest.raises(InputError, match="^bad.ldt: line 60: the file ends before"):
        read_photometry(write(tmp_path, "bad.ldt", text))


def _with_header(text, lines):
    head, rest = text.split("\n", 1)
    return "\n".join([head, *lines]) + "\n" + rest


def test_unknown_ies_keywords_are_noted_with_their_lines(tmp_path):
    """LM-63-2002 keyword lines: standard keywords and user ones ('_') pass silently; an
    unknown keyword or a line that is none is passed over with a note naming the line."""
    text = _with_header(ies_text(lambda g, c: 100.0 + 0 * g, np.array([0.0])),
                        ["[LUMCAT] D-1", "[_OURS] anything", "[COLOUR] warm", "free text"])
    path = tmp_path / "k.ies"
    path.write_text(text)
    notes = read_photometry(path).notes
    assert notes == ("k.ies: line 4: unknown keyword [COLOUR] passed over (user keywords start with '_')",
                     "k.ies: line 5: not a [KEYWORD] line, passed over: 'free text'")
    # files of 1986 have free text before TILT=
    path.write_text(_with_header(ies_text(lambda g, c: 100.0 + 0 * g, np.array([0.0]), version="IESNA91"),
                                 ["free text"]))
    assert read_photometry(path).notes == ()


def test_keyword_notes_reach_the_scene_once_per_file(tmp_path):
    from lbl_illum.scene import scene_from_dict

    (tmp_path / "k.ies").write_text(_with_header(ies_text(lambda g, c: 100.0 + 0 * g, np.array([0.0])),
                                                 ["[COLOUR] warm"]))
    data = {"geometry": [{"shape": "rectangle", "origin": [0, 0, 0], "u": [1, 0, 0], "v": [0, 1, 0],
                          "material": "m"}], "materials": {"m": {"type": "diffuse", "reflectance": 0.5}},
            "sky": {"type": "none"},
            "luminaires": [{"file": "k.ies", "position": [0.5, 0.5, 2]}, {"file": "k.ies", "position": [0, 0, 2]}]}
    scene = scene_from_dict(data, tmp_path, "s.toml")
    assert [w for w in scene.warnings if "COLOUR" in w] == [
        "k.ies: line 2: unknown keyword [COLOUR] passed over (user keywords start with '_')"]

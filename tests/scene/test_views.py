"""Views: Radiance's option strings, .vf files and [views.NAME] tables, and the rays of
each projection checked against the closed forms of Radiance's image.c and, when
pyradiance is installed, against Radiance's own ``vwrays`` (same origins and
directions to 1e-9)."""

from __future__ import annotations

import math
import subprocess

import numpy as np
import pytest

from lbl_illum.errors import InputError
from lbl_illum.io.radiance import radiance_programs
from lbl_illum.scene.views import (View, sample_offsets, view_from_file, view_from_header, view_from_string,
                             view_from_table, view_lines, views_from_table)

EXAMPLE = "-vtv -vp 2 5.7 1.5 -vd 0 -1 -0.1 -vu 0 0 1 -vh 80 -vv 60"


def _vwrays():
    programs = radiance_programs()
    if programs is None:
        return None
    path = programs["root"] / "bin" / "vwrays" if programs["root"] else None
    if path is None or not path.is_file():
        import shutil
        found = shutil.which("vwrays")
        return found
    return str(path)


VWRAYS = _vwrays()
needs_vwrays = pytest.mark.skipif(VWRAYS is None, reason="Radiance's vwrays (pyradiance) is not installed")


def angle(a, b):
    a = np.asarray(a, float)
    b = np.asarray(b, float)
    c = np.sum(a * b, axis=-1) / (np.linalg.norm(a, axis=-1) * np.linalg.norm(b, axis=-1))
    return np.degrees(np.arccos(np.clip(c, -1, 1)))


# ---------------------------------------------------------------------------
# Parsing
# ---------------------------------------------------------------------------

def test_example_string():
    view = view_from_string(EXAMPLE)
    assert view.type == "v"
    assert view.position == (2.0, 5.7, 1.5)
    assert view.direction == (0.0, -1.0, -0.1)
    assert view.up == (0.0, 0.0, 1.0)
    assert (view.horizontal, view.vertical) == (80.0, 60.0)
    assert (view.shift, view.lift, view.fore, view.aft) == (0.0, 0.0, 0.0, 0.0)


def test_defaults_are_radiance_standard_view():
    view = view_from_string("-vta")
    assert view == View(type="a")
    assert view.position == (0, 0, 0) and view.direction == (0, 1, 0) and view.up == (0, 0, 1)
    assert view.horizontal == view.vertical == 45.0


@pytest.mark.parametrize("text", ["VIEW= " + EXAMPLE, "VIEW=" + EXAMPLE, "rvu " + EXAMPLE,
                                  "/usr/local/bin/rpict " + EXAMPLE, "  " + EXAMPLE + "\n"])
def test_prefixes(text):
    assert view_from_string(text) == view_from_string(EXAMPLE)


def test_later_options_win_and_all_options_parse():
    view = view_from_string("-vtv -vh 30 -vtl -vh 4 -vv 3 -vs 0.25 -vl -0.5 -vo 1 -va 9 -vp 1 2 3")
    assert view.type == "l" and view.horizontal == 4 and view.vertical == 3
    assert (view.shift, view.lift, view.fore, view.aft) == (0.25, -0.5, 1.0, 9.0)


@pytest.mark.parametrize("text, words", [
    ("-vtv -vp 1 2", "-vp needs 3 numbers"),
    ("-vtv -vh", "-vh needs a number"),
    ("-vtv -vh eighty", "-vh needs a number"),
    ("-vtv -vz 3", "unknown view option '-vz'"),
    ("-vtv 12", "unexpected '12'"),
    ("-vtq", "unknown view type"),
    ("-vts -vh 180", "planispheric"),
    ("-vtvv", "bad view type option"),
    ("-vtv -vd 0 0 0", "zero view direction"),
    ("-vtv -vd 0 0 1", "parallel to view direction"),
    ("-vtv -vh 180", "illegal horizontal view size"),
    ("-vth -vv 200", "illegal vertical view size"),
    ("-vta -vh 361", "illegal horizontal view size"),
    ("-vtv -vh 0", "illegal horizontal view size"),
    ("-vtv -vo 2 -va 1", "fore/aft"),
    ("-vtv -vp 1 nan 2", "finite"),
    ("", "no view options"),
])
def test_bad_strings(text, words):
    with pytest.raises(InputError) as err:
        view_from_string(text, where="--view")
    message = str(err.value)
    assert message.startswith("--view: ") and words in message and "\n" not in message


@pytest.mark.parametrize("text, message", [
    # each refusal names the option, with the limit where there is one
    ("-vtv -vh 180", r"illegal horizontal view size -vh 180 for a perspective view \(below 180 degrees\)$"),
    ("-vtv -vv 179.99999999", r"illegal vertical view size -vv 180 for a perspective view \(below 180 degrees\)$"),
    ("-vtv -vh -10", r"illegal horizontal view size -vh -10$"),
    ("-vtv -vv 0", r"illegal vertical view size -vv 0$"),
    ("-vta -vh 360.5", r"illegal horizontal view size -vh 360.5 for an angular fisheye view \(at most 360 degrees\)$"),
    ("-vth -vh 181", r"-vh 181 for a hemispherical fisheye view \(at most 180 degrees\)$"),
    ("-vtc -vh 361", r"-vh 361 for a cylindrical panorama view \(at most 360 degrees\)$"),
    ("-vtc -vv 180", r"-vv 180 for a cylindrical panorama view \(below 180 degrees\)$"),
    ("-vtl -vh 3e9 -vv 1", r"-vh 3e\+09 m for a parallel view \(beyond 2e\+09 m\)$"),
    ("-vtv -vo -1", r"illegal fore/aft clipping distances -vo -1 -va 0$"),
    ("-vtv -va -2", r"illegal fore/aft clipping distances -vo 0 -va -2$"),
    ("-vtv -vo 2e9", r"-vo \(fore\) 2e\+09 m is beyond 1e\+09 m$"),
    ("-vtv -vd 0 0 0", r"zero view direction \(-vd\)$"),
    ("-vtv -vu 0 0 0", r"zero view up vector \(-vu\)$"),
    ("-vtv -vd 0 0 -2 -vu 0 0 5", r"view up \(-vu\) parallel to view direction \(-vd\)$"),
    ("-vtv -vd 1 0 1e-9 -vu 1e3 0 0", r"view up \(-vu\) parallel to view direction \(-vd\)$"),
    ("-vtv -vp 2e9 0 0", r"-vp \(position\) 2e\+09 m is beyond ±1e\+09 m$"),
    ("-vtv -vs 1e7", r"-vs \(shift\) 1e\+07 image widths is beyond ±1e\+06$"),
    ("-vtv -vl -1e300", r"-vl \(lift\) -1e\+300 image heights is beyond ±1e\+06$"),
    ("-vtv -vd 0 inf 0", r"-vd needs finite numbers, got 'inf'$"),
    ("-vtv -va nan", r"-va needs finite numbers, got 'nan'$"),
])
def test_view_values_out_of_range_are_refused_naming_the_option(text, message):
    with pytest.raises(InputError, match=r"^--view: .*" + message) as err:
        view_from_string(text, where="--view")
    assert "\n" not in str(err.value)


@pytest.mark.parametrize("field, value, message", [
    ("position", (0.0, float("nan"), 1.0), r"^view: -vp \(position\) must be finite, got 0 nan 1$"),
    ("direction", (float("inf"), 0.0, 0.0), r"^view: -vd \(direction\) must be finite, got inf 0 0$"),
    ("up", (0.0, 0.0, float("-inf")), r"^view: -vu \(up\) must be finite"),
    ("horizontal", float("nan"), r"^view: -vh \(horizontal\) must be finite, got nan$"),
    ("fore", float("inf"), r"^view: -vo \(fore\) must be finite, got inf$"),
    ("shift", float("nan"), r"^view: -vs \(shift\) must be finite"),
])
def test_view_objects_name_the_field_that_is_not_finite(field, value, message):
    with pytest.raises(InputError, match=message):
        View(**{field: value})


@pytest.mark.parametrize("text", ["-vtv -vd 1e200 0 0", "-vtv -vd 1e-200 2e-200 0 -vu 0 0 1e-300",
                                  "-vtv -vd 1e308 1e308 1e308", "-vtv -vh 179.9999 -vs 1e6",
                                  "-vtc -vv 179.9999 -vl 1e6", "-vtl -vh 2e9 -vv 2e9 -vs 1e6 -vl -1e6",
                                  "-vta -vh 360 -vv 360 -vs 0.3"])
def test_extreme_legal_views_give_finite_unit_rays(text):
    """Vectors of any finite, non-zero size are directions (Radiance's would overflow or
    underflow |v|² at 1e±200), and offsets up to the limits keep every ray finite."""
    view = view_from_string(text)
    with np.errstate(all="raise"):
        origins, directions, valid = view.rays(5, 4)
    assert np.isfinite(origins).all() and np.isfinite(directions).all()
    assert np.allclose(np.linalg.norm(directions, axis=1), 1.0)
    big = view_from_string(text.replace("1e200", "1").replace("1e308 1e308 1e308", "1 1 1")
                           .replace("1e-200 2e-200 0 -vu 0 0 1e-300", "1 2 0 -vu 0 0 1"))
    assert np.allclose(view.unit_direction, big.unit_direction, rtol=0, atol=1e-15)


def test_rvu_vf_file(tmp_path):
    path = tmp_path / "desk.vf"
    path.write_text("rvu -vtv -vp 2 5.7 1.5 -vd 0 -1 -0.1 -vu 0 0 1 -vh 80 -vv 60 -vo 0 -va 0 -vs 0 -vl 0\n")
    assert view_from_file(path) == view_from_string(EXAMPLE)


def test_vf_options_spread_over_lines(tmp_path):
    path = tmp_path / "spread.vf"
    path.write_text("#?RADIANCE\nrpict -x 512 -y 512 -vtv -vp 2 5.7 1.5 -ab 2\n"
                    "some other header line -vh 10\nVIEW= -vd 0 -1 -0.1 -vh 80 -vv 60\n")
    view = view_from_file(path)
    assert view == view_from_string(EXAMPLE)
    assert view_lines(path.read_text()) == ["rpict -x 512 -y 512 -vtv -vp 2 5.7 1.5 -ab 2",
                                            "VIEW= -vd 0 -1 -0.1 -vh 80 -vv 60"]


def test_view_from_picture_header_stops_at_blank_line(tmp_path):
    path = tmp_path / "pic.hdr"
    path.write_bytes(b"#?RADIANCE\nVIEW= -vta -vh 180 -vv 180\nFORMAT=32-bit_rle_rgbe\n\n-Y 1 +X 1\n"
                     b"VIEW= -vtv\x00\x01")
    assert view_from_file(path) == View(type="a", horizontal=180, vertical=180)


def test_bad_view_files(tmp_path):
    with pytest.raises(InputError, match=r"^missing\.vf: no such view file$"):
        view_from_file(tmp_path / "missing.vf")
    empty = tmp_path / "empty.vf"
    empty.write_text("# nothing here\n")
    with pytest.raises(InputError, match=r"^empty\.vf: no view found"):
        view_from_file(empty)
    broken = tmp_path / "broken.vf"
    broken.write_text("rvu -vtv\nrvu -vp 1 2\n")
    with pytest.raises(InputError, match=r"^broken\.vf: line 2: -vp needs 3 numbers"):
        view_from_file(broken)
    assert view_from_header("no views\nhere", "x") is None


def test_toml_table_full():
    table = {"type": "fisheye", "position": [200, 300, 120], "direction": [0, 1, 0], "up": [0, 0, 1],
             "horizontal": 180, "vertical": 170, "shift": 0.1, "lift": -0.1, "fore": 10, "aft": 1000}
    view = view_from_table(table, "scene.toml: [views.glare]", unit_scale=0.01)
    assert view == View(type="a", position=(2, 3, 1.2), direction=(0, 1, 0), horizontal=180, vertical=170,
                        shift=0.1, lift=-0.1, fore=0.1, aft=10)


def test_toml_defaults_target_and_parallel_units():
    view = view_from_table({"position": [0, 0, 1.2], "target": [3, 4, 1.2]}, "v")
    assert view.type == "v" and view.horizontal == view.vertical == 45
    assert np.allclose(view.unit_direction, [0.6, 0.8, 0])
    fisheye = view_from_table({"type": "hemispherical", "position": [0, 0, 1], "direction": [0, 0, 1],
                               "up": [0, 1, 0]}, "v")
    assert fisheye.horizontal == fisheye.vertical == 180
    plan = view_from_table({"type": "parallel", "position": [500, 400, 1000], "direction": [0, 0, -1],
                            "up": [0, 1, 0], "horizontal": 1000, "vertical": 800}, "v", unit_scale=0.01)
    assert plan.horizontal == pytest.approx(10) and plan.vertical == pytest.approx(8)
    assert plan.position == pytest.approx((5, 4, 10))


def test_toml_radiance_string_and_all_views():
    views = views_from_table({"desk": {"radiance": EXAMPLE},
                              "door": {"position": [1, 1, 1.6], "direction": [1, 0, 0]}}, "scene.toml")
    assert list(views) == ["desk", "door"]
    assert views["desk"] == view_from_string(EXAMPLE)
    assert views_from_table(None, "scene.toml") == {}


@pytest.mark.parametrize("table, words", [
    ({"position": [0, 0, 1], "direction": [0, 1, 0], "horizontl": 60},
     "unknown key 'horizontl' (did you mean 'horizontal'?)"),
    ({"direction": [0, 1, 0]}, "missing key 'position'"),
    ({"position": [0, 0, 1]}, "give either 'direction' or 'target'"),
    ({"position": [0, 0, 1], "direction": [0, 1, 0], "target": [0, 2, 1]}, "give either"),
    ({"position": [0, 0, 1], "target": [0, 0, 1]}, "same point"),
    ({"type": "fish", "position": [0, 0, 1], "direction": [0, 1, 0]}, "'type' must be one of"),
    ({"type": "parallel", "position": [0, 0, 1], "direction": [0, 1, 0]}, "missing key 'horizontal'"),
    ({"position": [0, 0, 1], "direction": [0, 1, 0], "horizontal": 190}, "illegal horizontal view size"),
    ({"position": [0, 0, 1], "direction": [0, 1, 0], "horizontal": -5}, "'horizontal' must be > 0"),
    ({"position": [0, 0], "direction": [0, 1, 0]}, "'position' must be a list of 3 numbers"),
    ({"radiance": "-vtv -vh x"}, "'radiance': -vh needs a number"),
    ({"radiance": EXAMPLE, "up": [0, 0, 1]}, "remove 'up'"),
])
def test_bad_tables(table, words):
    with pytest.raises(InputError) as err:
        views_from_table({"desk": table}, "scene.toml")
    message = str(err.value)
    assert message.startswith("scene.toml: [views.desk]") and words in message and "\n" not in message


def test_to_radiance_round_trip():
    for text in (EXAMPLE, "-vta -vp 1.25 -3 0.5 -vd 1 0.3 0 -vh 180 -vv 180 -vo 0.1 -va 20 -vs 0.2 -vl -0.1",
                 "-vtl -vp 0.1 0.2 0.3 -vd 0 0 -1 -vu 0 1 0 -vh 12.5 -vv 1e-3"):
        view = view_from_string(text)
        line = view.to_radiance()
        assert line.startswith("VIEW= -vt")
        assert view_from_string(line) == view
    assert view_from_string(EXAMPLE).to_radiance() == (
        "VIEW= -vtv -vp 2 5.7 1.5 -vd 0 -1 -0.1 -vu 0 0 1 -vh 80 -vv 60 -vo 0 -va 0 -vs 0 -vl 0")


# ---------------------------------------------------------------------------
# Resolution
# ---------------------------------------------------------------------------

def test_resolution_like_rpict():
    assert view_from_string(EXAMPLE).resolution(512, 512) == (512, 352)     # tan 30° / tan 40°
    assert view_from_string("-vtv -vh 60 -vv 80").resolution(512, 512) == (352, 512)
    assert view_from_string("-vta -vh 180 -vv 180").resolution(800, 600) == (600, 600)
    assert view_from_string("-vtl -vh 10 -vv 5").resolution(512, 512) == (512, 256)
    assert view_from_string(EXAMPLE).resolution(512, 512, pixel_aspect=0) == (512, 512)
    assert view_from_string(EXAMPLE).resolution(512, 512, pixel_aspect=2) == (512, 176)
    with pytest.raises(InputError, match="-x resolution"):
        View().resolution(0, 10)


# ---------------------------------------------------------------------------
# Projections (closed forms of viewray())
# ---------------------------------------------------------------------------

def test_perspective_edges_and_plane():
    view = view_from_string("-vtv -vp 1 2 3 -vd 0 1 0 -vh 80 -vv 60")
    o, d, ok = view.image_rays(np.array([0.5, 1.0, 0.5, 0.0]), np.array([0.5, 0.5, 1.0, 0.0]))
    assert ok.all() and np.allclose(o, [1, 2, 3])
    assert np.allclose(d[0], [0, 1, 0])
    assert angle(d[1], [0, 1, 0]) == pytest.approx(40.0)                       # -vh / 2
    assert d[1][0] > 0                                                         # right is east for a north view
    assert angle(d[2], [0, 1, 0]) == pytest.approx(30.0) and d[2][2] > 0       # -vv / 2, up
    # the corner lies on the image plane one unit ahead spanning 2 tan(h/2) x 2 tan(v/2)
    corner = d[3] / d[3][1]
    assert np.allclose(corner, [-math.tan(math.radians(40)), 1, -math.tan(math.radians(30))])


def test_angular_fisheye_is_linear_in_radius():
    for size in (180.0, 360.0):
        view = View(type="a", direction=(1, 0, 0), horizontal=size, vertical=size)
        r = np.linspace(0, 0.5, 11)
        o, d, ok = view.image_rays(0.5 + r, np.full_like(r, 0.5))
        assert ok.all()
        assert np.allclose(angle(d, [1, 0, 0]), r / 0.5 * size / 2, atol=1e-9)
    # a 180 deg fisheye: corners look behind (valid), beyond a 360 deg circle nothing
    view = View(type="a", horizontal=180, vertical=180)
    _, d, ok = view.image_rays(np.array([1.0]), np.array([1.0]))
    assert ok.all() and angle(d[0], [0, 1, 0]) == pytest.approx(math.degrees(math.pi * math.sqrt(0.5)))
    whole = View(type="a", horizontal=360, vertical=360)
    _, _, ok = whole.image_rays(np.array([1.0, 0.5 + 0.5 * 0.999]), np.array([1.0, 0.5]))
    assert ok.tolist() == [False, True]


def test_hemispherical_fisheye_is_orthographic():
    view = View(type="h", direction=(0, 0, 1), up=(0, 1, 0), horizontal=180, vertical=180)
    theta = np.radians(np.linspace(0, 89, 9))
    _, d, ok = view.image_rays(0.5 + 0.5 * np.sin(theta), np.full_like(theta, 0.5))
    assert ok.all() and np.allclose(np.radians(angle(d, [0, 0, 1])), theta)
    _, _, ok = view.image_rays(np.array([0.0, 0.5]), np.array([0.0, 0.0]))
    assert ok.tolist() == [False, True]


def test_parallel_and_cylindrical():
    plan = view_from_string("-vtl -vp 5 4 10 -vd 0 0 -1 -vu 0 1 0 -vh 10 -vv 8 -vo 2")
    o, d, ok = plan.image_rays(np.array([0.0, 1.0, 0.5]), np.array([0.0, 1.0, 0.5]))
    assert np.allclose(d, [0, 0, -1])
    assert np.allclose(o, [[0, 0, 8], [10, 8, 8], [5, 4, 8]])  # right = -z x +y = +x
    pano = View(type="c", direction=(0, 1, 0), horizontal=360, vertical=60)
    x = np.linspace(0.0, 1.0, 9)
    _, d, _ = pano.image_rays(x, np.full_like(x, 0.5))
    azimuth = np.degrees(np.arctan2(d[:, 0], d[:, 1]))             # clockwise from north
    assert np.allclose(np.unwrap(np.radians(azimuth)), np.radians((x - 0.5) * 360))


def test_shift_lift_fore_aft():
    base = view_from_string("-vtv -vp 0 0 0 -vd 0 1 0 -vh 60 -vv 60 -vs 0.5 -vl 0.5 -vo 2 -va 5")
    o, d, _ = base.image_rays(np.array([0.0, 0.5]), np.array([0.0, 0.5]))
    assert np.allclose(d[0], [0, 1, 0])                      # shifted by half a width and height
    assert np.allclose(o[:, 1], 2.0)                         # origins on the fore plane y = 2
    assert np.allclose(base.aft_distances(d) * d[:, 1], 3.0)  # the aft plane y = 5
    assert np.isinf(View().aft_distances(np.array([[0, 1, 0]]))).all()
    fish = View(type="a", horizontal=180, vertical=180, fore=1.0, aft=4.0)
    o, d, _ = fish.image_rays(np.array([0.2]), np.array([0.7]))
    assert np.linalg.norm(o[0]) == pytest.approx(1.0) and fish.aft_distances(d)[0] == pytest.approx(3.0)


# ---------------------------------------------------------------------------
# Pixels and samples
# ---------------------------------------------------------------------------

def test_pixel_order_top_left_first():
    view = view_from_string("-vtv -vp 0 0 0 -vd 0 1 0 -vh 60 -vv 40")
    o, d, ok = view.rays(4, 3)
    assert o.shape == d.shape == (12, 3) and ok.shape == (12,)
    grid = d.reshape(3, 4, 3)
    assert grid[0, 0, 0] < 0 and grid[0, 0, 2] > 0            # top-left looks left and up
    assert grid[2, 3, 0] > 0 and grid[2, 3, 2] < 0            # bottom-right looks right and down
    assert np.allclose(np.linalg.norm(d, axis=1), 1.0)
    x, y = view.pixel_coordinates(4, 3)
    assert np.allclose(x[:4], (np.arange(4) + 0.5) / 4) and np.allclose(y[:4], 2.5 / 3)


def test_samples_stay_in_their_pixel_and_are_unbiased():
    view = View()
    rng = np.random.default_rng(3)
    x_res, y_res, s = 5, 4, 7
    x, y = view.pixel_coordinates(x_res, y_res, rng, s)
    col = np.floor(x * x_res).reshape(y_res, x_res, s)
    row_from_bottom = np.floor(y * y_res).reshape(y_res, x_res, s)
    assert (col == np.arange(x_res)[None, :, None]).all()
    assert (row_from_bottom == (y_res - 1 - np.arange(y_res))[:, None, None]).all()
    # every sample is uniform over its pixel: the mean offset over many draws is the centre
    offsets = np.array([view.pixel_coordinates(1, 1, np.random.default_rng(i), 4)[0] for i in range(4000)])
    assert offsets.mean() == pytest.approx(0.5, abs=0.01) and offsets.min() >= 0 and offsets.max() < 1
    # stratified: one sample per column stratum of the lattice
    lattice = sample_offsets(8)
    assert sorted(np.floor(lattice[:, 0] * 8).astype(int)) == list(range(8))
    assert np.allclose(sample_offsets(1), [[0.5, 0.5]])


def test_fisheye_mask_in_rays():
    view = View(type="a", horizontal=360, vertical=360)
    o, d, ok = view.rays(64, 64)
    assert ok.mean() == pytest.approx(math.pi / 4, abs=0.02)
    assert np.allclose(d[~ok], view.unit_direction) and np.allclose(np.linalg.norm(d, axis=1), 1)


# ---------------------------------------------------------------------------
# Against Radiance's vwrays
# ---------------------------------------------------------------------------

VWRAYS_VIEWS = [
    EXAMPLE + " -vs 0.2 -vl -0.1 -vo 0.5",
    "-vta -vp 1 2 3 -vd 1 0.3 0 -vh 180 -vv 180 -vo 0.2",
    "-vta -vp 1 2 3 -vd 1 0.3 0.2 -vh 360 -vv 300",
    "-vth -vp 1 2 3 -vd 0 0 1 -vu 0 1 0 -vh 180 -vv 170 -vs 0.1",
    "-vtl -vp 1 2 3 -vd 0 0 -1 -vu 0 1 0 -vh 10 -vv 7 -vo 1 -vl 0.3",
    "-vtc -vp 1 2 3 -vd 1 1 0 -vh 300 -vv 70 -vo 0.3",
]


@needs_vwrays
@pytest.mark.parametrize("text", VWRAYS_VIEWS)
def test_rays_match_vwrays(text):
    view = view_from_string(text)
    size = subprocess.run([VWRAYS, "-d", "-x", "37", "-y", "29", *text.split()], capture_output=True,
                          text=True, check=True).stdout.split()
    x_res, y_res = view.resolution(37, 29)
    assert size == ["-x", str(x_res), "-y", str(y_res)]
    raw = subprocess.run([VWRAYS, "-fd", "-x", "37", "-y", "29", *text.split()], capture_output=True,
                         check=True).stdout
    ref = np.frombuffer(raw, dtype=np.float64).reshape(-1, 6)
    o, d, ok = view.rays(x_res, y_res)
    assert ref.shape[0] == x_res * y_res
    radiance_ok = np.linalg.norm(ref[:, 3:], axis=1) > 0      # vwrays writes a zero direction when invalid
    assert (radiance_ok == ok).all()
    assert np.abs(o[ok] - ref[ok, :3]).max() < 1e-9
    assert np.abs(d[ok] - ref[ok, 3:]).max() < 1e-9


FOOT = 0.3048


def test_view_lengths_are_in_the_scene_units():
    """-vp, -vo, -va (and -vh/-vv of a parallel view) are scaled to metres; angles and
    directions are not."""
    v = view_from_string("-vtv -vp 10 20 5 -vd 0 1 0 -vh 60 -vv 40 -vo 2 -va 30", unit_scale=FOOT)
    assert np.allclose(v.position, [10 * FOOT, 20 * FOOT, 5 * FOOT])
    assert v.fore == pytest.approx(2 * FOOT) and v.aft == pytest.approx(30 * FOOT)
    assert v.horizontal == 60 and v.vertical == 40
    p = view_from_string("-vtl -vp 0 0 10 -vd 0 0 -1 -vu 0 1 0 -vh 20 -vv 10", unit_scale=FOOT)
    assert p.horizontal == pytest.approx(20 * FOOT) and p.vertical == pytest.approx(10 * FOOT)
    # the same string in a scene in metres is unchanged
    assert np.allclose(view_from_string("-vp 10 20 5").position, [10, 20, 5])


def test_view_file_and_radiance_key_lengths_are_in_the_scene_units(tmp_path):
    from lbl_illum.scene.views import view_from_table

    (tmp_path / "desk.vf").write_text("rvu -vtv -vp 10 20 5 -vd 0 1 0 -vh 60 -vv 40\n")
    assert np.allclose(view_from_file(tmp_path / "desk.vf", unit_scale=FOOT).position,
                       [10 * FOOT, 20 * FOOT, 5 * FOOT])
    v = view_from_table({"radiance": "-vtv -vp 10 20 5 -vd 0 1 0"}, "views.desk", unit_scale=FOOT)
    assert np.allclose(v.position, [10 * FOOT, 20 * FOOT, 5 * FOOT])

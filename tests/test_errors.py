"""The bad-input catalogue (docs/user-guide.md §7): every case through the command line.

Each refused case ends with one line on standard error, ``lbl-illum: error: ...``, naming
the file and the line or key; exit status 2; no traceback; and no file written, changed
or left behind: every file in the folder (inputs, earlier outputs given as sentinels,
would-be temporary files) is compared byte for byte before and after.  The cases that are
accepted with a warning (reflectance 1, unused materials, dropped triangles, a sun below
the horizon) are checked for their warning line and their result.
"""

from __future__ import annotations

import os
import re

import numpy as np
import pytest

from lbl_illum.cli.main import main
from lbl_illum.errors import InputError
from lbl_illum.io.files import atomic_write_bytes, atomic_write_text
from lbl_illum.scene.scenefile import MAX_BOUNCES, load_scene, scene_from_dict
from lbl_illum.io.points import read_points

# a 1 m square floor under a uniform sky
GOOD = """\
units = "m"

[[geometry]]
shape = "rectangle"
origin = [0, 0, 0]
u = [1, 0, 0]
v = [0, 1, 0]
material = "floor"

[materials.floor]
type = "diffuse"
reflectance = 0.5

[sky]
type = "uniform"
horizontal_illuminance = 10000
"""
GOOD_POINTS = "0.5 0.5 0.1 0 0 1\n0.25 0.25 0.1 0 0 1 desk\n"
#: cheap settings for the cases that run
FAST = ["--samples", "16", "--bounces", "1", "--point-samples", "16"]
#: earlier outputs of the folder, each with content that must survive a refused run
SENTINELS = {"out.csv": "x,y,z,nx,ny,nz,illuminance\n0,0,0,0,0,1,123\n", "out.summary.json": "{}\n",
             "stats.json": "{}\n", "plan.png": "not a png\n"}
OBJ_TRIANGLE = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"


def edit(old: str, new: str, text: str = GOOD) -> str:
    assert old in text, old
    return text.replace(old, new, 1)


def add(extra: str) -> str:
    return GOOD + extra


FILE_ENTRY = edit('shape = "rectangle"\norigin = [0, 0, 0]\nu = [1, 0, 0]\nv = [0, 1, 0]\n', 'file = "room.obj"\n')


def snapshot(folder):
    """Every file and folder below ``folder`` with its bytes."""
    return {p.relative_to(folder).as_posix(): p.read_bytes() if p.is_file() else "folder"
            for p in sorted(folder.rglob("*"))}


def run_cli(argv, capsys):
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


def refused(folder, capsys, argv, expect: str) -> str:
    """Run, and check the refusal: exit 2, one line naming what ``expect`` (a regex) says,
    nothing on standard output, no traceback, and the folder unchanged."""
    before = snapshot(folder)
    code, out, err = run_cli(argv, capsys)
    lines = err.splitlines()
    assert code == 2, err
    assert len(lines) == 1 and lines[0].startswith("lbl-illum: error: "), err
    assert re.search(expect, lines[0]), lines[0]
    assert "Traceback" not in err and out == ""
    assert snapshot(folder) == before
    return lines[0]


def prepare(folder, scene=GOOD, points=GOOD_POINTS, files=None):
    """scene.toml, p.pts, the sentinel outputs and any extra files (str, bytes, or a
    function that writes the file at the path it is given)."""
    for name, content in {"scene.toml": scene, "p.pts": points, **SENTINELS, **(files or {})}.items():
        if content is None:
            continue
        path = folder / name
        path.parent.mkdir(parents=True, exist_ok=True)
        if callable(content):
            content(path)
        else:
            (path.write_bytes if isinstance(content, bytes) else path.write_text)(content)


def cache_file(**edit):
    """A function writing a one-record cache file with the module's own writer (so its
    checksum is right) whose arrays ``edit`` changes: a file no run wrote."""
    from lbl_illum.io.cachefile import CACHE_FORMAT, CacheData, write_cache_file

    def write(path):
        arrays = {"L0_P": np.zeros((1, 3)), "L0_N": np.array([[0, 0, 1]], np.float32),
                  "L0_E": np.full((1, 3), 100, np.float32), "L0_R": np.ones(1, np.float32),
                  "L0_Gr": np.zeros((1, 3, 3), np.float32), "L0_Gt": np.zeros((1, 3, 3), np.float32)}
        arrays.update({f"L0_{k}": np.asarray(v, arrays[f"L0_{k}"].dtype) for k, v in edit.items()})
        header = {"format": CACHE_FORMAT, "fingerprint": "0" * 64, "settings": None, "domains": "round",
                  "center": [0, 0, 0], "half": 1.0, "levels": [{"accuracy": 0.2, "records": 1, "center": [0, 0, 0],
                                                               "half": 1.0}]}
        write_cache_file(path, CacheData(header, arrays))
    return write


def illuminance_args(folder, *extra):
    return ["illuminance", folder / "scene.toml", "--points", folder / "p.pts", "-o", folder / "out.csv",
            "--stats", folder / "stats.json", "--cache", folder / "c.lblcache", "--plot", folder / "plan.png",
            *FAST, *extra]


# ---------------------------------------------------------------------------
# The catalogue: (case, scene text, points text, extra files, extra arguments, message)
# ---------------------------------------------------------------------------

CATALOGUE = [
    # files
    ("scene file missing", None, GOOD_POINTS, {}, [], r"error: scene.toml: no such file$"),
    ("scene file is a folder", None, GOOD_POINTS, {"scene.toml/x": "x"}, [],
     r"scene.toml: is a folder, not a scene file$"),
    ("scene file not UTF-8", b'units = "m"\n# caf\xe9\n', GOOD_POINTS, {}, [],
     r"scene.toml: line 2: not UTF-8 text \(byte 17\)$"),
    ("points file missing", GOOD, None, {}, [], r"p.pts: no such file$"),
    ("points file is a folder", GOOD, None, {"p.pts/x": "x"}, [], r"p.pts: is a folder, not a points file$"),
    ("geometry file missing", FILE_ENTRY, GOOD_POINTS, {}, [], r"scene.toml: geometry\[0\] room.obj: no such file"),
    ("geometry file trimesh cannot read", FILE_ENTRY.replace("room.obj", "room.glb"), GOOD_POINTS,
     {"room.glb": b"glTF\x02\x00\x00\x00garbage"}, [], r"geometry\[0\] room.glb: cannot read the file \(\w+"),
    ("geometry file with no faces", FILE_ENTRY, GOOD_POINTS, {"room.obj": "v 0 0 0\nv 1 0 0\n"}, [],
     r"geometry\[0\] room.obj: the file contains no triangles$"),
    ("geometry file face with a missing vertex", FILE_ENTRY, GOOD_POINTS,
     {"room.obj": "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n"}, [], r"room.obj: .*(vertex|index)"),
    ("cache file not a cache", GOOD, GOOD_POINTS, {"c.lblcache": "not a cache\n"}, [],
     r"c.lblcache: not an lbl_illum cache file"),
    # cache files whose checksum is right but whose records no evaluation gives
    ("cache record normal not unit length", GOOD, GOOD_POINTS, {"c.lblcache": cache_file(N=[[0, 0, 0.9]])}, [],
     r"c.lblcache: damaged cache file \(array L0_N: record 0 has a normal of length 0.9, not a unit vector"),
    ("cache record irradiance negative", GOOD, GOOD_POINTS, {"c.lblcache": cache_file(E=[[10, -1, 10]])}, [],
     r"c.lblcache: damaged cache file \(array L0_E: record 0 has a negative irradiance -1 lux"),
    ("cache record irradiance NaN", GOOD, GOOD_POINTS, {"c.lblcache": cache_file(E=[[10, np.nan, 10]])}, [],
     r"c.lblcache: damaged cache file \(array L0_E holds non-finite numbers\)$"),
    ("cache record radius zero", GOOD, GOOD_POINTS, {"c.lblcache": cache_file(R=[0])}, [],
     r"c.lblcache: damaged cache file \(array L0_R holds radii <= 0\)$"),
    ("cache record position infinite", GOOD, GOOD_POINTS, {"c.lblcache": cache_file(P=[[0, np.inf, 0]])}, [],
     r"c.lblcache: damaged cache file \(array L0_P holds non-finite numbers\)$"),
    ("cache record gradient NaN", GOOD, GOOD_POINTS,
     {"c.lblcache": cache_file(Gt=np.full((1, 3, 3), np.nan))}, [],
     r"c.lblcache: damaged cache file \(array L0_Gt holds non-finite numbers\)$"),
    # TOML syntax
    ("TOML syntax error", edit("reflectance = 0.5", "reflectance = = 0.5"), GOOD_POINTS, {}, [],
     r"scene.toml: line 12, column 15: "),
    ("TOML key given twice", edit("reflectance = 0.5", "reflectance = 0.5\nreflectance = 0.6"), GOOD_POINTS, {}, [],
     r"scene.toml: line 13, column \d+: Cannot overwrite a value"),
    ("TOML value unquoted", edit('type = "uniform"', "type = uniform"), GOOD_POINTS, {}, [],
     r"scene.toml: line 15, column 8: Invalid value"),
    ("integer beyond 64 bits", add("[settings]\nseed = 99999999999999999999999\n"), GOOD_POINTS, {}, [],
     r"scene.toml: 'settings.seed': integer of 77 bits is beyond TOML's 64-bit range"),
    # unknown keys, with the nearest valid one
    ("unknown top-level key", add("[setings]\nbounces = 2\n"), GOOD_POINTS, {}, [],
     r"scene.toml: unknown key 'setings' \(did you mean 'settings'\?\)$"),
    ("unknown material key", edit("reflectance = 0.5", "reflectence = 0.5"), GOOD_POINTS, {}, [],
     r"scene.toml: \[materials.floor\]: unknown key 'reflectence' \(did you mean 'reflectance'\?\)$"),
    ("unknown geometry key", edit('material = "floor"', 'matrial = "floor"'), GOOD_POINTS, {}, [],
     r"scene.toml: geometry\[0\]: unknown key 'matrial' \(did you mean 'material'\?\)$"),
    ("unknown settings key", add("[settings]\nbounce = 2\n"), GOOD_POINTS, {}, [],
     r"\[settings\]: unknown key 'bounce' \(did you mean 'bounces'\?\)$"),
    ("unknown sky key", edit("horizontal_illuminance", "horizontal_iluminance"), GOOD_POINTS, {}, [],
     r"\[sky\]: unknown key 'horizontal_iluminance' \(did you mean 'horizontal_illuminance'\?\)$"),
    ("unknown sun key", add("[sun]\naltitude = 40\nazimut = 180\n"), GOOD_POINTS, {}, [],
     r"\[sun\]: unknown key 'azimut' \(did you mean 'azimuth'\?\)$"),
    ("unknown material type", edit('type = "diffuse"', 'type = "difuse"'), GOOD_POINTS, {}, [],
     r"\[materials.floor\]: 'type' must be one of diffuse, glass, mirror, plastic, metal, light, opening, translucent, got 'difuse' "
     r"\(did you mean 'diffuse'\?\)$"),
    ("unknown shape", edit('shape = "rectangle"', 'shape = "rectangel"'), GOOD_POINTS, {}, [],
     r"geometry\[0\]: unknown shape 'rectangel' \(did you mean 'rectangle'\?\)$"),
    ("unknown sky type", edit('type = "uniform"', 'type = "overcast"'), GOOD_POINTS, {}, [],
     r"\[sky\]: 'type' must be one of"),
    ("unknown preset", add('[settings]\npreset = "fast"\n'), GOOD_POINTS, {}, [], r"\[settings\]: 'preset' must be one of"),
    # wrong types
    ("reflectance a string", edit("reflectance = 0.5", 'reflectance = "high"'), GOOD_POINTS, {}, [],
     r"\[materials.floor\]: 'reflectance' must be a number, got 'high'$"),
    ("reflectance of 2 channels", edit("reflectance = 0.5", "reflectance = [0.5, 0.5]"), GOOD_POINTS, {}, [],
     r"'reflectance' must be a number or \[r, g, b\]"),
    ("vertices not a list", edit('shape = "rectangle"\norigin = [0, 0, 0]\nu = [1, 0, 0]\nv = [0, 1, 0]',
                                 'shape = "polygon"\nvertices = 3'), GOOD_POINTS, {}, [],
     r"geometry\[0\]: 'vertices' must be a list of \[x, y, z\] points, got 3$"),
    ("materials not a table", edit("[materials.floor]", "[[materials]]"), GOOD_POINTS, {}, [],
     r"scene.toml: \[materials\] must be a table, got \["),
    ("geometry not an array of tables", edit("[[geometry]]", "[geometry]"), GOOD_POINTS, {}, [],
     r"'geometry' must be an array of tables"),
    ("bounces not whole", add("[settings]\nbounces = 1.5\n"), GOOD_POINTS, {}, [],
     r"\[settings\]: 'bounces' must be a whole number, got 1.5$"),
    ("material named by a number", edit('material = "floor"', "material = 3"), GOOD_POINTS, {}, [],
     r"geometry\[0\]: a material must be given by its name \(a string\), got 3$"),
    ("a long wrong value is cut", edit("reflectance = 0.5", "reflectance = [" + ", ".join(["[1]"] * 40) + "]"),
     GOOD_POINTS, {}, [], r"'reflectance' must be a number or \[r, g, b\], got \[\[1\], .{20,60}\.\.\.$"),
    # units
    ("unknown unit", edit('units = "m"', 'units = "yd"'), GOOD_POINTS, {}, [],
     r"scene.toml: 'units': unknown unit 'yd' \(valid: m, cm, mm, km, ft, in\)$"),
    ("unit not a string", edit('units = "m"', "units = 5"), GOOD_POINTS, {}, [], r"'units': unknown unit 5"),
    # reflectance and transmittance
    ("reflectance negative", edit("reflectance = 0.5", "reflectance = -0.1"), GOOD_POINTS, {}, [],
     r"\[materials.floor\]: 'reflectance' must be >= 0, got -0.1$"),
    ("reflectance NaN", edit("reflectance = 0.5", "reflectance = nan"), GOOD_POINTS, {}, [],
     r"\[materials.floor\]: 'reflectance' must be finite, got nan$"),
    ("reflectance above 1", edit("reflectance = 0.5", "reflectance = [0.5, 1.2, 0.5]"), GOOD_POINTS, {}, [],
     r"\[materials.floor\]: 'reflectance' must be <= 1, got 1.2$"),
    ("transmittance above 1", add('[materials.pane]\ntype = "glass"\ntransmittance = 1.2\nmodel = "constant"\n'),
     GOOD_POINTS, {}, [], r"\[materials.pane\]: 'transmittance' must be <= 1, got 1.2$"),
    ("Fresnel transmittance above clear glass", add('[materials.pane]\ntype = "glass"\ntransmittance = 0.95\n'),
     GOOD_POINTS, {}, [], r"\[materials.pane\]: 'transmittance' 0.95 is more than 1 clear pane of refractive index "
                          r"1.52 transmit \(0.9183\)"),
    ("double-pane transmittance above clear glass",
     add('[materials.pane]\ntype = "glass"\ntransmittance = 0.9\npanes = 2\n'), GOOD_POINTS, {}, [],
     r"more than 2 clear panes of refractive index 1.52 transmit \(0.8490\)"),
    ("constant glass passing more than it gets",
     add('[materials.pane]\ntype = "glass"\nmodel = "constant"\ntransmittance = 0.9\nreflectance = 0.2\n'),
     GOOD_POINTS, {}, [], r"\[materials.pane\]: transmittance \+ reflectance must not exceed 1$"),
    # vertices
    ("NaN vertex in the scene file", edit("origin = [0, 0, 0]", "origin = [0, nan, 0]"), GOOD_POINTS, {}, [],
     r"geometry\[0\]: 'origin' must be finite, got nan$"),
    ("infinite vertex in the scene file", edit("u = [1, 0, 0]", "u = [inf, 0, 0]"), GOOD_POINTS, {}, [],
     r"geometry\[0\]: 'u' must be finite, got inf$"),
    ("NaN vertex in a geometry file", FILE_ENTRY, GOOD_POINTS, {"room.obj": OBJ_TRIANGLE.replace("v 1 0 0", "v nan 0 0")},
     [], r"geometry\[0\] room.obj: 1 triangle with a NaN or infinite vertex coordinate$"),
    ("vertex far beyond any scene", edit("origin = [0, 0, 0]", "origin = [0, 1e300, 0]"), GOOD_POINTS, {}, [],
     r"geometry\[0\]: 'origin' 1e\+300 m is beyond ±1e\+09 m$"),
    ("geometry file vertex far beyond any scene", FILE_ENTRY, GOOD_POINTS,
     {"room.obj": OBJ_TRIANGLE.replace("v 1 0 0", "v 1e12 0 0")}, [],
     r"room.obj: 1 triangle with a vertex coordinate beyond ±1e\+09 m"),
    # empty geometry
    ("no geometry", edit('[[geometry]]\nshape = "rectangle"\norigin = [0, 0, 0]\nu = [1, 0, 0]\nv = [0, 1, 0]\n'
                         'material = "floor"\n', ""), GOOD_POINTS, {}, [],
     r"scene.toml: the scene has no geometry \(add \[\[geometry\]\] entries\)$"),
    ("only zero-area triangles", FILE_ENTRY, GOOD_POINTS, {"room.obj": "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n"}, [],
     r"scene.toml: the scene has no triangles$"),
    ("polygon of zero area", edit('shape = "rectangle"\norigin = [0, 0, 0]\nu = [1, 0, 0]\nv = [0, 1, 0]',
                                  'shape = "polygon"\nvertices = [[0, 0, 0], [1, 0, 0], [2, 0, 0]]'),
     GOOD_POINTS, {}, [], r"geometry\[0\]: the polygon has zero area$"),
    # materials
    ("material used but not defined", edit('material = "floor"', 'material = "flor"'), GOOD_POINTS, {}, [],
     r"geometry\[0\]: unknown material 'flor' \(did you mean 'floor'\?\)$"),
    ("material missing its type", edit('type = "diffuse"\n', ""), GOOD_POINTS, {}, [],
     r"\[materials.floor\]: missing key 'type' \(one of diffuse, glass, mirror, plastic, metal, light, opening, translucent\)$"),
    # .pts files
    ("points: malformed line", GOOD, "0.5 0.5 0.1 0 0 1\n0.5 x 0.1 0 0 1\n", {}, [],
     r"p.pts: line 2: not a number: 'x'$"),
    ("points: too few numbers", GOOD, "# header\n0.5 0.5 0.1 0 0\n", {}, [],
     r"p.pts: line 2: expected 6 numbers 'x y z nx ny nz' and an optional area name, got 5 fields$"),
    ("points: zero-length normal", GOOD, "0.5 0.5 0.1 0 0 1\n\n0.5 0.5 0.1 0 0 0\n", {}, [],
     r"p.pts: line 3: zero-length normal$"),
    ("points: none", GOOD, "# only a comment\n\n", {}, [], r"p.pts: no points$"),
    ("points: not finite", GOOD, "0.5 0.5 nan 0 0 1\n", {}, [], r"p.pts: line 1: values must be finite$"),
    ("points: not UTF-8", GOOD, b"0.5 0.5 0.1 0 0 1\n0.5 0.5 0.1 0 0 1 caf\xe9\n", {}, [],
     r"p.pts: line 2: not UTF-8 text \(byte 39\)$"),
    ("points: lines numbered at line feeds only", GOOD, "# a \u2028 b \x85 c\n0.5 0.5 0.1 0 0\n", {}, [],
     r"p.pts: line 2: expected 6 numbers"),
    ("points: area name a number", GOOD, "0.5 0.5 0.1 0 0 1 12\n", {}, [],
     r"p.pts: line 1: area name '12' looks like a number$"),
    # settings on the command line and in [settings]
    ("--samples 0", GOOD, GOOD_POINTS, {}, ["--samples", "0"], r"argument --samples: must be >= 1, got 0$"),
    ("--samples not whole", GOOD, GOOD_POINTS, {}, ["--samples", "1.5"],
     r"argument --samples: expected a whole number, got '1.5'$"),
    ("--accuracy negative", GOOD, GOOD_POINTS, {}, ["--accuracy=-1"], r"argument --accuracy: must be >= 0, got -1$"),
    ("--accuracy NaN", GOOD, GOOD_POINTS, {}, ["--accuracy", "nan"],
     r"argument --accuracy: must be a finite number, got 'nan'$"),
    ("--bounces negative", GOOD, GOOD_POINTS, {}, ["--bounces=-1"], r"argument --bounces: must be >= 0, got -1$"),
    ("--bounces beyond the limit", GOOD, GOOD_POINTS, {}, ["--bounces", "100000"],
     rf"argument --bounces: must be <= {MAX_BOUNCES}, got 100000$"),
    ("--point-samples negative", GOOD, GOOD_POINTS, {}, ["--point-samples=-5"],
     r"argument --point-samples: must be >= 0, got -5$"),
    ("--seed negative", GOOD, GOOD_POINTS, {}, ["--seed=-1"], r"argument --seed: must be >= 0, got -1$"),
    ("--ambient infinite", GOOD, GOOD_POINTS, {}, ["--ambient", "inf"], r"argument --ambient: must be a finite number"),
    ("--min-spacing 0", GOOD, GOOD_POINTS, {}, ["--min-spacing", "0"], r"argument --min-spacing: must be > 0, got 0$"),
    ("min above max spacing", add("[settings]\nmax_spacing = 1\n"), GOOD_POINTS, {}, ["--min-spacing", "2"],
     r"the command line with scene.toml \[settings\]: 'min_spacing' \(2\) must not exceed max_spacing \(1\)$"),
    ("--thresholds NaN", GOOD, GOOD_POINTS, {}, ["--thresholds", "300", "nan"],
     r"argument --thresholds: must be a finite number, got 'nan'$"),
    ("--preset unknown", GOOD, GOOD_POINTS, {}, ["--preset", "fast"], r"argument --preset: invalid choice: 'fast'"),
    ("[settings] samples 0", add("[settings]\nsamples = 0\n"), GOOD_POINTS, {}, [],
     r"scene.toml: \[settings\]: 'samples' must be >= 1, got 0$"),
    ("[settings] accuracy negative", add("[settings]\naccuracy = -0.1\n"), GOOD_POINTS, {}, [],
     r"scene.toml: \[settings\]: 'accuracy' must be >= 0, got -0.1$"),
    ("[settings] bounces beyond the limit", add("[settings]\nbounces = 5000\n"), GOOD_POINTS, {}, [],
     rf"scene.toml: \[settings\]: 'bounces' must be <= {MAX_BOUNCES}, got 5000$"),
    ("[settings] interpolation unknown", add('[settings]\ninterpolation = "linear"\n'), GOOD_POINTS, {}, [],
     r"\[settings\]: 'interpolation' must be one of paper, gradients, hessian, got 'linear'$"),
    # sky and sun values
    ("sun altitude beyond 90", add("[sun]\naltitude = 95\nazimuth = 180\n"), GOOD_POINTS, {}, [],
     r"\[sun\]: 'altitude' must be <= 90, got 95$"),
    ("CIE sky type NaN", edit('type = "uniform"', 'type = "cie-general"\nsky_type = nan'), GOOD_POINTS, {}, [],
     r"\[sky\]: 'sky_type' must be a whole number 1…15, got nan$"),
    ("Perez sky brighter than the Sun", edit('type = "uniform"\nhorizontal_illuminance = 10000',
                                            'type = "perez"\ndiffuse_horizontal_illuminance = 1e300\n'
                                            'direct_normal_illuminance = 0')
     + "[sun]\naltitude = 40\nazimuth = 180\n", GOOD_POINTS, {}, [],
     r"scene.toml: \[sky\]: 'diffuse_horizontal_illuminance' 1e\+300 lux is more than reaches the top of the "
     r"atmosphere \(138014 lux at the Sun's nearest\)$"),
    ("Perez direct normal irradiance above the solar constant",
     edit('type = "uniform"\nhorizontal_illuminance = 10000',
          'type = "perez"\ndirect_normal_irradiance = 1500\ndiffuse_horizontal_irradiance = 100')
     + "[sun]\naltitude = 40\nazimuth = 180\n", GOOD_POINTS, {}, [],
     r"scene.toml: \[sky\]: 'direct_normal_irradiance' 1500 W/m2 is more than reaches the top of the atmosphere"),
    ("Perez diffuse irradiance NaN", edit('type = "uniform"\nhorizontal_illuminance = 10000',
                                         'type = "perez"\ndirect_normal_irradiance = 500\n'
                                         'diffuse_horizontal_irradiance = nan')
     + "[sun]\naltitude = 40\nazimuth = 180\n", GOOD_POINTS, {}, [],
     r"scene.toml: \[sky\]: 'diffuse_horizontal_irradiance' must be finite, got nan$"),
    ("sky zenith luminance too large for a float", edit("horizontal_illuminance = 10000", "zenith_luminance = 1e308"),
     GOOD_POINTS, {}, [], r"scene.toml: \[sky\]: 'zenith_luminance' 1e\+308 is too large"),
    ("sky horizontal illuminance negative", edit("horizontal_illuminance = 10000", "horizontal_illuminance = -1"),
     GOOD_POINTS, {}, [], r"scene.toml: \[sky\]: 'horizontal_illuminance' must be >= 0, got -1$"),
    ("sun azimuth infinite", add("[sun]\naltitude = 40\nazimuth = -inf\n"), GOOD_POINTS, {}, [],
     r"scene.toml: \[sun\]: 'azimuth' must be finite, got -inf$"),
    # [views.NAME] tables (read with the scene by every command)
    ("view wider than a perspective can be",
     add('[views.desk]\nposition = [0.5, 0.5, 1]\ndirection = [0, 1, 0]\nhorizontal = 185\n'), GOOD_POINTS, {}, [],
     r"scene.toml: \[views.desk\]: illegal horizontal view size -vh 185 for a perspective view \(below 180 degrees\)$"),
    ("view direction parallel to up",
     add('[views.desk]\nposition = [0.5, 0.5, 1]\ndirection = [0, 0, -1]\n'), GOOD_POINTS, {}, [],
     r"scene.toml: \[views.desk\]: view up \(-vu\) parallel to view direction \(-vd\)$"),
    ("view direction zero",
     add('[views.desk]\nposition = [0.5, 0.5, 1]\ndirection = [0, 0, 0]\n'), GOOD_POINTS, {}, [],
     r"scene.toml: \[views.desk\]: zero view direction \(-vd\)$"),
    ("view fore clipping negative",
     add('[views.desk]\nposition = [0.5, 0.5, 1]\ndirection = [0, 1, 0]\nfore = -1\n'), GOOD_POINTS, {}, [],
     r"scene.toml: \[views.desk\]: 'fore' must be >= 0, got -1$"),
    ("view fisheye beyond 360 degrees",
     add('[views.fish]\ntype = "fisheye"\nposition = [0.5, 0.5, 1]\ndirection = [0, 0, 1]\nup = [0, 1, 0]\n'
         'horizontal = 400\n'), GOOD_POINTS, {}, [],
     r"\[views.fish\]: illegal horizontal view size -vh 400 for an angular fisheye view \(at most 360 degrees\)$"),
    ("view position NaN", add('[views.desk]\nposition = [0.5, nan, 1]\ndirection = [0, 1, 0]\n'), GOOD_POINTS, {},
     [], r"scene.toml: \[views.desk\]: 'position' must be finite, got nan$"),
    # outputs
    ("output of an unknown format", GOOD, GOOD_POINTS, {}, ["-o", "out.xlsx"], r"out.xlsx: output must end in .csv or .txt$"),
    ("output folder missing", GOOD, GOOD_POINTS, {}, ["-o", "nowhere/out.csv"], r"folder nowhere does not exist$"),
    ("output is a folder", GOOD, GOOD_POINTS, {"dir.csv/x": "x"}, ["-o", "dir.csv"], r"dir.csv: is a folder"),
    ("statistics file is a folder", GOOD, GOOD_POINTS, {"st/x": "x"}, ["--stats", "st"], r"st: is a folder"),
    ("plot of an unknown format", GOOD, GOOD_POINTS, {}, ["--plot", "plan.bmp"], r"plan.bmp: .*must end in"),
]


@pytest.mark.parametrize("case, scene, points, files, args, expect", CATALOGUE, ids=[c[0] for c in CATALOGUE])
def test_refused_input(tmp_path, capsys, monkeypatch, case, scene, points, files, args, expect):
    monkeypatch.chdir(tmp_path)          # relative output names in ``args`` land in the folder
    prepare(tmp_path, scene, points, files)
    refused(tmp_path, capsys, illuminance_args(tmp_path, *args), expect)


def test_catalogue_cases_have_distinct_names():
    names = [c[0] for c in CATALOGUE]
    assert len(names) == len(set(names)) and len(names) >= 80


@pytest.mark.skipif(not hasattr(os, "geteuid") or os.geteuid() == 0, reason="root reads any file")
def test_unreadable_files(tmp_path, capsys):
    prepare(tmp_path)
    for name, expect in (("scene.toml", r"scene.toml: cannot read \(Permission denied\)$"),
                         ("p.pts", r"p.pts: cannot read \(Permission denied\)$")):
        (tmp_path / name).chmod(0)
        try:
            refused(tmp_path, capsys, illuminance_args(tmp_path), expect)
        finally:
            (tmp_path / name).chmod(0o644)


# ---------------------------------------------------------------------------
# Accepted, with a warning
# ---------------------------------------------------------------------------

def accepted(tmp_path, capsys, scene, points=GOOD_POINTS, files=None):
    """Run a case that is accepted: exit 0, the outputs written; returns (stderr lines, results)."""
    tmp_path.mkdir(exist_ok=True)
    prepare(tmp_path, scene, points, files)
    code, _, err = run_cli(illuminance_args(tmp_path), capsys)
    assert code == 0, err
    lines = (tmp_path / "out.csv").read_text().splitlines()
    header = lines[0].split(",")
    rows = [dict(zip(header, line.split(","))) for line in lines[1:]]
    return err.splitlines(), rows


def test_reflectance_of_exactly_1_is_accepted_with_a_warning(tmp_path, capsys):
    """ρ = 1: the bounce limit is always finite (bounces ≤ MAX_BOUNCES, specular chains
    stop at 8), so the result is finite; the warning says it grows with the bounces."""
    lines, rows = accepted(tmp_path, capsys, edit("reflectance = 0.5", "reflectance = 1"))
    assert any(re.search(r"warning: scene.toml: \[materials.floor\]: reflectance 1 absorbs no light.*'bounces'", l)
               for l in lines)
    assert all(np.isfinite(float(r["illuminance"])) for r in rows)
    scene = scene_from_dict({"geometry": [{"shape": "box", "center": [0, 0, 0], "size": [1, 1, 1],
                                           "material": "white"}],
                             "materials": {"white": {"type": "mirror", "reflectance": [1, 1, 1]}}}, ".", "s.toml")
    assert any("reflectance 1" in w for w in scene.warnings)


def test_unused_material_is_a_warning(tmp_path, capsys):
    lines, _ = accepted(tmp_path, capsys, add('[materials.white]\ntype = "diffuse"\nreflectance = 0.8\n'))
    assert "lbl-illum: warning: scene.toml: [materials.white] is not used by any geometry" in lines


def test_zero_area_and_duplicate_faces_are_dropped_and_counted(tmp_path, capsys):
    obj = OBJ_TRIANGLE + "v 2 0 0\nf 2 3 1\nf 1 3 2\nf 1 2 4\nf 1 1 3\n"     # 2 duplicates, 2 zero-area
    lines, rows = accepted(tmp_path, capsys, FILE_ENTRY, files={"room.obj": obj})
    assert "lbl-illum: warning: scene.toml: geometry[0] room.obj: dropped 2 zero-area and 2 duplicate triangles" \
        in lines
    assert len(rows) == 2


def test_sun_below_the_horizon_gives_no_direct_sun_and_says_so(tmp_path, capsys):
    scene = add("[sun]\naltitude = -5\nazimuth = 180\ndirect_normal_illuminance = 80000\n")
    lines, rows = accepted(tmp_path / "below", capsys, scene)
    assert any("warning: scene.toml: [sun]: the sun is below the horizon (altitude -5°): no direct sun" in l
               for l in lines)
    # the same numbers as without the sun (same seed): it adds nothing
    _, without = accepted(tmp_path / "none", capsys, GOOD)
    assert rows == without
    _, above = accepted(tmp_path / "above", capsys, scene.replace("altitude = -5", "altitude = 5"))
    assert all(float(a["direct"]) > float(r["direct"]) + 1000 for a, r in zip(above, rows))


# ---------------------------------------------------------------------------
# Every command: bad input leaves every output as it was
# ---------------------------------------------------------------------------

VIEW = "--view=-vtv -vp 0.5 0.5 2 -vd 0 0 -1 -vu 0 1 0 -vh 60 -vv 60"
BAD_SCENE = edit("reflectance = 0.5", "reflectence = 0.5")
COMMANDS = {
    "illuminance": (lambda f: illuminance_args(f), "samples"),
    "daylight-factor": (lambda f: ["daylight-factor", f / "scene.toml", "--points", f / "p.pts", "-o", f / "out.csv",
                                   "--stats", f / "stats.json", "--plot", f / "plan.png", *FAST], "samples"),
    "grid": (lambda f: ["grid", f / "scene.toml", "-o", f / "grid.pts", "--plot", f / "plan.png"], "spacing"),
    "render": (lambda f: ["render", f / "scene.toml", VIEW, "-x", "8", "-y", "8", "-o", f / "image.hdr",
                          "--preview", f / "preview.png", "--stats", f / "stats.json", "--samples", "16",
                          "--bounces", "1"], "samples"),
    "export radiance": (lambda f: ["export", "radiance", f / "scene.toml", f / "rad", "--points", f / "p.pts",
                                   "--force"], "points"),
    "view --screenshot": (lambda f: ["view", f / "scene.toml", "--results", f / "out.csv", "--screenshot",
                                     f / "shot.png"], "results"),
}
OUTPUTS = {"grid.pts": "0 0 0.8 0 0 1\n", "image.hdr": "not an image\n", "preview.png": "not a png\n",
           "shot.png": "not a png\n", "rad/materials.rad": "# earlier export\n"}


@pytest.mark.parametrize("command", list(COMMANDS))
@pytest.mark.parametrize("fault", ["scene", "option"])
def test_every_command_leaves_its_outputs_alone(tmp_path, capsys, command, fault):
    if command == "view --screenshot":
        pytest.importorskip("pyvista")
    build, option = COMMANDS[command]
    prepare(tmp_path, BAD_SCENE if fault == "scene" else GOOD, files=OUTPUTS)
    argv = build(tmp_path)
    if fault == "scene":
        expect = r"scene.toml: \[materials.floor\]: unknown key 'reflectence'"
    elif option == "samples":
        argv, expect = argv + ["--samples", "0"], r"argument --samples: must be >= 1, got 0$"
    elif option == "spacing":
        argv, expect = argv + ["--spacing", "-1"], r"argument --spacing: must be > 0, got -1$"
    elif option == "points":
        (tmp_path / "p.pts").write_text("0 0 1 0 0 0\n")
        expect = r"p.pts: line 1: zero-length normal$"
    else:
        (tmp_path / "out.csv").write_text("x,y,z,nx,ny,nz,illuminance\n0,0,nope,0,0,1,1\n")
        expect = r"out.csv: line 2: column 'z': not a number$"
    refused(tmp_path, capsys, argv, expect)


# ---------------------------------------------------------------------------
# render: image sizes refused before any work
# ---------------------------------------------------------------------------

@pytest.mark.parametrize("size, expect", [
    (["-x", "100000", "-y", "100000"], r"error: -x 100000 is more than the 16384 pixels allowed per side$"),
    (["-x", "512", "-y", "16385"], r"error: -y 16385 is more than the 16384 pixels allowed per side$"),
    (["-x", "0"], r"error: -x must be a positive whole number, got 0$"),
    (["-y=-3"], r"error: -y must be a positive whole number, got -3$"),
    (["--pixel-samples", "0"], r"error: --pixel-samples must be a positive whole number, got 0$"),
    (["-x", "4096", "-y", "4096"], r"error: -x 4096 -y 4096 with 1 pixel sample is 16,777,216 camera rays, traced in "
                                   r"one batch: about 16 GiB of memory, more than the 1 GiB available; render a "
                                   r"smaller image$"),
    (["-x", "1024", "-y", "1024", "--pixel-samples", "2"], r"-x 1024 -y 1024 with 2 pixel samples is 2,097,152 "
                                                           r"camera rays.*about 2 GiB of memory"),
])
def test_render_sizes_are_refused_before_any_work(tmp_path, capsys, monkeypatch, size, expect):
    """With 1 GiB said to be available: nothing is read, rendered or written."""
    import lbl_illum.cli.render as render

    monkeypatch.setattr(render, "_available_memory", lambda: 2 ** 30)
    monkeypatch.setattr(render, "render_command", lambda args: pytest.fail("render started"))
    prepare(tmp_path, BAD_SCENE, files=OUTPUTS)          # not even the scene is read
    argv = ["render", tmp_path / "scene.toml", VIEW, "-o", tmp_path / "image.hdr", *size]
    refused(tmp_path, capsys, argv, expect)


def test_render_sizes_that_fit_go_ahead(tmp_path, capsys, monkeypatch):
    import lbl_illum.cli.render as render

    started = []
    monkeypatch.setattr(render, "_available_memory", lambda: 2 ** 30)
    monkeypatch.setattr(render, "render_command", lambda args: started.append((args.x, args.y)) or 0)
    assert main(["render", "s.toml", VIEW, "-o", str(tmp_path / "i.hdr"), "-x", "1024", "-y", "1024"]) == 0
    monkeypatch.setattr(render, "_available_memory", lambda: None)         # unknown: only the side limit
    assert main(["render", "s.toml", VIEW, "-o", str(tmp_path / "i.hdr"), "-x", "16384", "-y", "16384"]) == 0
    assert started == [(1024, 1024), (16384, 16384)]
    have = render._available_memory()
    assert have is None or have > 0


# ---------------------------------------------------------------------------
# Outputs are written whole or not at all
# ---------------------------------------------------------------------------

def test_a_failed_write_keeps_the_old_file_and_leaves_no_temporary(tmp_path, monkeypatch):
    path = tmp_path / "out.csv"
    path.write_text("old\n")

    def fail(src, dst):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(os, "replace", fail)
    with pytest.raises(OSError):
        atomic_write_text(path, "new\n")
    assert path.read_text() == "old\n" and [p.name for p in tmp_path.iterdir()] == ["out.csv"]
    monkeypatch.undo()
    atomic_write_bytes(path, b"new\n")
    assert path.read_bytes() == b"new\n" and [p.name for p in tmp_path.iterdir()] == ["out.csv"]


def test_an_interrupted_write_keeps_the_old_file(tmp_path, monkeypatch):
    """Ctrl-C while the bytes are written: the rename never happens."""
    path = tmp_path / "out.txt"
    path.write_text("old\n")
    real_fdopen = os.fdopen

    class Interrupted:
        def __init__(self, fd, mode):
            self.fh = real_fdopen(fd, mode)

        def __enter__(self):
            return self

        def __exit__(self, *exc):
            self.fh.close()

        def write(self, data):
            self.fh.write(data[:3])
            raise KeyboardInterrupt

    monkeypatch.setattr(os, "fdopen", Interrupted)
    with pytest.raises(KeyboardInterrupt):
        atomic_write_text(path, "new content\n")
    assert path.read_text() == "old\n" and [p.name for p in tmp_path.iterdir()] == ["out.txt"]


# ---------------------------------------------------------------------------
# Crashes the fuzz tests found (tests/test_fuzz.py), kept as plain cases
# ---------------------------------------------------------------------------

def _minimal(**change):
    data = {"geometry": [{"shape": "rectangle", "origin": [0, 0, 0], "u": [1, 0, 0], "v": [0, 1, 0],
                          "material": "floor"}],
            "materials": {"floor": {"type": "diffuse", "reflectance": 0.5}}}
    data.update(change)
    return data


@pytest.mark.parametrize("data, message", [
    (_minimal(geometry=[{"shape": ["box"], "material": "floor"}]), r"unknown shape \['box'\]"),
    (_minimal(materials={"floor": {"type": {"a": 1}}}), r"'type' must be one of .*got \{'a': 1\}$"),
    (_minimal(materials={"floor": {"type": "glass", "transmittance": 0.5, "model": ["fresnel"]}}),
     r"'model' must be one of"),
    (_minimal(settings={"preset": ["high"]}), r"\[settings\]: 'preset' must be a name"),
    (_minimal(sky={"type": "cie-general", "sky_type": float("inf")}, sun={"altitude": 30, "azimuth": 0}),
     r"'sky_type' must be a whole number 1…15, got inf$"),
    (_minimal(geometry=[{"shape": "box", "center": [0, 0, 0], "size": [1e308, 1, 1], "material": "floor"}]),
     r"'size' 1e\+308 m is beyond"),
    (_minimal(geometry=[{"shape": "polygon", "vertices": [[0, 0, 0], [1e200, 0, 0], [0, 1e200, 0]],
                         "material": "floor"}]), r"'vertices' 1e\+200 m is beyond"),
    (_minimal(portals=[{"vertices": [[0, 0, 0], [1e300, 0, 0], [0, 1, 0]]}]), r"portals\[0\] 'vertices'.*beyond"),
    # the view's own range check, or the overflow of its direction's length: which comes
    # first depends on how numpy computes that length (scaled or not), both one line
    (_minimal(views={"desk": {"position": [1e200, 0, 0], "target": [0, 0, 0]}}),
     r"(\[views\]: a value is too large for the views \(overflow\)|\[views\.desk\]: -vp \(position\) 1e\+200 m "
     r"is beyond ±1e\+09 m)$"),
    (_minimal(geometry=[{"shape": "sphere", "center": [0, 0, 0], "radius": 5e-324, "material": "floor"}],
              units="mm"), r"'radius' must be > 0, got 5e-324 \(zero in metres\)$"),
])
def test_values_that_once_crashed_the_reader(data, message):
    with pytest.raises(InputError, match=message):
        scene_from_dict(data, ".", "s.toml")


def test_integers_beyond_python_s_digit_limit(tmp_path):
    path = tmp_path / "scene.toml"
    path.write_text(GOOD + "[settings]\nseed = " + "9" * 5000 + "\n")
    with pytest.raises(InputError, match=r"^scene.toml: an integer is too long to read"):
        load_scene(path)
    path.write_text(GOOD + "[settings]\nseed = 0x" + "f" * 5000 + "\n")       # no digit limit in hex
    with pytest.raises(InputError, match=r"^scene.toml: 'settings.seed': integer of 20000 bits"):
        load_scene(path)


def test_pts_normals_of_any_size_are_normalised(tmp_path):
    path = tmp_path / "p.pts"
    path.write_text("0 0 0 1e200 0 1e200\n0 0 0 1e-10 0 0\n0 0 0 1e308 1e308 1e308\n")
    _, normals = read_points(path)
    assert np.allclose(normals, [[2 ** -0.5, 0, 2 ** -0.5], [1, 0, 0], [3 ** -0.5] * 3], rtol=1e-15)


def test_pts_lines_are_numbered_at_line_feeds_only(tmp_path):
    """U+2028, U+0085 and the file separators are not line breaks of a .pts file (Python's
    splitlines would count them, and the numbers in messages would be off)."""
    path = tmp_path / "p.pts"
    path.write_bytes("# a comment with \u2028 and \x85 in it\n\n0 0 0 0 0 1\n0 0 0 0 0\n".encode())
    with pytest.raises(InputError, match=r"^p.pts: line 4: expected 6 numbers"):
        read_points(path)
    path.write_bytes(b"0 0 0 0 0 1\r\n0 0 0 0 0 1\r\n0 0 x 0 0 1\r\n")
    with pytest.raises(InputError, match=r"^p.pts: line 3: not a number: 'x'$"):
        read_points(path)
    path.write_text("0 0 1_0 0 0 1\n")              # Python's float reads it; a .pts reader must not
    with pytest.raises(InputError, match=r"line 1: not a number: '1_0'$"):
        read_points(path)


def test_pts_coordinates_beyond_any_scene(tmp_path):
    path = tmp_path / "p.pts"
    path.write_text("0 0 1e12 0 0 1\n")
    with pytest.raises(InputError, match=r"^p.pts: line 1: a coordinate is beyond ±1e\+09 m$"):
        read_points(path)
    assert read_points(path, 1e-6)[0][0, 2] == pytest.approx(1e6)      # in mm (scaled): fine

"""Property and fuzz tests (hypothesis): readers of user files end in a valid result or a
clean one-line InputError, never another exception; octree invariants under random records.

Readers: the scene file (``load_scene`` from bytes, ``scene_from_dict`` from parsed values),
the ``.pts`` reader (``read_points``) and the cache loader (``IrradianceCache.load``).  Inputs
are random byte strings and random edits of a valid file: byte flips, truncations, deleted
and duplicated lines, numbers and words replaced by odd values (NaN, inf, 1e308, a string, a
table, ...), inserted bytes.  NumPy floating-point warnings count as failures (they would be
stray lines beside the one-line message).  The number of examples is set by the environment
variable ``LBL_ILLUM_FUZZ_EXAMPLES`` (default 200, about 15 s for the module); 2,500 found
nothing more.

The octree properties are not covered by tests/test_octree.py's brute-force comparisons:
additivity (the records of A ∪ B serve a query with count_A + count_B records and weight
w_A + w_B, so adding records never uncovers a covered query), independence of the
insertion order, batch split and initial root cube, self-coverage (every record serves its
own position and normal), the range a·R beyond which no record serves, and invariance
under an exact change of length unit (a power of two).
"""

from __future__ import annotations

import copy
import datetime as dt
import json
import math
import os
import re
import shutil
import warnings
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, assume, given, settings, strategies as st

from lbl_illum.engine.cache import IrradianceCache, LevelRecords
from lbl_illum.io.cachefile import CacheData, write_cache_file
from lbl_illum.errors import InputError
from lbl_illum.scene.geometry import MAX_COORDINATE
from lbl_illum.scene.scenefile import Scene, load_scene, scene_from_dict
from lbl_illum.io.points import MIN_NORMAL, read_points

DATA = Path(__file__).parent / "data"

#: Examples per reader fuzzer (about 2 s each at 200); set LBL_ILLUM_FUZZ_EXAMPLES to fuzz longer.
EXAMPLES = int(os.environ.get("LBL_ILLUM_FUZZ_EXAMPLES", "200"))
#: hypothesis settings of the reader fuzzers.
FUZZ = settings(max_examples=EXAMPLES, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture,
                                                                          HealthCheck.too_slow])

# ---------------------------------------------------------------------------
# Valid inputs the edits start from
# ---------------------------------------------------------------------------

#: Every kind of table a scene may have, primitives only (fast to load).
SCENE_PRIMITIVES = """\
schema = 1
units = "cm"

[[geometry]]
shape = "box"
center = [0, 0, 150]
size = [400, 600, 300]
material = "wall"

[[geometry]]
shape = "polygon"
vertices = [[-100, -300, 100], [100, -300, 100], [100, -300, 200], [-100, -300, 200]]
material = "glazing"

[[geometry]]
shape = "rectangle"
origin = [-50, -50, 80]
u = [100, 0, 0]
v = [0, 100, 0]
material = "desk"

[materials.wall]
type = "diffuse"
reflectance = [0.5, 0.55, 0.6]

[materials.desk]
type = "mirror"
reflectance = 0.3

[materials.glazing]
type = "glass"
transmittance = 0.6
model = "fresnel"
panes = 2
refractive_index = 1.5

[materials.lamp]
type = "light"
luminance = 100

[materials.pane]
type = "glass"
transmittance = 0.7
model = "constant"
reflectance = 0.08
portal = false

[[portals]]
name = "door"
vertices = [[-50, 300, 0], [50, 300, 0], [50, 300, 200], [-50, 300, 200]]

[site]
latitude = 37.9
longitude = -122.2
time_zone = -8

[sky]
type = "cie-general"
sky_type = 7
horizontal_illuminance = 20000
ground_reflectance = 0.2
time = "2024-06-21 12:00"

[settings]
accuracy = 0.2
bounces = 2
samples = 64
min_spacing = 10
max_spacing = 100
interpolation = "gradients"

[views.desk]
type = "perspective"
position = [0, 250, 150]
target = [0, 0, 80]
up = [0, 0, 1]
horizontal = 80
vertical = 60

[views.glare]
radiance = "-vta -vp 0 0 1.2 -vd 0 -1 0 -vh 180 -vv 180"
"""

#: A geometry file with a material mapping, a sun placed by time at a site, a Perez sky.
SCENE_FILE_PEREZ = """\
[[geometry]]
file = "room_corner.obj"
material = "grey"
materials = { Floor = "floor", wall = "grey" }

[materials.floor]
type = "diffuse"
reflectance = 0.2

[materials.grey]
type = "diffuse"
reflectance = [0.5, 0.5, 0.4]

[site]
latitude = 37.876
longitude = -122.247
time_zone = -8
elevation = 200

[sun]
time = "2024-12-21 12:00"
direct_normal_illuminance = 70000

[sky]
type = "perez"
diffuse_horizontal_illuminance = 12000
direct_normal_illuminance = 70000
dew_point = 5

[settings]
preset = "draft"
point_samples = 0
seed = 3
bounce_scaling = false
"""

#: An hour of a weather file.
SCENE_WEATHER = """\
[[geometry]]
shape = "rectangle"
origin = [0, 0, 0]
u = [1, 0, 0]
v = [0, 1, 0]
material = "floor"

[materials.floor]
type = "diffuse"
reflectance = 0.2

[sky]
weather = "berkeley_excerpt.epw"
time = "06-20 13:00"
weather_values = "irradiance"
ground_reflectance = 0.3
"""

#: A sun by altitude and azimuth under a CIE clear sky scaled by its zenith luminance.
SCENE_SUN = """\
units = "ft"

[[geometry]]
shape = "box"
center = [0, 0, 1]
size = [0.5, 0.5, 0.5]
material = "floor"

[[geometry]]
shape = "rectangle"
origin = [0, 0, 0]
u = [1, 0, 0]
v = [0, 1, 0]
material = "floor"

[materials.floor]
type = "diffuse"
reflectance = 0.2

[sun]
altitude = 40
azimuth = 180
direct_normal_illuminance = 80000

[sky]
type = "cie-clear"
zenith_luminance = 3000
"""

SCENES = {"primitives": SCENE_PRIMITIVES, "file_perez": SCENE_FILE_PEREZ, "weather": SCENE_WEATHER,
          "sun": SCENE_SUN}

POINTS = """\
# lbl-illum grid: a comment line
0 0 0.8 0 0 1 floor
1 0 0.8 0 0 1

2.5 1e-3 0.8 0 0.1 1  # a trailing comment
-3.25 3 3 1 1 1 desk
"""

#: Values a number, a word or a whole line may be replaced with.
ODD_TOKENS = [b"0", b"-1", b"1e308", b"-1e308", b"nan", b"inf", b"-inf", b"1e-320", b"2", b"1e200", b"1e-200",
              b"99999999999999999999999", b"0x7fffffffffffffffffff", b"-0", b"[]", b"{}", b"[1, 2]",
              b"[[1, 2, 3]]", b'"x"', b'""', b"true", b"1979-05-27", b"12:00:00", b"x", b"#", b"1,2", b"\xff",
              b"\x00", b"\x1c", b"\xc2\x85", b"\xe2\x80\xa8", b"\r", b"1_0", b"\xef\xbc\x91", b"[" * 50,
              b"{ a = 1 }", b"'''"]


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    """A folder with the geometry and weather files the scenes name."""
    path = tmp_path_factory.mktemp("fuzz")
    shutil.copy(DATA / "scene" / "room_corner.obj", path)
    shutil.copy(DATA / "berkeley_excerpt.epw", path)
    return path


def test_the_valid_inputs_are_valid(folder):
    for name, text in SCENES.items():
        (folder / f"{name}.toml").write_text(text)
        scene = load_scene(folder / f"{name}.toml")
        _check_scene(scene)
    primitives = load_scene(folder / "primitives.toml")
    assert primitives.sun is not None and set(primitives.views) == {"desk", "glare"}
    (folder / "p.pts").write_text(POINTS)
    points, normals, areas = read_points(folder / "p.pts", with_areas=True)
    assert len(points) == 4 and list(areas) == ["floor", "", "", "desk"]


# ---------------------------------------------------------------------------
# Edits
# ---------------------------------------------------------------------------

_TOKEN = re.compile(rb"-?\d+(\.\d+)?([eE][+-]?\d+)?|\"[^\"\n]*\"|[A-Za-z_]+")


@st.composite
def edits(draw, text: bytes, max_edits: int = 3) -> bytes:
    """``text`` after 1…max_edits random edits."""
    data = bytearray(text)
    for _ in range(draw(st.integers(1, max_edits))):
        op = draw(st.sampled_from(["flip", "truncate", "delete line", "duplicate line", "token", "line",
                                   "insert"]))
        where = draw(st.integers(0, 1 << 20))
        if op == "flip" and data:
            data[where % len(data)] ^= 1 << draw(st.integers(0, 7))
        elif op == "truncate":
            data = data[: where % (len(data) + 1)]
        elif op in ("delete line", "duplicate line", "line"):
            lines = bytes(data).split(b"\n")
            i = where % len(lines)
            if op == "delete line":
                del lines[i]
            elif op == "duplicate line":
                lines.insert(i, lines[i])
            else:
                lines[i] = draw(st.sampled_from(ODD_TOKENS))
            data = bytearray(b"\n".join(lines))
        elif op == "token":
            tokens = list(_TOKEN.finditer(bytes(data)))
            if tokens:
                m = tokens[where % len(tokens)]
                data[m.start():m.end()] = draw(st.sampled_from(ODD_TOKENS))
        else:
            at = where % (len(data) + 1)
            data[at:at] = draw(st.binary(min_size=1, max_size=8))
    return bytes(data)


def _clean(call):
    """``call()``'s result, or None for a clean InputError; NumPy floating-point warnings
    and any other exception fail the test."""
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        try:
            return call()
        except InputError as exc:
            message = str(exc)
            assert message and "\n" not in message and "\r" not in message, repr(message)
            assert len(message) < 400, message
            return None


# ---------------------------------------------------------------------------
# Scene files
# ---------------------------------------------------------------------------

def _check_scene(scene: Scene) -> None:
    tri = scene.triangles
    assert len(tri) > 0
    assert np.isfinite(tri.vertices).all() and np.abs(tri.vertices).max() <= MAX_COORDINATE
    assert tri.material.min() >= 0 and tri.material.max() < len(scene.materials)
    assert np.all(tri.areas > 0)
    assert all(isinstance(w, str) and "\n" not in w for w in scene.warnings)
    assert np.isfinite(scene.unit_scale) and scene.unit_scale > 0


def _load(folder: Path, data: bytes):
    path = folder / "fuzzed.toml"
    path.write_bytes(data)
    scene = _clean(lambda: load_scene(path))
    if scene is not None:
        _check_scene(scene)
    return scene


@FUZZ
@given(data=st.binary(max_size=600))
def test_scene_parser_on_random_bytes(folder, data):
    _load(folder, data)


@FUZZ
@given(data=st.one_of(*(edits(text.encode()) for text in SCENES.values())))
def test_scene_parser_on_edited_files(folder, data):
    _load(folder, data)


def _paths(value, prefix=()):
    """Every key path of a parsed TOML document."""
    items = value.items() if isinstance(value, dict) else enumerate(value) if isinstance(value, list) else ()
    for key, item in items:
        yield prefix + (key,)
        yield from _paths(item, prefix + (key,))


#: Values of every TOML type, and extreme numbers, for type confusion.
ODD_VALUES = [None, [], {}, [1, 2], [[1, 2, 3]], ["a"], {"a": 1}, "x", "", True, False, 0, -1, 1.5, 1e308, -1e308,
              math.nan, math.inf, -math.inf, 2 ** 63 - 1, -2 ** 63, 1e-320, dt.date(2024, 1, 1),
              dt.datetime(2024, 1, 1, 12), dt.time(12)]


@FUZZ
@given(scene=st.sampled_from(sorted(SCENES)), pick=st.integers(0, 1 << 20),
       value=st.sampled_from(range(len(ODD_VALUES))))
def test_scene_values_of_every_type_in_every_place(folder, scene, pick, value):
    """A parsed scene with one value (or table entry) replaced by a value of another type or
    an extreme one (None: the key deleted): scene_from_dict refuses it cleanly or builds a
    valid scene."""
    import tomllib

    data = tomllib.loads(SCENES[scene])
    paths = list(_paths(data))
    path = paths[pick % len(paths)]
    parent = data
    for key in path[:-1]:
        parent = parent[key]
    if ODD_VALUES[value] is None:
        del parent[path[-1]]
    else:
        parent[path[-1]] = copy.deepcopy(ODD_VALUES[value])
    result = _clean(lambda: scene_from_dict(data, folder, "s.toml"))
    if result is not None:
        _check_scene(result)


# ---------------------------------------------------------------------------
# .pts files
# ---------------------------------------------------------------------------

def _read_pts(folder: Path, data: bytes):
    path = folder / "fuzzed.pts"
    path.write_bytes(data)
    result = _clean(lambda: read_points(path, 0.3048, with_areas=True))
    if result is not None:
        points, normals, areas = result
        assert len(points) >= 1 and points.shape == normals.shape == (len(areas), 3)
        assert np.isfinite(points).all() and np.abs(points).max() <= MAX_COORDINATE
        assert np.allclose(np.linalg.norm(normals, axis=1), 1.0, atol=1e-12)
        assert all(isinstance(a, str) and not any(c.isspace() or c in '#,"' for c in a) for a in areas)
    return result


@FUZZ
@given(data=st.binary(max_size=300))
def test_pts_reader_on_random_bytes(folder, data):
    _read_pts(folder, data)


@FUZZ
@given(data=edits(POINTS.encode()))
def test_pts_reader_on_edited_files(folder, data):
    _read_pts(folder, data)


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(rows=st.lists(st.tuples(*[st.floats(allow_nan=True, allow_infinity=True, width=64)] * 6), min_size=1,
                     max_size=5))
def test_pts_reader_on_any_floats(folder, rows):
    """Any six floats per line, written with repr: finite rows with a normal are read back
    exactly (normalised), the others refused with the line number."""
    text = "".join(" ".join(repr(v) for v in row) + "\n" for row in rows)
    result = _read_pts(folder, text.encode())
    ok = [all(math.isfinite(v) for v in row) and math.hypot(*row[3:]) > MIN_NORMAL
          and max(abs(v) for v in row[:3]) * 0.3048 <= MAX_COORDINATE for row in rows]
    if all(ok):
        assert result is not None
        assert np.array_equal(result[0], np.array([r[:3] for r in rows]) * 0.3048)
    else:
        assert result is None


# ---------------------------------------------------------------------------
# Cache files
# ---------------------------------------------------------------------------

@pytest.fixture(scope="module")
def cache_files(tmp_path_factory):
    """Two small valid cache files (round and elliptical record domains) of a box room
    with a window, at low settings; their bytes and their parsed header and arrays."""
    from lbl_illum.engine.integrator import Integrator
    from lbl_illum.options import Options

    data = {"geometry": [{"shape": "box", "center": [0, 0, 1.5], "size": [4, 4, 3], "material": "wall"},
                         {"shape": "rectangle", "origin": [-1, -2, 1], "u": [2, 0, 0], "v": [0, 0, 1],
                          "material": "glass"}],
            "materials": {"wall": {"type": "diffuse", "reflectance": 0.5},
                          "glass": {"type": "glass", "transmittance": 0.6}},
            "sky": {"type": "cie-overcast"}}
    scene = scene_from_dict(data, ".", "t.toml")
    folder = tmp_path_factory.mktemp("caches")
    points = np.array([[0, 0, 0.8], [1, 1, 0.8], [-1, 0.5, 0.8]])
    normals = np.tile([0.0, 0.0, 1.0], (3, 1))
    out = []
    for interpolation in ("gradients", "hessian"):
        integ = Integrator(scene, Options(accuracy=0.3, bounces=1, samples=32, interpolation=interpolation))
        integ.compute(points, normals)
        path = folder / f"{interpolation}.lblcache"
        integ.cache.save(path)
        with np.load(path) as npz:
            header = json.loads(str(npz["header"]))
            arrays = {k: npz[k] for k in npz.files if k != "header"}
        assert sum(integ.cache.record_counts) > 0
        out.append((path.read_bytes(), header, arrays))
    return folder, out


def _check_cache(cache: IrradianceCache) -> None:
    """A loaded cache holds records an evaluation could give (finite positions, unit normals,
    irradiance ≥ 0, radii > 0) and answers lookups at and near them with finite values."""
    for level in cache.levels:
        if level.count:
            P = np.asarray(level.P[: level.count], np.float64)
            N = np.asarray(level.N[: level.count], np.float64)
            assert np.isfinite(P).all() and np.all(np.abs(np.linalg.norm(N, axis=1) - 1) <= 1e-3)
            assert np.all(level.E[: level.count] >= 0) and np.all(level.R[: level.count] > 0)
            for gradients in (False, True):
                E, w, n = level.lookup(P + 0.01, N, gradients=gradients)
                assert np.isfinite(E).all() and np.isfinite(w).all() and np.all(n >= 0)


def _load_cache(folder: Path, data: bytes):
    path = folder / "fuzzed.lblcache"
    path.write_bytes(data)
    cache = _clean(lambda: IrradianceCache.load(path))
    if cache is not None:
        _check_cache(cache)
    return cache


def test_the_valid_caches_load(cache_files):
    folder, files = cache_files
    for data, header, _ in files:
        cache = _load_cache(folder, data)
        assert cache is not None and cache.record_counts == [lv["records"] for lv in header["levels"]]


@FUZZ
@given(data=st.binary(max_size=400), zip_magic=st.booleans())
def test_cache_loader_on_random_bytes(cache_files, data, zip_magic):
    folder, _ = cache_files
    _load_cache(folder, b"PK\x03\x04" + data if zip_magic else data)


@FUZZ
@given(which=st.integers(0, 1), data=st.data())
def test_cache_loader_on_edited_files(cache_files, which, data):
    folder, files = cache_files
    _load_cache(folder, data.draw(edits(files[which][0])))


#: Header values and array entries the structured cache edits write.
CACHE_VALUES = [None, [], {}, [1, 2], "x", "", True, 0, -1, 0.5, 1.5, 1e308, -1e308, 2 ** 70, [0, 0, 0],
                [1e308, 0, 0], 10 ** 6, 1025]


@FUZZ
@given(which=st.integers(0, 1), data=st.data())
def test_cache_loader_on_consistent_but_wrong_contents(cache_files, which, data):
    """Header values and arrays edited and the file rewritten with a valid checksum (a file
    no run wrote): the loader refuses it by its contents, or loads a usable cache."""
    folder, files = cache_files
    _, header, arrays = files[which]
    header, arrays = copy.deepcopy(header), {k: v.copy() for k, v in arrays.items()}
    for _ in range(data.draw(st.integers(1, 3))):
        op = data.draw(st.sampled_from(["header", "entry", "record", "truncate", "dtype", "flatten", "drop",
                                        "extra"]))
        if op == "header":
            paths = [p for p in _paths(header) if p[0] != "checksum"]
            path = data.draw(st.sampled_from(paths))
            parent = header
            for key in path[:-1]:
                parent = parent[key]
            value = data.draw(st.sampled_from(CACHE_VALUES))
            if value is None:
                del parent[path[-1]]
            else:
                parent[path[-1]] = copy.deepcopy(value)
        elif arrays:
            name = data.draw(st.sampled_from(sorted(arrays)))
            arr = arrays[name]
            if op == "record" and arr.ndim == 2 and arr.dtype.kind == "f" and len(arr):
                # one record's normal scaled, or one irradiance channel made negative
                row = data.draw(st.integers(0, len(arr) - 1))
                if name.endswith("_N"):
                    arr[row] *= data.draw(st.sampled_from([0.0, 0.5, 0.998, 1.002, 2.0, -1.0]))
                else:
                    arr[row, data.draw(st.integers(0, 2))] = data.draw(st.sampled_from([-1e-6, -1.0, -1e30]))
            elif op == "entry" and arr.size:
                values = ([np.nan, np.inf, -1.0, 0.0, 1e30, -1e30, 1e-30] if arr.dtype.kind == "f"
                          else [0, 1, int(np.iinfo(arr.dtype).max)])
                arr.flat[data.draw(st.integers(0, arr.size - 1))] = data.draw(st.sampled_from(values))
            elif op == "truncate":
                arrays[name] = arr[: data.draw(st.integers(0, len(arr)))]
            elif op == "dtype":
                with np.errstate(invalid="ignore"):         # NaN to integers: any value will do
                    arrays[name] = arr.astype(data.draw(st.sampled_from([np.float32, np.float64, np.int64,
                                                                         np.uint32])))
            elif op == "flatten":
                arrays[name] = arr.reshape(-1)
            elif op == "drop":
                del arrays[name]
            else:
                arrays["L9_X"] = np.zeros(3)
    path = folder / "consistent.lblcache"
    try:
        write_cache_file(path, CacheData(header, arrays))
    except (TypeError, ValueError):          # a header the writer cannot write as JSON
        assume(False)
    cache = _clean(lambda: IrradianceCache.load(path))
    if cache is not None:
        _check_cache(cache)


# ---------------------------------------------------------------------------
# Octree invariants
# ---------------------------------------------------------------------------

def _unit(v):
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def _records(rng, n, spread, shaped):
    """Records like a cache's: half on a floor facing up, half anywhere, radii over two
    decades; with ``shaped`` elliptical axes and leak masks as well."""
    from lbl_illum.engine.hemisphere import orthonormal_basis

    P = rng.uniform(-spread, spread, (n, 3))
    P[: n // 2, 2] = 0.0
    N = _unit(rng.normal(size=(n, 3)))
    N[: n // 2] = [0.0, 0.0, 1.0]
    R = (spread * 10 ** rng.uniform(-2, 0, n)).astype(np.float32)
    E = rng.uniform(0, 1000, (n, 3)).astype(np.float32)
    shape = {}
    if shaped:
        t, _ = orthonormal_basis(N)
        shape = {"W": (t * rng.uniform(0, 2, (n, 1))).astype(np.float32),
                 "leak": np.where(rng.random(n) < 0.5, 0, rng.integers(0, 2 ** 32, n, dtype=np.uint64))
                 .astype(np.uint32)}
    return P, N.astype(np.float32), R, E, shape


def _queries(rng, P, R, spread, n=400):
    near = P[rng.integers(0, len(P), n)] + rng.normal(size=(n, 3)) * R[rng.integers(0, len(P), n), None]
    qP = np.vstack([near, rng.uniform(-1.5 * spread, 1.5 * spread, (n // 4, 3))])
    qN = np.tile([0.0, 0.0, 1.0], (len(qP), 1))
    qN[::2] = _unit(rng.normal(size=(len(qN[::2]), 3)))
    return qP, qN


def _level(a, spread, shaped, P, N, R, E, shape, batches=1, half=None):
    lv = LevelRecords(a, center=np.zeros(3), half=spread * 1.01 if half is None else half, anisotropic=shaped)
    for part in np.array_split(np.arange(len(P)), batches):
        lv.add(P[part], N[part], R[part], E[part], **{k: v[part] for k, v in shape.items()})
    return lv


OCTREE = settings(max_examples=max(25, EXAMPLES // 8), deadline=None)
record_sets = dict(seed=st.integers(0, 2 ** 31 - 1), n_a=st.integers(1, 150), n_b=st.integers(1, 150),
                   a=st.sampled_from([0.05, 0.2, 0.5, 1.0]), spread=st.sampled_from([0.5, 4.0, 50.0]),
                   shaped=st.booleans())


@OCTREE
@given(**record_sets)
def test_records_add_up_and_never_uncover_a_query(seed, n_a, n_b, a, spread, shaped):
    """For disjoint record sets A and B, the records of A ∪ B serving a query are those of
    A plus those of B: counts and weights add, and the value is the weighted mean of the
    two.  Hence adding records never makes a covered query uncovered."""
    rng = np.random.default_rng(seed)
    P, N, R, E, shape = _records(rng, n_a + n_b, spread, shaped)
    A, B = np.arange(n_a), np.arange(n_a, n_a + n_b)
    take = lambda idx: (P[idx], N[idx], R[idx], E[idx], {k: v[idx] for k, v in shape.items()})  # noqa: E731
    qP, qN = _queries(rng, P, R, spread)
    la, lb = (_level(a, spread, shaped, *take(idx)) for idx in (A, B))
    both = _level(a, spread, shaped, P, N, R, E, shape)
    (Ea, wa, na), (Eb, wb, nb), (E2, w2, n2) = (lv.lookup(qP, qN) for lv in (la, lb, both))
    assert np.array_equal(n2, na + nb)
    assert np.all(n2 >= na)                                     # monotone: covered stays covered
    assert np.allclose(w2, wa + wb, rtol=1e-12, atol=0)
    served = n2 > 0
    mean = (wa[:, None] * Ea + wb[:, None] * Eb)[served] / (wa + wb)[served, None]
    assert np.allclose(E2[served], mean, rtol=1e-9, atol=1e-9)
    assert np.all(E2[~served] == 0)
    # the coverage test agrees with the sum
    assert np.array_equal(both.covers(qP, qN), (na + nb) > 0)


@OCTREE
@given(**record_sets, batches=st.integers(1, 7), small_root=st.booleans())
def test_lookups_do_not_depend_on_insertion_order_batches_or_root(seed, n_a, n_b, a, spread, shaped, batches,
                                                                 small_root):
    """The same records inserted shuffled, in several batches, and into a root cube far
    too small (the tree grows around it) answer every query with the same records, the
    same weight and the same value (to round-off of the summation order)."""
    rng = np.random.default_rng(seed)
    P, N, R, E, shape = _records(rng, n_a + n_b, spread, shaped)
    qP, qN = _queries(rng, P, R, spread)
    ref = _level(a, spread, shaped, P, N, R, E, shape).lookup(qP, qN, gradients=True)
    order = rng.permutation(len(P))
    other = _level(a, spread, shaped, P[order], N[order], R[order], E[order], {k: v[order] for k, v in shape.items()},
                   batches=batches, half=spread * 0.01 if small_root else None)
    got = other.lookup(qP, qN, gradients=True)
    assert np.array_equal(got[2], ref[2])
    assert np.allclose(got[1], ref[1], rtol=1e-12, atol=0)
    assert np.allclose(got[0], ref[0], rtol=1e-9, atol=1e-9)


@OCTREE
@given(**record_sets)
def test_every_record_serves_its_own_place_and_none_serves_beyond_a_R(seed, n_a, n_b, a, spread, shaped):
    """Eq. 6's error is 0 at a record's own position and normal, so every record serves
    there (the value is a convex combination of record values, without gradients); and
    ε_i(P) ≥ |P − P_i| / R_i, so a query farther than a·R_i from every record P_i is served
    by none."""
    rng = np.random.default_rng(seed)
    P, N, R, E, shape = _records(rng, n_a + n_b, spread, shaped)
    lv = _level(a, spread, shaped, P, N, R, E, shape)
    E_own, _, n_own = lv.lookup(P, N.astype(np.float64))
    assert np.all(n_own >= 1)
    assert np.all(E_own >= E.min(axis=0) - 1e-3) and np.all(E_own <= E.max(axis=0) + 1e-3)
    qP, qN = _queries(rng, P, R, spread)
    far = np.all(np.linalg.norm(qP[:, None, :] - P[None, :, :], axis=2) > a * R[None, :].astype(np.float64) * 1.0001,
                 axis=1)
    _, w, n = lv.lookup(qP, qN)
    assert np.all(n[far] == 0) and np.all(w[far] == 0)


@OCTREE
@given(**record_sets, power=st.integers(-8, 8))
def test_lookups_do_not_depend_on_the_unit_of_length(seed, n_a, n_b, a, spread, shaped, power):
    """Positions, radii and queries multiplied by 2^k (exact in floating point; the
    gradients ∇_t scaled by 2^-k): the same records serve each query, with the same
    weights and values.  Eq. 6 is dimensionless."""
    rng = np.random.default_rng(seed)
    P, N, R, E, shape = _records(rng, n_a + n_b, spread, shaped)
    qP, qN = _queries(rng, P, R, spread)
    s = 2.0 ** power
    ref = _level(a, spread, shaped, P, N, R, E, shape).lookup(qP, qN)
    got = _level(a, spread * s, shaped, P * s, N, (R * s).astype(np.float32), E, shape).lookup(qP * s, qN)
    assert np.array_equal(got[2], ref[2])
    assert np.allclose(got[1], ref[1], rtol=1e-9, atol=0)
    assert np.allclose(got[0], ref[0], rtol=1e-9, atol=1e-9)

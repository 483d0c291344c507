"""Geometry files kept between runs (lbl_illum/scene/geometry_cache.py): a file read
again comes back equal without being parsed; a changed file, scale or place is parsed
again; the cache off, unwritable or damaged never stops a run."""

import numpy as np
import pytest

from lbl_illum.scene import geometry
from lbl_illum.scene.geometry import load_mesh_file

# a unit square as one quad and a face of zero area (dropped, with a warning)
OBJ = """v 0 0 0
v 2 0 0
v 2 1 0
v 0 1 0
v 5 5 5
v 6 6 6
v 7 7 7
v 8 8 8
g Floor
usemtl carpet
f 1 2 3 4
g Junk
usemtl carpet
f 5 6 7 8
"""


@pytest.fixture
def cache_on(tmp_path, monkeypatch):
    folder = tmp_path / "cache"
    monkeypatch.setenv("LBL_ILLUM_CACHE_DIR", str(folder))
    return folder / "geometry"


def _read(path, scale=1.0, where="room.toml: geometry[0]"):
    warnings = []
    parts = load_mesh_file(path, where, scale, warnings)
    return parts, warnings


def _no_parsing(monkeypatch):
    def refuse(*args, **kwargs):
        raise AssertionError("the file was parsed again")

    monkeypatch.setattr(geometry, "_load_trimesh_scene", refuse)


def test_a_file_read_again_comes_from_the_cache_equal(tmp_path, cache_on, monkeypatch):
    path = tmp_path / "room.obj"
    path.write_text(OBJ)
    first, first_warnings = _read(path)
    assert first_warnings and len(list(cache_on.glob("*.npz"))) == 1
    _no_parsing(monkeypatch)
    again, again_warnings = _read(path)
    assert again_warnings == first_warnings
    assert [(p.name, p.node, p.group, p.material) for p in again] == \
        [(p.name, p.node, p.group, p.material) for p in first]
    for a, b in zip(again, first):
        assert a.vertices.dtype == np.float64 and np.array_equal(a.vertices, b.vertices)


@pytest.mark.parametrize("change", ["bytes", "scale", "where"])
def test_a_changed_file_scale_or_place_is_parsed_again(tmp_path, cache_on, monkeypatch, change):
    path = tmp_path / "room.obj"
    path.write_text(OBJ)
    first, _ = _read(path)
    calls = []
    real = geometry._load_trimesh_scene
    monkeypatch.setattr(geometry, "_load_trimesh_scene", lambda *a: calls.append(1) or real(*a))
    if change == "bytes":
        path.write_text(OBJ.replace("v 2 0 0", "v 3 0 0"))
        parts, _ = _read(path)
        assert parts[0].vertices.max() == 3.0
    elif change == "scale":
        parts, _ = _read(path, scale=0.3048)
        assert np.allclose(parts[0].vertices, first[0].vertices * 0.3048)
    else:
        parts, warnings = _read(path, where="other.toml: geometry[2]")
        assert all(w.startswith("other.toml: geometry[2]") for w in warnings)
    assert calls == [1]


def test_cache_off_writes_nothing(tmp_path, monkeypatch):
    monkeypatch.setenv("LBL_ILLUM_CACHE_DIR", "off")
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    path = tmp_path / "room.obj"
    path.write_text(OBJ)
    _read(path)
    assert not (tmp_path / "xdg").exists()


def test_an_unwritable_cache_or_a_damaged_entry_costs_only_the_parse(tmp_path, monkeypatch):
    blocker = tmp_path / "a-file"
    blocker.write_text("not a folder")
    monkeypatch.setenv("LBL_ILLUM_CACHE_DIR", str(blocker))      # <file>/geometry cannot be made
    path = tmp_path / "room.obj"
    path.write_text(OBJ)
    parts, _ = _read(path)
    assert len(parts) >= 1
    folder = tmp_path / "cache"
    monkeypatch.setenv("LBL_ILLUM_CACHE_DIR", str(folder))
    _read(path)
    (entry,) = (folder / "geometry").glob("*.npz")
    entry.write_bytes(b"damaged")
    again, _ = _read(path)
    assert np.array_equal(again[0].vertices, parts[0].vertices)


def test_radiance_and_gltf_files_are_not_kept_as_single_files(tmp_path, cache_on):
    """They read other files: glTF is not kept, Radiance files by the files they read
    (below)."""
    from lbl_illum.scene.geometry_cache import cache_key

    for name in ("room.rad", "room.gltf"):
        (tmp_path / name).write_text("x")
        assert cache_key(tmp_path / name, "w", 1.0) is None
    (tmp_path / "room.obj").write_text(OBJ)
    assert cache_key(tmp_path / "room.obj", "w", 1.0) is not None


def test_a_kept_shape_is_built_once_and_read_back_equal(cache_on, monkeypatch):
    """kept_shape builds a shape once; a later call (another run) reads it back equal
    without building it; another name is another entry; with the cache off it is built
    every time."""
    from lbl_illum.scene.geometry_cache import kept_shape

    built = []

    def make():
        built.append(True)
        return np.arange(18, dtype=np.float64).reshape(2, 3, 3) / 7.0

    first = kept_shape("test-shape", make)
    second = kept_shape("test-shape", make)
    assert len(built) == 1 and np.array_equal(first, second) and second.shape == (2, 3, 3)
    kept_shape("another-shape", make)
    assert len(built) == 2
    monkeypatch.setenv("LBL_ILLUM_CACHE_DIR", "off")
    kept_shape("test-shape", make)
    assert len(built) == 3


def test_radiance_spheres_come_from_the_kept_icosphere_without_trimesh(cache_on):
    """A Radiance sphere is tessellated from trimesh's icosphere the first time, and from the
    kept copy afterwards (a new process does not import trimesh): the same bits."""
    import subprocess
    import sys

    from lbl_illum.scene import radfile

    code = ("import sys, numpy as np; from lbl_illum.scene import radfile; s = radfile._unit_sphere(); "
            "print('trimesh' in sys.modules, s.shape, float(np.abs(s).sum()).hex())")
    env = {**__import__("os").environ, "LBL_ILLUM_CACHE_DIR": str(cache_on.parent)}
    first = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True)
    again = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True)
    built = radfile._build_unit_sphere()
    assert first.stdout.split()[0] == "True" and again.stdout.split()[0] == "False"
    assert first.stdout.split()[1:] == again.stdout.split()[1:] == \
        ["(320,", "3,", "3)", float(np.abs(built).sum()).hex()]


ROOM_RAD = """void plastic white 0 0 5 0.6 0.6 0.6 0 0
void glass pane 0 0 3 0.8 0.8 0.8
white polygon floor 0 0 12  0 0 0  4 0 0  4 5 0  0 5 0
# a wall with a window hole drawn as a keyhole
white polygon wall 0 0 30  0 0 0  0 0 3  4 0 3  4 0 0  3 0 1  3 0 2  1 0 2  1 0 1  3 0 1  4 0 0
!xform -t 0 0 0.8 desk.rad
white sphere lamp 0 0 4 2 2 2.5 0.1
void light bulb 0 0 3 10 10 10
"""
DESK_RAD = """white polygon top 0 0 12  1 1 0  3 1 0  3 2 0  1 2 0
"""


def _radiance_scene(folder):
    (folder / "room.rad").write_text(ROOM_RAD)
    (folder / "desk.rad").write_text(DESK_RAD)
    (folder / "scene.toml").write_text('[[geometry]]\nfile = "room.rad"\n\n[sky]\ntype = "cie-overcast"\n'
                                        'horizontal_illuminance = 10000\n')
    return folder / "scene.toml"


def _scene_bits(scene):
    tri = scene.triangles
    return (tri.vertices.tobytes(), tri.material.tobytes(), repr(scene.materials), list(scene.warnings))


def test_a_radiance_file_read_again_comes_from_the_cache_equal(tmp_path, cache_on, monkeypatch):
    """The second load of a Radiance scene (a keyhole wall, an !xform include, a sphere, a
    modifier used by none) neither parses nor triangulates, and gives the same triangles,
    materials and warnings."""
    from lbl_illum import load_scene
    from lbl_illum.scene import radfile

    path = _radiance_scene(tmp_path)
    first = _scene_bits(load_scene(path))

    def refuse(*args, **kwargs):
        raise AssertionError("read again")

    monkeypatch.setattr(radfile, "read_rad", refuse)
    monkeypatch.setattr(radfile, "rad_surfaces", refuse)
    assert _scene_bits(load_scene(path)) == first
    assert len(list(cache_on.glob("*.npz"))) == 1 + 1              # the room, and the kept unit sphere


@pytest.mark.parametrize("edit", ["room.rad", "desk.rad"])
def test_an_edited_radiance_file_or_include_is_read_again(tmp_path, cache_on, edit):
    """Editing the file or a file its !xform includes makes the next load read it again
    (the desk top, 0.8 m up, moved to 1.8 m shows), never the kept copy."""
    from lbl_illum import load_scene

    path = _radiance_scene(tmp_path)
    load_scene(path)
    target = tmp_path / edit
    text = target.read_text()
    target.write_text(text.replace("-t 0 0 0.8", "-t 0 0 1.8") if edit == "room.rad"
                      else "white polygon top 0 0 12  1 1 1  3 1 1  3 2 1  1 2 1\n")
    z = load_scene(path).triangles.vertices[..., 2]
    assert np.isclose(z, 1.8).any() and not np.isclose(z, 0.8).any()


def test_a_radiance_reading_that_ran_a_command_is_not_kept(tmp_path, cache_on):
    """A file whose reading ran a program (its output is no file to check) is never kept."""
    from lbl_illum.scene.geometry import MeshPart
    from lbl_illum.scene.geometry_cache import load_radiance, radiance_key, store_radiance

    rad = tmp_path / "room.rad"
    rad.write_text(DESK_RAD)
    key = radiance_key(rad, "w", 1.0)
    part = MeshPart("white", "white", None, "white", np.zeros((1, 3, 3)))
    store_radiance(key, [rad, None], [], [part], [])
    assert load_radiance(key) is None
    store_radiance(key, [rad], [], [part], ["a note"])
    prims, parts, notes = load_radiance(key)
    assert prims == [] and notes == ["a note"] and np.array_equal(parts[0].vertices, part.vertices)

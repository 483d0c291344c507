"""Reading scene files (lbl_illum.scene): parsing, units, material mapping and every error path."""

import copy
from pathlib import Path

import numpy as np
import pytest

from lbl_illum.errors import InputError
from lbl_illum.options import Options
from lbl_illum.scene import Scene, load_scene, scene_from_dict
from lbl_illum.sky import CIEOvercastSky, NoSky

DATA = Path(__file__).parent / "data" / "scene"

MATERIALS = {
    "floor": {"type": "diffuse", "reflectance": 0.2},
    "white": {"type": "diffuse", "reflectance": 0.8},
}

RECTANGLE = {"shape": "rectangle", "origin": [0, 0, 0], "u": [2, 0, 0], "v": [0, 1, 0], "material": "floor"}


def minimal(**extra) -> dict:
    """A plain-dict scene: one 2 × 1 rectangle."""
    data = {"geometry": [dict(RECTANGLE)], "materials": copy.deepcopy(MATERIALS)}
    data["materials"].pop("white")
    data.update(extra)
    return data


def write(tmp_path: Path, text: str, name: str = "scene.toml") -> Path:
    path = tmp_path / name
    path.write_text(text)
    return path


def raises(message: str):
    return pytest.raises(InputError, match=message)


# -- the example scene file ------------------------------------------------------------

@pytest.fixture(scope="module")
def room() -> Scene:
    return load_scene(DATA / "room_corner.toml")


def test_example_scene(room):
    t = room.triangles
    assert [m.name for m in room.materials] == ["floor", "white", "grey"]
    assert t.vertices.dtype == np.float64 and t.vertices.shape == (len(t), 3, 3)
    assert t.material.dtype == np.int32 and t.sphere.dtype == np.int32
    assert len(t) == 2 + 2 + 1 + 12 + 81920 + 4 + 2
    assert room.warnings == []
    assert room.path == DATA / "room_corner.toml" and room.units == "m" and room.unit_scale == 1.0
    assert isinstance(room.sky, CIEOvercastSky) and room.sky.horizontal_illuminance == 10000
    assert room.sky.sun_horizontal_illuminance == pytest.approx(80000 * np.sin(np.radians(40)))
    assert room.sun.altitude == 40 and room.options.bounces == 3


def test_obj_usemtl_and_group_mapping_with_default(room):
    """Floor by its usemtl name, the wall by its group name, the unmapped Trim by the default."""
    t = room.triangles
    obj = slice(0, 5)                                  # the OBJ's five triangles come first
    area = {m.name: t.areas[obj][t.material[obj] == i].sum() for i, m in enumerate(room.materials)}
    assert area == pytest.approx({"floor": 2.0, "white": 2.0, "grey": 0.5})


def test_primitive_areas_and_sphere_ids(room):
    t = room.triangles
    sphere = t.sphere == 0
    assert sphere.sum() == 81920 and set(np.unique(t.sphere)) == {-1, 0}
    assert np.allclose(t.sphere_center, [[1, 0.5, 2]]) and np.allclose(t.sphere_radius, [0.25])
    white = t.areas[(t.material == 1) & ~sphere].sum()
    assert white == pytest.approx(2.0 + 6 * 0.25)                    # OBJ wall + box
    grey = t.areas[t.material == 2].sum()
    assert grey == pytest.approx(0.5 + 3.0 + 2.0)                    # trim + L polygon + rectangle


# -- units -------------------------------------------------------------------------------

def scaled(factor: float, units: str) -> dict:
    s = lambda v: [factor * x for x in v]  # noqa: E731
    return {
        "units": units,
        "materials": copy.deepcopy(MATERIALS),
        "geometry": [
            {"shape": "sphere", "center": s([0, 0, 1]), "radius": factor * 0.5, "material": "white"},
            {"shape": "box", "center": s([3, 0, 0.5]), "size": s([1, 2, 1]), "material": "white"},
            {"shape": "polygon", "vertices": [s(v) for v in [[-5, -5, 0], [5, -5, 0], [5, 5, 0], [-5, 5, 0]]],
             "material": "floor"},
            {"shape": "rectangle", "origin": s([0, 0, 3]), "u": s([1, 0, 0]), "v": s([0, 1, 0]),
             "material": "white"},
            {"file": "room_corner.obj", "material": "white"},
        ],
        "settings": {"min_spacing": factor * 0.1, "max_spacing": factor * 2},
    }


def test_mm_and_m_give_the_same_metres(tmp_path):
    obj = (DATA / "room_corner.obj").read_text()
    (tmp_path / "m").mkdir()
    (tmp_path / "mm").mkdir()
    (tmp_path / "m" / "room_corner.obj").write_text(obj)
    coords = lambda line: " ".join(str(1000 * float(x)) for x in line.split()[1:])  # noqa: E731
    (tmp_path / "mm" / "room_corner.obj").write_text("\n".join(
        f"v {coords(line)}" if line.startswith("v ") else line for line in obj.splitlines()))
    m = scene_from_dict(scaled(1.0, "m"), tmp_path / "m", "m.toml")
    mm = scene_from_dict(scaled(1000.0, "mm"), tmp_path / "mm", "mm.toml")
    assert mm.units == "mm" and mm.unit_scale == 0.001
    assert np.allclose(mm.triangles.vertices, m.triangles.vertices, rtol=1e-12, atol=1e-12)
    assert np.array_equal(mm.triangles.material, m.triangles.material)
    assert np.allclose(mm.triangles.sphere_radius, [0.5]) and np.allclose(mm.triangles.sphere_center, [[0, 0, 1]])
    # spacings stay in scene units (as on the command line): the same metres once scaled
    assert mm.options.min_spacing * mm.unit_scale == pytest.approx(m.options.min_spacing * m.unit_scale)
    assert mm.options.max_spacing * mm.unit_scale == pytest.approx(2.0)


def test_feet():
    scene = scene_from_dict(minimal(units="ft"), Path("."), "s.toml")
    assert scene.triangles.areas.sum() == pytest.approx(2 * 0.3048 ** 2)


# -- scene_from_dict -----------------------------------------------------------------------

def test_scene_from_dict_defaults():
    scene = scene_from_dict(minimal(), Path("."), "dict")
    assert isinstance(scene, Scene) and scene.path is None
    assert len(scene.triangles) == 2 and scene.triangles.areas.sum() == pytest.approx(2.0)
    assert isinstance(scene.sky, NoSky) and scene.sun is None and scene.options == Options()
    assert np.allclose(scene.triangles.normals, [0, 0, 1])
    assert scene.triangles.sphere_center.shape == (0, 3) and scene.triangles.sphere_radius.shape == (0,)


def test_schema_1_accepted_others_refused():
    scene_from_dict(minimal(schema=1), Path("."), "s.toml")
    with raises(r"^s.toml: 'schema' 2 is not supported"):
        scene_from_dict(minimal(schema=2), Path("."), "s.toml")


def test_unused_material_warns():
    data = minimal()
    data["materials"]["white"] = {"type": "diffuse", "reflectance": 0.8}
    scene = scene_from_dict(data, Path("."), "s.toml")
    assert [m.name for m in scene.materials] == ["floor", "white"]
    assert scene.warnings == ["s.toml: [materials.white] is not used by any geometry"]


def test_sun_below_horizon_warning_reaches_scene():
    sun = {"altitude": -5, "azimuth": 0, "direct_normal_illuminance": 100}
    scene = scene_from_dict(minimal(sun=sun), Path("."), "s.toml")
    assert any("below the horizon" in w and w.startswith("s.toml: [sun]") for w in scene.warnings)


# -- zero-area and duplicate triangles -------------------------------------------------------

def test_zero_area_and_duplicates_dropped_with_one_warning(tmp_path):
    (tmp_path / "messy.obj").write_text(
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 2 0 0\n"
        "f 1 2 3\n"            # kept
        "f 2 3 1\n"            # duplicate (rotated)
        "f 1 3 2\n"            # duplicate (reversed)
        "f 1 2 4\n"            # zero area (collinear)
        "f 1 1 3\n")           # zero area (repeated corner)
    data = minimal()
    data["geometry"].append({"file": "messy.obj", "material": "floor"})
    data["geometry"].append(dict(RECTANGLE))                    # duplicates the first entry
    scene = scene_from_dict(data, tmp_path, "scene.toml")
    assert len(scene.triangles) == 3
    assert scene.warnings == [
        "scene.toml: geometry[1] messy.obj: dropped 2 zero-area and 2 duplicate triangles",
        "scene.toml: geometry[2]: dropped 2 duplicate triangles",
    ]


# -- errors: every message names the file and the key or line ------------------------------------

def test_missing_scene_file(tmp_path):
    with raises(r"^scene.toml: no such file$"):
        load_scene(tmp_path / "scene.toml")


def test_toml_syntax_error_line_and_column(tmp_path):
    path = write(tmp_path, 'units = "m"\n\n[sky]\ntype = cie-overcast\n')
    with raises(r"^scene.toml: line 4, column 8: Invalid value$"):
        load_scene(path)


def test_missing_geometry_file(tmp_path):
    path = write(tmp_path, '[[geometry]]\nfile = "office.obj"\nmaterial = "floor"\n'
                           '[materials.floor]\ntype = "diffuse"\nreflectance = 0.2\n')
    with raises(r"^scene.toml: geometry\[0\] office.obj: no such file \(.*office.obj\)$"):
        load_scene(path)


def test_unreadable_geometry_file(tmp_path):
    (tmp_path / "bad.xyz").write_text("not a mesh\n")
    data = minimal()
    data["geometry"].append({"file": "bad.xyz", "material": "floor"})
    with raises(r"^s.toml: geometry\[1\] bad.xyz: cannot read the file"):
        scene_from_dict(data, tmp_path, "s.toml")


def test_unknown_top_level_key_suggests(tmp_path):
    path = write(tmp_path, '[setings]\nbounces = 2\n')
    with raises(r"^scene.toml: unknown key 'setings' \(did you mean 'settings'\?\)$"):
        load_scene(path)


def test_unknown_material_suggests():
    data = minimal()
    data["geometry"].append(dict(RECTANGLE, material="flor", origin=[0, 0, 1]))
    with raises(r"^office.toml: geometry\[1\]: unknown material 'flor' \(did you mean 'floor'\?\)$"):
        scene_from_dict(data, Path("."), "office.toml")


def test_unknown_material_in_file_mapping():
    data = minimal()
    data["geometry"] = [{"file": "room_corner.obj", "material": "floor", "materials": {"Floor": "flor"}}]
    with raises(r"^s.toml: geometry\[0\]: materials.Floor: unknown material 'flor' \(did you mean 'floor'\?\)$"):
        scene_from_dict(data, DATA, "s.toml")


def test_mapping_key_matching_nothing_suggests():
    data = minimal()
    data["geometry"] = [{"file": "room_corner.obj", "material": "floor", "materials": {"Flor": "floor"}}]
    with raises(r"^s.toml: geometry\[0\] room_corner.obj: 'materials' key 'Flor' .*did you mean 'Floor'\?"):
        scene_from_dict(data, DATA, "s.toml")


def test_unmapped_submesh_without_default():
    data = minimal()
    data["geometry"] = [{"file": "room_corner.obj", "materials": {"Floor": "floor", "Wall": "floor"}}]
    with raises(r"^s.toml: geometry\[0\] room_corner.obj: no material for sub-mesh 'trim_Trim' "
                r"\(group 'trim', material 'Trim'\)"):
        scene_from_dict(data, DATA, "s.toml")


@pytest.mark.parametrize("reflectance, message", [(-0.1, "must be >= 0"), (1.5, "must be <= 1"),
                                                  ("high", "must be a number")])
def test_bad_reflectance(tmp_path, reflectance, message):
    value = f'"{reflectance}"' if isinstance(reflectance, str) else reflectance
    path = write(tmp_path, f'[[geometry]]\nshape = "rectangle"\norigin = [0, 0, 0]\nu = [1, 0, 0]\n'
                           f'v = [0, 1, 0]\nmaterial = "wall"\n'
                           f'[materials.wall]\ntype = "diffuse"\nreflectance = {value}\n')
    with raises(rf"^scene.toml: \[materials.wall\]: 'reflectance' {message}"):
        load_scene(path)


def test_nan_vertex_in_toml(tmp_path):
    path = write(tmp_path, '[[geometry]]\nshape = "polygon"\n'
                           'vertices = [[0, 0, 0], [1, 0, nan], [1, 1, 0]]\nmaterial = "floor"\n'
                           '[materials.floor]\ntype = "diffuse"\nreflectance = 0.2\n')
    with raises(r"^scene.toml: geometry\[0\]: 'vertices\[1\]' must be finite, got nan$"):
        load_scene(path)


def test_nan_vertex_in_geometry_file(tmp_path):
    (tmp_path / "nan.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 nan 0\nf 1 2 3\n")
    data = minimal()
    data["geometry"] = [{"file": "nan.obj", "material": "floor"}]
    with raises(r"^s.toml: geometry\[0\] nan.obj: 1 triangle with a NaN or infinite vertex"):
        scene_from_dict(data, tmp_path, "s.toml")


def test_empty_geometry(tmp_path):
    with raises(r"^scene.toml: the scene has no geometry"):
        load_scene(write(tmp_path, 'units = "m"\n'))
    with raises(r"^s.toml: the scene has no triangles$"):
        scene_from_dict(minimal(geometry=[]), Path("."), "s.toml")


@pytest.mark.parametrize("change, message", [
    ({"units": "furlong"}, r"'units': unknown unit 'furlong'"),
    ({"sky": "overcast"}, r"\[sky\] must be a table"),
    ({"sky": {"type": "overcast"}}, r"\[sky\]: 'type' must be one of"),
    ({"sky": {"type": "uniform", "horizontal_iluminance": 1}}, r"\[sky\]: unknown key 'horizontal_iluminance' "
                                                                 r"\(did you mean 'horizontal_illuminance'\?\)"),
    ({"sun": {"altitude": 40}}, r"\[sun\]: missing key 'azimuth'"),
    ({"settings": {"bounce": 2}}, r"\[settings\]: unknown key 'bounce' \(did you mean 'bounces'\?\)"),
    ({"settings": {"accuracy": -1}}, r"\[settings\]: 'accuracy' must be >= 0"),
    ({"materials": {"floor": "grey"}}, r"\[materials.floor\] must be a table"),
    ({"materials": "floor"}, r"\[materials\] must be a table"),
    ({"geometry": {"shape": "box"}}, r"'geometry' must be an array of tables"),
    ({"geometry": ["box"]}, r"geometry\[0\]: must be a table"),
    ({"geometry": [{"material": "floor"}]}, r"geometry\[0\]: needs 'file' .* or 'shape'"),
    ({"geometry": [dict(RECTANGLE, file="a.obj")]}, r"geometry\[0\]: give either 'file' or 'shape'"),
    ({"geometry": [{k: v for k, v in RECTANGLE.items() if k != "material"}]}, r"geometry\[0\]: missing key 'material'"),
    ({"geometry": [dict(RECTANGLE, material=3)]}, r"geometry\[0\]: a material must be given by its name"),
    ({"geometry": [{"file": 7, "material": "floor"}]}, r"geometry\[0\]: 'file' must be a file name"),
    ({"geometry": [{"file": "a.obj", "matrial": "floor"}]}, r"geometry\[0\]: unknown key 'matrial' "
                                                            r"\(did you mean 'material'\?\)"),
    ({"geometry": [{"file": "a.obj", "materials": "floor"}]}, r"geometry\[0\]: 'materials' must be a table"),
])
def test_type_and_value_errors_are_clean(change, message):
    with raises(rf"^s.toml: {message}"):
        scene_from_dict(minimal(**change), Path("."), "s.toml")


def test_not_a_table():
    with raises(r"^s.toml: a scene must be a table"):
        scene_from_dict(["geometry"], Path("."), "s.toml")

"""Reading scene files (lbl_illum.scene.scenefile): parsing, units, material mapping and every error path."""

import copy
from pathlib import Path

import numpy as np
import pytest

from lbl_illum.errors import InputError
from lbl_illum.options import Options
from lbl_illum.scene.scenefile import Scene, load_scene, scene_from_dict
from lbl_illum.daylight.sky import CIEOvercastSky, NoSky

DATA = Path(__file__).resolve().parents[1] / "data" / "scene"

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
    # spacings are given in scene units and come out in metres, as every length does
    assert mm.options.min_spacing == pytest.approx(m.options.min_spacing) == pytest.approx(0.1)
    assert mm.options.max_spacing == pytest.approx(2.0)


def test_feet():
    scene = scene_from_dict(minimal(units="ft"), Path("."), "s.toml")
    assert scene.triangles.areas.sum() == pytest.approx(2 * 0.3048 ** 2)


# -- scene_from_dict -----------------------------------------------------------------------

def test_scene_from_dict_defaults():
    scene = scene_from_dict(minimal(), Path("."), "dict")
    assert isinstance(scene, Scene) and scene.path is None
    assert len(scene.triangles) == 2 and scene.triangles.areas.sum() == pytest.approx(2.0)
    assert isinstance(scene.sky, NoSky) and scene.sun is None and scene.options == Options().with_preset("high")
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


def test_unmapped_submesh_takes_the_material_of_its_name(tmp_path):
    """Without a mapping or a default, a sub-mesh takes a material named like one of its
    names (most specific first): a [materials] table, else a modifier of a Radiance file
    of the scene (Radiance's obj2rad makes a usemtl name a modifier); an alias is
    followed, and only the modifiers used become materials."""
    import shutil

    shutil.copy(DATA / "room_corner.obj", tmp_path)
    # a surface named like a group ('trim') is no material: the sub-mesh's next name decides
    (tmp_path / "trim.mat").write_text("void metal brass\n0\n0\n5 .9 .6 .2 .8 .05\n\nvoid alias Trim brass\n\n"
                                       "brass polygon trim\n0\n0\n9 5 5 0  6 5 0  5 6 0\n")
    data = minimal()
    data["geometry"] = [{"file": "trim.mat"}, {"file": "room_corner.obj", "materials": {"Wall": "floor"}}]
    data["materials"]["white"] = {"type": "diffuse", "reflectance": 0.8}
    scene = scene_from_dict(data, tmp_path, "s.toml")
    names = [m.name for m in scene.materials]
    used = {names[i] for i in np.unique(scene.triangles.material)}
    assert used == {"floor", "brass"}             # group 'floor' (a table), usemtl 'Trim' (the alias)
    assert len(scene.materials) == 3
    brass = scene.materials[names.index("brass")]
    assert brass.kind == "metal" and brass.reflectance == (0.9, 0.6, 0.2) and brass.specularity == 0.8


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


# -- daylight: [site], time, CIE general and Perez skies, weather files ----------------------------

import datetime as dt
import shutil

from lbl_illum.daylight.sky import CIEGeneralSky, PerezSky
from lbl_illum.daylight.solar import solar_position

WEATHER = Path(__file__).resolve().parents[1] / "data" / "berkeley_excerpt.epw"
SITE = {"latitude": 37.876, "longitude": -122.247, "time_zone": -8, "elevation": 200}


def test_sun_with_zero_direct_normal_positions_the_sky_only():
    scene = scene_from_dict(minimal(sky={"type": "cie-clear", "horizontal_illuminance": 20000},
                                    sun={"altitude": 30, "azimuth": 135, "direct_normal_illuminance": 0}),
                            Path("."), "s.toml")
    assert isinstance(scene.sky, CIEGeneralSky) and scene.sky.sky_type == 12
    assert (scene.sky.sun_altitude, scene.sky.sun_azimuth) == (30, 135)
    assert not scene.sun.is_up and scene.sky.sun_horizontal_illuminance == 0.0
    assert scene.sky.ground_luminance == pytest.approx(0.2 * 20000 / np.pi)
    assert scene.warnings == []


def test_site_and_time_position_sky_and_sun():
    time = "2024-06-21 10:00"
    scene = scene_from_dict(minimal(site=SITE, sky={"type": "cie-general", "sky_type": 7},
                                    sun={"time": time, "direct_normal_illuminance": 70000}), Path("."), "s.toml")
    expect = solar_position(dt.datetime(2024, 6, 21, 18), 37.876, -122.247, 200)   # 10:00 PST = 18:00 UTC
    assert scene.sun.altitude == pytest.approx(expect.altitude, abs=1e-9)
    assert scene.sun.azimuth == pytest.approx(expect.azimuth, abs=1e-9)
    assert scene.sun.time == dt.datetime(2024, 6, 21, 18)
    assert (scene.sky.sun_altitude, scene.sky.sun_azimuth) == (scene.sun.altitude, scene.sun.azimuth)
    assert scene.sky.sun_horizontal_illuminance == pytest.approx(scene.sun.horizontal_illuminance)
    # the same instant in UTC, and a [sky] time without [sun]: a sun that only positions
    utc = scene_from_dict(minimal(site=SITE, sky={"type": "cie-general", "sky_type": 7, "time": "2024-06-21 18:00Z"}),
                          Path("."), "s.toml")
    assert utc.sun.altitude == pytest.approx(scene.sun.altitude, abs=1e-9)
    assert utc.sun.direct_normal_illuminance == 0.0 and not utc.sun.is_up


def test_perez_sky_in_a_scene_brings_its_sun():
    sky = {"type": "perez", "direct_normal_irradiance": 700, "diffuse_horizontal_irradiance": 110, "dew_point": 12,
           "time": "2024-06-21 12:00"}
    scene = scene_from_dict(minimal(site=SITE, sky=sky), Path("."), "s.toml")
    assert isinstance(scene.sky, PerezSky) and scene.sun.is_up
    assert scene.sun.direct_normal_illuminance == scene.sky.direct_normal_illuminance > 50000
    assert scene.sky.sun_horizontal_illuminance == pytest.approx(scene.sun.horizontal_illuminance)
    # a [sun] positions it instead; without direct_normal_illuminance the sky's value is used, 0 turns it off
    sky.pop("time")
    for sun, edn in (({"altitude": 50, "azimuth": 180}, scene.sky.direct_normal_illuminance),
                     ({"altitude": 50, "azimuth": 180, "direct_normal_illuminance": 0}, 0.0)):
        s = scene_from_dict(minimal(sky=sky, sun=sun), Path("."), "s.toml")
        assert s.sky.sun_altitude == 50 and s.sun.direct_normal_illuminance == pytest.approx(edn, rel=0.05)


def test_weather_file_hour(tmp_path):
    shutil.copy(WEATHER, tmp_path / "site.epw")
    path = write(tmp_path, 'units = "m"\n[[geometry]]\nshape = "rectangle"\norigin = [0, 0, 0]\nu = [1, 0, 0]\n'
                           'v = [0, 1, 0]\nmaterial = "g"\n[materials.g]\ntype = "diffuse"\nreflectance = 0.2\n'
                           '[sky]\nweather = "site.epw"\ntime = "06-20 11:30"\n')
    scene = load_scene(path)
    assert isinstance(scene.sky, PerezSky)
    # EPW hour 12 of 20 June (11:00–12:00 PST), sun at 11:30 PST = 19:30 UTC
    assert scene.sky.horizontal_illuminance == 15442 and scene.sun.direct_normal_illuminance == 90294
    assert scene.sun.time == dt.datetime(1999, 6, 20, 19, 30)
    expect = solar_position(dt.datetime(1999, 6, 20, 19, 30), 37.876, -122.247, 200)
    assert scene.sky.sun_altitude == pytest.approx(expect.altitude, abs=1e-9)
    assert 1.065 < scene.sky.clearness and scene.sky.brightness > 0
    # irradiance converted by the Perez efficacy model instead of the file's illuminance
    text = path.read_text().replace('time = "06-20 11:30"', 'time = "06-20 11:30"\nweather_values = "irradiance"')
    conv = load_scene(write(tmp_path, text, "conv.toml"))
    assert conv.sky.horizontal_illuminance == pytest.approx(15442, rel=0.01)   # the file was made that way
    # the overcast day: no direct sun
    night = load_scene(write(tmp_path, path.read_text().replace("06-20 11:30", "06-21 12:00"), "o.toml"))
    assert night.sun.direct_normal_illuminance == 0.0 and night.sky.clearness == 1.0


@pytest.mark.parametrize("change, message", [
    ({"sky": {"type": "cie-general", "sky_type": 0}}, r"\[sky\]: 'sky_type' must be a whole number 1…15, got 0$"),
    ({"sky": {"type": "cie-clear", "time": "2024-06-21 12:00"}}, r"\[sky\]: 'time' needs a \[site\] table"),
    ({"site": {"latitude": 40}, "sky": {"type": "cie-clear", "time": "2024-06-21 12:00"}},
     r"\[site\]: missing key 'longitude'$"),
    ({"site": {"latitude": 40, "longitude": -105}, "sky": {"type": "cie-clear", "time": "2024-06-21 12:00"}},
     r"\[sky\]: 'time' 2024-06-21 12:00 is local standard time: \[site\] needs 'time_zone'"),
    ({"site": SITE, "sky": {"type": "cie-clear", "time": "June 21"}}, r"\[sky\]: 'time' must look like"),
    ({"site": SITE, "sky": {"type": "cie-clear", "time": "2024-06-21 12:00"},
      "sun": {"altitude": 30, "azimuth": 0, "direct_normal_illuminance": 0}}, r"\[sky\]: 'time' and a \[sun\] table"),
    ({"site": SITE, "sun": {"time": "2024-06-21 12:00", "altitude": 3, "direct_normal_illuminance": 0}},
     r"\[sun\]: give the sun's position by 'altitude' and 'azimuth' or by 'time', not both"),
    ({"sky": {"type": "cie-clear"}}, r"\[sky\]: CIE general sky type 12 needs the sun's position"),
    ({"sky": {"weather": "x.epw", "time": "06-21 12:00", "type": "cie-clear"}}, r"\[sky\]: a 'weather' file gives "
                                                                                  r"a Perez sky"),
    ({"sky": {"weather": "x.epw"}}, r"\[sky\]: missing key 'time'"),
    ({"sky": {"weather": "x.epw", "time": "06-21 12:00"}, "site": SITE}, r"\[site\] is not used with a weather"),
    ({"sky": {"weather": "x.epw", "time": "06-21 12:00", "weather_values": "lux"}},
     r"\[sky\]: 'weather_values' must be one"),
    ({"sky": {"type": "cie-overcast", "weather_values": "lux"}},
     r"\[sky\]: 'weather_values' goes with a 'weather' file"),
    ({"sky": {"weather": "x.epw", "time": "06-21 12:00"}}, r"\[sky\] weather x.epw: no such weather file"),
])
def test_daylight_errors(change, message):
    with raises(rf"^s.toml: {message}") as exc:
        scene_from_dict(minimal(**change), Path("."), "s.toml")
    assert "\n" not in str(exc.value)


def test_weather_errors_name_file_and_line(tmp_path):
    lines = WEATHER.read_text().splitlines()
    lines[29] = lines[29].replace(",60,", ",sixty,", 1)
    (tmp_path / "bad.epw").write_text("\n".join(lines) + "\n")
    sky = {"weather": "bad.epw", "time": "06-20 12:00"}
    with raises(r"^s.toml: \[sky\] weather bad.epw: line 30: field 5 \(minute\) must be a number, got 'sixty'$"):
        scene_from_dict(minimal(sky=sky), tmp_path, "s.toml")
    shutil.copy(WEATHER, tmp_path / "ok.epw")
    with raises(r"^s.toml: \[sky\] \(weather ok.epw\): 'time' '01-15 12:00': no such hour in ok.epw \(the file "
                r"runs from 06-20 hour 1 to 12-21 hour 24\)$"):
        scene_from_dict(minimal(sky={"weather": "ok.epw", "time": "01-15 12:00"}), tmp_path, "s.toml")


def test_site_warnings():
    scene = scene_from_dict(minimal(site=dict(SITE, longitude=122.247), sky={"type": "cie-clear", "time":
                                                                             "2024-06-21 12:00"}),
                            Path("."), "s.toml")
    assert any("west longitudes are negative" in w for w in scene.warnings)
    unused = scene_from_dict(minimal(site=SITE), Path("."), "s.toml")
    assert unused.warnings == ["s.toml: [site]: not used (no 'time' in [sun] or [sky])"]
    night = scene_from_dict(minimal(site=SITE, sky={"type": "cie-clear", "time": "2024-06-21 23:00"}),
                            Path("."), "s.toml")
    assert any("CIE general sky is defined for a sun above it" in w for w in night.warnings)


def test_office_clear_sky_example_loads():
    from conftest import EXAMPLES

    scene = load_scene(EXAMPLES / "office" / "office_clear_sky.toml")
    assert isinstance(scene.sky, CIEGeneralSky) and scene.sky.sky_type == 12 and scene.sun.is_up
    assert scene.warnings == []

"""Radiance scene files as geometry and materials (lbl_illum.scene.radfile, scene loading)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from lbl_illum.errors import InputError
from lbl_illum.scene.radfile import read_rad, rad_surfaces, read_rad_surfaces
from lbl_illum.scene.scenefile import load_scene


def area(tri):
    return 0.5 * np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1).sum()


QUADRICS = """
m sphere ball
0
0
4 1 2 3 0.5

m cylinder pipe
0
0
7 0 0 0  0 0 2  0.25

m cone lamp
0
0
8 0 0 0  1 1 1  0.4 0.1

m cone flat
0
0
8 0 0 0  0 0 0.001  0.2 1.0

m cup shade
0
0
8 0 0 0  0 0 1  0.3 0.6

m ring disk
0
0
8 0 0 0  0 1 0  0 2

m ring washer
0
0
8 5 5 5  1 1 0  0.5 1.5
"""

EXACT = {
    "ball": 4 * np.pi * 0.25,
    "pipe": 2 * np.pi * 0.25 * 2,
    "lamp": np.pi * 0.5 * np.hypot(np.sqrt(3), 0.3),
    "flat": np.pi * 1.2 * np.hypot(0.001, 0.8),
    "shade": np.pi * 0.9 * np.hypot(1, 0.3),
    "disk": np.pi * 4,
    "washer": np.pi * (1.5 ** 2 - 0.5 ** 2),
}


@pytest.mark.parametrize("name", list(EXACT))
def test_quadric_areas_are_exact(tmp_path, name):
    prims = [p for p in read_rad(_write(tmp_path, "q.rad", QUADRICS), "q.rad") if p.name == name]
    (part,) = rad_surfaces([_with_modifier(p, name) for p in prims], "q.rad")
    assert area(part.vertices) == pytest.approx(EXACT[name], rel=1e-6)


def test_quadrics_lie_on_their_surfaces(tmp_path):
    prims = read_rad(_write(tmp_path, "q.rad", QUADRICS), "q.rad")
    parts = {p.name: p for p in rad_surfaces([_with_modifier(p, p.name) for p in prims], "q.rad")}
    v = parts["ball"].vertices.reshape(-1, 3)
    r = np.linalg.norm(v - [1, 2, 3], axis=1)
    assert np.all(np.abs(r / 0.5 - 1) < 0.03)           # within 3 % of the radius, area exact
    v = parts["pipe"].vertices.reshape(-1, 3)
    assert np.allclose(v[:, 2].min(), 0) and np.allclose(v[:, 2].max(), 2)
    assert np.all(np.abs(np.hypot(v[:, 0], v[:, 1]) / 0.25 - 1) < 0.01)
    n = np.cross(parts["disk"].vertices[:, 1] - parts["disk"].vertices[:, 0],
                 parts["disk"].vertices[:, 2] - parts["disk"].vertices[:, 0])
    assert np.all(n[:, 1] > 0)                            # along the ring's normal
    # a cup faces inwards, a cone outwards
    for name, sign in (("shade", -1), ("lamp", 1)):
        tri = parts[name].vertices
        centre = tri.mean(axis=1)
        normal = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
        axis = np.array([0, 0, 1.0]) if name == "shade" else np.ones(3) / np.sqrt(3)
        radial = centre - np.outer(centre @ axis, axis)
        assert np.all(sign * np.einsum("ij,ij->i", normal, radial) > 0)


def _write(folder, name, text):
    path = folder / name
    path.write_text(text)
    return path


def _with_modifier(p, name):
    p.modifier = name
    return p


KEYHOLE = """# a wall with a window hole, as SketchUp's exporter writes it
void plastic wallpaint
0
0
5 .5 .5 .5 0 0

void glass pane
0
0
3 .96 .96 .96

void alias paint2 wallpaint

wallpaint polygon south
0
0
30 0 0 0  6 0 0  6 0 3  0 0 3  0 0 0  1 0 1  2 0 1  2 0 2  1 0 2  1 0 1

pane polygon window
0
0
12 1 0 1  2 0 1  2 0 2  1 0 2

paint2 polygon north
0
0
12 0 5 0  6 5 0  6 5 3  0 5 3
"""


def test_scene_from_radiance_files_alone(tmp_path):
    _write(tmp_path, "room.rad", KEYHOLE)
    _write(tmp_path, "scene.toml", '[[geometry]]\nfile = "room.rad"\n[sky]\ntype = "uniform"\n'
                                   'horizontal_illuminance = 1000\n')
    scene = load_scene(tmp_path / "scene.toml")
    by_name = {m.name: m for m in scene.materials}
    assert set(by_name) == {"wallpaint", "pane"}                                  # paint2: an alias of wallpaint
    assert by_name["wallpaint"].kind == "diffuse" and by_name["wallpaint"].reflectance == (0.5, 0.5, 0.5)
    glass = by_name["pane"]
    # Radiance's glass of transmissivity 0.96 transmits (1-r)^2 t/(1 - r^2 t^2) at normal incidence
    r = ((1.52 - 1) / (1.52 + 1)) ** 2
    assert glass.transmittance[0] == pytest.approx((1 - r) ** 2 * 0.96 / (1 - (r * 0.96) ** 2), rel=1e-9)
    tri = scene.triangles
    wall = tri.material == [m.name for m in scene.materials].index("wallpaint")
    south = wall & (np.abs(tri.vertices[:, :, 1]).max(axis=1) < 1e-9)
    assert tri.areas[south].sum() == pytest.approx(18 - 1)                       # the window stays open
    assert tri.areas[wall & ~south].sum() == pytest.approx(18)                   # the north wall, by the alias


def test_mapping_and_scene_tables_win_over_definitions(tmp_path):
    _write(tmp_path, "room.rad", KEYHOLE)
    _write(tmp_path, "scene.toml", '[[geometry]]\nfile = "room.rad"\nmaterials = { pane = "clear" }\n'
                                   '[materials.clear]\ntype = "glass"\ntransmittance = 0.8\nmodel = "constant"\n'
                                   '[materials.wallpaint]\ntype = "diffuse"\nreflectance = 0.7\n'
                                   '[sky]\ntype = "uniform"\nhorizontal_illuminance = 1000\n')
    scene = load_scene(tmp_path / "scene.toml")
    names = [m.name for m in scene.materials]
    assert names == ["clear", "wallpaint"]
    assert scene.materials[1].reflectance == (0.7, 0.7, 0.7)


def test_definitions_from_a_separate_mat_file(tmp_path):
    body = KEYHOLE.split("wallpaint polygon south")[0]
    _write(tmp_path, "materials.mat", body)
    _write(tmp_path, "walls.rad", "wallpaint polygon south" + KEYHOLE.split("wallpaint polygon south")[1])
    _write(tmp_path, "scene.toml", '[[geometry]]\nfile = "walls.rad"\n[[geometry]]\nfile = "materials.mat"\n'
                                   '[sky]\ntype = "uniform"\nhorizontal_illuminance = 1000\n')
    scene = load_scene(tmp_path / "scene.toml")
    assert {m.name for m in scene.materials} == {"wallpaint", "pane"}


@pytest.mark.parametrize("text, message", [
    ("m polygon p\n0\n0\n7 0 0 0 1 0 0 1", "polygon 'p': needs 3 reals per vertex"),
    ("m polygon p\n0\n0\n9 0 0 0 1 0 0 1 x 0", "line 1: polygon 'p': a real argument is not a number"),
    ("m polygon p\n0\n0\n12 0 0 0 1 0 0", "12 real arguments announced, 6 left"),
    ("m sphere s\n0\n0\n3 0 0 0", "sphere 's': needs 4 reals"),
    ("m polygon p\n0\n0", "missing its real argument count"),
    ("m ring r\n0\n0\n8 0 0 0 0 0 1 2 2", "ring 'r': needs a normal and two different, non-negative radii"),
])
def test_malformed_files_are_refused_with_the_line(tmp_path, text, message):
    path = _write(tmp_path, "bad.rad", text)
    with pytest.raises(InputError, match="^bad.rad: .*" + message.replace("(", r"\(").replace(")", r"\)")
                       .replace("!", r"\!")):
        read_rad_surfaces(path, "bad.rad")


def test_undefined_modifier_is_refused_naming_it(tmp_path):
    _write(tmp_path, "room.rad", "unknown polygon p\n0\n0\n9 0 0 0 1 0 0 0 1 0\n")
    _write(tmp_path, "scene.toml", '[[geometry]]\nfile = "room.rad"\n[sky]\ntype = "uniform"\n'
                                   'horizontal_illuminance = 1000\n')
    with pytest.raises(InputError, match="modifier 'unknown' is not defined"):
        load_scene(tmp_path / "scene.toml")


def test_other_primitives_are_counted_in_one_warning(tmp_path):
    text = KEYHOLE + "\nvoid mesh chair\n1 chair.rtm\n0\n0\n\nvoid instance tree\n1 tree.oct\n0\n0\n"
    path = _write(tmp_path, "room.rad", text)
    warnings = []
    read_rad_surfaces(path, "room.rad", 1.0, warnings)
    assert warnings == ["room.rad: skipped 1 'mesh', 1 'instance' primitives (read: polygon, sphere, bubble, "
                        "cylinder, tube, cone, cup, ring, mesh; a mesh is read through the OBJ it was compiled from, "
                        "NAME.obj beside NAME.rtm)"]


MESH_ROOM = """void plastic Floor
0
0
5 .3 .3 .3 0 0
void plastic Wall
0
0
5 .5 .5 .5 0 0
void metal Trim
0
0
5 .9 .6 .2 .8 .05
void mesh chair
5 chair.rtm -t 10 0 0
0
0
Wall mesh chair2
6 chair.rtm -mx -t 20 0 0
0
0
"""


def test_mesh_is_read_through_its_source_obj(tmp_path):
    """``mod mesh id  1+ file.rtm [xform args]``: the faces of file.obj beside it (the
    room corner: floor 2, wall 2 as one quad, trim 0.5 in units²), moved as an instance;
    with ``void`` each face takes its usemtl name as modifier (obj2mesh's stored
    materials), otherwise the given modifier on every face (Radiance's mesh); a mirror
    keeps every triangle facing the side it faced."""
    import shutil

    shutil.copy(Path(__file__).resolve().parents[1] / "data" / "scene" / "room_corner.obj", tmp_path / "chair.obj")
    _write(tmp_path, "room.rad", MESH_ROOM)
    _write(tmp_path, "scene.toml", '[[geometry]]\nfile = "room.rad"\n[sky]\ntype = "uniform"\n'
                                   'horizontal_illuminance = 1000\n')
    scene = load_scene(tmp_path / "scene.toml")
    assert scene.warnings == []
    tri = scene.triangles
    names = [m.name for m in scene.materials]
    area = {n: tri.areas[tri.material == i].sum() for i, n in enumerate(names)}
    assert area == pytest.approx({"Floor": 2.0, "Wall": 2.0 + 4.5, "Trim": 0.5})
    assert scene.materials[names.index("Trim")].kind == "metal"
    x = tri.vertices[:, :, 0]
    first, second = x.max(axis=1) <= 12.0, x.min(axis=1) >= 18.0
    assert (first | second).all() and first.sum() == 5 and second.sum() == 5
    assert (tri.material[second] == names.index("Wall")).all()
    # the mirror image (in x) of the floor still faces up, of the wall (in the xz plane) still +y
    n = tri.normals
    floor2 = second & (np.abs(tri.vertices[:, :, 2]).max(axis=1) < 1e-12)
    assert floor2.sum() == 2 and np.allclose(n[floor2], [0, 0, 1])
    np.testing.assert_allclose(n[first & (tri.material == names.index("Wall"))], [[0, 1, 0]] * 2, atol=1e-12)
    np.testing.assert_allclose(n[second & (np.abs(tri.vertices[:, :, 1]).max(axis=1) < 1e-12)], [[0, 1, 0]] * 2,
                               atol=1e-12)


@pytest.mark.parametrize("spec,warned", [(0.0, False), (0.04, True)])
def test_trans_becomes_translucent(tmp_path, spec, warned):
    """Radiance's trans (C, s, α, t_d, t_s): diffuse reflectance C (1 − s)(1 − t_d) and
    diffuse transmittance C (1 − s) t_d; a specular part is warned."""
    _write(tmp_path, "shade.rad", f"void trans fabric\n0\n0\n7 0.8 0.6 0.4 {spec} 0 0.25 0\n\n"
                                  "fabric polygon shade\n0\n0\n12 0 0 1  1 0 1  1 1 1  0 1 1\n")
    _write(tmp_path, "scene.toml", '[[geometry]]\nfile = "shade.rad"\n[sky]\ntype = "uniform"\n'
                                   'horizontal_illuminance = 1000\n')
    scene = load_scene(tmp_path / "scene.toml")
    (m,) = scene.materials
    C = np.array([0.8, 0.6, 0.4]) * (1 - spec)
    assert m.kind == "translucent"
    assert np.allclose(m.reflectance, C * 0.75) and np.allclose(m.transmittance, C * 0.25)
    assert any("trans read as translucent" in w for w in scene.warnings) == warned


# -- commands: !xform read here, the others through Radiance ----------------------------------------------

SQUARE = "m polygon sq\n0\n0\n12 0 0 0 1 0 0 1 1 0 0 1 0\n"


def _area_and_centre(prims):
    parts = rad_surfaces(prims, "t")
    tri = np.concatenate([p.vertices for p in parts])
    return area(tri), tri.reshape(-1, 3).mean(axis=0)


def test_xform_moves_turns_scales_and_mirrors(tmp_path):
    _write(tmp_path, "sq.rad", SQUARE)
    _write(tmp_path, "top.rad", "!xform -rz 90 -t 5 0 0 -s 2 sq.rad\n")
    prims = read_rad(tmp_path / "top.rad", "top.rad")
    pts = prims[0].reals.reshape(-1, 3)
    # (x, y) -> rotated 90 degrees about z -> moved 5 along x -> scaled 2 about the origin
    expected = 2.0 * (np.array([[0, 0, 0], [0, 1, 0], [-1, 1, 0], [-1, 0, 0]]) + [5, 0, 0])
    np.testing.assert_allclose(pts, expected, atol=1e-12)
    # a mirror reverses the vertices, so the normal stays on the side it was on
    _write(tmp_path, "mir.rad", "!xform -mz sq.rad\n")
    m = read_rad(tmp_path / "mir.rad", "mir.rad")[0].reals.reshape(-1, 3)
    n = np.cross(m[1] - m[0], m[2] - m[0])
    assert n[2] < 0 and np.allclose(m[:, 2], 0)              # the plane's own normal was +z; mirrored it is -z
    sphere = "m sphere ball\n0\n0\n4 1 0 0 0.5\n"
    _write(tmp_path, "ball.rad", sphere)
    _write(tmp_path, "b.rad", "!xform -s 3 -t 0 0 1 ball.rad\n")
    np.testing.assert_allclose(read_rad(tmp_path / "b.rad", "b.rad")[0].reals, [3, 0, 1, 1.5])


def test_xform_arrays_nested_files_and_modifiers(tmp_path):
    (tmp_path / "parts").mkdir()
    _write(tmp_path / "parts", "sq.rad", SQUARE)
    _write(tmp_path / "parts", "row.rad", "!xform -a 3 -t 2 0 0 parts/sq.rad\n")     # paths from the top folder
    _write(tmp_path, "top.rad", "void plastic paint\n0\n0\n5 .5 .5 .5 0 0\n"
                                "!xform -m paint -a 2 -t 0 10 0 parts/row.rad\n")
    prims = read_rad(tmp_path / "top.rad", "top.rad")
    polys = [p for p in prims if p.kind == "polygon"]
    assert len(polys) == 6 and all(p.modifier == "paint" for p in polys)
    origins = sorted(tuple(p.reals[:2]) for p in polys)
    assert origins == [(0, 0), (0, 10), (2, 0), (2, 10), (4, 0), (4, 10)]
    total, _ = _area_and_centre(prims)
    assert total == pytest.approx(6.0)


@pytest.mark.parametrize("top, message", [
    ("!xform -t 1 0 0 missing.rad\n", "no such file 'missing.rad'"),
    ("!xform -t 1 0\n", "option '-t': missing or bad value"),
    ("!xform -q 1 sq.rad\n", "option '-q' is not supported"),
    ("!xform loop.rad\n", "recursive include"),
    ("!xform\n", "without a file"),
])
def test_bad_xform_is_one_line_naming_the_line(tmp_path, top, message):
    _write(tmp_path, "sq.rad", SQUARE)
    _write(tmp_path, "loop.rad", "!xform top.rad\n")
    _write(tmp_path, "top.rad", "# first\n" + top)
    with pytest.raises(InputError, match=r"^top.rad: line 2.*" + message.replace("(", r"\(").replace(")", r"\)")):
        read_rad(tmp_path / "top.rad", "top.rad")


def test_other_commands_need_radiance(tmp_path, monkeypatch):
    import lbl_illum.io.radiance as radiance

    _write(tmp_path, "box.rad", "void plastic m\n0\n0\n5 .5 .5 .5 0 0\n!genbox m box 1 2 3\n")
    monkeypatch.setattr(radiance, "radiance_programs", lambda: None)
    with pytest.raises(InputError, match=r"^box.rad: line 5: the command '!genbox m box 1 2 3' needs Radiance's genbox"):
        read_rad(tmp_path / "box.rad", "box.rad")


def test_other_commands_run_through_radiance(tmp_path):
    from conftest import radiance_tool

    if radiance_tool("genbox") is None:
        pytest.skip("Radiance's genbox is not installed (pip install pyradiance)")
    _write(tmp_path, "box.rad", "void plastic m\n0\n0\n5 .5 .5 .5 0 0\n!genbox m box 1 2 3\n")
    prims = read_rad(tmp_path / "box.rad", "box.rad")
    polys = [p for p in prims if p.kind == "polygon"]
    assert len(polys) == 6
    total, centre = _area_and_centre(prims)
    assert total == pytest.approx(2 * (1 * 2 + 2 * 3 + 1 * 3))
    np.testing.assert_allclose(centre, [0.5, 1.0, 1.5], atol=1e-9)


# -- the export's own forms read back ---------------------------------------------------------------------

def test_exported_office_reads_back_to_the_same_results(tmp_path):
    """`lbl-illum export radiance` then a scene file of its .rad files and the same sky:
    the same materials, triangles and so the same illuminance, bit for bit."""
    from lbl_illum import Integrator, Options, read_points
    from lbl_illum.io.radiance import export_radiance

    from conftest import EXAMPLES

    office = load_scene(EXAMPLES / "office" / "scene.toml")
    export_radiance(office, tmp_path)
    _write(tmp_path, "scene.toml", '[[geometry]]\nfile = "materials.rad"\n[[geometry]]\nfile = "geometry.rad"\n'
                                   '[sky]\ntype = "cie-overcast"\nhorizontal_illuminance = 10000\n'
                                   'ground_reflectance = 0.2\n')
    back = load_scene(tmp_path / "scene.toml")
    points, normals = read_points(EXAMPLES / "office" / "grid.pts")
    options = Options(accuracy=0.2, samples=32, bounces=2, point_samples=64)
    a = Integrator(office, options).compute(points[::6], normals[::6]).illuminance
    b = Integrator(back, options).compute(points[::6], normals[::6]).illuminance
    np.testing.assert_array_equal(a, b)


MATERIALS_TOML = """
[[geometry]]
file = "room.obj"
[materials.paint]
type = "diffuse"
reflectance = [0.6, 0.5, 0.4]
[materials.shiny]
type = "plastic"
reflectance = 0.5
specularity = 0.05
roughness = 0.1
[materials.mirror]
type = "mirror"
reflectance = 0.9
[materials.brass]
type = "metal"
reflectance = [0.9, 0.6, 0.2]
specularity = 0.8
roughness = 0.05
[materials.pane]
type = "glass"
transmittance = 0.7
[materials.double]
type = "glass"
transmittance = 0.6
panes = 2
[materials.flat]
type = "glass"
transmittance = [0.5, 0.55, 0.6]
model = "constant"
[materials.sheet]
type = "translucent"
reflectance = 0.3
transmittance = 0.4
[materials.tinted]
type = "translucent"
reflectance = [0.3, 0.3, 0.3]
transmittance = [0.2, 0.3, 0.4]
[materials.lamp]
type = "light"
luminance = 1000
"""


def test_every_exported_material_reads_back(tmp_path):
    from lbl_illum.io.radiance import export_radiance
    from lbl_illum.scene.materials import MaterialTable

    names = ["paint", "shiny", "mirror", "brass", "pane", "double", "flat", "sheet", "tinted", "lamp"]
    obj = [f"v {k} 0 0\nv {k + 1} 0 0\nv {k} 1 0\ng {n}\nf {3 * k + 1} {3 * k + 2} {3 * k + 3}"
           for k, n in enumerate(names)]
    _write(tmp_path, "room.obj", "\n".join(obj) + "\n")
    text = MATERIALS_TOML.replace('file = "room.obj"', 'file = "room.obj"\nmaterials = { ' +
                                  ", ".join(f'{n} = "{n}"' for n in names) + " }")
    _write(tmp_path, "scene.toml", text)
    original = load_scene(tmp_path / "scene.toml")
    export_radiance(original, tmp_path / "rad")
    _write(tmp_path / "rad", "scene.toml", '[[geometry]]\nfile = "materials.rad"\n[[geometry]]\nfile = "geometry.rad"\n')
    back = load_scene(tmp_path / "rad" / "scene.toml")
    a = {m.name: m for m in original.materials}
    b = {m.name: m for m in back.materials}
    for name in names:
        ta, tb = MaterialTable.from_materials([a[name]]), MaterialTable.from_materials([b[name]])
        for field in ("kind", "reflectance", "transmittance", "luminance", "diffuse_reflectance",
                      "diffuse_transmittance", "specularity", "roughness", "metallic"):
            np.testing.assert_allclose(getattr(tb, field), getattr(ta, field), rtol=1e-6, atol=1e-9,
                                       err_msg=f"{name}.{field}")
        assert b[name].model == a[name].model and b[name].panes == a[name].panes, name


def test_illum_reads_as_its_alternate_or_an_opening(tmp_path):
    _write(tmp_path, "w.rad", "void glass clear\n0\n0\n3 .96 .96 .96\n"
                              "void illum withglass\n1 clear\n0\n3 1 1 1\n"
                              "void illum bare\n0\n0\n3 1 1 1\n"
                              "withglass polygon a\n0\n0\n9 0 0 0 1 0 0 0 1 0\n"
                              "bare polygon b\n0\n0\n9 0 0 1 1 0 1 0 1 1\n")
    _write(tmp_path, "scene.toml", '[[geometry]]\nfile = "w.rad"\n')
    scene = load_scene(tmp_path / "scene.toml")
    kinds = {m.name: m.kind for m in scene.materials}
    assert kinds["withglass"] == "glass" and kinds["bare"] == "opening"
    assert any("illum read as its alternate material" in w for w in scene.warnings)


def test_other_brtdfunc_forms_are_refused(tmp_path):
    _write(tmp_path, "w.rad", "void BRTDfunc odd\n10 rr rg rb tr tg tb 0 0 0 my.cal\n0\n9 0 0 0 0 0 0 0 0 0\n"
                              "odd polygon a\n0\n0\n9 0 0 0 1 0 0 0 1 0\n")
    _write(tmp_path, "scene.toml", '[[geometry]]\nfile = "w.rad"\n')
    with pytest.raises(InputError, match=r"BRTDfunc 'odd': this BRTDfunc's form is not read"):
        load_scene(tmp_path / "scene.toml")


def test_a_type_that_is_no_radiance_primitive_is_refused(tmp_path):
    _write(tmp_path, "typo.rad", "void plastic m\n0\n0\n5 .5 .5 .5 0 0\nm polygn p\n0\n0\n9 0 0 0 1 0 0 0 1 0\n")
    with pytest.raises(InputError, match=r"^typo.rad: line 5: 'polygn' is not a Radiance primitive type"):
        read_rad_surfaces(tmp_path / "typo.rad", "typo.rad")
    _write(tmp_path, "inst.rad", "void plastic m\n0\n0\n5 .5 .5 .5 0 0\nm instance chair\n1 chair.oct\n0\n0\n")
    warnings = []
    read_rad_surfaces(tmp_path / "inst.rad", "inst.rad", warnings=warnings)
    assert any("skipped 1 'instance' primitive" in w for w in warnings)

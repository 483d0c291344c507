"""The LBNL open-plan office (validation/corpus/lbnl-open-office: LBNL-ETA/frads test
objects, BSD-style licence in LICENSE-frads.txt there) read from its own Radiance files
against the same model converted to an OBJ mesh.

The conversion here is written apart from :mod:`lbl_illum.scene.radfile`: a tokenizer of
Radiance's primitive format (modifier, type, identifier, then counts of string, integer
and real arguments) that writes every polygon as one OBJ face as drawn (its holes as the
keyhole seams the file has, a ``g``/``usemtl`` per modifier) and every other primitive of
the ``.rad`` files (the ground's material) to a ``.mat`` file.  The OBJ then goes through
the mesh loader's own polygon triangulation, and its faces take their materials by their
``usemtl`` names from the ``.mat`` definitions, as Radiance's ``obj2rad`` makes them
modifiers.
"""

from __future__ import annotations

import dataclasses
import re
from pathlib import Path

import numpy as np

from lbl_illum import Options, compute_illuminance, load_scene, read_points
from lbl_illum.scene.geometry import Triangles

OFFICE = Path(__file__).resolve().parents[2] / "validation" / "corpus" / "lbnl-open-office"


def _primitives(path: Path):
    """(modifier, type, identifier, reals) of each primitive of a Radiance file."""
    tokens = re.sub(r"#[^\n]*", " ", path.read_text()).split()
    i = 0
    while i < len(tokens):
        modifier, kind, name = tokens[i:i + 3]
        i += 3
        i += 1 + int(tokens[i])                      # string arguments
        i += 1 + int(tokens[i])                      # integer arguments
        n = int(tokens[i])
        yield modifier, kind, name, [float(v) for v in tokens[i + 1:i + 1 + n]]
        i += 1 + n


def _convert(scene_toml: Path, folder: Path) -> Path:
    """The scene's ``.rad`` files as office.obj + office.mat, and a scene file naming
    them, the .mat files and the same sky."""
    text = scene_toml.read_text()
    files = re.findall(r'^file = "([^"]+)"', text, flags=re.M)
    vertices, faces, definitions = [], {}, []
    for name in files:
        if name.endswith(".mat"):
            continue
        for modifier, kind, ident, reals in _primitives(OFFICE / name):
            if kind == "polygon":
                start = len(vertices) + 1
                vertices += [reals[k:k + 3] for k in range(0, len(reals), 3)]
                faces.setdefault(modifier, []).append(range(start, len(vertices) + 1))
            else:
                definitions.append(f"{modifier} {kind} {ident}\n0\n0\n{len(reals)} " + " ".join(map(repr, reals)))
    lines = ["v %r %r %r" % tuple(v) for v in vertices]
    for modifier, polygons in faces.items():
        lines += [f"g {modifier}", f"usemtl {modifier}"] + ["f " + " ".join(map(str, f)) for f in polygons]
    (folder / "office.obj").write_text("\n".join(lines) + "\n")
    (folder / "office.mat").write_text("\n".join(definitions) + "\n")
    mats = "".join(f'[[geometry]]\nfile = "{(OFFICE / n).as_posix()}"\n' for n in files if n.endswith(".mat"))
    sky = text[text.index("[sky]"):]
    (folder / "scene.toml").write_text(f'units = "ft"\n{mats}[[geometry]]\nfile = "office.mat"\n'
                                       f'[[geometry]]\nfile = "office.obj"\n{sky}')
    return folder / "scene.toml"


def _canonical(scene):
    """The scene with its materials in name order and its triangles in the order of
    (material, corners): two loaders' scenes of the same model become equal arrays."""
    order = sorted(range(len(scene.materials)), key=lambda i: scene.materials[i].name)
    new_id = np.empty(len(order), np.int32)
    new_id[order] = np.arange(len(order), dtype=np.int32)
    material = new_id[scene.triangles.material]
    corners = scene.triangles.vertices.reshape(-1, 9)
    index = np.lexsort(tuple(corners[:, k] for k in range(8, -1, -1)) + (material,))
    tri = Triangles(scene.triangles.vertices[index], material[index], scene.triangles.sphere[index])
    return dataclasses.replace(scene, triangles=tri, materials=[scene.materials[i] for i in order])


def test_lbnl_office_from_rad_equals_its_converted_mesh(tmp_path):
    """From its 14 Radiance files and from the converted OBJ (13,966 polygons, desk
    outlines up to 64 vertices, keyhole holes): the same 21,714 triangles, corner for
    corner, with the same materials (the same plastic and Fresnel glass from the same
    definitions); and in the same order the same illuminance at every point of the
    workplane grid (every fifth point, two bounces), bit for bit.  In file order the two
    scenes differ only in which random number meets which triangle."""
    rad = load_scene(OFFICE / "overcast.toml")
    mesh = load_scene(_convert(OFFICE / "overcast.toml", tmp_path))
    a, b = _canonical(rad), _canonical(mesh)
    assert len(a.triangles) == 21714
    np.testing.assert_array_equal(a.triangles.vertices, b.triangles.vertices)
    np.testing.assert_array_equal(a.triangles.material, b.triangles.material)
    assert a.materials == b.materials and len(a.materials) == 12
    kinds = {m.name: m.kind for m in a.materials}
    assert kinds["GlDay"] == "glass" and kinds["Desks"] == "plastic" and kinds["ground"] == "diffuse"
    points, normals = read_points(OFFICE / "grid.pts", rad.unit_scale)
    points, normals = points[::5], normals[::5]
    options = Options(bounces=2, samples=128, accuracy=0.2, seed=1)
    ours = compute_illuminance(a, points, normals, options).illuminance
    theirs = compute_illuminance(b, points, normals, options).illuminance
    assert len(ours) == 22 and ours.min() > 5.0
    np.testing.assert_array_equal(ours, theirs)

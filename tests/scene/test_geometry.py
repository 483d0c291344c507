"""Primitives, polygon triangulation, geometry files and triangle clean-up (lbl_illum.scene.geometry)."""

from pathlib import Path

import numpy as np
import pytest

from lbl_illum.errors import InputError
from lbl_illum.scene.geometry import (
    PLANAR_TOLERANCE, SPHERE_MAX_DEVIATION, SPHERE_SUBDIVISIONS, box_triangles, degenerate_mask,
    duplicate_mask, load_mesh_file, polygon_triangles, rectangle_triangles, shape_from_table,
    sphere_triangles,
)

DATA = Path(__file__).resolve().parents[1] / "data" / "scene"


def areas(tri):
    return 0.5 * np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1)


def normals(tri):
    n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    return n / np.linalg.norm(n, axis=1, keepdims=True)


# -- sphere -------------------------------------------------------------------

CENTER, RADIUS = np.array([1.0, -2.0, 3.0]), 2.5


@pytest.fixture(scope="module")
def sphere():
    return sphere_triangles(CENTER, RADIUS)


def test_sphere_count_and_vertices_on_sphere(sphere):
    assert SPHERE_SUBDIVISIONS == 6
    assert sphere.shape == (20 * 4 ** 6, 3, 3) == (81920, 3, 3)
    r = np.linalg.norm(sphere - CENTER, axis=2)
    assert np.allclose(r, RADIUS, rtol=1e-14, atol=0)


def test_sphere_deviation_bound(sphere):
    n = normals(sphere)
    plane = np.abs(np.einsum("ij,ij->i", n, sphere[:, 0] - CENTER))      # centre-to-facet-plane distance
    # the centre's foot on each plane falls inside its facet, so the plane distance is the nearest
    foot = CENTER + plane[:, None] * n
    for k in range(3):
        a, b = sphere[:, k], sphere[:, (k + 1) % 3]
        assert np.all(np.einsum("ij,ij->i", np.cross(b - a, foot - a), n) > 0)
    deviation = 1.0 - plane.min() / RADIUS
    assert deviation < SPHERE_MAX_DEVIATION < 2e-4
    assert deviation == pytest.approx(7.123e-5, rel=1e-3)
    # the edge-midpoint form r (1 - cos(θ_max / 2)) is smaller
    u = (sphere - CENTER) / RADIUS
    angle = max(np.arccos(np.clip(np.einsum("ij,ij->i", u[:, k], u[:, (k + 1) % 3]), -1, 1)).max()
                for k in range(3))
    assert 1.0 - np.cos(angle / 2) == pytest.approx(5.342e-5, rel=1e-3)


def test_sphere_area_and_outward_normals(sphere):
    a = areas(sphere).sum()
    exact = 4 * np.pi * RADIUS ** 2
    # inscribed convex polyhedron containing the ball of radius r (1 - deviation)
    assert exact * (1 - SPHERE_MAX_DEVIATION) ** 2 <= a <= exact
    outward = np.einsum("ij,ij->i", normals(sphere), sphere.mean(axis=1) - CENTER)
    assert np.all(outward > 0)


# -- box and rectangle ----------------------------------------------------------

def test_box():
    center, size = np.array([1.0, 2.0, 0.5]), np.array([1.0, 2.0, 3.0])
    tri = box_triangles(center, size)
    assert tri.shape == (12, 3, 3)
    assert areas(tri).sum() == pytest.approx(2 * (1 * 2 + 2 * 3 + 1 * 3))
    n = normals(tri)
    out = tri.mean(axis=1) - center
    assert np.all(np.einsum("ij,ij->i", n, out) > 0)
    # every face normal is an axis, each of the six twice
    assert sorted(map(tuple, np.round(n).astype(int))) == sorted(
        [tuple(s * np.eye(3, dtype=int)[k]) for k in range(3) for s in (-1, 1)] * 2)
    assert np.allclose(tri.reshape(-1, 3).min(axis=0), center - size / 2)
    assert np.allclose(tri.reshape(-1, 3).max(axis=0), center + size / 2)


def test_rectangle():
    tri = rectangle_triangles([0, 0, 1], [2, 0, 0], [1, 3, 0])       # parallelogram
    assert tri.shape == (2, 3, 3)
    assert areas(tri).sum() == pytest.approx(6.0)
    assert np.allclose(normals(tri), [0, 0, 1])
    with pytest.raises(InputError, match="span no area"):
        rectangle_triangles([0, 0, 0], [1, 0, 0], [2, 0, 0])


# -- polygon ---------------------------------------------------------------------

L_SHAPE = [[0, 0, 0], [2, 0, 0], [2, 1, 0], [1, 1, 0], [1, 2, 0], [0, 2, 0]]


def test_polygon_l_shape():
    tri = polygon_triangles(L_SHAPE)
    assert tri.shape == (4, 3, 3)
    assert areas(tri).sum() == pytest.approx(3.0)
    assert np.allclose(normals(tri), [0, 0, 1])
    # every triangle lies inside the L (its centroid is not in the missing quadrant)
    c = tri.mean(axis=1)
    assert not np.any((c[:, 0] > 1) & (c[:, 1] > 1))


def test_polygon_winding_follows_vertex_order():
    tri = polygon_triangles(L_SHAPE[::-1])
    assert np.allclose(normals(tri), [0, 0, -1])


def test_polygon_tilted_nonconvex_in_3d():
    """A star polygon in a tilted plane keeps its area and plane normal."""
    k = np.arange(10)
    r = np.where(k % 2 == 0, 2.0, 0.8)
    xy = np.stack([r * np.cos(k * np.pi / 5), r * np.sin(k * np.pi / 5)], axis=1)
    area = 0.5 * np.sum(xy[:, 0] * np.roll(xy[:, 1], -1) - np.roll(xy[:, 0], -1) * xy[:, 1])
    u, v = np.array([1.0, 0, 1]) / np.sqrt(2), np.array([0.0, 1, 0])
    points = 5.0 + xy[:, :1] * u + xy[:, 1:] * v
    tri = polygon_triangles(points)
    assert len(tri) == 8
    assert areas(tri).sum() == pytest.approx(area)
    assert np.allclose(normals(tri), np.cross(u, v))


def test_polygon_collinear_vertices():
    square = [[0, 0, 0], [1, 0, 0], [2, 0, 0], [2, 2, 0], [0, 2, 0], [0, 1, 0]]
    tri = polygon_triangles(square)
    assert areas(tri).sum() == pytest.approx(4.0)
    assert np.all(areas(tri) > 0)


@pytest.mark.parametrize("points, message", [
    ([[0, 0, 0], [1, 0, 0]], "at least 3 vertices"),
    ([[0, 0, 0], [1, 0, 0], [2, 0, 0]], "zero area"),
    ([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0.1]], "not planar"),
    ([[0, 0, 0], [4, 0, 0], [4, 2, 0], [1, -1, 0], [0, 2, 0]], "cannot be triangulated"),     # edges cross
    ([[0, 0, 0], [3, 0, 0], [0, 1, 0], [3, 1, 0]], "zero area"),                             # bow tie
])
def test_polygon_refused(points, message):
    with pytest.raises(InputError, match=f"^poly: .*{message}"):
        polygon_triangles(points, "poly")


def test_polygon_planarity_tolerance():
    polygon_triangles([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0.5 * PLANAR_TOLERANCE]])


# -- shape tables ------------------------------------------------------------------

def test_shape_from_table_scales_lengths():
    shape = shape_from_table({"shape": "sphere", "center": [0, 0, 1000], "radius": 500}, "s", scale=1e-3)
    assert np.allclose(shape.sphere_center, [0, 0, 1]) and shape.sphere_radius == pytest.approx(0.5)
    box = shape_from_table({"shape": "box", "center": [0, 0, 500], "size": [1000, 2000, 1000]}, "b", 1e-3)
    assert areas(box.vertices).sum() == pytest.approx(10.0)
    assert box.sphere_center is None


@pytest.mark.parametrize("table, message", [
    ({"shape": "spere", "center": [0, 0, 0], "radius": 1}, "unknown shape 'spere' \\(did you mean 'sphere'\\?\\)"),
    ({"shape": "sphere", "center": [0, 0, 0], "radius": 0}, "'radius' must be > 0"),
    ({"shape": "sphere", "center": [0, 0, 0], "radius": -1}, "'radius' must be > 0"),
    ({"shape": "sphere", "center": [0, 0, float("nan")], "radius": 1}, "'center' must be finite"),
    ({"shape": "sphere", "center": [0, 0], "radius": 1}, "'center' must be a list of 3 numbers"),
    ({"shape": "sphere", "center": [0, 0, 0], "radius": "1"}, "'radius' must be a number"),
    ({"shape": "sphere", "center": [0, 0, 0]}, "missing key 'radius'"),
    ({"shape": "box", "center": [0, 0, 0], "size": [1, 0, 1]}, "'size' must be > 0"),
    ({"shape": "box", "centre": [0, 0, 0], "size": [1, 1, 1]}, "unknown key 'centre' \\(did you mean 'center'\\?\\)"),
    ({"shape": "polygon", "vertices": [[0, 0, 0], [1, 0, float("inf")], [0, 1, 0]]},
     "'vertices\\[1\\]' must be finite"),
    ({"shape": "polygon", "vertices": "square"}, "'vertices' must be a list"),
    ({"shape": "rectangle", "origin": [0, 0, 0], "u": [1, 0, 0], "v": [0, 0, 0]}, "'u' and 'v' span no area"),
])
def test_shape_from_table_errors(table, message):
    with pytest.raises(InputError, match=f"^scene.toml: geometry\\[3\\]: {message}"):
        shape_from_table(table, "scene.toml: geometry[3]")


# -- geometry files ------------------------------------------------------------------

def test_obj_usemtl_groups():
    parts = load_mesh_file(DATA / "room_corner.obj", "obj", scale=1.0)
    by_material = {p.material: p for p in parts}
    assert set(by_material) == {"Floor", "Wall", "Trim"}
    assert by_material["Floor"].group == "floor" and by_material["Floor"].name == "floor_Floor"
    assert by_material["Wall"].keys == ("wall_Wall", "wall", "Wall")
    assert areas(by_material["Floor"].vertices).sum() == pytest.approx(2.0)
    assert len(by_material["Wall"].vertices) == 2                        # the quad, split
    assert areas(by_material["Wall"].vertices).sum() == pytest.approx(2.0)
    assert areas(by_material["Trim"].vertices).sum() == pytest.approx(0.5)


def test_obj_material_names_without_mtl_and_scale(tmp_path):
    (tmp_path / "a.obj").write_text("mtllib missing.mtl\nv 0 0 0\nv 1000 0 0\nv 0 1000 0\nv 0 0 1000\n"
                                    "f 1 2 3\nusemtl Glass\nf 1 2 4\n")
    parts = load_mesh_file(tmp_path / "a.obj", "a", scale=1e-3)
    assert [p.material for p in parts if p.material] == ["Glass"]
    assert np.isclose(np.max([p.vertices.max() for p in parts]), 1.0)


def test_gltf_transform_and_names(tmp_path):
    import trimesh
    from trimesh.visual.material import PBRMaterial

    tri = trimesh.Trimesh([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 2]], process=False)
    tri.visual = trimesh.visual.TextureVisuals(material=PBRMaterial(name="Glass"))
    scene = trimesh.Scene()
    scene.add_geometry(tri, geom_name="pane", node_name="pane_node",
                       transform=trimesh.transformations.translation_matrix([10, 0, 0]))
    scene.export(tmp_path / "t.glb")
    (part,) = load_mesh_file(tmp_path / "t.glb", "t", scale=2.0)
    assert part.keys == ("pane_node", "pane", "Glass")
    assert np.allclose(part.vertices[0], [[20, 0, 0], [22, 0, 0], [20, 2, 0]])


def test_mirroring_transform_keeps_outward_normals():
    from lbl_illum.scene.geometry import _transform

    box = box_triangles([0, 0, 0], [1, 1, 1])
    mirrored = _transform(box, np.diag([-1.0, 1, 1, 1]))
    assert np.all(np.einsum("ij,ij->i", normals(mirrored), mirrored.mean(axis=1)) > 0)


def test_missing_and_unreadable_files(tmp_path):
    with pytest.raises(InputError, match="^geometry\\[0\\] nope.obj: no such file"):
        load_mesh_file(tmp_path / "nope.obj", "geometry[0] nope.obj")
    (tmp_path / "junk.stl").write_bytes(b"garbage")
    with pytest.raises(InputError, match="^j: the file contains no triangles|^j: cannot read"):
        load_mesh_file(tmp_path / "junk.stl", "j")
    (tmp_path / "junk.xyz").write_text("1 2 3\n")
    with pytest.raises(InputError, match="^x: cannot read the file"):
        load_mesh_file(tmp_path / "junk.xyz", "x")


# -- clean-up --------------------------------------------------------------------------

def test_degenerate_and_duplicate_masks():
    a = [[0, 0, 0], [1, 0, 0], [0, 1, 0]]
    tri = np.array([a, [a[1], a[2], a[0]], [a[0], a[2], a[1]], [[0, 0, 0], [1, 1, 1], [2, 2, 2]],
                    [[0, 0, 0], [0, 0, 0], [0, 0, 1]], [[-0.0, 0, 0], [1, 0, 0], [0, 1, 0]],
                    [[0, 0, 0], [1, 0, 0], [0, 2, 0]]], dtype=float)
    assert degenerate_mask(tri).tolist() == [False, False, False, True, True, False, False]
    assert duplicate_mask(tri).tolist() == [False, True, True, False, False, True, False]


def test_duplicate_mask_on_a_mesh():
    """No false duplicates among the 81,920 sphere facets; a second copy (any corner order) is all duplicate."""
    s = sphere_triangles([0, 0, 0], 1.0)
    assert not duplicate_mask(s).any()
    both = duplicate_mask(np.concatenate([s, s[:, [2, 0, 1]]]))
    assert not both[:len(s)].any() and both[len(s):].all()


def test_corner_bounds_are_the_least_and_greatest_coordinates():
    from lbl_illum.scene.geometry import corner_bounds

    v = np.random.default_rng(0).normal(size=(1000, 3, 3)) * [1.0, 10.0, 100.0]
    np.testing.assert_array_equal(corner_bounds(v), [v.reshape(-1, 3).min(axis=0), v.reshape(-1, 3).max(axis=0)])

"""Polygons as drawn: non-convex faces, holes in keyhole form, either winding (lbl_illum.scene.polygons).

Every area below is computed independently of the triangulation: rectangles by hand, the
desk outline by the shoelace formula of its rings, coverage by an even-odd
point-in-polygon test of sample points against the triangles.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from lbl_illum.scene.geometry import load_mesh_file
from lbl_illum.scene.polygons import triangulate_face, triangulate_faces

L_SHAPE = np.array([[0, 0, 0], [2, 0, 0], [2, 1, 0], [1, 1, 0], [1, 2, 0], [0, 2, 0]], float)


def tri_areas(points, tri):
    v = points[tri]
    return 0.5 * np.linalg.norm(np.cross(v[:, 1] - v[:, 0], v[:, 2] - v[:, 0]), axis=1)


def covered(points2d, tri, queries):
    """How many triangles cover each 2-D query point (0 outside the triangulation)."""
    a, b, c = (points2d[tri[:, k]][None] for k in range(3))
    q = queries[:, None, :]

    def side(p0, p1):
        return (p1[..., 0] - p0[..., 0]) * (q[..., 1] - p0[..., 1]) - (p1[..., 1] - p0[..., 1]) * (q[..., 0] - p0[..., 0])

    s1, s2, s3 = side(a, b), side(b, c), side(c, a)
    inside = ((s1 > 0) & (s2 > 0) & (s3 > 0)) | ((s1 < 0) & (s2 < 0) & (s3 < 0))
    return inside.sum(axis=1)


def test_l_shape_area_and_coverage():
    tri, area = triangulate_face(L_SHAPE)
    assert area == pytest.approx(3.0)
    assert tri_areas(L_SHAPE, tri).sum() == pytest.approx(3.0)
    grid = np.random.default_rng(1).uniform(0.0, 2.0, (400, 2))       # off the triangles' edges
    count = covered(L_SHAPE[:, :2], tri, grid)
    in_l = ~((grid[:, 0] > 1) & (grid[:, 1] > 1))
    assert np.array_equal(count, in_l.astype(int))      # every point of the L once, none of the notch


def keyhole_wall(hole_winding: str):
    """A 6 x 3 m wall in the plane y = 0 with two 1 x 1.5 m windows, as one keyhole polygon:
    the outline, then for each window a seam in, its ring, and the seam back out."""
    outer = [[0, 0, 0], [6, 0, 0], [6, 0, 3], [0, 0, 3]]
    windows = [[[1, 0, 1], [2, 0, 1], [2, 0, 2.5], [1, 0, 2.5]],
               [[4, 0, 1], [5, 0, 1], [5, 0, 2.5], [4, 0, 2.5]]]
    points = list(outer) + [outer[0]]
    for w in windows:
        ring = w if hole_winding == "same" else w[::-1]
        points += ring + [ring[0], outer[0]]
    return np.array(points, float)


@pytest.mark.parametrize("winding", ["same", "opposite"])
def test_wall_with_two_keyhole_windows(winding):
    wall = keyhole_wall(winding)
    tri, area = triangulate_face(wall)
    assert area == pytest.approx(18.0 - 2 * 1.5)
    assert tri_areas(wall, tri).sum() == pytest.approx(15.0)
    xz = wall[:, [0, 2]]
    window_centres = np.array([[1.5, 1.75], [4.5, 1.75]])
    assert covered(xz, tri, window_centres).tolist() == [0, 0]
    wall_points = np.array([[0.53, 0.41], [3.07, 1.73], [5.51, 2.87], [1.46, 0.52], [4.49, 2.81]])
    assert covered(xz, tri, wall_points).tolist() == [1] * 5
    # wound like the outline: normals along (outline's Newell normal) = -y here
    n = np.cross(wall[tri[:, 1]] - wall[tri[:, 0]], wall[tri[:, 2]] - wall[tri[:, 0]])
    assert np.all(n[:, 1] < 0) and np.allclose(n[:, [0, 2]], 0)


def desk_outline():
    """A 64-vertex desk top: a 1.8 x 0.9 m top whose front edge has a 0.6 m wide bay cut into
    it (42 arc vertices), with a 16-gon cable grommet (r = 4 cm) joined by a keyhole seam.
    Returns (points (64, 3), exact area by the shoelace formula of its two rings)."""
    arc = np.linspace(np.pi, 0, 42)
    bay = np.stack([0.9 + 0.3 * np.cos(arc), 0.25 * np.sin(arc)], 1)              # (0.6, 0) to (1.2, 0)
    outline = np.vstack([[[0.0, 0.0]], bay, [[1.8, 0.0], [1.8, 0.9], [0.0, 0.9]]])
    angles = np.linspace(0, 2 * np.pi, 16, endpoint=False)
    grommet = np.stack([1.5 + 0.04 * np.cos(angles), 0.7 + 0.04 * np.sin(angles)], 1)
    corner = len(outline) - 2                                                      # (1.8, 0.9)
    ring = np.vstack([outline[:corner + 1], grommet, grommet[:1], outline[corner:]])
    assert len(ring) == 64

    def shoelace(xy):
        return 0.5 * abs(np.dot(xy[:, 0], np.roll(xy[:, 1], -1)) - np.dot(np.roll(xy[:, 0], -1), xy[:, 1]))

    area = shoelace(outline) - shoelace(grommet)
    return np.column_stack([ring, np.full(len(ring), 0.72)]), area


def test_desk_outline_of_64_vertices():
    points, exact = desk_outline()
    tri, area = triangulate_face(points)
    assert area == pytest.approx(exact, rel=1e-12)
    assert tri_areas(points, tri).sum() == pytest.approx(exact, rel=1e-12)
    xy = points[:, :2]
    assert covered(xy, tri, np.array([[1.5, 0.7], [0.9, 0.1]])).tolist() == [0, 0]     # grommet, the arc's bay
    assert covered(xy, tri, np.array([[0.3, 0.5], [1.5, 0.78], [0.9, 0.6]])).tolist() == [1, 1, 1]
    # a fan from the first vertex gets the area wrong: the reason for all this
    fan = np.stack([np.zeros(62, int), np.arange(1, 63), np.arange(2, 64)], 1)
    assert abs(tri_areas(points, fan).sum() - exact) > 0.01


def test_faces_in_bulk_match_one_by_one():
    rng = np.random.default_rng(3)
    faces, points = [], []
    offset = 0
    for k in (3, 4, 5, 8, 12):
        for _ in range(20):                                  # convex polygons in random planes
            angles = np.sort(rng.uniform(0, 2 * np.pi, k))
            xy = np.stack([np.cos(angles), np.sin(angles)], 1) * rng.uniform(0.5, 3)
            basis = np.linalg.qr(rng.normal(size=(3, 3)))[0]
            points.append(xy @ basis[:2] + rng.normal(size=3))
            faces.append(np.arange(offset, offset + k))
            offset += k
    points.append(L_SHAPE)
    faces.append(np.arange(offset, offset + 6))
    vertices = np.concatenate(points)
    bulk = triangulate_faces(vertices, faces)
    for f, face in enumerate(faces):
        _, area = triangulate_face(vertices[face])
        assert bulk.polygon_area[f] == pytest.approx(area, rel=1e-9)
        assert bulk.triangle_area[f] == pytest.approx(area, rel=1e-9)
    assert len(bulk.mismatched()) == 0


@settings(max_examples=60, deadline=None)
@given(st.integers(5, 40), st.integers(0, 2 ** 32 - 1))
def test_star_shaped_polygons_keep_their_area(k, seed):
    """Random star-shaped (non-convex) polygons: triangles' area is the shoelace area."""
    rng = np.random.default_rng(seed)
    angles = np.sort(rng.uniform(0, 2 * np.pi, k))
    gaps = np.diff(np.concatenate([angles, angles[:1] + 2 * np.pi]))
    if gaps.min() < 1e-3 or gaps.max() >= 0.95 * np.pi:      # simple only when it winds around the origin
        return
    r = rng.uniform(0.2, 2.0, k)
    xy = np.stack([r * np.cos(angles), r * np.sin(angles)], 1)
    exact = 0.5 * abs(np.dot(xy[:, 0], np.roll(xy[:, 1], -1)) - np.dot(np.roll(xy[:, 0], -1), xy[:, 1]))
    points = np.column_stack([xy, np.zeros(k)])
    tri, area = triangulate_face(points)
    assert area == pytest.approx(exact, rel=1e-9)
    assert tri_areas(points, tri).sum() == pytest.approx(exact, rel=1e-9)


def test_crossing_edges_are_reported_as_a_mismatch():
    bow = np.array([[0, 0, 0], [4, 0, 0], [4, 2, 0], [1, -1, 0], [0, 2, 0]], float)
    result = triangulate_faces(bow, [np.arange(5)])
    assert result.mismatched().tolist() == [0]


# -- OBJ faces of more than three vertices -----------------------------------------------


def write_obj(path, faces_text, vertices):
    path.write_text("".join(f"v {x:.17g} {y:.17g} {z:.17g}\n" for x, y, z in vertices) + faces_text)
    return path


def part_area(parts):
    return sum(tri_areas(p.vertices.reshape(-1, 3), np.arange(3 * len(p.vertices)).reshape(-1, 3)).sum()
               for p in parts)


def test_obj_l_shaped_face_is_not_fanned(tmp_path):
    path = write_obj(tmp_path / "l.obj", "f 1 2 3 4 5 6\n", L_SHAPE)
    warnings = []
    parts = load_mesh_file(path, "l.obj", 1.0, warnings)
    assert part_area(parts) == pytest.approx(3.0)
    assert warnings == []


def test_obj_keyhole_wall_keeps_its_windows(tmp_path):
    wall = keyhole_wall("same")
    tokens = " ".join(f"{i + 1}/{i + 1}/1" for i in range(len(wall)))          # v/t/n references kept
    text = "vn 0 -1 0\n" + "".join(f"vt {x} {z}\n" for x, _, z in wall) + f"usemtl wall\nf {tokens}\n"
    path = write_obj(tmp_path / "wall.obj", text, wall)
    parts = load_mesh_file(path, "wall.obj", 0.5)                                  # file units of 0.5 m
    assert part_area(parts) == pytest.approx(15.0 * 0.25)
    assert parts[0].material == "wall"


def test_obj_negative_indices_and_quads(tmp_path):
    square = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], float)
    dart = np.array([[0, 0, 1], [2, 0, 1], [0.5, 0.5, 1], [0, 2, 1]], float)         # non-convex quad
    path = write_obj(tmp_path / "q.obj", "f 1 2 3 4\nf -4 -3 -2 -1\n", np.vstack([square, dart]))
    parts = load_mesh_file(path, "q.obj")
    exact_dart = 0.5 * abs(np.dot(dart[:, 0], np.roll(dart[:, 1], -1)) - np.dot(np.roll(dart[:, 0], -1), dart[:, 1]))
    assert part_area(parts) == pytest.approx(1.0 + exact_dart)


def test_obj_area_mismatch_is_a_warning_naming_the_face(tmp_path):
    bow = np.array([[0, 0, 0], [4, 0, 0], [4, 2, 0], [1, -1, 0], [0, 2, 0]], float)
    flat = np.array([[0, 0, 5], [1, 0, 5], [2, 0, 5], [3, 0, 5]], float)           # zero area
    path = write_obj(tmp_path / "bad.obj", "f 1 2 3 4 5\nf 6 7 8 9\nf 1 2 3\n", np.vstack([bow, flat]))
    warnings = []
    load_mesh_file(path, "bad.obj", 1.0, warnings)
    assert len(warnings) == 2
    assert warnings[0].startswith("bad.obj: 1 face whose triangles' area differs")
    assert "line 10 (5 vertices)" in warnings[0] and "polygon 2 m²" in warnings[0]
    assert warnings[1] == "bad.obj: dropped 1 face of zero area: line 11 (4 vertices)"


def test_scene_reports_the_mismatch_and_keeps_keyhole_windows_open(tmp_path):
    from lbl_illum.scene.scenefile import load_scene

    wall = keyhole_wall("opposite")
    bow = np.array([[0, 5, 0], [4, 5, 0], [4, 7, 0], [1, 4, 0], [0, 7, 0]], float)
    n = len(wall)
    faces = "f " + " ".join(str(i + 1) for i in range(n)) + "\n" + "f " + " ".join(str(n + i + 1) for i in range(5)) + "\n"
    write_obj(tmp_path / "room.obj", faces, np.vstack([wall, bow]))
    (tmp_path / "scene.toml").write_text('units = "cm"\n[[geometry]]\nfile = "room.obj"\nmaterial = "w"\n'
                                         '[materials.w]\ntype = "diffuse"\nreflectance = 0.5\n'
                                         '[sky]\ntype = "uniform"\nhorizontal_illuminance = 1000\n')
    scene = load_scene(tmp_path / "scene.toml")
    wall_area = scene.triangles.areas[scene.triangles.vertices[:, :, 1].max(axis=1) < 1e-9].sum()
    assert wall_area == pytest.approx(15.0e-4)
    (message,) = [w for w in scene.warnings if "differs from the polygon's" in w]
    assert message.startswith("scene.toml: geometry[0] room.obj: 1 face whose")
    assert f"line {n + 5 + 2} (5 vertices)" in message      # after n + 5 vertex lines and the wall

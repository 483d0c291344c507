"""Workplane grids: the EN 12464-1 spacing, L-shaped rooms, columns, several rooms, the outdoor
ground, rotated rooms, area names in .pts files, and bad input."""

import math

import numpy as np
import pytest

from lbl_illum.errors import InputError
from lbl_illum.workplane.grid import (ENCLOSED_RADIUS, cell_layout, en12464_spacing, outline_angle, plan_outline,
                            section_segments, workplane_grid)
from lbl_illum.scene.scenefile import load_scene
from lbl_illum.io.points import read_points, write_points

from conftest import EXAMPLES, GROUND, L_ROOM, MATERIALS, inside_polygon, make_scene, room_geometry, scene_of





def column_box(cx, cy, width, height=3.0):
    """A floor-to-ceiling box column (outward normals, caps on the floor and ceiling)."""
    return {"shape": "box", "center": [cx, cy, height / 2], "size": [width, width, height], "material": "column"}


def open_column(cx, cy, width, height=3.0):
    """Four outward-facing sides of a column, without caps."""
    h = width / 2
    corners = [(cx - h, cy - h), (cx + h, cy - h), (cx + h, cy + h), (cx - h, cy + h)]
    return [{"shape": "polygon", "material": "column",
             "vertices": [[ax, ay, 0], [bx, by, 0], [bx, by, height], [ax, ay, height]]}
            for (ax, ay), (bx, by) in zip(corners, corners[1:] + corners[:1])]




def lattice(lo, hi, margin, p):
    """The EN 12464-1 cell-centred coordinates along one side, computed here from the rule."""
    length = hi - lo - 2 * margin
    n = math.ceil(length / p - 1e-9)
    s = length / n
    return lo + margin + (np.arange(n) + 0.5) * s


def segment_distance(p, a, b):
    """Distance from (n, 2) points to the segment a-b."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    t = np.clip(((p - a) @ (b - a)) / ((b - a) @ (b - a)), 0.0, 1.0)
    return np.linalg.norm(p - (a + t[:, None] * (b - a)), axis=1)




def boundary_distance(p, poly):
    poly = [tuple(v) for v in poly]
    return np.min([segment_distance(p, a, b) for a, b in zip(poly, poly[1:] + poly[:1])], axis=0)




# ---------------------------------------------------------------------------
# The spacing rule
# ---------------------------------------------------------------------------

@pytest.mark.parametrize("d, p", [(1.0, 0.2), (10.0, 1.0), (100.0, 5.0), (2.0, 0.2 * 5 ** math.log10(2)),
                                  (5.0, 0.61601), (0.4, 0.2 / 5 ** math.log10(2.5)), (1e4, 10.0)])
def test_en12464_spacing(d, p):
    # p = 0.2 · 5^log10(d) (EN 12464-1:2011 §4.4): 0.2 m at 1 m, 1 m at 10 m, 5 m at 100 m; p <= 10 m
    assert en12464_spacing(d) == pytest.approx(p, rel=1e-5)


def test_en12464_spacing_refuses_bad_lengths():
    for d in (0.0, -1.0, float("nan"), float("inf")):
        with pytest.raises(ValueError):
            en12464_spacing(d)


def test_cell_layout_keeps_spacing_at_most_p_and_whole_ratios():
    assert cell_layout(5.0, en12464_spacing(5.0)) == (9, pytest.approx(5 / 9))
    assert cell_layout(4.0, 0.5) == (8, 0.5)               # an exact ratio is not rounded up
    assert cell_layout(0.1, 0.5) == (1, 0.1)               # at least one cell
    for length in np.linspace(0.3, 40, 57):
        p = en12464_spacing(length)
        n, s = cell_layout(length, p)
        assert s <= p * (1 + 1e-12) and (n == 1 or length / (n - 1) > p)


# ---------------------------------------------------------------------------
# Room shapes
# ---------------------------------------------------------------------------

def test_l_shaped_room_points_are_the_lattice_inside_less_the_margin():
    grid = workplane_grid(scene_of(room_geometry(L_ROOM)))
    # bounding square 6 x 6 m, less 0.5 m each side: d = 5 m, p = 0.616 m, 9 x 9 cells of 5/9 m
    xs = lattice(0, 6, 0.5, en12464_spacing(5.0))
    X, Y = np.meshgrid(xs, xs)
    cand = np.column_stack([X.ravel(), Y.ravel()])
    expect = cand[inside_polygon(cand, L_ROOM) & (boundary_distance(cand, L_ROOM) >= 0.5 - 1e-9)]
    assert len(grid.points) == len(expect) == 56
    got = grid.points[np.lexsort(grid.points[:, :2].T[::-1])]
    assert np.allclose(got[:, :2], expect[np.lexsort(expect.T[::-1])], atol=1e-9)
    assert np.allclose(grid.points[:, 2], 0.8) and np.allclose(grid.normals, [0, 0, 1])
    assert set(grid.areas) == {"floor"} and grid.lattices[0].counts == (9, 9)
    assert grid.lattices[0].dropped["margin"] + grid.lattices[0].dropped.get("outside", 0) == 81 - 56


@pytest.mark.parametrize("margin, column, geometry, rule", [
    (0.5, 1.0, "box", None),               # within the margin of the column's faces
    (0.0, 1.0, "box", "enclosed"),         # every horizontal ray meets the column within 1 m
    (0.0, 2.4, "box", "inside"),           # too wide to be enclosed: found by the winding
    (0.0, 0.8, "open", "enclosed"),        # sides only, no caps
])
def test_no_point_inside_a_column(margin, column, geometry, rule):
    room = [(0, 0), (7, 0), (7, 7), (0, 7)]
    extra = [column_box(3.5, 3.5, column)] if geometry == "box" else open_column(3.5, 3.5, column)
    grid = workplane_grid(scene_of(room_geometry(room) + extra), margin=margin)
    xs = lattice(0, 7, margin, en12464_spacing(7 - 2 * margin))
    X, Y = np.meshgrid(xs, xs)
    cand = np.column_stack([X.ravel(), Y.ravel()])
    h = column / 2 + margin
    outside_column = np.max(np.abs(cand - 3.5), axis=1) >= h - 1e-9
    assert len(grid.points) == int(outside_column.sum()) < len(cand)
    assert np.all(np.max(np.abs(grid.points[:, :2] - 3.5), axis=1) >= column / 2)
    if rule:
        assert grid.lattices[0].dropped[rule] == len(cand) - len(grid.points)


def test_column_in_a_room_wound_outwards_is_found_by_size():
    # a box primitive as the room: every normal faces out, so the winding rule cannot help,
    # and a 1.2 m column (closer than ENCLOSED_RADIUS everywhere inside) is found by size
    geo = [{"shape": "box", "center": [3, 3, 1.5], "size": [6, 6, 3], "material": "floor"}, column_box(3, 3, 1.0)]
    grid = workplane_grid(scene_of(geo), margin=0.0, spacing=0.3)
    assert 1.0 * math.sqrt(2) <= ENCLOSED_RADIUS             # any point inside sees every side within it
    inside = np.max(np.abs(grid.points[:, :2] - 3), axis=1) < 0.5
    assert len(grid.points) == 20 * 20 - 4 * 4 and not inside.any()
    assert sum(lat.dropped.get("overlap", 0) for lat in grid.lattices) == 4 * 4     # the column's own bottom


def test_several_named_rooms_keep_their_names_and_own_lattices():
    geo = room_geometry([(0, 0), (4, 0), (4, 5), (0, 5)], floor="floor_a") + \
        room_geometry([(4, 0), (9, 0), (9, 3), (4, 3)], floor="floor_b")
    grid = workplane_grid(scene_of(geo), surfaces=["floor_b", "floor_a"], height=0.75)
    assert grid.area_names == ["floor_b", "floor_a"]
    a, b = grid.points[grid.areas == "floor_a"], grid.points[grid.areas == "floor_b"]
    # each room's lattice is centred in its own room, at 0.5 m + half a cell from its walls
    for pts, (x0, x1, y0, y1) in ((a, (0, 4, 0, 5)), (b, (4, 9, 0, 3))):
        d = max(x1 - x0, y1 - y0) - 1.0
        xs, ys = lattice(x0, x1, 0.5, en12464_spacing(d)), lattice(y0, y1, 0.5, en12464_spacing(d))
        assert len(pts) == len(xs) * len(ys)
        assert np.allclose(np.unique(pts[:, 0].round(9)), xs) and np.allclose(np.unique(pts[:, 1].round(9)), ys)
    assert np.allclose(grid.points[:, 2], 0.75)


def test_rooms_meeting_under_a_wall_get_a_lattice_each():
    # floors meet along part of the wall x = 6 and share two corners; the same material
    geo = room_geometry(L_ROOM) + room_geometry([(6, 0), (10, 0), (10, 4), (6, 4)])
    default = workplane_grid(scene_of(geo))
    assert len(default.lattices) == 2 and set(default.areas) == {"floor"}
    named = workplane_grid(scene_of(room_geometry(L_ROOM, floor="floor_a")
                                    + room_geometry([(6, 0), (10, 0), (10, 4), (6, 4)], floor="floor_b")),
                           surfaces=["floor_a", "floor_b"])
    order = lambda p: p[np.lexsort(p.T[::-1])]           # noqa: E731
    assert np.allclose(order(default.points), order(named.points))
    assert len(default.points) == 56 + 7 * 7


def test_a_door_does_not_join_rooms_and_a_column_does_not_split_one():
    left = room_geometry([(0, 0), (4, 0), (4, 4), (0, 4)])
    right = room_geometry([(4, 0), (8, 0), (8, 4), (4, 4)])
    # the wall x = 4 of both rooms, less a 1 x 2.1 m door at y 1.5 … 2.5
    walls = [g for g in left + right if not all(v[0] == 4 for v in g["vertices"])]
    door = [[[4, 0, 0], [4, 0, 3], [4, 1.5, 3], [4, 1.5, 0]], [[4, 2.5, 0], [4, 2.5, 3], [4, 4, 3], [4, 4, 0]],
            [[4, 1.5, 2.1], [4, 1.5, 3], [4, 2.5, 3], [4, 2.5, 2.1]]]
    geo = walls + [{"shape": "polygon", "material": "wall", "vertices": v} for v in door]
    assert len(workplane_grid(scene_of(geo)).lattices) == 2
    assert len(workplane_grid(scene_of(walls)).lattices) == 1          # no wall between: one floor
    one = workplane_grid(scene_of(room_geometry([(0, 0), (6, 0), (6, 6), (0, 6)]) + [column_box(3, 3, 1.0)]))
    assert len(one.lattices) == 1          # the column stands on the floor's diagonal


def test_t_junctions_do_not_split_a_floor():
    plain = workplane_grid(scene_of(room_geometry([(0, 0), (4, 0), (4, 4), (0, 4)])))
    geo = room_geometry([(0, 0), (4, 0), (4, 4), (0, 4)])[1:]          # walls and ceiling
    for x0, y0, x1, y1 in ((0, 0, 4, 2), (0, 2, 2, 4), (2, 2, 4, 4)):     # (2, 2) is a T-junction
        geo.append({"shape": "polygon", "material": "floor",
                    "vertices": [[x0, y0, 0], [x1, y0, 0], [x1, y1, 0], [x0, y1, 0]]})
    split = workplane_grid(scene_of(geo))
    assert len(split.lattices) == 1 and np.allclose(split.points, plain.points)


def test_default_floor_leaves_out_the_ground_outside():
    # the ground runs under the room and beyond it, at the floor's height
    grid = workplane_grid(scene_of(room_geometry(L_ROOM) + [GROUND]))
    assert len(grid.points) == 56
    assert np.all(inside_polygon(grid.points[:, :2], L_ROOM))
    # the office: ground at z = 0 around the room's footprint
    office = workplane_grid(load_scene(EXAMPLES / "office" / "scene.toml"))
    assert len(office.points) == 5 * 9
    assert office.points[:, 0].min() > 0.5 and office.points[:, 0].max() < 3.5
    assert office.points[:, 1].min() > 0.5 and office.points[:, 1].max() < 5.5


def test_ground_under_a_raised_floor_is_not_the_floor():
    room = room_geometry([(0, 0), (5, 0), (5, 5), (0, 5)], z0=0.3)
    ground = dict(GROUND, vertices=[[-50, -50, 0], [50, -50, 0], [50, 50, 0], [-50, 50, 0]])
    grid = workplane_grid(scene_of(room + [ground]))
    n = len(lattice(0, 5, 0.5, en12464_spacing(4.0)))
    assert np.allclose(grid.points[:, 2], 1.1) and len(grid.points) == n * n == 64


def test_points_over_a_desk_stay_and_a_desk_can_be_a_surface():
    desk = {"shape": "box", "center": [2.0, 2.0, 0.36], "size": [1.6, 0.8, 0.72], "material": "desk"}
    scene = scene_of(room_geometry([(0, 0), (4, 0), (4, 4), (0, 4)]) + [desk])
    grid = workplane_grid(scene)
    over = np.all(np.abs(grid.points[:, :2] - 2.0) < [0.8, 0.4], axis=1)
    n = len(lattice(0, 4, 0.5, en12464_spacing(3.0)))
    assert len(grid.points) == n * n == 49 and over.sum() == 3        # 3 lattice points lie over the desk
    top = workplane_grid(scene, surfaces=["desk"], height=0.05, margin=0.1)
    assert np.allclose(top.points[:, 2], 0.77) and set(top.areas) == {"desk"}
    assert np.all(np.abs(top.points[:, :2] - 2.0) <= [0.7, 0.3])


def test_a_rug_does_not_hide_the_floor():
    rug = {"shape": "polygon", "material": "desk", "vertices": [[1.5, 1.5, 0.01], [3.5, 1.5, 0.01],
                                                                [3.5, 3.5, 0.01], [1.5, 3.5, 0.01]]}
    room = room_geometry([(0, 0), (5, 0), (5, 5), (0, 5)])
    plain, with_rug = workplane_grid(scene_of(room)), workplane_grid(scene_of(room + [rug]))
    assert len(with_rug.points) == len(plain.points) == 64
    assert np.allclose(np.sort(with_rug.points[:, 2]), np.sort(plain.points[:, 2]))      # heights from the floor


def test_furniture_rising_just_above_the_grid_is_not_a_wall():
    room = room_geometry([(0, 0), (5, 0), (5, 5), (0, 5)])
    xs = lattice(0, 5, 0.5, en12464_spacing(4.0))         # 0.75, 1.25, ... 4.25
    # slabs 0.1 m thick just north of the row y = 2.25, 0.2 m from it, spanning x 1 … 4
    low = {"shape": "box", "center": [2.5, 2.5, 0.5], "size": [3.0, 0.1, 1.0], "material": "desk"}
    tall = dict(low, center=[2.5, 2.5, 1.0], size=[3.0, 0.1, 2.0])
    near_row = np.isclose(workplane_grid(scene_of(room)).points[:, 1], 2.25) | \
        np.isclose(workplane_grid(scene_of(room)).points[:, 1], 2.75)
    assert near_row.sum() == 2 * len(xs)
    assert len(workplane_grid(scene_of(room + [low])).points) == 64          # a chair back: no margin
    g = workplane_grid(scene_of(room + [tall]))                               # a cabinet: a wall
    # every point of the two rows is within 0.5 m of it (the end ones 0.32 m from its corners)
    assert not np.isin(np.round(g.points[:, 1], 6), [2.25, 2.75]).any() and len(g.points) == 64 - 16
    assert g.lattices[0].dropped == {"wall": 16}


def test_walls_wound_away_from_the_room_switch_the_winding_rule_off():
    room = room_geometry([(0, 0), (5, 0), (5, 5), (0, 5)])
    for entry in room[2:]:
        entry["vertices"] = entry["vertices"][::-1]
    grid = workplane_grid(scene_of(room))
    assert len(grid.points) == 64 and grid.lattices[0].winding_ignored
    assert any("not wound towards the room" in w for w in grid.warnings)


def test_rotated_room_gets_a_rotated_grid():
    angle = math.radians(30)
    rot = np.array([[math.cos(angle), -math.sin(angle)], [math.sin(angle), math.cos(angle)]])
    outline = [tuple(rot @ np.array(p, float) + 10) for p in [(0, 0), (5, 0), (5, 4), (0, 4)]]
    scene = scene_of(room_geometry(outline))
    grid = workplane_grid(scene)
    assert grid.lattices[0].angle == pytest.approx(30.0, abs=1e-9)
    local = (grid.points[:, :2] - 10) @ rot           # back into the room's own frame
    xs, ys = lattice(0, 5, 0.5, en12464_spacing(4.0)), lattice(0, 4, 0.5, en12464_spacing(4.0))
    assert np.allclose(np.unique(local[:, 0].round(9)), xs) and np.allclose(np.unique(local[:, 1].round(9)), ys)
    assert len(grid.points) == len(xs) * len(ys)
    assert workplane_grid(scene, align="scene").lattices[0].angle == 0.0


def test_outline_angle_is_modulo_90_degrees():
    square = np.array([[[0, 0, 0], [1, 0, 0], [1, 1, 0]], [[0, 0, 0], [1, 1, 0], [0, 1, 0]]], float)
    assert outline_angle(square) == 0.0
    c, s = math.cos(math.radians(-20)), math.sin(math.radians(-20))
    turned = square @ np.array([[c, s, 0], [-s, c, 0], [0, 0, 1]])
    assert math.degrees(outline_angle(turned)) == pytest.approx(-20.0)


# ---------------------------------------------------------------------------
# Plan geometry
# ---------------------------------------------------------------------------

def test_section_of_a_box_is_its_outline():
    from lbl_illum.scene.geometry import box_triangles

    seg = section_segments(box_triangles([1, 2, 1.5], [2, 4, 3]), 0.8)
    length = np.linalg.norm(seg[:, 1] - seg[:, 0], axis=1).sum()
    assert length == pytest.approx(2 * (2 + 4))
    assert np.allclose(seg.reshape(-1, 2).min(axis=0), [0, 0]) and np.allclose(seg.reshape(-1, 2).max(axis=0), [2, 4])
    assert len(section_segments(box_triangles([0, 0, 0], [1, 1, 1]), 2.0)) == 0


def test_plan_outline_of_the_office():
    walls, glazing = plan_outline(load_scene(EXAMPLES / "office" / "scene.toml"), 0.8)
    assert np.linalg.norm(walls[:, 1] - walls[:, 0], axis=1).sum() == pytest.approx(2 * (4 + 6))
    assert np.allclose(np.sort(glazing[:, :, 0].ravel())[[0, -1]], [0.5, 3.5]) and np.allclose(glazing[:, :, 1], 0)


# ---------------------------------------------------------------------------
# Area names in .pts files
# ---------------------------------------------------------------------------

def test_area_names_round_trip(tmp_path):
    geo = room_geometry([(0, 0), (4, 0), (4, 5), (0, 5)], floor="floor_a") + \
        room_geometry([(4, 0), (9, 0), (9, 3), (4, 3)], floor="floor_b")
    grid = workplane_grid(scene_of(geo), surfaces=["floor_a", "floor_b"])
    path = tmp_path / "g.pts"
    write_points(path, grid.points, grid.normals, grid.areas, header="two rooms")
    points, normals, areas = read_points(path, with_areas=True)
    assert np.allclose(points, grid.points, atol=1e-9) and np.allclose(normals, grid.normals)
    assert list(areas) == list(grid.areas)
    assert np.allclose(read_points(path)[0], points)         # the two-item form still reads it
    assert path.read_text().splitlines()[1].split()[-1] == "floor_a"


def test_six_column_files_read_as_before(tmp_path):
    path = tmp_path / "p.pts"
    path.write_text("# header\n0 0 1 0 0 2\n1 2 3 0 0 1 desk_1  # named\n")
    points, normals, areas = read_points(path, 2.0, with_areas=True)
    assert np.allclose(points, [[0, 0, 2], [2, 4, 6]]) and np.allclose(normals[0], [0, 0, 1])
    assert list(areas) == ["", "desk_1"]


@pytest.mark.parametrize("line, expect", [
    ("0 0 1 0 0 1 0.5", "looks like a number"),
    ("0 0 1 0 0 1 a,b", "one word"),
    ("0 0 1 0 0 1 a b", "got 8 fields"),
])
def test_bad_area_names_are_refused(tmp_path, line, expect):
    path = tmp_path / "p.pts"
    path.write_text(line + "\n")
    with pytest.raises(InputError, match=expect) as err:
        read_points(path)
    assert "p.pts: line 1" in str(err.value)


# ---------------------------------------------------------------------------
# Bad input
# ---------------------------------------------------------------------------

@pytest.mark.parametrize("kwargs, expect", [
    (dict(surfaces=["flor"]), "did you mean 'floor'"),
    (dict(surfaces=["wall"]), "no horizontal triangles"),
    (dict(surfaces=["floor", "floor"]), "named twice"),
    (dict(margin=2.6), "smaller --margin"),
    (dict(spacing=0.0), "--spacing"),
    (dict(height=-1.0), "--height"),
    (dict(spacing=1e-4), "larger --spacing"),
])
def test_bad_grid_requests(kwargs, expect):
    with pytest.raises(InputError, match=expect):
        workplane_grid(scene_of(room_geometry([(0, 0), (5, 0), (5, 5), (0, 5)])), **kwargs)


def test_open_scene_has_no_floor():
    with pytest.raises(InputError, match="no floor found"):
        workplane_grid(scene_of([GROUND]))

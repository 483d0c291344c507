"""False-colour plans: written whole with their labels, never written from bad input."""

import numpy as np
import pytest

pytest.importorskip("matplotlib")

from lbl_illum.errors import InputError
from lbl_illum.workplane.grid import plan_outline, workplane_grid
from lbl_illum.viz.plots import (REACH_MIN, _masked_triangulation, _plan_field, _plan_rooms, nice_length,
                                 plan_plot)

from conftest import L_ROOM, inside_polygon, room_geometry, scene_of


@pytest.fixture(scope="module")
def l_room():
    scene = scene_of(room_geometry(L_ROOM))
    grid = workplane_grid(scene)
    walls, glazing = plan_outline(scene, 0.8)
    values = 100.0 + 50.0 * grid.points[:, 0] + 20.0 * grid.points[:, 1]
    return grid, walls, values


def test_svg_plan_has_the_labels_units_scale_and_names(tmp_path, l_room):
    grid, walls, values = l_room
    path = tmp_path / "plan.svg"
    plan_plot(path, grid.points, values, areas=grid.areas, outline=walls, thresholds=[300, 500])
    text = path.read_text()
    for label in ("Illuminance [lux]", "300 lux", "500 lux", "floor", "1 m", "x (east) [m]",
                  "walls (section at the grid)"):
        assert label in text, label
    assert not [p for p in tmp_path.iterdir() if p.suffix == ".tmp"]


def test_png_plan_is_a_picture_in_false_colour(tmp_path, l_room):
    from PIL import Image

    grid, walls, values = l_room
    path = tmp_path / "plan.png"
    plan_plot(path, grid.points, values, areas=grid.areas, outline=walls, quantity="Daylight factor", unit="%",
              thresholds=[2])
    image = np.asarray(Image.open(path).convert("RGB")).astype(int)
    assert image.shape[0] > 500 and image.shape[1] > 500
    spread = image.max(axis=2) - image.min(axis=2)
    assert (spread > 80).mean() > 0.05          # coloured, not only black lines on white


def test_points_only_plan(tmp_path, l_room):
    grid, walls, _ = l_room
    path = tmp_path / "grid.svg"
    plan_plot(path, grid.points, None, areas=grid.areas, outline=walls)
    assert f"{len(grid.points)} points" in path.read_text()


def test_colour_does_not_bridge_the_notch_of_an_l_shaped_room(l_room):
    grid = l_room[0]
    tri = _masked_triangulation(grid.points[:, :2])
    kept = tri.triangles[~tri.mask]
    centres = grid.points[kept, :2].mean(axis=1)
    assert len(kept) > 50 and inside_polygon(centres, L_ROOM).all()
    assert (~inside_polygon(grid.points[tri.triangles, :2].mean(axis=1), L_ROOM)).any()   # Delaunay did bridge it


@pytest.mark.parametrize("name, change, expect", [
    ("plan.png", dict(values="nan"), "finite"),
    ("plan.png", dict(values="short"), "values for"),
    ("plan.png", dict(areas="short"), "area names"),
    ("plan.gif", {}, "must end in"),
    ("missing/plan.png", {}, "does not exist"),
])
def test_bad_input_writes_nothing(tmp_path, l_room, name, change, expect):
    grid, walls, values = l_room
    values = values.copy()
    areas = grid.areas
    if change.get("values") == "nan":
        values[3] = np.nan
    if change.get("values") == "short":
        values = values[:-1]
    if change.get("areas") == "short":
        areas = areas[:-1]
    path = tmp_path / name
    with pytest.raises(InputError, match=expect):
        plan_plot(path, grid.points, values, areas=areas, outline=walls)
    assert not path.exists() and not list(tmp_path.glob("*.tmp"))


def test_nice_length():
    assert [nice_length(x) for x in (4.6, 10.0, 37.0, 0.9)] == [1.0, 2.0, 5.0, 0.2]


def test_plan_sheet_has_title_summary_north_arrow_and_log_scale(tmp_path, l_room):
    grid, walls, values = l_room
    path = tmp_path / "plan.svg"
    plan_plot(path, grid.points, values * 100, areas=grid.areas, outline=walls, thresholds=[300, 500, 2000],
              title="Level 2, east wing", summary="mean 512 lux, min 120", scale="log")
    text = path.read_text()
    for label in ("Level 2, east wing", "mean 512 lux, min 120", ">N<", "log scale", "1 m", "2000 lux"):
        assert label in text or label.strip("<>") in text, label
    fixed = tmp_path / "fixed.svg"
    plan_plot(fixed, grid.points, values, areas=grid.areas, outline=walls, value_range=(0.0, 5000.0))
    assert "Illuminance [lux]" in fixed.read_text()


@pytest.mark.parametrize("kwargs, message", [
    ({"scale": "cubic"}, "colour scale must be one of linear, log"),
    ({"value_range": (5.0, 1.0)}, "the first below the second"),
    ({"scale": "log", "value_range": (0.0, 100.0)}, "log colour scale needs a range above 0"),
])
def test_plan_bad_scales_are_refused(tmp_path, l_room, kwargs, message):
    grid, walls, values = l_room
    with pytest.raises(InputError, match=message):
        plan_plot(tmp_path / "p.png", grid.points, values, outline=walls, **kwargs)
    assert not (tmp_path / "p.png").exists()


# ---------------------------------------------------------------------------
# colour out to the walls
# ---------------------------------------------------------------------------

RECT = [(0, 0), (6, 0), (6, 4), (0, 4)]
VIEW = (np.array([-1.0, -1.0]), np.array([7.0, 7.0]))


def linear(xy):
    """A field of 50 lux/m eastwards and 20 lux/m northwards [lux]."""
    return 100.0 + 50.0 * xy[:, 0] + 20.0 * xy[:, 1]


def cell_centres(field, extent):
    """x, y [m] of the raster's cell centres (shaped as ``field``) and the cell size [m]."""
    ny, nx = field.shape
    x0, x1, y0, _ = extent
    step = (x1 - x0) / nx
    x, y = np.meshgrid(x0 + (np.arange(nx) + 0.5) * step, y0 + (np.arange(ny) + 0.5) * step)
    return x, y, step


def room_segments(outline):
    """(k, 2, 2) plan segments of a closed plan polygon."""
    outline = np.asarray(outline, float)
    return np.stack([outline, np.roll(outline, -1, axis=0)], axis=1)


@pytest.fixture(scope="module")
def rect_room():
    """A 6 x 4 m room, its EN 12464-1 grid 0.5 m from the walls, its outline and a linear field."""
    scene = scene_of(room_geometry(RECT))
    grid = workplane_grid(scene)
    walls, glazing = plan_outline(scene, 0.8)
    return grid.points[:, :2], grid.areas, walls, glazing, linear(grid.points)


def test_colour_reaches_the_walls_of_a_rectangular_room(rect_room):
    xy, areas, walls, glazing, values = rect_room
    assert xy[:, 0].min() > 0.5 and xy[:, 1].max() < 3.5         # cell centres within the 0.5 m margin
    rooms = _plan_rooms(xy, walls, glazing)
    assert len(rooms) == 1 and rooms[0].area == pytest.approx(24.0, rel=1e-6)
    field, extent, own = _plan_field(xy, values, areas, rooms, *VIEW)
    x, y, step = cell_centres(field, extent)
    coloured = ~np.ma.getmaskarray(field)
    assert (own == 0).all() and step < 0.05
    inside = (x > 0) & (x < 6) & (y > 0) & (y < 4)
    assert coloured[inside].all() and not coloured[~inside].any()
    assert x[coloured].min() < step and x[coloured].max() > 6 - step
    assert y[coloured].min() < step and y[coloured].max() > 4 - step


def test_colour_beyond_the_points_is_the_value_at_the_nearest_edge_point_and_linear_within(rect_room):
    """Between the outer points and the walls a cell takes the value at the nearest point of
    the points' outline, linear along it: for values linear in position and a rectangular
    grid, the linear function at the cell clamped into the grid's rectangle."""
    xy, areas, walls, glazing, values = rect_room
    field, extent, _ = _plan_field(xy, values, areas, _plan_rooms(xy, walls, glazing), *VIEW)
    x, y, _ = cell_centres(field, extent)
    coloured = ~np.ma.getmaskarray(field)
    cells = np.column_stack([x[coloured], y[coloured]])
    got = field.compressed()
    lo, hi = xy.min(axis=0), xy.max(axis=0)
    within = ((cells > lo) & (cells < hi)).all(axis=1)
    assert within.sum() > 1000 and np.allclose(got[within], linear(cells[within]), rtol=0, atol=1e-6)
    beyond = cells[~within]
    assert len(beyond) > 1000
    assert np.allclose(got[~within], linear(np.clip(beyond, lo, hi)), rtol=0, atol=1e-6)
    # at the west wall: the outer point's value, not the gradient carried on to the wall
    wall_side = beyond[:, 0] < 0.05
    assert wall_side.sum() > 50
    assert np.all(np.abs(got[~within][wall_side] - linear(beyond[wall_side])) > 20.0)


@pytest.fixture(scope="module")
def l_room_with_column():
    column = {"shape": "box", "center": [1.5, 4.5, 1.5], "size": [0.4, 0.4, 3.0], "material": "column"}
    scene = scene_of(room_geometry(L_ROOM) + [column])
    grid = workplane_grid(scene)
    walls, glazing = plan_outline(scene, 0.8)
    return grid.points[:, :2], grid.areas, walls, glazing, linear(grid.points)


def test_colour_keeps_out_of_the_notch_and_the_column_and_reaches_their_walls(l_room_with_column):
    xy, areas, walls, glazing, values = l_room_with_column
    rooms = _plan_rooms(xy, walls, glazing)
    assert len(rooms) == 1 and rooms[0].area == pytest.approx(27.0 - 0.16, rel=1e-6)
    field, extent, _ = _plan_field(xy, values, areas, rooms, *VIEW)
    x, y, step = cell_centres(field, extent)
    coloured = ~np.ma.getmaskarray(field)
    cells = np.column_stack([x.ravel(), y.ravel()])
    in_l = inside_polygon(cells, L_ROOM).reshape(x.shape)
    in_column = (np.abs(x - 1.5) < 0.2) & (np.abs(y - 4.5) < 0.2)
    assert in_column.sum() > 100 and not coloured[in_column].any()
    assert not coloured[~in_l].any() and coloured[in_l & ~in_column].all()
    notch_walls = in_l & (((x > 3 - step) & (y > 3)) | ((x > 3) & (y > 3 - step)))
    assert notch_walls.sum() > 100                # the cells along the notch's two walls are coloured


def test_colour_does_not_cross_a_wall_to_the_next_room():
    walls = np.concatenate([room_segments([(0, 0), (3, 0), (3, 4), (0, 4)]),
                            room_segments([(3, 0), (6, 0), (6, 4), (3, 4)])])
    # b's first column, 0.2 m past the wall, is nearer the wall's west side than a's last
    # one, and the triangulation spans the wall
    a = np.array([(x, y) for x in (0.5, 1.5, 2.3) for y in (0.5, 1.5, 2.5, 3.5)])
    b = np.array([(x, y) for x in (3.2, 4.2, 5.2) for y in (0.5, 1.5, 2.5, 3.5)])
    xy = np.concatenate([a, b])
    values = np.r_[np.full(len(a), 100.0), np.full(len(b), 1000.0)]
    rooms = _plan_rooms(xy, walls, np.zeros((0, 2, 2)))
    assert len(rooms) == 2
    field, extent, own = _plan_field(xy, values, np.full(len(xy), "", dtype=object), rooms, *VIEW)
    x, y, step = cell_centres(field, extent)
    coloured = ~np.ma.getmaskarray(field)
    west = coloured & (x < 3)
    tri = _masked_triangulation(xy)
    east = xy[tri.triangles[~tri.mask], 0] > 3
    assert (east.any(axis=1) & ~east.all(axis=1)).sum() > 4
    assert len(set(own)) == 2 and x[west].max() > 3 - step     # room a is coloured up to the wall...
    assert np.all(field[west] == 100.0)                          # ...by its own points alone
    assert np.all(field[coloured & (x > 3)] == 1000.0)


def test_areas_sharing_a_room_split_it_by_their_nearest_points():
    xy = np.array([(x, y) for x in (0.5, 1.5, 2.5, 3.5, 4.5, 5.5) for y in (0.5, 1.5, 2.5, 3.5)])
    names = np.where(xy[:, 0] < 3, "west", "east").astype(object)
    values = np.where(names == "west", 100.0, 1000.0)
    rooms = _plan_rooms(xy, room_segments(RECT), np.zeros((0, 2, 2)))
    field, extent, _ = _plan_field(xy, values, names, rooms, *VIEW)
    x, y, _ = cell_centres(field, extent)
    coloured = ~np.ma.getmaskarray(field)
    assert len(rooms) == 1 and coloured[(x > 0) & (x < 6) & (y > 0) & (y < 4)].all()
    assert np.all(field[coloured & (x < 3)] == 100.0) and np.all(field[coloured & (x > 3)] == 1000.0)


@pytest.mark.parametrize("under_roof_light", [True, False])
def test_a_roof_light_is_coloured_a_column_is_not(under_roof_light):
    walls = np.concatenate([room_segments(RECT), room_segments([(4, 2), (4.4, 2), (4.4, 2.4), (4, 2.4)])])
    roof_light = room_segments([(1, 1), (2, 1), (2, 2), (1, 2)])
    xy = np.array([(x, y) for x in np.arange(0.5, 6, 0.5) for y in np.arange(0.5, 4, 0.5)])
    keep = ~((np.abs(xy[:, 0] - 4.2) < 0.5) & (np.abs(xy[:, 1] - 2.2) < 0.5))
    if not under_roof_light:
        keep &= ~((xy[:, 0] > 0.9) & (xy[:, 0] < 2.1) & (xy[:, 1] > 0.9) & (xy[:, 1] < 2.1))
    rooms = _plan_rooms(xy[keep], walls, roof_light)
    assert len(rooms) == 1
    import shapely

    inside = shapely.contains_xy(rooms[0], [1.5, 1.05, 4.2, 3.0], [1.5, 1.05, 2.2, 3.0])
    assert inside.tolist() == [True, True, False, True]
    assert rooms[0].area == pytest.approx(24.0 - 0.16, rel=1e-6)


def test_a_task_area_colours_only_its_surroundings(rect_room):
    _, _, walls, glazing, _ = rect_room
    xy = np.array([(x, y) for x in (2.5, 3.0, 3.5) for y in (1.5, 2.0, 2.5)])
    field, extent, _ = _plan_field(xy, linear(xy), np.full(len(xy), "", dtype=object),
                                   _plan_rooms(xy, walls, glazing), *VIEW)
    x, y, _ = cell_centres(field, extent)
    coloured = ~np.ma.getmaskarray(field)
    gap = np.hypot(np.maximum(np.abs(x - 3.0) - 0.5, 0.0), np.maximum(np.abs(y - 2.0) - 0.5, 0.0))
    assert coloured[gap < REACH_MIN - 0.05].all() and not coloured[gap > REACH_MIN + 0.05].any()
    assert (gap > REACH_MIN + 0.05).sum() > 1000     # the corners of the room stay blank


def _coloured_share(path):
    from PIL import Image

    image = np.asarray(Image.open(path).convert("RGB")).astype(int)
    return ((image.max(axis=2) - image.min(axis=2)) > 40).mean()


def test_the_plan_is_coloured_to_the_walls_and_an_open_outline_falls_back(tmp_path, rect_room):
    xy, areas, walls, glazing, values = rect_room
    closed, open_, bare = tmp_path / "closed.png", tmp_path / "open.png", tmp_path / "bare.png"
    plan_plot(closed, xy, values, areas=areas, outline=walls, windows=glazing)
    east = np.all(np.isclose(walls[:, :, 0], 6.0), axis=1)
    assert east.any()
    assert _plan_rooms(xy, walls[~east], glazing) == []
    plan_plot(open_, xy, values, areas=areas, outline=walls[~east], windows=glazing)     # no error
    plan_plot(bare, xy, values, areas=areas)
    # 24 m2 of floor against 15 m2 within the points (the colour bar is in all three)
    assert _coloured_share(closed) > 1.25 * _coloured_share(open_)
    assert _coloured_share(open_) > 0.05 and _coloured_share(bare) > 0.05

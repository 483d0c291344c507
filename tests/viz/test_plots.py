"""False-colour plans: written whole with their labels, never written from bad input."""

import numpy as np
import pytest

pytest.importorskip("matplotlib")

from lbl_illum.errors import InputError
from lbl_illum.workplane.grid import plan_outline, workplane_grid
from lbl_illum.viz.plots import _masked_triangulation, nice_length, plan_plot

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

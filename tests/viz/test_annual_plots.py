"""Pictures of the annual metrics: written whole with their labels and values, never from bad input."""

import numpy as np
import pytest

pytest.importorskip("matplotlib")

from lbl_illum.errors import InputError
from lbl_illum.viz.annual_plots import _daily_span, ase_plan, da_plan, day_hour_grid, day_hour_plot, sda_plan
from lbl_illum.workplane.annual import lm83_occupancy

WALLS = np.array([[[0, 0], [0, 6]], [[0, 6], [4, 6]], [[4, 6], [4, 0]], [[4, 0], [3.5, 0]], [[0.5, 0], [0, 0]]],
                 float)
WINDOWS = np.array([[[0.5, 0], [3.5, 0]]], float)


@pytest.fixture(scope="module")
def room():
    """A 4 x 6 m room lit from y = 0: DA falls with the distance from the window."""
    x, y = np.meshgrid(np.arange(0.5, 4.0, 0.5), np.arange(0.5, 6.0, 0.5))
    points = np.column_stack([x.ravel(), y.ravel(), np.full(x.size, 0.8)])
    da = 100.0 * np.exp(-points[:, 1] / 2.0)
    ase = 600.0 * np.exp(-points[:, 1])
    areas = np.where(points[:, 0] < 2.0, "west", "east").astype(object)
    return points, da, ase, areas


def no_temporaries(folder):
    return not [p for p in folder.iterdir() if p.suffix == ".tmp"]


def test_da_plan_labels_units_and_the_50_percent_line(tmp_path, room):
    points, da, _, areas = room
    path = tmp_path / "da.svg"
    da_plan(path, points, da, areas=areas, outline=WALLS, windows=WINDOWS)
    text = path.read_text()
    for label in ("Daylight autonomy DA300 [%]", "50 %", "west", "east", "glazing", "x (east) [m]"):
        assert label in text, label
    assert no_temporaries(tmp_path)


def test_sda_plan_counts_points_at_exactly_50_percent_as_passing(tmp_path, room):
    points = room[0][:4]
    path = tmp_path / "sda.svg"
    sda_plan(path, points, [50.0, 49.9, 100.0, 0.0])
    text = path.read_text()
    assert "sDA300/50% = 50 % of points" in text and "1 pass, 0 fail" in text
    sda_plan(path, points, [50.0, 50.0, 100.0, 0.0])
    assert "sDA300/50% = 75 % of points" in path.read_text()


def test_ase_plan_has_the_250_hour_line_and_counts_more_than_250(tmp_path, room):
    points = room[0][:4]
    path = tmp_path / "ase.svg"
    ase_plan(path, points, [251.0, 250.0, 0.0, 0.0])
    text = path.read_text()
    assert "ASE1000,250 = 25 %" in text and "250 h" in text and "Direct sun &gt;= 1000 lux [h]" in text


def test_png_plans_are_pictures_in_false_colour(tmp_path, room):
    from PIL import Image

    points, da, ase, areas = room
    for name, draw, values in (("da.png", da_plan, da), ("sda.png", sda_plan, da), ("ase.png", ase_plan, ase)):
        path = tmp_path / name
        draw(path, points, values, areas=areas, outline=WALLS, windows=WINDOWS)
        image = np.asarray(Image.open(path).convert("RGB")).astype(int)
        assert image.shape[0] > 500 and image.shape[1] > 500
        assert ((image.max(axis=2) - image.min(axis=2)) > 80).mean() > 0.05, name


def year(points=3):
    """Illuminance [lux] of ``points`` points: zero at night, 1000 lux from 6 to 18 h in
    summer, and one bright hour: 20 000 lux at point 0 on 2 January, 11:00-12:00."""
    E = np.zeros((points, 8760), np.float32)
    day = np.arange(8760) // 24
    hour = np.arange(8760) % 24 + 1
    E[:, (hour > 6) & (hour <= 18) & (day > 150) & (day < 240)] = 1000.0
    E[0, 24 + 11] = 20000.0
    return E


def test_day_hour_grid_puts_each_row_at_its_day_and_hour():
    E = year()
    grid, label, n = day_hour_grid(E)
    assert grid.shape == (24, 365) and (label, n) == ("all points", 3)
    assert grid[11, 1] == pytest.approx(20000.0 / 3)          # hour-ending 12 of day 2: mean of 3 points
    assert grid[6, 200] == 1000.0 and grid[5, 200] == 0.0 and grid[17, 200] == 1000.0 and grid[18, 200] == 0.0
    grid, label, n = day_hour_grid(E, ["a", "b", "b"], "b")
    assert (label, n) == ("area b", 2) and grid[11, 1] == 0.0
    grid, _, _ = day_hour_grid(E[0])
    assert grid[11, 1] == 20000.0


def test_day_hour_plot(tmp_path):
    from PIL import Image

    E = year()
    path = tmp_path / "heat.svg"
    day_hour_plot(path, E, areas=["a", "a", "b"], area="a", occupancy=lm83_occupancy())
    text = path.read_text()
    for label in ("Mean illuminance [lux]", "Jan", "Dec", "hour (local standard time)", "occupied hours",
                  "area a (2 points)"):
        assert label in text, label
    png = tmp_path / "heat.png"
    day_hour_plot(png, E, scale="log")
    image = np.asarray(Image.open(png).convert("RGB")).astype(int)
    assert image.shape[1] > 1000 and ((image.max(axis=2) - image.min(axis=2)) > 80).mean() > 0.05
    assert no_temporaries(tmp_path)


def test_occupied_span_of_each_day():
    first, last = _daily_span(lm83_occupancy(dst="us", year=2023).reshape(365, 24))
    assert (first[0], last[0]) == (8.0, 18.0)                  # 8:00-18:00 standard time
    assert (first[181], last[181]) == (7.0, 17.0)              # 1 July: 8:00-18:00 clock time
    occ = np.zeros((365, 24))
    occ[3, 9:12] = 1.0
    first, last = _daily_span(occ)
    assert (first[3], last[3]) == (9.0, 12.0) and np.isnan(first[0]) and np.isnan(last[0])


@pytest.mark.parametrize("kwargs, message", [
    ({"illuminance": np.zeros((2, 100))}, "8760 hourly values"),
    ({"illuminance": np.full((1, 8760), np.nan)}, "must be finite"),
    ({"area": "c", "areas": ["a", "b"]}, "no point in area 'c'"),
    ({"area": "a", "areas": ["a"]}, "1 area names for 2 points"),
    ({"scale": "cubic"}, "colour scale"),
    ({"value_range": (10.0, 1.0)}, "colour range"),
    ({"occupancy": np.ones(10)}, "occupancy needs 8760"),
])
def test_bad_heat_map_input_writes_nothing(tmp_path, kwargs, message):
    args = {"illuminance": np.ones((2, 8760))} | kwargs
    path = tmp_path / "heat.png"
    with pytest.raises(InputError, match=message):
        day_hour_plot(path, args.pop("illuminance"), **args)
    assert not path.exists() and no_temporaries(tmp_path)


def test_bad_plot_name(tmp_path, room):
    with pytest.raises(InputError, match="must end in"):
        da_plan(tmp_path / "da.jpg", room[0], room[1])
    with pytest.raises(InputError, match="must end in"):
        day_hour_plot(tmp_path / "heat.bmp", np.ones(8760))


def test_the_pass_fail_plan_has_its_boundary_and_no_round_isolines(tmp_path, room, monkeypatch):
    """Round-value isolines on a 0/1 map would stack up where pass turns to fail: the sDA
    plan draws only its boundary at ½, the DA plan its isolines as any plan."""
    import matplotlib.axes

    labels = []
    real = matplotlib.axes.Axes.clabel
    monkeypatch.setattr(matplotlib.axes.Axes, "clabel", lambda self, *a, **k: labels.append(1) or real(self, *a, **k))
    points, da, _, areas = room
    sda_plan(tmp_path / "sda.png", points, da, areas=areas, outline=WALLS, windows=WINDOWS)
    assert labels == []
    da_plan(tmp_path / "da.png", points, da, areas=areas, outline=WALLS, windows=WINDOWS)
    assert labels

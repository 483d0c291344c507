"""3-D views: an off-screen screenshot of a room with coloured points, extra layers, bad input.

Skipped without pyvista (CI installs only the test extra) or where VTK cannot render off
screen (no EGL/OSMesa); the skip says which.
"""

import sys

import numpy as np
import pytest

pytest.importorskip("pyvista")

from lbl_illum import view3d
from lbl_illum.errors import InputError
from lbl_illum.grid import workplane_grid
from lbl_illum.scene import load_scene

from conftest import EXAMPLES


def _offscreen():
    ok, reason = view3d.offscreen_available()
    if not ok:
        pytest.skip(reason)


@pytest.fixture(scope="module")
def office():
    scene = load_scene(EXAMPLES / "office" / "scene.toml")
    grid = workplane_grid(scene)
    return scene, grid


def _image(path):
    from PIL import Image

    return np.asarray(Image.open(path).convert("RGB")).astype(int)


def test_screenshot_of_the_room_with_coloured_points(tmp_path, office):
    _offscreen()
    scene, grid = office
    values = 2000.0 * np.exp(-grid.points[:, 1])
    path = tmp_path / "shot.png"
    view3d.render(scene, [view3d.GeometryLayer(scene), view3d.PointLayer(grid.points, values, areas=grid.areas)],
                  points=grid.points, screenshot=path, window_size=(640, 480))
    image = _image(path)
    assert image.shape == (480, 640, 3)
    # viridis points: strongly coloured pixels (the room itself is drawn in greys and pale blue)
    coloured = (image.max(axis=2) - image.min(axis=2)) > 100
    assert coloured.sum() > 200
    bare = tmp_path / "bare.png"
    view3d.render(scene, screenshot=bare, window_size=(640, 480))
    assert ((_image(bare).max(axis=2) - _image(bare).min(axis=2)) > 100).sum() < coloured.sum() / 4


def test_any_object_with_add_to_is_a_layer(tmp_path, office):
    _offscreen()
    import pyvista as pv

    scene, grid = office
    seen = []

    class Spheres:                       # the shape of a future layer (e.g. cache records)
        def add_to(self, plotter, frame):
            seen.append((frame.lo.copy(), frame.hi.copy(), frame.cut_above))
            plotter.add_mesh(pv.Sphere(radius=0.4, center=(2, 3, 1.5)), color="red")

    path = tmp_path / "layers.png"
    view3d.render(scene, [view3d.GeometryLayer(scene), Spheres()], points=grid.points, screenshot=path,
                  window_size=(320, 240))
    lo, hi, cut = seen[0]
    assert np.all(lo[:2] < grid.points[:, :2].min(axis=0)) and np.all(hi[:2] > grid.points[:, :2].max(axis=0))
    assert cut == pytest.approx(0.85)                   # the ceiling (z = 3 m) is left out above the points
    red = _image(path)
    assert ((red[:, :, 0] > 150) & (red[:, :, 1] < 90) & (red[:, :, 2] < 90)).sum() > 100


@pytest.mark.parametrize("name, expect", [("shot.jpg", "must end in .png"), ("missing/shot.png", "does not exist")])
def test_bad_screenshot_paths(tmp_path, office, name, expect):
    with pytest.raises(InputError, match=expect):
        view3d.render(office[0], screenshot=tmp_path / name)
    assert not (tmp_path / name).exists()


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="the headless check is for Linux")
def test_no_window_without_a_display(monkeypatch, office):
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    with pytest.raises(InputError, match="--screenshot"):
        view3d.render(office[0])

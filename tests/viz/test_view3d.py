"""3-D views: an off-screen screenshot of a room with coloured points, extra layers, bad input.

Skipped without pyvista (CI installs only the test extra) or where VTK cannot render off
screen (no EGL/OSMesa); the skip says which.
"""

import sys

import numpy as np
import pytest

pytest.importorskip("pyvista")

from lbl_illum.viz import view3d
from lbl_illum.errors import InputError
from lbl_illum.workplane.grid import workplane_grid
from lbl_illum.scene.scenefile import load_scene

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


# -- cache records (the paper's Figure 5b) -------------------------------------------------

def test_record_outlines_are_the_valid_domains():
    """Round: a circle of radius a·R_i in the tangent plane; elliptical: radius
    a·R_i / sqrt(1 + |W|²) along W and a·R_i across it (the lookup's test, octree.py)."""
    P = np.array([[1.0, 2.0, 3.0], [0.0, 0.0, 0.0]])
    N = np.array([[0.0, 0.0, 1.0], [1.0, 1.0, 0.0]]) / np.array([[1.0], [np.sqrt(2.0)]])
    R = np.array([2.0, 0.5])
    ring = view3d.record_outlines(P, N, R, 0.1, sides=16)
    d = ring - P[:, None, :]
    np.testing.assert_allclose(np.linalg.norm(d, axis=2), np.repeat((0.1 * R)[:, None], 16, axis=1), rtol=1e-12)
    np.testing.assert_allclose(np.einsum("nkj,nj->nk", d, N), 0.0, atol=1e-12)
    W = np.array([[3.0, 0.0, 0.0], [0.0, 0.0, 0.0]])            # short axis along x, |W| = 3
    ell = view3d.record_outlines(P, N, R, 0.1, W, sides=16, lift=0.01)
    d = ell - P[:, None, :] - 0.01 * N[:, None, :]
    np.testing.assert_allclose(np.abs(d[0, :, 0]).max(), 0.2 / np.sqrt(10.0), rtol=1e-12)
    np.testing.assert_allclose(np.abs(d[0, :, 1]).max(), 0.2, rtol=1e-12)
    # every corner lies on the domain's boundary: (|d|² + (d·W)²) / R² = a²
    q = (np.sum(d[0] ** 2, axis=1) + (d[0] @ W[0]) ** 2) / R[0] ** 2
    np.testing.assert_allclose(q, 0.01, rtol=1e-12)
    np.testing.assert_allclose(np.linalg.norm(d[1], axis=1), 0.05, rtol=1e-12)   # W = 0: round


ROOM_TOML = """
units = "m"
[[geometry]]
shape = "box"
center = [0, 0, 1.5]
size = [4, 4, 3]
material = "wall"
[[geometry]]
shape = "rectangle"
origin = [-0.5, -0.5, 2.99]
u = [1, 0, 0]
v = [0, 1, 0]
material = "lamp"
[materials.wall]
type = "diffuse"
reflectance = 0.5
[materials.lamp]
type = "light"
luminance = 2000
[sky]
type = "none"
"""


@pytest.fixture(scope="module")
def room_cache(tmp_path_factory):
    """A closed 4 m room lit by a ceiling lamp, and a cache file of a few records made
    for 9 points on its floor (two levels)."""
    from lbl_illum import Options
    from lbl_illum.engine.integrator import Integrator

    folder = tmp_path_factory.mktemp("room")
    (folder / "room.toml").write_text(ROOM_TOML)
    scene = load_scene(folder / "room.toml")
    g = np.linspace(-1.2, 1.2, 3)
    points = np.column_stack([np.repeat(g, 3), np.tile(g, 3), np.full(9, 0.001)])
    integ = Integrator(scene, Options(accuracy=0.3, samples=32, bounces=2, seed=1))
    integ.compute(points, np.tile([0.0, 0.0, 1.0], (9, 1)))
    path = folder / "room.cache"
    counts = integ.cache.save(path)
    assert counts[0] > 0 and counts[1] > 0
    return folder, scene, path, counts


def _level_pixels(image, k):
    """Pixels within 40 of level k's colour (tab10), in any shade of its blend with white."""
    colour = 255 * np.array(view3d._level_colours(k))
    rgb = image.astype(float)
    # a blend of the colour with a grey/white background lies on the line between them
    t = np.clip(((255 - rgb) @ (255 - colour)) / np.sum((255 - colour) ** 2), 0.15, 1.0)
    near = np.linalg.norm(rgb - (255 - t[..., None] * (255 - colour)), axis=2) < 40
    return near & (image.max(axis=2) - image.min(axis=2) > 25)


def test_view_of_a_cache_file_draws_its_records_by_level(tmp_path, room_cache):
    _offscreen()
    from lbl_illum.cli.main import main

    folder, scene, path, counts = room_cache
    shot = tmp_path / "cache.png"
    assert main(["view", str(folder / "room.toml"), "--cache", str(path), "--screenshot", str(shot), "-q"]) == 0
    image = _image(shot)
    assert image.shape[2] == 3 and image.std() > 5                # not blank
    bare = tmp_path / "bare.png"
    assert main(["view", str(folder / "room.toml"), "--screenshot", str(bare), "-q"]) == 0
    bare_image = _image(bare)
    for k in range(2):      # each level's colour appears with the records (the bare view's axes
        # widget has an orange and a green arrow)
        assert _level_pixels(image, k).sum() > 1000 + 5 * _level_pixels(bare_image, k).sum(), k
    only0 = tmp_path / "level0.png"
    assert main(["view", str(folder / "room.toml"), "--cache", str(path), "--levels", "0",
                 "--screenshot", str(only0), "-q"]) == 0
    assert _level_pixels(_image(only0), 1).sum() < _level_pixels(image, 1).sum() / 10


def test_cache_layer_from_a_live_cache_counts_what_it_draws(tmp_path, room_cache):
    _offscreen()
    from lbl_illum.engine.cache import IrradianceCache

    folder, scene, path, counts = room_cache
    layer = view3d.CacheLayer.from_cache(IrradianceCache.load(path))
    view3d.render(scene, [view3d.GeometryLayer(scene), layer], screenshot=tmp_path / "live.png",
                  window_size=(320, 240), cut_ceiling=False)
    assert (tmp_path / "live.png").stat().st_size > 0
    assert [layer.drawn[k] for k in range(len(counts))] == counts      # all inside the room


def test_view_refuses_a_file_that_is_not_a_cache(tmp_path, room_cache, capsys):
    from lbl_illum.cli.main import main

    folder = room_cache[0]
    bogus = tmp_path / "records.npz"
    np.savez(bogus, P=np.zeros((3, 3)))
    shot = tmp_path / "x.png"
    for bad, expect in ((bogus, "not an lbl_illum cache file"), (folder / "room.toml", "not an lbl_illum cache"),
                        (tmp_path / "none.cache", "no such cache file")):
        assert main(["view", str(folder / "room.toml"), "--cache", str(bad), "--screenshot", str(shot)]) == 2
        err = capsys.readouterr().err.strip()
        assert expect in err and len(err.splitlines()) == 1, err
    assert main(["view", str(folder / "room.toml"), "--cache", str(room_cache[2]), "--levels", "7",
                 "--screenshot", str(shot)]) == 2
    assert "no level 7" in capsys.readouterr().err
    assert main(["view", str(folder / "room.toml"), "--levels", "0", "--screenshot", str(shot)]) == 2
    assert "--cache" in capsys.readouterr().err
    assert not shot.exists()

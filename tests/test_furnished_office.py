"""The furnished office generator (examples/furnished_office/make_furnished_office.py).

A ~2,000-triangle version is generated once into a temporary folder, loaded with
``load_scene`` and computed against the bare office (examples/office) at the same sensors
and settings.  The physics checks rest on one fact: the furniture only adds opaque
surfaces inside the room, so the sky seen through the window can only be hidden, never
added, and where a chair back hides the whole window the sky component is exactly zero.
"""

from __future__ import annotations

import importlib.util
import sys

import numpy as np
import pytest

from lbl_illum import Options, compute_illuminance, load_scene, read_points

from conftest import EXAMPLES

GENERATOR = EXAMPLES / "furnished_office" / "make_furnished_office.py"
REQUEST = 2_000
#: quick settings shared by both scenes (same seed, same points)
QUICK = dict(accuracy=0.2, samples=256)
#: sky component (bounces = 0) of the furnished room over the bare room's, largest allowed:
#: 1 plus the sampling noise of 256-sample records at a = 0.2 (measured ≤ 1.063 over two seeds)
SKY_RATIO_MAX = 1.10
#: mean over the grid of furnished / bare illuminance with two bounces: measured 0.89
MEAN_RATIO_MAX = 0.95


@pytest.fixture(scope="module")
def gen():
    spec = importlib.util.spec_from_file_location("make_furnished_office", GENERATOR)
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module          # dataclasses look their module up
    spec.loader.exec_module(module)
    yield module
    sys.modules.pop(spec.name, None)


@pytest.fixture(scope="module")
def built(gen, tmp_path_factory):
    out = tmp_path_factory.mktemp("furnished_office")
    summary = gen.write(out, REQUEST)
    scene = load_scene(out / "scene.toml")
    points, normals = read_points(out / "grid.pts", scene.unit_scale)
    return out, summary, scene, points, normals


@pytest.fixture(scope="module")
def bare():
    scene = load_scene(EXAMPLES / "office" / "scene.toml")
    return scene


def _material_mask(scene, names):
    ids = [i for i, m in enumerate(scene.materials) if m.name in names]
    return np.isin(scene.triangles.material, ids)


def test_triangle_count_is_near_the_request_and_loads_whole(built):
    out, summary, scene, _, _ = built
    assert abs(len(scene.triangles) / REQUEST - 1) <= 0.30
    assert len(scene.triangles) == summary["triangles"]       # nothing dropped as degenerate or duplicate
    assert scene.warnings == []
    assert sorted(p.name for p in out.glob("*.ply")) == sorted(f"{g}.ply" for g in summary["per_group"])


@pytest.mark.parametrize("request_", [1_000, 10_000, 100_000])
def test_other_sizes_are_within_30_percent(gen, request_):
    detail = gen.detail_for(request_)
    total = sum(len(t) for t in gen.build_groups(detail).values())
    assert abs(total / request_ - 1) <= 0.30


def test_generation_is_deterministic(gen, built, tmp_path):
    out, _, _, _, _ = built
    gen.write(tmp_path, REQUEST)
    for path in out.iterdir():
        assert (tmp_path / path.name).read_bytes() == path.read_bytes(), path.name


def test_furniture_and_ceiling_lie_inside_the_room(gen, built):
    _, _, scene, _, _ = built
    inside = _material_mask(scene, {"desk", "chair", "shelf", "books", "ceiling"})
    corners = scene.triangles.vertices[inside].reshape(-1, 3)
    assert len(corners) > 0
    assert np.all(corners >= -1e-9) and np.all(corners <= np.array([gen.W, gen.D, gen.H]) + 1e-9)
    # the furniture stands on the floor and nothing of it is above the ceiling plane
    furniture = scene.triangles.vertices[_material_mask(scene, {"desk", "chair", "shelf"})].reshape(-1, 3)
    assert furniture[:, 2].min() == pytest.approx(0.0, abs=1e-12)


def test_sensors_are_the_office_grid_inside_the_room_and_outside_furniture(gen, built):
    _, _, _, points, normals = built
    office_points, _ = read_points(EXAMPLES / "office" / "grid.pts")
    np.testing.assert_array_equal(points, office_points)
    assert np.all((points > 0) & (points < np.array([gen.W, gen.D, gen.H])))
    assert not gen.sensors_in_furniture(points).any()
    np.testing.assert_array_equal(normals, np.tile([0.0, 0.0, 1.0], (len(points), 1)))


def _behind_chair_backs(gen, points):
    """Sensors from which a chair back hides the whole window, by projection: the window
    is a convex rectangle, so it is hidden when its four corners, projected from the
    sensor onto the plane of the back's front face, fall inside the back's rectangle."""
    o = gen.office
    window = np.array([(x, 0.0, z) for x in (o.WIN_X0, o.WIN_X1) for z in (o.WIN_Z0, o.WIN_Z1)])
    bw, by0, _, bz0, bz1 = gen.CHAIR_BACK
    hidden = np.zeros(len(points), dtype=bool)
    for cx, cy in gen.DESK_CENTRES:
        plane_y = cy + gen.CHAIR_OFFSET + by0
        for i, p in enumerate(points):
            if p[1] <= plane_y:
                continue
            s = (p[1] - plane_y) / (p[1] - window[:, 1])       # fraction of the way to each corner
            hit = p + s[:, None] * (window - p)
            hidden[i] |= bool(np.all((np.abs(hit[:, 0] - cx) < bw / 2) & (hit[:, 2] > bz0) & (hit[:, 2] < bz1)))
    return hidden


def test_furniture_only_hides_sky_and_chair_backs_hide_it_all(gen, built, bare):
    _, _, scene, points, normals = built
    opts = Options(bounces=0, **QUICK)          # light straight from the sky through the window
    furnished = compute_illuminance(scene, points, normals, opts).illuminance
    empty = compute_illuminance(bare, points, normals, opts).illuminance
    hidden = _behind_chair_backs(gen, points)
    assert hidden.sum() == 4                    # one sensor behind each chair
    assert np.all(empty[hidden] > 30.0)          # the bare room sees the sky there (38-180 lux)
    assert np.all(furnished[hidden] == 0.0)
    assert np.all(np.isfinite(furnished)) and np.all(furnished[~hidden] > 0)
    assert np.all(furnished <= SKY_RATIO_MAX * empty)


def test_interreflected_illuminance_is_lower_on_average(built, bare):
    _, _, scene, points, normals = built
    opts = Options(bounces=2, **QUICK)
    furnished = compute_illuminance(scene, points, normals, opts).illuminance
    empty = compute_illuminance(bare, points, normals, opts).illuminance
    assert np.all(np.isfinite(furnished)) and np.all(furnished > 0)
    assert np.mean(furnished / empty) < MEAN_RATIO_MAX

"""Luminous openings of luminaires: near-field direct light per sensor against closed-form
configuration factors, the opening seen in images and in a mirror, and no double counting.

References (independent of the engine's cells):
* A Lambertian opening of uniform luminance L (an IES file written from I(γ) = L A_p(γ))
  gives E = π L F, F the configuration factor from the sensor to the opening: for a
  parallel rectangle by corner superposition of Howell's catalogue B-3 (differential
  planar element to a parallel rectangle, normal through a corner), for a parallel disk
  Howell's B-13 (element displaced from the disk's axis),
  F = ½ [1 − (h² + a² − r²) / √((h² + a² + r²)² − 4 a² r²)].
  A box's or a cylinder's bottom face is the only face a sensor under its footprint sees.
* A camera ray meeting an opening sees L(−d) = I(−d)/A_p(−d), a mirror of reflectance ρ
  shows ρ times it.
Tolerances: 1 % per sensor and per pixel (the tables' bilinear interpolation is below
0.3 %; the cells' midpoint error below 0.7 %, module lbl_illum.engine.luminous_openings).
"""

import math

import numpy as np
import pytest

from lbl_illum import Options, compute_illuminance
from lbl_illum.engine.luminous_openings import NEAR_RATIO, cell_counts, opening_cells
from lbl_illum.engine.render import render_image
from lbl_illum.scene import scene_from_dict
from lbl_illum.scene.photometric import LuminousOpening
from lbl_illum.scene.views import View

from conftest import ies_text

DIRECT_ONLY = Options(bounces=0)
LUMINANCE = 1000.0          # [cd/m²]
FLOOR = {"shape": "rectangle", "origin": [-50, -50, 0], "u": [100, 0, 0], "v": [0, 100, 0], "material": "black"}
BLACK = {"black": {"type": "diffuse", "reflectance": 0.0}}


def corner_factor(X, Y, h):
    """Howell B-3: from a point at distance h below a corner of a parallel rectangle X × Y
    (signed sides: the factor is odd in each)."""
    a, b = np.abs(X) / h, np.abs(Y) / h
    f = (a / np.sqrt(1 + a * a) * np.arctan(b / np.sqrt(1 + a * a))
         + b / np.sqrt(1 + b * b) * np.arctan(a / np.sqrt(1 + b * b))) / (2 * np.pi)
    return np.sign(X) * np.sign(Y) * f


def rectangle_factor(x, y, h, length, width):
    """F from floor points (x, y) to the rectangle |X| ≤ length/2, |Y| ≤ width/2 at height h."""
    def c(X, Y):
        return corner_factor(X, Y, h)
    lx, ly = length / 2, width / 2
    return c(lx - x, ly - y) - c(-lx - x, ly - y) - c(lx - x, -ly - y) + c(-lx - x, -ly - y)


def disk_factor(a, h, r):
    """Howell B-13: F from a point at distance h below the plane of a parallel disk of
    radius r, displaced a from its axis."""
    return 0.5 * (1 - (h * h + a * a - r * r) / np.sqrt((h * h + a * a + r * r) ** 2 - 4 * a * a * r * r))


def lambertian(opening):
    """I(γ, C) [cd] = L · A_p of ``opening`` along the emission direction (γ from the nadir)."""
    def fn(gamma, c):
        g, cc = np.radians(gamma), np.radians(c)
        e = np.stack([np.sin(g) * np.cos(cc), np.sin(g) * np.sin(cc), -np.cos(g)], axis=-1)
        return LUMINANCE * opening.projected_area(e.reshape(-1, 3)).reshape(np.shape(g))
    return fn


def asymmetric(gamma, c):
    """An asymmetric distribution [cd] with light in every direction."""
    g, cc = np.radians(gamma), np.radians(c)
    return 1000.0 * (1.1 + np.cos(g)) * (1.0 + 0.5 * np.cos(cc) + 0.3 * np.sin(2 * cc)) / 2.1


def file_dims(opening):
    """IES (width, length, height) of an opening: round ones as negative diameters."""
    if opening.shape in ("disk", "cylinder"):
        return (-opening.length, -opening.length, opening.height)
    return (opening.width, opening.length, opening.height)


def write_file(tmp_path, opening, fn, name="lum.ies", horizontal=np.array([0.0, 90.0]),
               vertical=np.arange(0, 180.1, 1.0)):
    (tmp_path / name).write_text(ies_text(fn, horizontal, vertical, dims=file_dims(opening)))
    return name


def scene_of(tmp_path, luminaires, geometry=(FLOOR,), materials=BLACK):
    data = {"units": "m", "geometry": list(geometry), "materials": dict(materials), "sky": {"type": "none"},
            "luminaires": list(luminaires)}
    return scene_from_dict(data, tmp_path, "test.toml")


def floor_grid(half, n=15):
    g = np.linspace(-half, half, n)
    X, Y = np.meshgrid(g, g)
    return np.column_stack([X.ravel(), Y.ravel(), np.zeros(X.size)]), np.tile([0, 0, 1.0], (X.size, 1))


@pytest.mark.parametrize("h,rotation", [(0.6, 0.0), (0.6, 90.0), (1.2, 0.0), (3.0, 0.0), (8.0, 0.0)])
def test_rectangle_every_floor_sensor_against_the_configuration_factor(tmp_path, h, rotation):
    """A 0.6 m × 0.4 m Lambertian opening (length along C0) at h = one length to 13 lengths
    above the floor, aimed down and turned by ``rotation``: every sensor within ±2.5 h is
    within 1 % of π L F.  Near, the point law misses by more than 5 %."""
    opening = LuminousOpening("rectangle", 0.6, 0.4)
    name = write_file(tmp_path, opening, lambertian(opening))
    scene = scene_of(tmp_path, [{"file": name, "position": [0.2, -0.1, h], "rotation": rotation}])
    assert scene.luminaires[0].photometry.opening == opening
    pts, nrm = floor_grid(2.5 * h)
    pts[:, :2] += [0.2, -0.1]
    E = compute_illuminance(scene, pts, nrm, DIRECT_ONLY).illuminance
    x, y = pts[:, 0] - 0.2, pts[:, 1] + 0.1
    if rotation:
        x, y = y, -x                        # the opening's length lies along +y
    ref = math.pi * LUMINANCE * rectangle_factor(x, y, h, 0.6, 0.4)
    assert np.abs(E / ref - 1).max() < 0.01
    d2 = x * x + y * y + h * h
    point = LUMINANCE * 0.24 * h ** 2 / d2 ** 2          # I(γ) cos θ / d², cos γ = cos θ = h/d
    if h < 1.0:
        assert np.abs(point / ref - 1).max() > 0.05


@pytest.mark.parametrize("h", [0.6, 1.5, 6.0])
def test_disk_every_floor_sensor_on_and_off_its_axis(tmp_path, h):
    """A Lambertian disk of diameter 0.6 m: every floor sensor within ±2.5 h (on and off
    the axis) within 1 % of π L F (Howell B-13)."""
    opening = LuminousOpening("disk", 0.6, 0.6)
    name = write_file(tmp_path, opening, lambertian(opening), horizontal=np.array([0.0]))
    scene = scene_of(tmp_path, [{"file": name, "position": [0.0, 0.0, h]}])
    assert scene.luminaires[0].photometry.opening == opening
    pts, nrm = floor_grid(2.5 * h)
    E = compute_illuminance(scene, pts, nrm, DIRECT_ONLY).illuminance
    ref = math.pi * LUMINANCE * disk_factor(np.hypot(pts[:, 0], pts[:, 1]), h, 0.3)
    assert np.abs(E / ref - 1).max() < 0.01


@pytest.mark.parametrize("opening", [LuminousOpening("box", 0.6, 0.4, 0.3), LuminousOpening("cylinder", 0.5, 0.5, 0.4)])
@pytest.mark.parametrize("h", [0.8, 3.0, 20.0])
def test_box_and_cylinder_light_from_their_bottom_face(tmp_path, opening, h):
    """Lambertian solids: a sensor under the footprint sees the bottom face only, at
    h − H/2, so E = π L F of that face; within 1 % at every such sensor, up to 20 m
    (33 sizes: the point at the centre would be 1.5 % low there, ~H/h)."""
    name = write_file(tmp_path, opening, lambertian(opening), horizontal=np.arange(0, 90.1, 2.5))
    scene = scene_of(tmp_path, [{"file": name, "position": [0.0, 0.0, h]}])
    g = np.linspace(-0.9, 0.9, 7)
    X, Y = np.meshgrid(g * opening.length / 2, g * opening.width / 2)
    pts = np.column_stack([X.ravel(), Y.ravel(), np.zeros(X.size)])
    if opening.shape == "cylinder":
        pts = pts[np.hypot(pts[:, 0], pts[:, 1]) < 0.9 * opening.length / 2]
    nrm = np.tile([0, 0, 1.0], (len(pts), 1))
    E = compute_illuminance(scene, pts, nrm, DIRECT_ONLY).illuminance
    z = h - opening.height / 2
    if opening.shape == "box":
        F = rectangle_factor(pts[:, 0], pts[:, 1], z, opening.length, opening.width)
    else:
        F = disk_factor(np.hypot(pts[:, 0], pts[:, 1]), z, opening.length / 2)
    assert np.abs(E / (math.pi * LUMINANCE * F) - 1).max() < 0.01


@pytest.mark.parametrize("opening", [LuminousOpening("rectangle", 0.6, 0.4), LuminousOpening("disk", 0.5, 0.5),
                                     LuminousOpening("box", 0.6, 0.4, 0.3),
                                     LuminousOpening("cylinder", 0.5, 0.5, 0.4)])
@pytest.mark.parametrize("k", [1, 3, 8, 12])
def test_the_cells_show_the_openings_projected_area(opening, k):
    """Σ_j a_j(ω) = A_p(ω) in every direction (so the cells together give I(ω)), and the
    cells cover the opening's area."""
    cells = opening_cells(opening, k)
    e = np.random.default_rng(k).normal(size=(500, 3))
    e /= np.linalg.norm(e, axis=1, keepdims=True)
    m = len(cells)
    a = cells.projected(np.tile(np.arange(m), len(e)), np.repeat(e, m, axis=0)).reshape(len(e), m)
    np.testing.assert_allclose(a.sum(axis=1), opening.projected_area(e), rtol=1e-12, atol=1e-15)
    area = {"rectangle": 0.24, "disk": math.pi * 0.0625, "box": 2 * (0.24 + 0.18 + 0.12),
            "cylinder": math.pi * 0.5 * 0.4 + 2 * math.pi * 0.0625}[opening.shape]
    assert cells.areas.sum() == pytest.approx(area, rel=1e-12)
    s = cells.shares(opening, np.tile(np.arange(m), len(e)), np.repeat(e, m, axis=0)).reshape(len(e), m)
    np.testing.assert_allclose(s.sum(axis=1), 1.0, rtol=1e-12)


def test_far_sensors_get_the_point_source_bit_for_bit(tmp_path):
    """Beyond NEAR_RATIO sizes a flat opening is today's point source: the same file with a
    point opening gives exactly the same illuminance; nearer sensors differ."""
    opening = LuminousOpening("rectangle", 0.3, 0.2)
    write_file(tmp_path, opening, asymmetric, "rect.ies", np.arange(0, 360.1, 5), np.arange(0, 180.1, 2.5))
    (tmp_path / "point.ies").write_text(ies_text(asymmetric, np.arange(0, 360.1, 5)))
    pts, nrm = floor_grid(6.0, 13)
    pts[:, 2] = -0.2
    entry = {"position": [0.1, 0.0, 2.2], "aim": [0.3, 0.1, -1.0], "rotation": 20.0}
    E_rect = compute_illuminance(scene_of(tmp_path, [dict(entry, file="rect.ies")]), pts, nrm, DIRECT_ONLY).illuminance
    E_point = compute_illuminance(scene_of(tmp_path, [dict(entry, file="point.ies")]), pts, nrm, DIRECT_ONLY).illuminance
    assert np.array_equal(E_rect, E_point)
    near = [0.1, 0.0, 2.2 - NEAR_RATIO * 0.3 + 0.5]
    E = [compute_illuminance(scene_of(tmp_path, [dict(entry, file=f)]), np.array([near]), nrm[:1],
                             DIRECT_ONLY).illuminance[0] for f in ("rect.ies", "point.ies")]
    assert E[0] != E[1]


def test_cell_counts_follow_the_distance_to_the_opening():
    op = LuminousOpening("rectangle", 0.6, 0.4)
    local = np.array([[0, 0, -0.6], [0, 0, -1.2], [0, 0, -4.7], [0, 0, -4.9], [0.5, 0, 0], [0.1, 0.1, 0.0]])
    assert cell_counts(op, local).tolist() == [8, 4, 2, 0, 12, 12]
    assert cell_counts(LuminousOpening("box", 0.6, 0.4, 0.3), np.array([[0, 0, -30.0], [0, 0, -61.0]])).tolist() == [1, 0]
    assert not cell_counts(LuminousOpening("sphere", 0.5, 0.5, 0.5), local).any()


def test_openings_block_nothing_and_hemisphere_rays_do_not_count_them(tmp_path):
    """A point luminaire 1 m above a 1 m × 1 m Lambertian opening: floor sensors get both
    (the opening blocks no shadow ray), and with a bounce over a black floor the indirect
    part is 0 (hemisphere rays that meet the opening add nothing: the direct step counted it)."""
    opening = LuminousOpening("rectangle", 1.0, 1.0)
    name = write_file(tmp_path, opening, lambertian(opening))
    lines = ["IESNA:LM-63-2002", "TILT=NONE", "1 -1 1 2 1 1 2 0 0 0", "1 1 10", "0 180", "0", "500 500"]
    (tmp_path / "iso.ies").write_text("\n".join(lines) + "\n")
    scene = scene_of(tmp_path, [{"file": name, "position": [0, 0, 1.0]}, {"file": "iso.ies", "position": [0, 0, 2.0]}])
    pts, nrm = floor_grid(2.0, 9)
    result = compute_illuminance(scene, pts, nrm, Options(bounces=1, samples=256, accuracy=0.1))
    d2 = np.sum((pts - [0, 0, 2.0]) ** 2, axis=1)
    ref = math.pi * LUMINANCE * rectangle_factor(pts[:, 0], pts[:, 1], 1.0, 1.0, 1.0) + 500 * 2.0 / d2 ** 1.5
    assert np.abs(result.illuminance / ref - 1).max() < 0.01
    assert np.all(result.indirect == 0.0)


def pixel_corner_rays(view, width, height):
    """(height, width, 4) ray origins and directions through each pixel's corners."""
    col, row = np.meshgrid(np.arange(width), np.arange(height))
    xs = [(col + dx) / width for dx in (0, 1, 1, 0)]
    ys = [(height - row - dy) / height for dy in (0, 0, 1, 1)]
    o, d, _ = view.image_rays(np.stack(xs, -1).ravel(), np.stack(ys, -1).ravel())
    return o.reshape(height, width, 4, 3), d.reshape(height, width, 4, 3)


def plane_hit(o, d, z):
    """(…, 2) x, y where rays cross the plane at height z."""
    t = (z - o[..., 2]) / d[..., 2]
    return (o + t[..., None] * d)[..., :2], t


def emitted(e):
    """I(−d)/A_p of the asymmetric file's 0.6 m × 0.4 m rectangle, e the emission direction."""
    gamma = np.degrees(np.arccos(np.clip(-e[..., 2], -1, 1)))
    c = np.degrees(np.arctan2(e[..., 1], e[..., 0])) % 360
    return asymmetric(gamma, c) / (0.24 * np.abs(e[..., 2]))


def test_image_of_an_opening_shows_I_over_projected_area(tmp_path):
    """A camera below and beside a 0.6 m × 0.4 m opening of the asymmetric distribution
    looks up at it: every pixel wholly inside its image shows I(γ, C)/(A cos γ) at the
    pixel's centre within 1 %, every pixel wholly outside 0 (nothing else is seen)."""
    opening = LuminousOpening("rectangle", 0.6, 0.4)
    write_file(tmp_path, opening, asymmetric, "lum.ies", np.arange(0, 360.1, 5), np.arange(0, 180.1, 2.5))
    scene = scene_of(tmp_path, [{"file": "lum.ies", "position": [0.0, 0.0, 2.5]}])
    view = View("v", (0.9, -0.6, 0.5), (-0.9, 0.6, 2.0), (0, 0, 1), 14.0, 14.0)
    w = h = 40
    image = render_image(scene, view, w, h, Options(bounces=0), pixel_samples=2).luminance
    o, d = pixel_corner_rays(view, w, h)
    xy, _ = plane_hit(o, d, 2.5)
    inside = (np.abs(xy[..., 0]) < 0.3) & (np.abs(xy[..., 1]) < 0.2)
    full, empty = inside.all(axis=2), ~inside.any(axis=2)
    assert full.sum() > 200 and empty.sum() > 200
    oc, dc = pixel_corner_rays(view, w, h)
    centre = dc.mean(axis=2)
    centre /= np.linalg.norm(centre, axis=-1, keepdims=True)
    ref = emitted(-centre)
    assert np.abs(image[full] / ref[full] - 1).max() < 0.01
    assert np.all(image[empty] == 0.0)


def test_mirror_floor_shows_the_opening_times_its_reflectance(tmp_path):
    """A mirror floor (ρ = 0.8) under the opening: a camera at 1.5 m looking down at the
    floor sees the opening's reflection, ρ I(e)/(A |cos γ|) with e the emission direction
    toward the mirror, within 1 % in every pixel wholly inside it."""
    opening = LuminousOpening("rectangle", 0.6, 0.4)
    write_file(tmp_path, opening, asymmetric, "lum.ies", np.arange(0, 360.1, 5), np.arange(0, 180.1, 2.5))
    mirror = dict(FLOOR, material="mirror")
    scene = scene_of(tmp_path, [{"file": "lum.ies", "position": [0.0, 0.0, 2.5]}], geometry=[mirror],
                     materials={"mirror": {"type": "mirror", "reflectance": 0.8}})
    view = View("v", (1.2, 0.3, 1.5), (-1.2, -0.3, -4.0), (0, 1, 0), 12.0, 12.0)
    w = h = 40
    image = render_image(scene, view, w, h, Options(bounces=0), pixel_samples=2).luminance
    o, d = pixel_corner_rays(view, w, h)
    # the reflection: rays mirrored about z = 0 from the image point, i.e. d_z → −d_z at the floor
    xy0, t0 = plane_hit(o, d, 0.0)
    d_ref = d * [1, 1, -1]
    start = np.concatenate([xy0, np.zeros(xy0.shape[:-1] + (1,))], axis=-1)
    xy, _ = plane_hit(start, d_ref, 2.5)
    inside = (t0 > 0) & (np.abs(xy[..., 0]) < 0.3) & (np.abs(xy[..., 1]) < 0.2)
    full, empty = inside.all(axis=2), ~inside.any(axis=2)
    assert full.sum() > 100 and empty.sum() > 100
    centre = d.mean(axis=2) * [1, 1, -1]
    centre /= np.linalg.norm(centre, axis=-1, keepdims=True)
    ref = 0.8 * emitted(-centre)
    assert np.abs(image[full] / ref[full] - 1).max() < 0.01
    assert np.all(image[empty] == 0.0)


def test_hemisphere_rays_see_the_opening_in_a_mirror(tmp_path):
    """Sensors facing down at the opening's height, beside it, over a mirror floor (ρ = 0.9):
    no direct light (the opening is edge-on), and the hemisphere rays see its image in the
    mirror, a parallel rectangle 2 h below: E = ρ π L F (Howell B-3).  Each sensor's own
    16,384 stratified rays: within 3 % (the rays that straddle the image's edge)."""
    opening = LuminousOpening("rectangle", 1.0, 1.0)
    name = write_file(tmp_path, opening, lambertian(opening))
    mirror = dict(FLOOR, material="mirror")
    scene = scene_of(tmp_path, [{"file": name, "position": [0, 0, 1.0]}], geometry=[mirror],
                     materials={"mirror": {"type": "mirror", "reflectance": 0.9}})
    x = np.array([0.8, 1.0, 1.5, 2.0])
    pts = np.column_stack([x, 0.3 * x, np.full(len(x), 1.0)])
    nrm = np.tile([0, 0, -1.0], (len(x), 1))
    result = compute_illuminance(scene, pts, nrm, Options(bounces=1, samples=256, point_samples=16384))
    assert np.all(result.direct == 0.0)
    ref = 0.9 * math.pi * LUMINANCE * rectangle_factor(pts[:, 0], pts[:, 1], 2.0, 1.0, 1.0)
    assert np.abs(result.illuminance / ref - 1).max() < 0.03

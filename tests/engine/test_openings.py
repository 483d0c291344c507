"""Openings found in the geometry and the portal set (lbl_illum.engine.openings, lbl_illum.engine.portals)."""

from __future__ import annotations

import numpy as np
import pytest

from lbl_illum.engine.context import LightingContext
from lbl_illum.engine.integrator import Integrator, RunPlan, RunStats
from lbl_illum.scene.materials import GLASS
from lbl_illum.engine.openings import find_openings
from lbl_illum.options import Options
from lbl_illum.engine.raycast import Tracer
from lbl_illum.scene.scenefile import scene_from_dict


def rect(origin, u, v, material):
    return {"shape": "rectangle", "origin": list(origin), "u": list(u), "v": list(v), "material": material}


def box_room(x0=0.0, width=4.0, depth=6.0, height=3.0, south=True):
    """The floor, ceiling, and east, west and north walls of a room at x0 .. x0 + width,
    y 0 .. depth; the south wall (y = 0) is left to the caller when ``south`` is false."""
    w = [rect([x0, 0, 0], [width, 0, 0], [0, depth, 0], "wall"), rect([x0, 0, height], [width, 0, 0], [0, depth, 0], "wall"),
         rect([x0, depth, 0], [width, 0, 0], [0, 0, height], "wall"), rect([x0, 0, 0], [0, depth, 0], [0, 0, height], "wall"),
         rect([x0 + width, 0, 0], [0, depth, 0], [0, 0, height], "wall")]
    if south:
        w.append(rect([x0, 0, 0], [width, 0, 0], [0, 0, height], "wall"))
    return w


def wall_with_hole(y, x0=0.0, width=4.0, height=3.0, hole=(1.0, 3.0, 1.0, 2.0)):
    """A wall in the plane y with a rectangular hole (x0 + a .. x0 + b, z c .. d), made of the
    four rectangles around the hole, as modellers build it."""
    a, b, c, d = hole
    return [rect([x0, y, 0], [width, 0, 0], [0, 0, c], "wall"), rect([x0, y, d], [width, 0, 0], [0, 0, height - d], "wall"),
            rect([x0, y, c], [a, 0, 0], [0, 0, d - c], "wall"), rect([x0 + b, y, c], [width - b, 0, 0], [0, 0, d - c], "wall")]


def scene_of(geometry, glass=None, **extra):
    materials = {"wall": {"type": "diffuse", "reflectance": 0.5}}
    if glass is not None:
        materials["pane"] = {"type": "glass", "transmittance": 0.7, **glass}
    data = {"geometry": geometry, "materials": materials,
            "sky": {"type": "cie-overcast", "horizontal_illuminance": 10000}, **extra}
    return scene_from_dict(data, ".", "test.toml")


def openings_of(scene):
    mt = scene.material_table
    tracer = Tracer(scene.triangles, mt.kind, mt.transmittance)
    return find_openings(scene.triangles.vertices, mt.kind[scene.triangles.material] == GLASS, tracer)


PANE = {"shape": "polygon", "material": "pane", "vertices": [[1, 0, 1], [3, 0, 1], [3, 0, 2], [1, 0, 2]]}


def test_a_hole_in_a_wall_is_an_opening_facing_out():
    (found,) = openings_of(scene_of(box_room(south=False) + wall_with_hole(0.0)))
    assert found.area == pytest.approx(2.0)
    assert np.allclose(found.normal, [0, -1, 0])
    assert found.centre[1] == pytest.approx(0.0) and 1 < found.centre[0] < 3 and 1 < found.centre[2] < 2
    assert found.describe().startswith("2.00 m² at (") and found.describe().endswith("facing south")


def test_a_keyhole_wall_and_a_roof_opening():
    outline = [[0, 0, 0], [4, 0, 0], [4, 0, 3], [0, 0, 3], [0, 0, 0]]
    hole = [[1, 0, 1], [1, 0, 2], [3, 0, 2], [3, 0, 1], [1, 0, 1]]
    keyhole = {"shape": "polygon", "material": "wall", "vertices": outline + hole}
    roof = [rect([0, 0, 3], [4, 0, 0], [0, 2, 0], "wall"), rect([0, 3, 3], [4, 0, 0], [0, 3, 0], "wall"),
            rect([0, 2, 3], [1, 0, 0], [0, 1, 0], "wall"), rect([2, 2, 3], [2, 0, 0], [0, 1, 0], "wall")]
    room = [w for w in box_room(south=False) if w["origin"][2] != 3 or w["u"][0] != 4 or w["v"][1] != 6]
    found = sorted(openings_of(scene_of(room + [keyhole] + roof)), key=lambda o: o.area)
    assert [round(o.area, 6) for o in found] == [1.0, 2.0]
    assert np.allclose(found[0].normal, [0, 0, 1]) and found[0].describe().endswith("a roof opening")
    assert np.allclose(found[1].normal, [0, -1, 0])


def test_a_search_made_before_is_read_back_with_the_random_state_it_left(tmp_path, monkeypatch):
    """The second search of the same triangles comes from the cache folder: the same openings
    and the random generator in the state a search leaves it in; other triangles, or no
    cache folder, are searched."""
    from lbl_illum.engine import openings

    monkeypatch.setenv("LBL_ILLUM_CACHE_DIR", str(tmp_path))
    scene = scene_of(box_room(south=False) + wall_with_hole(0.0, hole=(0.5, 2.5, 0.8, 2.2)))
    mt = scene.material_table
    tracer = Tracer(scene.triangles, mt.kind, mt.transmittance)
    glass = mt.kind[scene.triangles.material] == GLASS
    searches = []
    search = openings._search
    monkeypatch.setattr(openings, "_search", lambda *a: searches.append(1) or search(*a))

    def run(vertices):
        rng = np.random.default_rng(7)
        found = find_openings(vertices, glass, tracer, rng)
        return found, rng.random(4)

    first, after_first = run(scene.triangles.vertices)
    second, after_second = run(scene.triangles.vertices)
    assert len(searches) == 1 and len(first) == 1 and first[0].area == pytest.approx(2.8)
    np.testing.assert_array_equal(after_first, after_second)
    for a, b in zip(first, second):
        for name in ("triangles", "area", "normal", "centre", "sky_fraction"):
            np.testing.assert_array_equal(getattr(a, name), getattr(b, name))
    run(scene.triangles.vertices + [0.0, 0.0, 1e-9])
    assert len(searches) == 2
    monkeypatch.setenv("LBL_ILLUM_CACHE_DIR", "off")
    _, after_off = run(scene.triangles.vertices)
    assert len(searches) == 3
    np.testing.assert_array_equal(after_off, after_first)


def test_glazed_holes_and_interior_doorways_are_no_openings():
    glazed = box_room(south=False) + wall_with_hole(0.0) + [PANE]
    assert openings_of(scene_of(glazed, glass={})) == []
    # a pane set 5 cm behind the hole of the outer face of a thick wall
    recessed = dict(PANE, vertices=[[x, 0.05, z] for x, _, z in PANE["vertices"]])
    thick = box_room(south=False) + wall_with_hole(0.0) + [recessed]
    assert openings_of(scene_of(thick, glass={})) == []
    # two closed rooms joined by a doorway in the wall between them
    two = box_room(x0=0.0, depth=6) + [rect([0, 6, 0], [4, 0, 0], [0, 6, 0], "wall"), rect([0, 6, 3], [4, 0, 0], [0, 6, 0], "wall"),
                                        rect([0, 12, 0], [4, 0, 0], [0, 0, 3], "wall"), rect([0, 6, 0], [0, 6, 0], [0, 0, 3], "wall"),
                                        rect([4, 6, 0], [0, 6, 0], [0, 0, 3], "wall")]
    two = [w for w in two if not (w["origin"][1] == 6 and w["v"] == [0, 0, 3] and w["u"] == [4, 0, 0])]
    two += wall_with_hole(6.0)
    assert openings_of(scene_of(two)) == []


def test_portals_found_glass_checked_and_who_samples_them():
    # the found opening becomes a portal; interior glass between two rooms is no portal
    scene = scene_of(box_room(south=False) + wall_with_hole(0.0), glass={})
    integ = Integrator(scene, Options())
    ps = integ.portal_set
    assert len(ps.openings) == 1 and len(ps) == 2 and np.all(ps.prim == -1)
    assert np.allclose(ps.outward, [0, -1, 0])
    assert ps.inside(np.array([[2.0, 3.0, 1.0], [2.0, -3.0, 1.0]])).tolist() == [True, False]
    interior = box_room() + [rect([0, 6, 0], [4, 0, 0], [0, 6, 0], "wall"), rect([0, 6, 3], [4, 0, 0], [0, 6, 0], "wall"),
                             rect([0, 12, 0], [4, 0, 0], [0, 0, 3], "wall"), rect([0, 6, 0], [0, 6, 0], [0, 0, 3], "wall"),
                             rect([4, 6, 0], [0, 6, 0], [0, 0, 3], "wall"),
                             dict(PANE, vertices=[[1, 6, 1], [3, 6, 1], [3, 6, 2], [1, 6, 2]])]
    interior = [w for w in interior if not (w.get("origin") == [0, 6, 0] and w.get("u") == [4, 0, 0]
                                            and w.get("v") == [0, 0, 3])] + wall_with_hole(6.0)
    auto = Integrator(scene_of(interior, glass={}), Options()).portal_set
    assert auto is None                                      # no sky behind the pane: not sampled
    forced = Integrator(scene_of(interior, glass={"portal": True}), Options()).portal_set
    assert forced is not None and len(forced) == 2           # portal = true keeps it
    off = Integrator(scene_of(box_room(south=False) + wall_with_hole(0.0), find_openings=False), Options()).portal_set
    assert off is None


def test_an_opening_found_gives_what_a_drawn_portal_gives():
    """The sky seen by sensors behind a hole, pure Monte Carlo: with the opening found, with it drawn as
    [[portals]], and with neither; the first two agree within their noise and both are far
    less noisy than plain hemisphere sampling."""
    geometry = box_room(south=False, depth=8) + wall_with_hole(0.0)
    P = np.array([[x, y, 0.8] for x in (1.0, 2.0, 3.0) for y in (5.0, 7.0)])
    N = np.tile([0.0, 0, 1], (len(P), 1))
    drawn = [{"vertices": [[1, 0, 1], [3, 0, 1], [3, 0, 2], [1, 0, 2]]}]
    runs = {}
    for label, extra in (("found", {}), ("drawn", {"portals": drawn, "find_openings": False}),
                         ("none", {"find_openings": False})):
        scene = scene_of(geometry, **extra)
        runs[label] = np.array([Integrator(scene, Options(accuracy=0, samples=256, bounces=0, seed=s)).compute(P, N)
                                .illuminance for s in range(6)])
    mean = {k: r.mean(axis=0) for k, r in runs.items()}
    spread = {k: (r.std(axis=0, ddof=1) / r.mean(axis=0)).mean() for k, r in runs.items()}
    se = np.hypot(runs["found"].std(axis=0, ddof=1), runs["drawn"].std(axis=0, ddof=1)) / np.sqrt(6)
    assert np.all(np.abs(mean["found"] - mean["drawn"]) < 4 * se + 1e-3 * mean["drawn"])
    assert spread["found"] < spread["none"] / 20, spread          # measured: 0.65 % against 128 %


def test_zones_part_the_room_from_the_ground_around_it():
    """The office: the floor behind the window is zone 1; the ground in front of it and the
    ground behind the building (behind the window's plane, but outside the room the window
    sees) are zone 0."""
    from lbl_illum.scene.scenefile import load_scene
    from pathlib import Path

    root = Path(__file__).resolve().parents[2]
    scene = load_scene(root / "examples" / "office" / "scene.toml")
    ps = Integrator(scene, Options()).portal_set
    floor = np.array([[0.05, 0.02, 0.0], [2.0, 3.0, 0.0], [3.9, 5.9, 0.0], [2.0, 3.0, 2.99]])
    ground = np.array([[2.0, -0.5, 0.0], [2.0, -20.0, 0.0], [2.0, 9.0, 0.0], [30.0, 3.0, 0.0]])
    assert ps.zone(floor).tolist() == [1, 1, 1, 1]
    assert ps.zone(ground).tolist() == [0, 0, 0, 0]


def test_records_serve_only_queries_of_their_zone():
    from lbl_illum.engine.cache import LevelRecords

    lv = LevelRecords(0.2, np.zeros(3), 10.0)
    lv.add(np.array([[0.0, -0.3, 0.0], [0.0, 0.3, 0.0]]), np.array([[0, 0, 1.0]] * 2), np.array([5.0, 5.0]),
           E=np.array([[9000.0] * 3, [100.0] * 3]), zone=np.array([0, 1], np.uint8))
    q = np.array([[0.0, 0.1, 0.0], [0.0, -0.1, 0.0]])
    n = np.array([[0, 0, 1.0]] * 2)
    E, _, count = lv.lookup(q, n, zone=np.array([1, 0], np.uint8))
    assert count.tolist() == [1, 1] and E[:, 0].tolist() == [100.0, 9000.0]
    E, _, count = lv.lookup(q, n)                            # no zones given: zone 0 for all
    assert count.tolist() == [1, 1] and E[:, 0].tolist() == [9000.0, 9000.0]
    assert lv.covers(q, n, np.array([1, 1], np.uint8)).all()
    assert not LevelRecords(0.2, np.zeros(3), 10.0).covers(q, n).any()


def test_interreflected_estimate_of_a_closed_room():
    """The split-flux estimate behind the record sizes: Φ ρ / A over the inside surfaces,
    with Φ = π Σ L_k A_k through the portals."""
    scene = scene_of(box_room(south=False) + wall_with_hole(0.0))
    context = LightingContext.of(scene)
    P = np.array([[2.0, 3.0, 0.8]])
    luminance = context.portal_luminance((P[0], P[0]))
    A = 4 * 6 * 2 + 2 * 6 * 3 + 4 * 3 + 4 * 3 - 2.0                      # the room's surfaces, less the hole
    flux = np.pi * float((luminance * context.portals.area).sum())
    first, rho = context.inside_stats(luminance)
    assert rho == pytest.approx(0.5) and first == pytest.approx(flux * 0.5 / A, rel=1e-9)
    run = RunPlan(4, 0.1, 1.0, (P[0], P[0]), luminance, (first, rho), RunStats())
    assert run.interreflected(4) == 0.0                                  # the bounce limit: none to come
    assert run.interreflected(2) == pytest.approx(first * (1 + 0.5), rel=1e-12)

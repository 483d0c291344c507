"""Ray casting: no self-hits off surfaces at any scale or angle; glass along shadow rays."""

import numpy as np
import pytest

from lbl_illum.scene.geometry import Triangles, box_triangles
from lbl_illum.engine.hemisphere import stratified_directions
from lbl_illum.scene.materials import DIFFUSE, GLASS
from lbl_illum.engine.raycast import RayCaster, Tracer

KINDS = np.array([DIFFUSE, GLASS], np.int8)
TAU = np.array([[0, 0, 0], [0.7, 0.7, 0.7]], float)


def tilted_plane(center, size, normal):
    normal = np.asarray(normal, float) / np.linalg.norm(normal)
    u = np.cross(normal, [0.3, 0.5, 0.8])
    u /= np.linalg.norm(u)
    v = np.cross(normal, u)
    c = np.asarray(center, float)
    corners = [c + size * (-u - v), c + size * (u - v), c + size * (u + v), c + size * (-u + v)]
    verts = np.array([[corners[0], corners[1], corners[2]], [corners[0], corners[2], corners[3]]])
    return Triangles(verts, np.zeros(2, np.int32), np.full(2, -1, np.int32)), normal, u, v


@pytest.mark.parametrize("scale", [1e-4, 1.0, 1e4])
def test_rays_leaving_a_surface_never_hit_it_again(scale):
    tri, n, u, v = tilted_plane(np.array([3.0, -7.0, 11.0]) * scale, 5 * scale, [0.2, 0.3, 0.9])
    tracer = Tracer(tri, KINDS, TAU)
    rng = np.random.default_rng(0)
    s, t = rng.uniform(-4, 4, (2, 2000)) * scale
    points = tri.vertices[0, 0] * 0 + np.array([3.0, -7.0, 11.0]) * scale + s[:, None] * u + t[:, None] * v
    # hit the plane from above with random rays, then leave it from the hit points
    origins = points + n * scale
    hits = tracer.intersect(origins, np.tile(-n, (2000, 1)))
    assert hits.hit.all()
    P, Ng, Ns = tracer.surface(origins, np.tile(-n, (2000, 1)), hits)
    assert np.abs((P - points) @ n).max() < 1e-9 * scale
    d = stratified_directions(Ns, 4, 12, rng).reshape(-1, 3)       # includes near-grazing rays
    o = np.repeat(tracer.offset(P, Ng), 48, axis=0)
    assert not tracer.intersect(o, d).hit.any()


def test_shadow_ray_through_glass_and_blocked_by_opaque():
    glass = np.array([[[-1, -1, 1], [1, -1, 1], [1, 1, 1]], [[-1, -1, 1], [1, 1, 1], [-1, 1, 1]]], float)
    wall = glass + [0, 0, 2.0]
    tri = Triangles(np.concatenate([glass, glass + [0, 0, 0.5], wall]), np.array([1, 1, 1, 1, 0, 0], np.int32),
                    np.full(6, -1, np.int32))
    tracer = Tracer(tri, KINDS, TAU)
    o = np.zeros((2, 3))
    d = np.array([[0, 0, 1.0], [0, 0, 1.0]])
    T = tracer.transmittance(o, d, np.array([2.0, 10.0]))
    assert np.allclose(T[0], 0.49)          # two panes before the wall at z = 3
    assert np.allclose(T[1], 0.0)           # the wall blocks the longer segment


def _rotation(seed):
    q, _ = np.linalg.qr(np.random.default_rng(seed).normal(size=(3, 3)))
    return q * np.sign(np.linalg.det(q))


def test_sensor_facing_a_surface_closer_than_the_offset_starts_its_rays_in_front_of_it():
    """A 200 m wall makes ε ≈ 3 mm: the plain offset of a sensor 1 mm in front of it,
    facing it, lands behind the wall; the sensor's origin must stay in front."""
    wall = np.array([[[-100, 0, 0], [100, 0, 0], [100, 0, 100]], [[-100, 0, 0], [100, 0, 100], [-100, 0, 100]]], float)
    tracer = Tracer(Triangles(wall, np.zeros(2, np.int32), np.full(2, -1, np.int32)), KINDS, TAU)
    P = np.array([[0.0, -1e-3, 50.0], [30.0, -5e-4, 20.0]])
    N = np.tile([0.0, 1.0, 0.0], (2, 1))
    assert np.all(tracer.offset(P, N)[:, 1] > 0.0)            # the plain offset crosses the wall
    o = tracer.sensor_origins(P, N)
    assert np.all(o[:, 1] < 0.0) and np.all(o[:, 1] > P[:, 1])
    d = stratified_directions(N, 8, 25, np.random.default_rng(1)).reshape(-1, 3)
    assert tracer.intersect(np.repeat(o, 200, axis=0), d).hit.all()   # the wall fills the view


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_sensors_in_corners_and_on_edges_of_a_closed_box_start_inside_it(seed):
    """Origins on an edge lie in the plane of the adjacent face, where rays slipped
    through the edge; from sensor_origins no ray leaves the box (rotated at random so
    that nothing is axis-aligned)."""
    rot = _rotation(seed)
    box = box_triangles([2.0, 3.0, 1.5], [4.0, 6.0, 3.0]) @ rot.T
    tracer = Tracer(Triangles(box, np.zeros(12, np.int32), np.full(12, -1, np.int32)), KINDS, TAU)
    P = np.array([[0, 0, 0], [0, 0, 0], [0, 0, 0], [4, 6, 3], [2, 0, 0], [0, 3, 3], [4, 0, 1.5], [2, 3, 0]], float)
    N = np.array([[0, 0, 1], [1, 0, 0], [1, 1, 1], [0, 0, -1], [0, 0, 1], [1, 0, 0], [-1, 0, 0], [0, 0, 1]], float)
    N /= np.linalg.norm(N, axis=1, keepdims=True)
    P, N = P @ rot.T, N @ rot.T
    o = tracer.sensor_origins(P, N)
    d = stratified_directions(N, 16, 50, np.random.default_rng(seed)).reshape(-1, 3)
    assert tracer.intersect(np.repeat(o, 800, axis=0), d).hit.all()
    assert np.all(np.linalg.norm(o - P, axis=1) < 1e-3)
    # a sensor in the middle of the floor keeps the plain offset
    assert np.array_equal(o[-1], tracer.offset(P[-1:], N[-1:])[0])
    # every corner and edge, facing into the room in random directions
    C = np.array([[x, y, z] for x in (0, 4) for y in (0, 6) for z in (0, 3)]
                 + [[2, 0, 0], [0, 3, 0], [4, 6, 1.5], [0, 0, 1.5], [2, 6, 3], [4, 3, 3]], float)
    inward = np.where(C == 0, 1.0, np.where(C == [4, 6, 3], -1.0, 0.0))     # towards the faces it lies on
    raw = np.random.default_rng(seed).normal(size=C.shape)
    N = np.where(inward != 0, inward * (0.05 + np.abs(raw)), raw)
    N /= np.linalg.norm(N, axis=1, keepdims=True)
    o = tracer.sensor_origins(C @ rot.T, N @ rot.T)
    d = stratified_directions(N @ rot.T, 8, 25, np.random.default_rng(seed)).reshape(-1, 3)
    assert tracer.intersect(np.repeat(o, 200, axis=0), d).hit.all()


def test_rays_leaving_the_inside_of_a_sphere_reach_its_far_side():
    """Hits on a sphere primitive are moved onto the true sphere, up to 7.2e-5·r outside
    its facets.  Leaving towards the inside, the origin must clear the facets: before the
    fix ~97 % of the rays and shadow rays from the inner wall of a closed sphere hit the
    facet they left (an integrating sphere lost 97 % of its direct light)."""
    from lbl_illum.scene.geometry import sphere_triangles

    radius = 2.0
    center = np.array([0.3, -0.2, 1.0])
    verts = sphere_triangles(center, radius)
    tri = Triangles(verts, np.zeros(len(verts), np.int32), np.zeros(len(verts), np.int32),
                    center[None, :], np.array([radius]))
    tracer = Tracer(tri, KINDS, TAU)
    rng = np.random.default_rng(5)
    u = rng.normal(size=(300, 3))
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    points, inward = center + radius * u, -u
    o = tracer.offset(points, inward)
    # shadow rays to the centre pass; hemisphere rays cross the sphere (chord ≥ 2r·cos θ)
    assert tracer.transmittance(o, inward, np.full(300, radius)).min() == 1.0
    d = stratified_directions(inward, 4, 12, rng).reshape(-1, 3)
    hits = tracer.intersect(np.repeat(o, 48, axis=0), d)
    assert hits.hit.all()
    cos = np.einsum("ij,ij->i", d, np.repeat(inward, 48, axis=0))
    assert np.all(hits.t > 0.99 * 2 * radius * cos - 1e-3)
    # leaving outwards keeps the plain offset
    eps = 1e-5 * (np.abs(points).max(axis=1) + tracer.length_scale)
    assert np.allclose(np.linalg.norm(tracer.offset(points, u) - points, axis=1), eps)


def test_ray_caster_first_hit_occlusion_and_counts_against_closed_form_distances():
    """A unit square at z = 2: rays from the origin hit it at t = 2 / cos θ, miss it outside
    its edges, are occluded only when tmax reaches it; an empty caster hits nothing."""
    verts = np.array([[[-1, -1, 2], [1, -1, 2], [1, 1, 2]], [[-1, -1, 2], [1, 1, 2], [-1, 1, 2]]], float)
    caster = RayCaster(verts)
    d = np.array([[0, 0, 1.0], [0.3, 0.2, 1.0], [1.0, 0, 1.0], [0, 0, -1.0]])
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    o = np.zeros((4, 3))
    t, prim = caster.first_hit(o, d)
    np.testing.assert_allclose(t[:2], 2.0 / d[:2, 2], rtol=1e-6)
    assert np.all(prim[:2] >= 0) and np.all(np.isinf(t[2:])) and np.all(prim[2:] == -1)
    assert caster.occluded(o[:2], d[:2], 10.0).all()
    assert not caster.occluded(o[:2], d[:2], 1.9).any()
    assert caster.rays_traced == 8
    np.testing.assert_allclose(caster.normals, [[0, 0, 1.0], [0, 0, 1.0]])
    # ε = SELF_HIT_EPSILON · (|P|∞ + ℓ), ℓ the median first edge (of 2 m and 2√2 m)
    np.testing.assert_allclose(caster.epsilon(np.array([[3.0, -5.0, 1.0]])), [1e-5 * (5.0 + 1.0 + 2 ** 0.5)])
    empty = RayCaster(np.zeros((0, 3, 3)))
    t, prim = empty.first_hit(o, d)
    assert empty.empty and np.all(np.isinf(t)) and np.all(prim == -1) and not empty.occluded(o, d).any()


def _pane_scene():
    """A horizontal Fresnel pane (τ_n = 0.6) at z = 1, a vertical Fresnel pane (τ_n = 0.8) at
    x = 2.5, a target at x = 5 and, for rays at y ≈ 3 only, an opaque wall at x = 2."""
    from lbl_illum import Options
    from lbl_illum.engine.integrator import Integrator
    from conftest import make_scene

    geo = [{"shape": "rectangle", "origin": [-5, -4, 1], "u": [10, 0, 0], "v": [0, 8, 0], "material": "fresnel"},
           {"shape": "rectangle", "origin": [2.5, -4, -1], "u": [0, 8, 0], "v": [0, 0, 6], "material": "upright"},
           {"shape": "rectangle", "origin": [5, -4, -1], "u": [0, 8, 0], "v": [0, 0, 8], "material": "target"},
           {"shape": "rectangle", "origin": [2, 2, -1], "u": [0, 2, 0], "v": [0, 0, 6], "material": "wall"}]
    mats = {"fresnel": {"type": "glass", "transmittance": 0.6},
            "upright": {"type": "glass", "transmittance": 0.8},
            "target": {"type": "diffuse", "reflectance": 0.5},
            "wall": {"type": "diffuse", "reflectance": 0.5}}
    scene = make_scene(geo, mats)
    integ = Integrator(scene, Options(bounces=0))
    names = [m.name for m in scene.materials]
    return integ.tracer, integ.materials, names


def test_through_panes_multiplies_each_panes_own_angle_and_stops_where_told():
    """Rays at 55° from the vertical in the xz-plane meet the horizontal pane at 55° and the
    vertical one at 35°: T = τ_A(55°) · τ_B(35°), each pane's own τ(θ)
    (MaterialTable.glass_transmittance; τ_A(55°) = 0.524 for τ_n = 0.6, test_direct's closed form).  Distances are the planes' along the ray
    (x / sin 55°), to Embree's float32 round-off (rel 1e-6); products to 1e-12."""
    from lbl_illum.engine.raycast import through_panes

    tracer, materials, names = _pane_scene()
    fresnel, upright, target = names.index("fresnel"), names.index("upright"), names.index("target")
    mat = tracer.triangles.material
    s, c = np.sin(np.radians(55.0)), np.cos(np.radians(55.0))
    tau55 = materials.glass_transmittance(np.array([fresnel]), np.array([c]))[0]
    tau35 = materials.glass_transmittance(np.array([upright]), np.array([s]))[0]
    assert tau55 == pytest.approx(np.full(3, 0.524), abs=1e-3)
    # (each pane's own angle matters: pane B at 55° passes 0.739, 6 % less than at 35°)
    assert materials.glass_transmittance(np.array([upright]), np.array([c]))[0, 0] < tau35[0] - 0.01
    # 0: through both panes to the target; 1: the wall at x = 2 after the first pane;
    # 2: towards −x, through the first pane into nothing
    o = np.array([[0.0, 0.0, 0.0], [0.0, 3.0, 0.0], [0.0, 0.0, 0.0]])
    d = np.array([[s, 0.0, c], [s, 0.0, c], [-s, 0.0, c]])
    both, first = tau55 * tau35, tau55

    path = through_panes(tracer, materials, o, d, stop=lambda prim, ray: mat[prim] == target)
    np.testing.assert_array_equal(path.reached, [True, False, False])
    np.testing.assert_array_equal(path.blocked, [False, True, False])
    assert mat[path.prim[0]] == target and names[mat[path.prim[1]]] == "wall" and path.prim[2] == -1
    np.testing.assert_allclose(path.distance[:2], [5.0 / s, 2.0 / s], rtol=1e-6)
    assert path.distance[2] == np.inf
    np.testing.assert_allclose(path.product, [both, first, first], rtol=1e-12)

    # without a stop rule a segment is reached when nothing opaque lies before its end:
    # ray 0 ends between the panes (tmax 2 / sin 55°), ray 2 at infinity, ray 1 at the wall
    path = through_panes(tracer, materials, o, d, tmax=np.array([2.0 / s, np.inf, np.inf]))
    np.testing.assert_array_equal(path.reached, [True, False, True])
    np.testing.assert_array_equal(path.blocked, [False, True, False])
    np.testing.assert_array_equal(path.prim[[0, 2]], [-1, -1])
    np.testing.assert_allclose(path.product, [first, first, first], rtol=1e-12)

    # the stop rule sees the rays' own indices; one query crosses one pane and ends nowhere
    path = through_panes(tracer, materials, o[:1].repeat(2, 0), d[:1].repeat(2, 0),
                         stop=lambda prim, ray: (mat[prim] == target) & (ray == 1))
    np.testing.assert_array_equal(path.reached, [False, True])
    np.testing.assert_array_equal(path.blocked, [True, False])
    path = through_panes(tracer, materials, o[:1], d[:1], stop=lambda prim, ray: mat[prim] == target, layers=1)
    assert not path.reached[0] and not path.blocked[0] and path.prim[0] == -1
    np.testing.assert_allclose(path.product[0], first, rtol=1e-12)


def test_closest_hits_in_a_glazed_scene_before_and_after_the_bvh_over_every_triangle(monkeypatch):
    """With glass, a closest hit is first the nearer of the opaque and the glass BVHs'; once
    closest-hit rays reach ALL_BVH_RAYS_PER_TRIANGLE a triangle, a BVH over every triangle
    answers.  Both give a caster's over all triangles, hit for hit, and count each ray once."""
    from lbl_illum.engine import raycast

    rng = np.random.default_rng(3)
    box = box_triangles([2, 3, 1.5], [4, 6, 3])
    panes = np.array([[[1, -0.01, 1], [3, -0.01, 1], [3, -0.01, 2]], [[1, 1, 1], [3, 1, 1], [3, 1, 2.5]]], float)
    verts = np.concatenate([panes[:1], box, panes[1:]])
    tri = Triangles(verts, np.array([1] + [0] * len(box) + [1], np.int32), np.full(len(verts), -1, np.int32))
    monkeypatch.setattr(raycast, "ALL_BVH_RAYS_PER_TRIANGLE", 2)
    tracer = Tracer(tri, KINDS, TAU)
    reference = RayCaster(verts)
    o = rng.uniform([0.1, 0.1, 0.1], [3.9, 5.9, 2.9], (1000, 3))
    d = rng.normal(size=(1000, 3))
    o[:200, 1] = -2.0                                  # from outside, at the outer pane
    d[:200] = rng.uniform([1.2, 0, 1.2], [2.8, 0, 1.8], (200, 3)) - o[:200]
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    want_t, want_prim = reference.first_hit(o, d)
    assert (want_prim == 0).sum() > 50 and (want_prim == len(verts) - 1).sum() > 5   # panes before walls
    for call in range(2):                              # 1000 rays ≥ 2 × 14 triangles: the second builds it
        hits = tracer.intersect(o, d)
        assert (tracer._all is not None) == (call == 1)
        np.testing.assert_array_equal(hits.prim, want_prim)
        np.testing.assert_array_equal(hits.t, want_t)
    assert tracer.rays_traced == 2000

"""Ray casting: no self-hits off surfaces at any scale or angle; glass along shadow rays."""

import numpy as np
import pytest

from lbl_illum.geometry import Triangles
from lbl_illum.hemisphere import stratified_directions
from lbl_illum.materials import DIFFUSE, GLASS
from lbl_illum.raycast import Tracer

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

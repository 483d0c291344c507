"""Direct light from light surfaces: the closed form with a visible share
(lbl_illum/engine/emitters.py) against the area sampling it replaced, in one run.

Cases (sensors facing up over a black floor, direct light only, unless stated):

* a 1.2 × 0.6 m panel 1.2 m above 41 × 41 sensors (exact: Howell's corner factors);
* a sphere of radius 0.1 m 1.5 m above them (exact: Nusselt, π L (r/d)² cos θ);
* the panel with a 0.4 × 2 m plate halfway: a penumbra at every sensor of a row (reference:
  the panel integrated over a 1000 × 1000 grid with the plate's shadow found exactly);
* a luminous ceiling of 600 panels (1,200 triangles), 4 × 6 m at 2.8 m (exact: the sum of
  the panels' corner factors);
* that ceiling and the single panel in a closed room of reflectance 0.5 (floor 0.3),
  3 bounces: the cost of the direct light at every hit of the indirect calculation.

The baseline is the estimator the engine used before, written out here: triangles chosen
in proportion to area × luminance, points uniform on them, E = (1/n) Σ L cos θ_r cos θ_l
/ (d² p_A), one ray per hit and 16 at sensors.  For each sensor case: seconds of the
direct step alone (the new one at the engine's 16 rays per sensor) and the mean and
largest per-sensor error, the baseline at 16 to 4,096 rays; the time ratio at equal mean
error is printed where the baseline reaches the new method's error within that ladder
(it never does where the new method is exact).  For the rooms: seconds of the whole
calculation with either estimator at every hit.

Usage (from the repository root)::

    python validation/bench/direct_emitters.py

Prints a table; about a minute on 2 cores.  Seconds drift between runs on shared
machines; the ratios are taken in one run.
"""

from __future__ import annotations

import time

import numpy as np

from lbl_illum import Integrator, Options
from lbl_illum.photometry import luminance
from lbl_illum.scene import LIGHT, scene_from_dict

L = 1000.0
FLOOR = {"shape": "rectangle", "origin": [-50, -50, 0], "u": [100, 0, 0], "v": [0, 100, 0], "material": "floor"}
PANEL = {"shape": "rectangle", "origin": [-0.6, -0.3, 1.2], "u": [1.2, 0, 0], "v": [0, 0.6, 0], "material": "lamp"}
LADDER = (16, 64, 256, 1024, 4096)


class AreaSampled:
    """The baseline: light surfaces sampled uniformly over their area (module text)."""

    def __init__(self, triangles, materials):
        ids = np.flatnonzero(materials.kind[triangles.material] == LIGHT)
        self.L = materials.luminance[triangles.material[ids]]
        self.v = triangles.vertices[ids]
        self.normals = triangles.normals[ids]
        area = triangles.areas[ids]
        self.pdf_area = 1.0 / (area * self.L.mean(axis=1)).sum() * self.L.mean(axis=1)   # prob/area
        cdf = np.cumsum(area * self.L.mean(axis=1))
        self.cdf = cdf / cdf[-1]

    def illuminance(self, points, normals, origins, rng, samples, transmittance):
        n = len(points)
        E = np.zeros((n, 3))
        for _ in range(max(1, samples)):
            k = np.minimum(np.searchsorted(self.cdf, rng.random(n)), len(self.cdf) - 1)
            r1, r2 = np.sqrt(rng.random(n)), rng.random(n)
            v = self.v[k]
            x = (1 - r1)[:, None] * v[:, 0] + (r1 * (1 - r2))[:, None] * v[:, 1] + (r1 * r2)[:, None] * v[:, 2]
            w = x - origins
            d = np.linalg.norm(w, axis=1)
            w /= np.maximum(d, 1e-300)[:, None]
            cr = np.einsum("ij,ij->i", normals, w)
            cl = np.abs(np.einsum("ij,ij->i", self.normals[k], w))
            use = np.flatnonzero((d > 0) & (cr > 0) & (cl > 0))
            T = transmittance(origins[use], w[use], d[use] * (1 - 1e-6) - 1e-9)
            g = cr[use] * cl[use] / (d[use] ** 2 * self.pdf_area[k[use]])
            E[use] += self.L[k[use]] * g[:, None] * T / samples
        return E


def _scene(geometry, floor=0.0):
    mats = {"floor": {"type": "diffuse", "reflectance": floor}, "lamp": {"type": "light", "luminance": L},
            "plate": {"type": "diffuse", "reflectance": 0.0}, "wall": {"type": "diffuse", "reflectance": 0.5}}
    return scene_from_dict({"units": "m", "geometry": [FLOOR] + geometry, "materials": mats,
                            "sky": {"type": "none"}}, ".", "bench.toml")


def _corner(a, b, c):
    A, B = a / c, b / c
    sa, sb = np.sqrt(1 + A * A), np.sqrt(1 + B * B)
    return (A / sa * np.arctan(B / sa) + B / sb * np.arctan(A / sb)) / (2 * np.pi)


def _rectangle(p, x0, x1, y0, y1, h):
    x, y, z = p.T
    c = h - z
    return np.pi * L * (_corner(x1 - x, y1 - y, c) - _corner(x0 - x, y1 - y, c) - _corner(x1 - x, y0 - y, c)
                        + _corner(x0 - x, y0 - y, c))


def _grid(half, n=41):
    g = np.linspace(-half, half, n)
    X, Y = np.meshgrid(g, g)
    return np.column_stack([X.ravel(), Y.ravel(), np.zeros(X.size)]), np.tile([0, 0, 1.0], (X.size, 1))


def _direct_step(scene, P, N, rays, baseline):
    """(seconds, illuminance) of the light surfaces' direct step alone at the sensors (the
    engine's own origins and shadow-ray transmittance), after a warm-up call."""
    direct = Integrator(scene, Options(bounces=0)).context.direct
    tracer = direct.tracer
    lights = AreaSampled(tracer.triangles, direct.materials) if baseline else direct.lights
    origins = tracer.sensor_origins(P, N)
    rng = np.random.default_rng(1)
    lights.illuminance(P[:4], N[:4], origins[:4], rng, rays, direct.transmittance)
    t = time.perf_counter()
    E = lights.illuminance(P, N, origins, rng, rays, direct.transmittance)
    return time.perf_counter() - t, luminance(E)


def _whole_run(scene, P, N, options, baseline):
    """(seconds, illuminance) of a whole calculation, the light surfaces' estimator swapped
    for :class:`AreaSampled` at every hit when ``baseline``, after a warm-up call."""
    integ = Integrator(scene, options)
    if baseline:
        integ.context.direct.lights = AreaSampled(integ.tracer.triangles, integ.materials)
    Integrator(scene, options, context=integ.context).compute(P[:4], N[:4])
    t = time.perf_counter()
    r = Integrator(scene, options, context=integ.context).compute(P, N)
    return time.perf_counter() - t, r.illuminance


def cases():
    P, N = _grid(2.0)
    yield "panel at 1.2 m", _scene([PANEL]), P, N, _rectangle(P, -0.6, 0.6, -0.3, 0.3, 1.2), Options(bounces=0)
    w = np.array([0, 0, 1.5]) - P
    d = np.linalg.norm(w, axis=1)
    yield ("sphere r 0.1 m at 1.5 m", _scene([{"shape": "sphere", "center": [0, 0, 1.5], "radius": 0.1,
                                               "material": "lamp"}]), P, N, np.pi * L * (0.1 / d) ** 2 * w[:, 2] / d,
           Options(bounces=0))
    panel = dict(PANEL, origin=[-0.5, -0.5, 1.0], u=[1, 0, 0], v=[0, 1, 0])
    plate = {"shape": "rectangle", "origin": [-0.2, -1.0, 0.5], "u": [0.4, 0, 0], "v": [0, 2, 0], "material": "plate"}
    row = np.column_stack([np.linspace(-0.8, 0.8, 33), np.zeros(33), np.zeros(33)])
    g = (np.arange(1000) + 0.5) / 1000 - 0.5
    X, Y = np.meshgrid(g, g)
    ref = []
    for p in row:
        hidden = (np.abs(0.5 * (p[0] + X)) < 0.2) & (np.abs(0.5 * (p[1] + Y)) < 1.0)
        ref.append(L * np.sum(np.where(hidden, 0.0, 1.0 / ((X - p[0]) ** 2 + (Y - p[1]) ** 2 + 1.0) ** 2)) / 1e6)
    yield "penumbra: panel and plate", _scene([panel, plate]), row, np.tile([0, 0, 1.0], (33, 1)), np.array(ref), \
        Options(bounces=0)
    panels, ref = [], np.zeros(len(P))
    for i in range(20):
        for j in range(30):
            x0, y0 = -2 + 0.2 * i, -3 + 0.2 * j
            panels.append(dict(PANEL, origin=[x0, y0, 2.8], u=[0.15, 0, 0], v=[0, 0.15, 0]))
            ref += _rectangle(P, x0, x0 + 0.15, y0, y0 + 0.15, 2.8)
    yield "luminous ceiling, 1,200 triangles", _scene(panels), P, N, ref, Options(bounces=0)
    room = [{"shape": "box", "center": [0, 0, 1.5], "size": [4.2, 6.2, 3.0], "material": "wall"}]
    opts = Options(bounces=3, accuracy=0.2, samples=64)
    yield "room, luminous ceiling, 3 bounces", _scene(room + panels, 0.3), P[::7], N[::7], None, opts
    yield "room, one panel, 3 bounces", _scene(room + [dict(PANEL, origin=[-0.6, -0.3, 2.8])], 0.3), P[::7], N[::7], \
        None, opts


def main():
    print("seconds of the direct step at the sensors (light surfaces only); whole runs for the rooms")
    print(f"{'case':36s} {'new s':>8s} {'mean':>8s} {'max':>8s} | baseline at rays: s, mean, max | new/baseline "
          "at equal mean error")
    for name, scene, P, N, ref, opts in cases():
        if ref is None:
            t_new, _ = _whole_run(scene, P, N, opts, False)
            t_old, _ = _whole_run(scene, P, N, opts, True)
            print(f"{name:36s} {t_new:8.3f} {'-':>8s} {'-':>8s} | 1 ray per hit, 16 at sensors: {t_old:.3f} s"
                  f" | {t_new / t_old:.2f} (time only)")
            continue
        t_new, E_new = _direct_step(scene, P, N, 16, False)
        err_new = np.abs(E_new / ref - 1)
        line = f"{name:36s} {t_new:8.3f} {100 * err_new.mean():7.3f}% {100 * err_new.max():7.2f}%"
        ratio = "not reached"
        for rays in LADDER:
            t_old, E_old = _direct_step(scene, P, N, rays, True)
            err = np.abs(E_old / ref - 1)
            line += f" | {rays}: {t_old:.3f}, {100 * err.mean():.2f}%, {100 * err.max():.1f}%"
            if ratio == "not reached" and err.mean() <= err_new.mean():
                ratio = f"{t_new / t_old:.2f}"
        print(line + f" | {ratio}")


if __name__ == "__main__":
    main()

"""Shared fixtures and helpers: small scenes built from plain dicts, as a scene file would give
them, and the closed forms and rooms that test modules of several layers use."""

from __future__ import annotations

import copy
import os
import tempfile
from pathlib import Path

# What lbl_illum keeps between runs (parsed geometry, luminance weights) goes to a folder of
# the test session's own, not the user's: set before lbl_illum is imported, so command-line
# tests run in child processes inherit it.
os.environ["LBL_ILLUM_CACHE_DIR"] = tempfile.mkdtemp(prefix="lbl-illum-tests-")

import numpy as np
import pytest

from lbl_illum.scene.materials import ward_brdf
from lbl_illum.scene.scenefile import scene_from_dict

ROOT = Path(__file__).resolve().parent.parent
EXAMPLES = ROOT / "examples"

GROUND = {"shape": "polygon", "material": "ground",
          "vertices": [[-50, -50, 0], [50, -50, 0], [50, 50, 0], [-50, 50, 0]]}


def make_scene(geometry, materials, sky=None, sun=None, settings=None, units="m", base_dir=ROOT):
    """A scene from the pieces of a scene file."""
    data = {"units": units, "geometry": copy.deepcopy(geometry), "materials": copy.deepcopy(materials)}
    if sky is not None:
        data["sky"] = dict(sky)
    if sun is not None:
        data["sun"] = dict(sun)
    if settings is not None:
        data["settings"] = dict(settings)
    return scene_from_dict(data, base_dir, "test.toml")


@pytest.fixture
def open_ground():
    """A 100 m ground plane of reflectance 0.2 under nothing else."""
    def build(sky=None, sun=None, reflectance=0.2):
        return make_scene([GROUND], {"ground": {"type": "diffuse", "reflectance": reflectance}}, sky, sun)
    return build


def horizontal(n=1, z=0.0):
    """n sensors on the ground plane facing up, spread over a few metres."""
    x = np.linspace(-2, 2, n)
    points = np.column_stack([x, np.zeros(n), np.full(n, z)])
    normals = np.tile([0.0, 0.0, 1.0], (n, 1))
    return points, normals


# -- shared with several test modules (from test_materials.py)

def lobe_albedo(theta, alpha, nb=400, nps=256):
    """∫ f_s/ρ_s cos θ_o dω_o at incidence θ [rad] by quadrature of :func:`ward_brdf` alone:
    Gauss–Legendre in the angle β from the mirror direction (β ≤ min(π, 20 α), beyond
    which exp(−tan²δ/α²) < e^{-90}), midpoints in the azimuth about it.  Against 2400 × 1024
    nodes the default 400 × 256 is within 3.3e-5 at α = 0.02–0.3 and 0°–88°."""
    v = np.array([np.sin(theta), 0.0, np.cos(theta)])
    r = np.array([-v[0], 0.0, v[2]])
    t = np.array([np.cos(theta), 0.0, np.sin(theta)])
    b = np.cross(r, t)
    x, w = np.polynomial.legendre.leggauss(nb)
    top = min(np.pi, 20.0 * alpha)
    beta, wb = 0.5 * top * (x + 1.0), 0.5 * top * w
    psi = (np.arange(nps) + 0.5) * 2.0 * np.pi / nps
    B, S = np.meshgrid(beta, psi, indexing="ij")
    o = (np.cos(B)[..., None] * r + (np.sin(B) * np.cos(S))[..., None] * t
         + (np.sin(B) * np.sin(S))[..., None] * b).reshape(-1, 3)
    k = len(o)
    f = ward_brdf(np.tile([0.0, 0.0, 1.0], (k, 1)), np.tile(-v, (k, 1)), o, alpha)
    g = (f * np.maximum(o[:, 2], 0.0)).reshape(B.shape) * np.sin(B)
    return float((g.sum(axis=1) * (2.0 * np.pi / nps) * wb).sum())


# -- shared with several test modules (from test_integrator.py)

PLASTIC_FLOOR = {"shape": "polygon", "material": "floor",
                 "vertices": [[-1000, -1000, 0], [1000, -1000, 0], [1000, 1000, 0], [-1000, 1000, 0]]}


UNIFORM_SKY = {"type": "uniform", "horizontal_illuminance": 10000.0, "ground_reflectance": 0.2}


DOWN = (np.array([[0.0, 0.0, 1.0]]), np.array([[0.0, 0.0, -1.0]]))


def plastic_floor_reference(C, s, alpha, E_h=10000.0, metal=False):
    """Illuminance [lux] at a sensor facing down over an infinite floor of plastic (or, with
    ``metal``, Radiance's metal) of colour C under a uniform sky of horizontal
    illuminance E_h: E_h ∫ (ρ_d(μ) + ρ_s(μ)) 2μ dμ by 16-point Gauss–Legendre quadrature
    in μ = cos θ.  A metal's specular part is coloured: F + s C (1 − F) polished, s C
    times the lobe's albedo rough; with an RGB C the photometric value is returned."""
    from lbl_illum.photometry import luminance
    from lbl_illum.scene.materials import plastic_fresnel

    C = np.atleast_1d(np.asarray(C, np.float64))[:, None]        # (channels, 1)
    x, w = np.polynomial.legendre.leggauss(16)
    mu, w = 0.5 * (x + 1.0), 0.5 * w
    if alpha ** 2 <= 1e-6:
        F = plastic_fresnel(mu) if s >= 0.018 else np.zeros_like(mu)
        rho_s = s + F * (1.0 - s)
        rho_d, spec = (1.0 - rho_s) * C, (F + s * C * (1.0 - F) if metal else rho_s + 0.0 * C)
    else:
        rho_d = np.full((len(C), len(mu)), (1.0 - s)) * C
        spec = s * np.array([lobe_albedo(np.arccos(m), alpha, 200, 128) for m in mu]) * (C if metal else 1.0)
    E = E_h * np.sum(w * (rho_d + spec) * 2.0 * mu, axis=1)
    return float(E[0]) if len(E) == 1 else float(luminance(E))


# -- shared with several test modules (from test_grid.py)

MATERIALS = {name: {"type": "diffuse", "reflectance": r} for name, r in
             (("floor", 0.2), ("floor_a", 0.2), ("floor_b", 0.2), ("wall", 0.5), ("ceiling", 0.8),
              ("column", 0.5), ("desk", 0.4), ("ground", 0.2))}


def room_geometry(outline, height=3.0, floor="floor", z0=0.0):
    """Floor, ceiling and walls of a room over the counter-clockwise plan polygon ``outline``,
    every surface wound towards the inside of the room."""
    outline = [tuple(map(float, p)) for p in outline]
    top = z0 + height
    geo = [{"shape": "polygon", "material": floor, "vertices": [[x, y, z0] for x, y in outline]},
           {"shape": "polygon", "material": "ceiling", "vertices": [[x, y, top] for x, y in outline[::-1]]}]
    for (ax, ay), (bx, by) in zip(outline, outline[1:] + outline[:1]):
        geo.append({"shape": "polygon", "material": "wall",
                    "vertices": [[ax, ay, z0], [ax, ay, top], [bx, by, top], [bx, by, z0]]})
    return geo


def scene_of(geometry):
    return make_scene(geometry, MATERIALS, sky={"type": "cie-overcast"})


def inside_polygon(p, poly):
    """Even-odd rule for (n, 2) points against a plan polygon."""
    poly = np.asarray(poly, float)
    x, y = p[:, 0], p[:, 1]
    inside = np.zeros(len(p), bool)
    for (ax, ay), (bx, by) in zip(poly, np.roll(poly, -1, axis=0)):
        crosses = (ay > y) != (by > y)
        xc = ax + (y - ay) * (bx - ax) / np.where(by != ay, by - ay, 1.0)
        inside ^= crosses & (x < xc)
    return inside


L_ROOM = [(0, 0), (6, 0), (6, 3), (3, 3), (3, 6), (0, 6)]


#: Quality of the office cache files of the cache tests (tests/io/test_cachefile.py, tests/cli/test_cache.py).
CACHE_OPTIONS = {"accuracy": 0.2, "bounces": 2, "samples": 128}


@pytest.fixture(scope="session")
def office_quarter():
    """The bundled office and every fourth point of its grid: (scene, points, normals)."""
    from lbl_illum import load_scene, read_points

    scene = load_scene(EXAMPLES / "office" / "scene.toml")
    points, normals = read_points(EXAMPLES / "office" / "grid.pts", scene.unit_scale)
    return scene, points[::4], normals[::4]


@pytest.fixture(scope="session")
def office_cache(office_quarter, tmp_path_factory):
    """A cache file of the office at CACHE_OPTIONS, and the integrator that wrote it."""
    from lbl_illum import Integrator, Options

    scene, points, normals = office_quarter
    integ = Integrator(scene, Options(**CACHE_OPTIONS))
    integ.compute(points, normals)
    path = tmp_path_factory.mktemp("saved") / "office.lblcache"
    integ.cache.save(path)
    return path, integ


def ies_text(fn, horizontal, vertical=np.arange(0, 180.1, 2.5), version="IESNA:LM-63-2002", units=2,
             dims=(0, 0, 0), multiplier=1.0, ballast=1.0, lumens=-1, ptype=1, tilt="TILT=NONE", per_line=10):
    """The text of an IES LM-63 file of the distribution ``fn(vertical, horizontal)`` [cd]
    tabulated on the given angles [deg] (tests of photometric files and luminaires)."""
    H, V = np.meshgrid(horizontal, vertical, indexing="ij")
    values = fn(V, H)
    lines = [version, "[TEST] lbl_illum test", "[MANUFAC] none", tilt,
             f"1 {lumens} {multiplier} {len(vertical)} {len(horizontal)} {ptype} {units} {dims[0]} {dims[1]} {dims[2]}",
             f"{ballast} 1.0 30"]

    def wrap(numbers):
        numbers = [f"{x:.6g}" for x in numbers]
        return [" ".join(numbers[i:i + per_line]) for i in range(0, len(numbers), per_line)]

    lines += wrap(vertical) + wrap(horizontal)
    for row in values:
        lines += wrap(row)
    return "\n".join(lines) + "\n"


def radiance_tool(name: str) -> str | None:
    """The path of one of Radiance's programs (the pyradiance wheel's, else on PATH), or None."""
    import shutil

    from lbl_illum.io.radiance import radiance_programs

    programs = radiance_programs()
    if programs is not None and programs["root"] is not None:
        path = programs["root"] / "bin" / name
        if path.is_file():
            return str(path)
    return shutil.which(name)

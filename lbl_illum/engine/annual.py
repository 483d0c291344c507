"""A year of daylight at sensor points from the cache's daylight coefficients.

One calculation of the irradiance cache, whose records carry daylight coefficients
(:mod:`lbl_illum.engine.coefficients`), gives each sensor i a row of coefficients: D_ip
[lux per cd/m²] for each sky patch p (the ground glow is patch 0) and G_ij [lux per lux]
for the interreflected light of a sun at position j (:func:`sun_positions`).  For the
hour h of a weather file, with the sky matrix L_ph [cd/m²] of the Perez all-weather model
(:func:`lbl_illum.daylight.skymatrix.sky_matrix`, the sun apart) and the sun's direct
normal illuminance E_dn(h) [lux] shared among the 4 sun positions around it with
bilinear weights s_jh,

    E_ih = Σ_p D_ip L_ph + Σ_j G_ij s_jh E_dn(h) + E_sun,ih        [lux]

where E_sun is the sun's direct light at the sensor, by a shadow ray to the sun's own
position of that hour (:func:`~lbl_illum.engine.sun_hours.direct_sun_matrix`), never
smeared into patches.

**Which sky places the records.**  Records are placed as for a point-in-time run
(their positions and radii depend on the light through the gradient limit of
:mod:`lbl_illum.engine.sizing`); the coefficients then serve every hour.  The sky that
places them is the CIE overcast sky of the scene's ground reflectance: its light arrives
from every part of the sky, as the year's does, where a sunny hour's would crowd the
records round one sunlit patch and leave the rest of the room to the hours it misses.
The scene's own ``[sky]`` and ``[sun]`` play no part; electric light is not daylight and
is left out.

The interpolation of the coefficients uses the paper's weights without the gradient terms
(module :mod:`~lbl_illum.engine.coefficients`); the sensors of every preset have their own
records (point samples), so this applies to the reflections, not to the sensors.
"""

from __future__ import annotations

import dataclasses
import time
from dataclasses import dataclass

import numpy as np

from ..daylight.sky import CIEOvercastSky, PerezSky
from ..daylight.sun import Sun
from ..daylight.skymatrix import SkyMatrix, sky_matrix
from ..daylight.weather import HourlyWeather
from ..options import Options
from .coefficients import CoefficientRecords
from .integrator import Integrator, RunStats
from .sun_hours import direct_sun_matrix

__all__ = ["AnnualLight", "annual_light", "sun_positions", "hour_scene", "shaded_scene", "DESIGN_SKY_ILLUMINANCE",
           "SUN_STEP"]

#: Horizontal illuminance [lux] of the overcast sky that places the records (its scale
#: changes nothing but the records' irradiance, which no hour uses).
DESIGN_SKY_ILLUMINANCE = 10_000.0
#: Spacing [°] of the sun positions in declination and hour angle (:func:`sun_positions`).
SUN_STEP = 12.0


@dataclass
class AnnualLight:
    """A year (the rows of a weather file) of illuminance at sensor points.

    illuminance : (n, hours) float32 [lux], total (sky, interreflected sun, direct sun)
    direct_sun : (n, hours) float32 [lux], the sun's disk alone through the glazing
    sky : the :class:`~lbl_illum.daylight.skymatrix.SkyMatrix` (sun apart)
    sky_coefficients : (n, patches) float32 [lux per cd/m²], D of the module text
    sun_coefficients : (n, J) float32 [lux per lux], G;  sun_directions : (J, 3) the J sun
        positions (:func:`sun_positions`)
    stats : the cache calculation's :class:`~lbl_illum.engine.integrator.RunStats`
    record_bytes : bytes of coefficients per record (all levels alike)
    seconds : the whole calculation [s]
    context : the :class:`~lbl_illum.engine.context.LightingContext` of the calculation (its
        tracer and glazing, for more shadow rays: the sky patches seen from a view point)
    """

    illuminance: np.ndarray
    direct_sun: np.ndarray
    sky: SkyMatrix
    sky_coefficients: np.ndarray
    sun_coefficients: np.ndarray
    sun_directions: np.ndarray
    stats: RunStats
    record_bytes: int
    seconds: float
    context: object = None


def sun_positions(matrix: SkyMatrix, latitude: float, step: float = SUN_STEP) -> tuple[np.ndarray, np.ndarray]:
    """The sun positions whose interreflected light the coefficients hold, and each hour's
    share of them: ``(directions, shares)``, (J, 3) unit vectors and (J, hours) float32
    weights times the hour's direct normal illuminance [lux].

    The year's suns lie on a band of the sky that declination δ and hour angle ω map onto
    a rectangle: s = (−cos δ sin ω, cos φ sin δ − sin φ cos δ cos ω, sin φ sin δ + cos φ
    cos δ cos ω) (east, north, up) at latitude φ.  The positions are the nodes of a grid
    of ``step`` degrees in (δ, ω) over the hours with direct sun, and each hour's sun is
    shared among the 4 nodes around it with bilinear weights, which reproduce any light
    that varies linearly with δ and ω (``gendaymtx``'s 4 nearest patches, weighted by
    proximity, do not: on the office example an afternoon's interreflected sun read 10 %
    low).  Nodes below the horizon are left out, their weight given to the others."""
    phi = np.radians(latitude)
    hours = np.flatnonzero(matrix.daylight & (matrix.direct_normal_illuminance > 0.0))
    if len(hours) == 0:
        return np.zeros((0, 3)), np.zeros((0, matrix.shape[1]), np.float32)
    s = matrix.sun_direction[hours]
    delta = np.arcsin(np.clip(np.sin(phi) * s[:, 2] + np.cos(phi) * s[:, 1], -1.0, 1.0))
    omega = np.arctan2(-s[:, 0], np.cos(phi) * s[:, 2] - np.sin(phi) * s[:, 1])
    h = np.radians(step)
    d0, w0 = delta.min(), omega.min()
    nd = max(2, int(np.ceil((delta.max() - d0) / h)) + 1)
    nw = max(2, int(np.ceil((omega.max() - w0) / h)) + 1)
    gd, gw = np.meshgrid(d0 + h * np.arange(nd), w0 + h * np.arange(nw), indexing="ij")
    nodes = np.column_stack([(-np.cos(gd) * np.sin(gw)).ravel(),
                             (np.cos(phi) * np.sin(gd) - np.sin(phi) * np.cos(gd) * np.cos(gw)).ravel(),
                             (np.sin(phi) * np.sin(gd) + np.cos(phi) * np.cos(gd) * np.cos(gw)).ravel()])
    u, v = (delta - d0) / h, (omega - w0) / h
    i, j = np.minimum(u.astype(np.int64), nd - 2), np.minimum(v.astype(np.int64), nw - 2)
    fu, fv = u - i, v - j
    corner = np.stack([i * nw + j, i * nw + j + 1, (i + 1) * nw + j, (i + 1) * nw + j + 1], axis=1)
    weight = np.stack([(1 - fu) * (1 - fv), (1 - fu) * fv, fu * (1 - fv), fu * fv], axis=1)
    up = nodes[corner, 2] > 0.0
    kept = np.where(up, weight, 0.0)
    total = kept.sum(axis=1, keepdims=True)
    highest = np.argmax(nodes[corner, 2], axis=1)
    lone = total[:, 0] <= 0.0                 # every node around it below the horizon
    kept[lone, highest[lone]] = 1.0
    kept /= np.where(lone[:, None], 1.0, total)
    shares = np.zeros((len(nodes), matrix.shape[1]))
    np.add.at(shares, (corner, np.repeat(hours[:, None], 4, axis=1)),
              kept * matrix.direct_normal_illuminance[hours, None])
    used = np.flatnonzero(shares.any(axis=1) & (nodes[:, 2] > 0.0))
    return nodes[used], shares[used].astype(np.float32)


def annual_light(scene, points, normals, weather: HourlyWeather, options: Options | None = None, mf: int = 1,
                 values: str = "irradiance", ground_reflectance: float | None = None, progress=None,
                 matrix: SkyMatrix | None = None, design=None, solve=None) -> AnnualLight:
    """The illuminance of every row of ``weather`` at (n, 3) ``points`` [m] facing unit
    ``normals`` (module text).

    options : quality options (default: the scene's);  mf : sky subdivision (1: Tregenza
    145 + ground; 2, 4: Reinhart);  values : ``"irradiance"`` or ``"illuminance"``, what
    sets the hours' brightness (:func:`~lbl_illum.daylight.skymatrix.sky_matrix`);
    ground_reflectance : of the ground glow (default: the scene sky's);  progress : as the
    integrator's;  matrix : a sky matrix made already (``sun="separate"``);  design :
    ``(sky, sun)`` that place the records instead of the CIE overcast sky (for measuring
    that choice);  solve : what computes the coefficients and the direct sun in place of
    this process — called as ``solve(design_scene, integrator, matrix, suns, points,
    normals)``, it returns ``(stats, vectors, direct, record_bytes)``: the run's
    :class:`RunStats`, the (n, K) photometric coefficient vectors of the points, the (n,
    hours) direct sun and the bytes of coefficients a record holds (a run on a cluster,
    :func:`lbl_illum.distributed.annual.annual_solver`)
    """
    t0 = time.perf_counter()
    options = options or scene.options
    rho_g = scene.sky.ground_reflectance if ground_reflectance is None else float(ground_reflectance)
    if matrix is None:
        matrix = sky_matrix(weather, mf=mf, sun="separate", values=values, ground_reflectance=rho_g)
    suns, shares = sun_positions(matrix, weather.site.latitude)
    sky, sun = design if design is not None else (
        CIEOvercastSky(horizontal_illuminance=DESIGN_SKY_ILLUMINANCE, ground_reflectance=rho_g), None)
    design = dataclasses.replace(scene, sky=sky, sun=sun)
    points = np.ascontiguousarray(points, np.float64).reshape(-1, 3)
    normals = np.asarray(normals, np.float64).reshape(-1, 3)
    normals = normals / np.linalg.norm(normals, axis=1, keepdims=True)
    integrator = Integrator(design, options, progress=progress)
    if solve is None:
        dc = CoefficientRecords(integrator, matrix.patches.mf, suns)
        result = integrator.compute(points, normals)
        own = np.arange(len(points)) if integrator.cache.levels[0].accuracy == 0.0 else None
        vectors = dc.photometric(dc.at_points(points, normals, own))
        if progress is not None:
            progress.describe("direct sun, hour by hour")
        direct = direct_sun_matrix(integrator.direct, integrator.tracer, points, normals, matrix.sun_direction,
                                   matrix.direct_normal_illuminance)
        stats, record_bytes = result.stats, dc.channels * dc.sources * 4
    else:
        stats, vectors, direct, record_bytes = solve(design, integrator, matrix, suns, points, normals)
    patches = vectors.shape[1] - len(suns)
    D, G = vectors[:, :patches], vectors[:, patches:]
    E = D @ np.asarray(matrix.luminance, np.float32)
    if len(suns):
        E += G @ shares
    E += direct
    np.maximum(E, 0.0, out=E)
    return AnnualLight(illuminance=E, direct_sun=direct, sky=matrix, sky_coefficients=D, sun_coefficients=G,
                       sun_directions=suns, stats=stats, record_bytes=record_bytes,
                       seconds=time.perf_counter() - t0, context=integrator.context)


def hour_scene(scene, matrix: SkyMatrix, hour: int):
    """``scene`` under the Perez sky and sun of row ``hour`` of ``matrix``, as a
    point-in-time run would see them: the same ε, Δ, sun position, diffuse horizontal and
    direct normal illuminance and ground reflectance (for checking the year against
    single hours)."""
    h = int(hour)
    if not matrix.daylight[h]:
        raise ValueError(f"row {h} of the weather file has no daylight")
    alt, az = float(matrix.sun_altitude[h]), float(matrix.sun_azimuth[h])
    dh, dn = float(matrix.diffuse_horizontal_illuminance[h]), float(matrix.direct_normal_illuminance[h])
    sky = PerezSky(horizontal_illuminance=dh, ground_reflectance=matrix.ground_reflectance,
                   sun_horizontal_illuminance=dn * max(np.sin(np.radians(alt)), 0.0), sun_altitude=alt,
                   sun_azimuth=az, clearness=float(matrix.clearness[h]), brightness=float(matrix.brightness[h]),
                   direct_normal_illuminance=dn)
    sun = Sun(altitude=alt, azimuth=az, direct_normal_illuminance=dn) if dn > 0.0 else None
    return dataclasses.replace(scene, sky=sky, sun=sun)


def shaded_scene(scene, materials, factor: float):
    """``scene`` with the shades of a window group closed: the transmittance of each glass
    or translucent material named in ``materials`` multiplied by ``factor`` (0…1), the
    closed shade as a neutral filter over the pane (IES LM-83-12 §2.2.6 leaves the shade's
    optics to the modeller; LEED v4.1 reviewers accept a transmittance of a few percent).
    A name that is not such a material of the scene is a ValueError naming it."""
    factor = float(factor)
    if not 0.0 <= factor <= 1.0:
        raise ValueError(f"the shades' transmittance factor must be within 0 and 1, got {factor:g}")
    names = list(dict.fromkeys(materials))
    by_name = {m.name: m for m in scene.materials}
    for name in names:
        m = by_name.get(name)
        if m is None or m.kind not in ("glass", "translucent"):
            kinds = sorted(x.name for x in scene.materials if x.kind in ("glass", "translucent"))
            raise ValueError(f"'{name}' is not a glass or translucent material of the scene (those are: "
                             f"{', '.join(kinds) or 'none'})")
    shaded = [dataclasses.replace(m, transmittance=tuple(factor * t for t in m.transmittance))
              if m.name in names else m for m in scene.materials]
    return dataclasses.replace(scene, materials=shaded)

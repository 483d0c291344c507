"""Direct sunlight at sensor points for every hour of a year, exactly, by shadow rays.

For an annual study the sun is not smeared into sky patches where it reaches a sensor
directly: for sensor i and hour h with the sun above the horizon,

    E_sun(i, h) = E_dn(h) · max(0, N_i · s_h) · T_i(s_h)   [lux]

with E_dn the direct normal illuminance of the hour [lux], s_h the unit direction to the
sun's centre, N_i the sensor's normal and T_i(s) the photometric transmittance of the
shadow ray from the sensor towards the sun: 0 behind an opaque surface, else the product
over the panes of glass it crosses of each pane's τ(θ) at its own angle of incidence
(:meth:`lbl_illum.engine.direct.DirectLight.transmittance`).  No reflection counts (the
sun's images in mirrors and panes, the light the room returns): this is the "direct sun
only" of IES LM-83-12's annual sunlight exposure (ASE, §2.3), which the interreflected
daylight leaves out.

The disk, not its centre alone (``disk``, as :func:`direct_sun_matrix` asks): a shadow ray
to the disk's centre and :data:`RIM_RAYS` to its rim; where they disagree (a window head or
a fin crosses the disk: a penumbra) T is the mean over :data:`DISK_SAMPLES` directions
across the disk, as the point-in-time direct step (:mod:`lbl_illum.engine.direct`) samples
it.  On the office a whole row of sensors lies 1 cm below the shadow of the window head
at one afternoon hour: the centre alone read them 14 % high.  The sun's light at the hits
of the daylight coefficients takes the centre alone.
Rays start at the sensors' own origins (:meth:`lbl_illum.engine.raycast.Tracer.sensor_origins`),
as the point-in-time direct light does, and are traced in batches of at most
``MAX_BATCH`` rays.
"""

from __future__ import annotations

import numpy as np

from ..daylight.sun import SUN_COS_HALF_ANGLE
from ..photometry import luminance
from ..scene.geometry import orthonormal_basis

__all__ = ["direct_sun_matrix", "sun_visibility", "MAX_BATCH"]

#: Most shadow rays traced in one call (bounds the temporaries).
MAX_BATCH = 1 << 20
#: Rays on the rim of the sun's disk that tell whether a point sees all of it, none of it
#: or part (a penumbra), and the directions over the disk that weigh a penumbra.
RIM_RAYS = 8
DISK_SAMPLES = 256


def sun_visibility(direct, tracer, points, normals, sun_directions, origins=None, rgb: bool = False,
                   pairs=None, disk: bool = False) -> np.ndarray:
    """(points, suns) float32 max(0, N_i · s) T_i(s): the direct illuminance [lux] at each
    point per lux of direct normal illuminance from each sun direction ``s`` (module
    docstring); ``rgb``: (points, 3, suns), T per channel, else its photometric value.

    direct : the :class:`~lbl_illum.engine.direct.DirectLight` of an integrator (its glass
        model gives τ(θ));  tracer : its :class:`~lbl_illum.engine.raycast.Tracer`
    points, normals : (n, 3) positions [m] and unit normals;  origins : (n, 3) where the
        shadow rays start (default: the sensors' own origins, :meth:`Tracer.sensor_origins`)
    sun_directions : (h, 3) unit vectors to the sun (x east, y north, z up); those at or
        below the horizon give zero columns
    pairs : (point, sun) index arrays of the only pairs to trace (the others are zero;
        the caller knows them dark), else every pair with N · s > 0
    disk : T over the sun's disk, not along its centre alone (:func:`_disk_transmittance`)
    """
    points = np.ascontiguousarray(points, np.float64).reshape(-1, 3)
    normals = np.asarray(normals, np.float64).reshape(-1, 3)
    normals = normals / np.linalg.norm(normals, axis=1, keepdims=True)
    s = np.asarray(sun_directions, np.float64).reshape(-1, 3)
    out = np.zeros((len(points), 3, len(s)) if rgb else (len(points), len(s)), np.float32)
    up = np.flatnonzero(s[:, 2] > 0.0)
    if len(points) == 0 or len(up) == 0:
        return out
    s_up = s[up] / np.linalg.norm(s[up], axis=1, keepdims=True)
    if origins is None:
        origins = tracer.sensor_origins(points, normals)
    cos = normals @ s_up.T                                   # (n, suns up)
    if pairs is None:
        point, sun = np.nonzero(cos > 0.0)
    else:
        rank = np.full(len(s), -1)
        rank[up] = np.arange(len(up))
        point, sun = np.asarray(pairs[0]), rank[np.asarray(pairs[1])]
        keep = sun >= 0
        point, sun = point[keep], sun[keep]
        keep = cos[point, sun] > 0.0
        point, sun = point[keep], sun[keep]
    for start in range(0, len(point), MAX_BATCH):
        p, k = point[start:start + MAX_BATCH], sun[start:start + MAX_BATCH]
        T = direct.transmittance(origins[p], s_up[k])
        if disk:
            T = _disk_transmittance(direct, origins[p], s_up[k], T)
        if rgb:
            out[p, :, up[k]] = (cos[p, k, None] * T).astype(np.float32)
        else:
            out[p, up[k]] = (cos[p, k] * luminance(T)).astype(np.float32)
    return out


def _disk_directions(s: np.ndarray, r2: np.ndarray, turn: np.ndarray) -> np.ndarray:
    """(m, k, 3) directions within the sun's disk about the (m, 3) unit ``s``: (k,) ``r2``
    in [0, 1] linear in the disk's area, ``turn`` in [0, 1) around it."""
    t, b = orthonormal_basis(s)
    cos_t = 1.0 - r2 * (1.0 - SUN_COS_HALF_ANGLE)
    sin_t = np.sqrt(np.maximum(0.0, 1.0 - cos_t * cos_t))
    phi = 2.0 * np.pi * turn
    return ((sin_t * np.cos(phi))[None, :, None] * t[:, None] + (sin_t * np.sin(phi))[None, :, None] * b[:, None]
            + cos_t[None, :, None] * s[:, None])


def _disk_transmittance(direct, origins, s, T_centre) -> np.ndarray:
    """(m, 3) T over the sun's disk: the centre's ``T_centre`` where :data:`RIM_RAYS` rays
    on the disk's rim agree with it (lit or not), else the mean over :data:`DISK_SAMPLES`
    directions at the centres of a square grid's cells mapped onto the disk (Shirley &
    Chiu's concentric map): a penumbra, where the edge of a window head or a fin crosses
    the disk.  Deterministic, as the annual figures should be."""
    from .direct import _concentric

    m = len(s)
    rim = _disk_directions(s, np.ones(RIM_RAYS), np.arange(RIM_RAYS) / RIM_RAYS)         # (m, R, 3)
    T_rim = direct.transmittance(np.repeat(origins, RIM_RAYS, axis=0), rim.reshape(-1, 3)).reshape(m, RIM_RAYS, 3)
    lit = T_centre.max(axis=1) > 0.0
    mixed = np.flatnonzero(~((T_rim.max(axis=2) > 0.0) == lit[:, None]).all(axis=1))
    if len(mixed) == 0:
        return T_centre
    g = int(round(np.sqrt(DISK_SAMPLES)))
    cell = (np.arange(g) + 0.5) / g
    r2, turn = _concentric(np.repeat(cell, g), np.tile(cell, g))
    out = T_centre.copy()
    per = max(1, MAX_BATCH // (g * g))
    for lo in range(0, len(mixed), per):
        rows = mixed[lo:lo + per]
        d = _disk_directions(s[rows], r2, turn).reshape(-1, 3)
        T = direct.transmittance(np.repeat(origins[rows], g * g, axis=0), d).reshape(len(rows), g * g, 3)
        out[rows] = T.mean(axis=1)
    return out


def direct_sun_matrix(direct, tracer, points, normals, sun_directions, direct_normal) -> np.ndarray:
    """(points, hours) float32 direct-sun illuminance [lux] (module docstring).

    direct, tracer, points, normals : as :func:`sun_visibility`
    sun_directions : (h, 3) unit vectors to the sun (x east, y north, z up)
    direct_normal : (h,) direct normal illuminance [lux]; hours with the sun below the
        horizon or no direct light are zero columns
    """
    s = np.asarray(sun_directions, np.float64).reshape(-1, 3)
    e_dn = np.asarray(direct_normal, np.float64).reshape(-1)
    if len(s) != len(e_dn):
        raise ValueError(f"{len(s)} sun directions for {len(e_dn)} hours")
    out = np.zeros((len(np.asarray(points).reshape(-1, 3)), len(s)), np.float32)
    up = np.flatnonzero((s[:, 2] > 0.0) & (e_dn > 0.0))
    if len(up):
        out[:, up] = sun_visibility(direct, tracer, points, normals, s[up], disk=True) * e_dn[up].astype(np.float32)
    return out

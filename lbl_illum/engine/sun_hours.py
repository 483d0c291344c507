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

One shadow ray per point and hour, to the disk's centre: the point-in-time direct step
(:mod:`lbl_illum.engine.direct`) samples the 0.53° disk to soften penumbrae; annual metrics
count hours above a threshold, where a penumbra a few millimetres wide changes nothing.
Rays start at the sensors' own origins (:meth:`lbl_illum.engine.raycast.Tracer.sensor_origins`),
as the point-in-time direct light does, and are traced in batches of at most
``MAX_BATCH`` rays.
"""

from __future__ import annotations

import numpy as np

from ..photometry import luminance

__all__ = ["direct_sun_matrix", "sun_visibility", "MAX_BATCH"]

#: Most shadow rays traced in one call (bounds the temporaries).
MAX_BATCH = 1 << 20


def sun_visibility(direct, tracer, points, normals, sun_directions, origins=None, rgb: bool = False,
                   pairs=None) -> np.ndarray:
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
        if rgb:
            out[p, :, up[k]] = (cos[p, k, None] * T).astype(np.float32)
        else:
            out[p, up[k]] = (cos[p, k] * luminance(T)).astype(np.float32)
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
        out[:, up] = sun_visibility(direct, tracer, points, normals, s[up]) * e_dn[up].astype(np.float32)
    return out

"""What an irradiance cache's records depend on: their fingerprint and its readable summary.

Records stay valid across runs (the paper's §3: a cache reused from a file) only while
the scene, its daylight and the options that change their values or domains stay the
same.  :func:`scene_fingerprint` hashes all of that; :func:`record_settings` says it in
words for a cache file's header, so that a refusal can name what differs.  Left out of
both, because records stay valid when they change: the seed, the spacing limits and the
query points.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json

import numpy as np

from ..options import Options
from ..scene.scenefile import Scene

__all__ = ["SIZING_VERSION", "scene_fingerprint", "record_settings", "plain_json"]


#: Version of the rules that make records' values and sizes (part of the fingerprint: a
#: cache file made with other rules is refused).  3: light limits from the portals in
#: closed form inside, zones (docs/architecture.md, "Record domains"); 4: the sun's images
#: in mirrors and panes are direct light (lbl_illum.engine.sunmirrors); 5: and in polished plastic,
#: with the sun's highlight on rough plastic seen by hemisphere rays; 6: images seen through
#: panes on the way to the reflector count (dimmed by them) instead of being dropped.
SIZING_VERSION = 6


def scene_fingerprint(scene: Scene, options: Options, portals=None) -> str:
    """Hash of everything the records depend on (not the seed, spacing or query points):
    the geometry, the materials, the daylight, the options that change records, the rule
    that sizes them (:data:`SIZING_VERSION`) and the ``portals`` (a
    :class:`~lbl_illum.engine.portals.PortalSet`), whose zones decide which records serve which
    queries."""
    h = hashlib.sha256()
    tri = scene.triangles
    for arr in (tri.vertices, tri.material, tri.sphere, tri.sphere_center, tri.sphere_radius):
        h.update(np.ascontiguousarray(arr).tobytes())
    if portals is not None:
        for arr in (portals.sampler.vertices, portals.outward, portals.enclosure):
            if arr is not None:
                h.update(np.ascontiguousarray(arr, np.float64).tobytes())
    desc = {
        "materials": [(m.kind, m.reflectance, m.transmittance, m.luminance, m.model, m.panes, m.index)
                      + ((m.specularity, m.roughness) if m.kind in ("plastic", "metal") else ())
                      for m in scene.materials],
        "sky": scene.sky.parameters,
        "sun": None if scene.sun is None else (scene.sun.altitude, scene.sun.azimuth,
                                               scene.sun.direct_normal_illuminance),
        "options": (options.ambient, [options.level_accuracy(k) for k in range(options.bounces + 1)],
                    [options.level_samples(k) for k in range(options.bounces + 1)]),
    }
    if scene.luminaires:
        # their photometry, luminous opening, placement and multiplier (only when there are
        # any, so that the fingerprints of scenes without luminaires are those of earlier versions)
        for lum in scene.luminaires:
            p = lum.photometry
            for arr in (p.horizontal, p.vertical, p.candela, lum.position, lum.frame):
                h.update(np.ascontiguousarray(arr, np.float64).tobytes())
        desc["luminaires"] = [(lum.photometry.kind, lum.photometry.symmetry, lum.multiplier,
                               dataclasses.astuple(lum.photometry.opening)) for lum in scene.luminaires]
    desc["sizing"] = SIZING_VERSION
    if options.interpolation == "hessian":      # other record radii
        desc["domains"] = "hessian"
    h.update(json.dumps(desc, sort_keys=True).encode())
    return h.hexdigest()



def record_settings(scene, options) -> dict:
    """A readable summary of what a cache's records depend on: the geometry's size and
    bounds [m], every material (all its parameters but its name and the portal flag), the
    sky's and the sun's parameters, and the options that change the records' values or
    domains (``domains`` is ``elliptical`` for ``interpolation = "hessian"``, else
    ``round``).  Left out, because records stay valid when they change: the seed, the
    spacing limits, the query points and the interpolation rule of round domains.  The
    portals are in the fingerprint (their zones decide which records serve which queries)
    but not in this summary.

    Written to the header of cache files and compared with the current summary when a
    file is refused, to name what differs.  Plain JSON types (lists, not tuples).
    """
    tri = scene.triangles
    bounds = tri.bounds if len(tri) else (np.zeros(3), np.zeros(3))
    materials = {}
    for m in scene.materials:
        d = dataclasses.asdict(m) if dataclasses.is_dataclass(m) else dict(vars(m))
        d.pop("portal", None)
        materials[str(d.pop("name", len(materials)))] = d
    sun = None
    if scene.sun is not None:
        sun = {"altitude": float(scene.sun.altitude), "azimuth": float(scene.sun.azimuth),
               "direct_normal_illuminance": float(scene.sun.direct_normal_illuminance)}
    B = options.bounces
    out = {
        "geometry": {"triangles": len(tri), "spheres": int(len(tri.sphere_radius)),
                     "bounds": [np.asarray(bounds[0]).tolist(), np.asarray(bounds[1]).tolist()]},
        "materials": materials,
        "sky": dict(scene.sky.parameters),
        "sun": sun,
        "accuracy": options.accuracy, "bounces": B, "samples": options.samples, "ambient": options.ambient,
        "bounce_scaling": options.bounce_scaling, "point_samples": options.point_samples,
        "domains": "elliptical" if options.interpolation == "hessian" else "round",
        "level_accuracy": [options.level_accuracy(k) for k in range(B + 1)],
        "level_samples": [options.level_samples(k) for k in range(B + 1)],
    }
    if scene.luminaires:
        out["luminaires"] = [{"name": lum.name, "file": lum.photometry.name, "position": lum.position.tolist(),
                              "aim": lum.aim.tolist(), "multiplier": lum.multiplier} for lum in scene.luminaires]
    return json.loads(json.dumps(out, default=plain_json))      # plain JSON types, as a file gives them back


def plain_json(value):
    """JSON for the numpy scalars and arrays a settings summary may hold."""
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, np.generic):
        return value.item()
    raise TypeError(f"{type(value).__name__} is not JSON serialisable")

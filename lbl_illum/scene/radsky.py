"""The sky and sun of a Radiance scene description: what ``gensky`` and ``gendaylit``
write, read as this package's sky and sun when the scene file gives neither.

``gensky`` (``skybright.cal``) and ``gendaylit`` (``perezlum.cal``) write a ``brightfunc``
(``skyfunc``) that a ``glow`` modifies, on ``source`` hemispheres, and the sun as a
``light`` on a ``source`` of 0.5°:

* sun: ``void light solar 0 0 3 R G B`` and ``solar source sun 0 0 4 x y z a`` → a sun at
  the direction (x, y, z) of direct normal illuminance 179 · Y(R, G, B) · Ω, Ω = 2π (1 −
  cos(a/2)) the disk's solid angle (Y the luminance of the colour, :mod:`lbl_illum.photometry`);
* ``skybright.cal``, arguments A1 … A7 (type, zenith brightness, ground brightness,
  normalisation, sun direction): type 1 (``gensky +s``/``-s``, the CIE clear sky, which is
  CIE general sky 12), 2 (``-c``, CIE overcast) and 3 (``-u``, uniform), their zenith
  luminance 179 · Y(glow) times the formula's value at the zenith; type 4 (``-i``, an
  intermediate sky that is none of the CIE general skies) is refused;
* ``perezlum.cal``, A1 … A10 (diffuse normalisation, ground brightness, the Perez
  coefficients a … e, sun direction): a Perez sky of those coefficients,
  L = 179 · Y(glow) · A1 · lv (:class:`~lbl_illum.daylight.sky.PerezSky` with the
  coefficients given);
* the ground: the ground brightness gives the ground glow's luminance, 179 · Y · A,
  turned into the reflectance ρ_g = π L_g / (E_h + E_sun, h) of this package's ground glow.

Radiance blends sky and ground within a few degrees of the horizon (``wmean`` of the two
with weights (Dz + 1.01)^±10); here the sky ends at the horizon, as this package's skies do.
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import InputError
from ..photometry import RADIANCE_WHITE_EFFICACY, luminance

__all__ = ["radiance_daylight"]


def _colour(prim) -> float:
    return float(luminance(np.asarray(prim.reals[:3], np.float64)[None])[0])


def _alt_az(d) -> tuple[float, float]:
    d = np.asarray(d, np.float64)
    d = d / np.linalg.norm(d)
    return math.degrees(math.asin(np.clip(d[2], -1.0, 1.0))), math.degrees(math.atan2(d[0], d[1])) % 360.0


def radiance_daylight(prims, where: str):
    """``(sky, sun, note)`` from the primitives of a scene's Radiance files, or None when
    they describe no sky (module text).  ``sun`` is None without a ``solar`` source."""
    from ..daylight.sky import PerezSky, sky_from_table
    from ..daylight.sun import Sun

    by_name = {p.name: p for p in prims}
    funcs = [p for p in prims if p.kind == "brightfunc" and len(p.strings) >= 2
             and _file_name(p.strings[1]) in ("skybright.cal", "perezlum.cal")]
    sun = None
    sources = [p for p in prims if p.kind == "source" and len(p.reals) == 4]
    for s in sources:
        light = by_name.get(s.modifier)
        if light is not None and light.kind == "light" and len(light.reals) >= 3:
            half = math.radians(s.reals[3]) / 2.0
            omega = 2.0 * math.pi * (1.0 - math.cos(half))
            alt, az = _alt_az(s.reals[:3])
            sun = Sun(altitude=alt, azimuth=az,
                      direct_normal_illuminance=RADIANCE_WHITE_EFFICACY * _colour(light) * omega)
            break
    if not funcs:
        return None if sun is None else (None, sun, "the sun of a Radiance 'source'")
    func = funcs[0]
    label = f"{where}: line {func.line}: brightfunc '{func.name}'"
    glows = [p for p in prims if p.kind == "glow" and p.modifier == func.name and len(p.reals) >= 3]
    factor = RADIANCE_WHITE_EFFICACY * (_colour(glows[0]) if glows else 1.0)
    a = func.reals
    sun_h = sun.direct_normal_illuminance * max(math.sin(math.radians(sun.altitude)), 0.0) if sun else 0.0
    if _file_name(func.strings[1]) == "skybright.cal":
        if len(a) != 7:
            raise InputError(f"{label}: skybright.cal needs 7 real arguments, got {len(a)}")
        kind, zenith_brightness, ground, norm = int(a[0]), a[1], a[2], a[3]
        sdir = a[4:7]
        zt = math.acos(np.clip(sdir[2] / max(np.linalg.norm(sdir), 1e-300), -1.0, 1.0))
        if kind == 1:
            lz = zenith_brightness * (0.91 + 10 * math.exp(-3 * zt) + 0.45 * math.cos(zt) ** 2) \
                * (1 - math.exp(-0.32)) / norm
            table = {"type": "cie-clear", "zenith_luminance": factor * lz}
        elif kind in (2, 3):
            table = {"type": "cie-overcast" if kind == 2 else "uniform", "zenith_luminance": factor * zenith_brightness}
        else:
            raise InputError(f"{label}: skybright.cal sky type {kind} (gensky -i's intermediate sky) is not read; "
                             "give the scene file a [sky] table")
        alt, az = _alt_az(sdir)
        probe = sky_from_table(table, label, sun_h, (alt, az))
        rho = _ground(factor * ground, probe.horizontal_illuminance + sun_h)
        sky = sky_from_table({**table, "ground_reflectance": rho}, label, sun_h, (alt, az))
        return sky, sun, f"the {table['type']} sky of gensky (skybright.cal)"
    if len(a) != 10:
        raise InputError(f"{label}: perezlum.cal needs 10 real arguments, got {len(a)}")
    alt, az = _alt_az(a[7:10])
    sky = PerezSky.from_coefficients(tuple(float(v) for v in a[2:7]), alt, az, factor * a[0], sun_h)
    rho = _ground(factor * a[1], sky.horizontal_illuminance + sun_h)
    sky = PerezSky.from_coefficients(tuple(float(v) for v in a[2:7]), alt, az, factor * a[0], sun_h, rho)
    return sky, sun, "the Perez sky of gendaylit (perezlum.cal)"


def _ground(luminance_g: float, horizontal: float) -> float:
    """ρ_g giving a ground glow of ``luminance_g`` [cd/m²] under ``horizontal`` [lux]."""
    if horizontal <= 0.0:
        return 0.0
    return float(min(1.0, max(0.0, math.pi * luminance_g / horizontal)))


def _file_name(text: str) -> str:
    """The file name of a Radiance argument (a path or a name)."""
    return text.replace("\\", "/").rsplit("/", 1)[-1]

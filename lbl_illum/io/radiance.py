"""Export a scene as an equivalent Radiance scene (``lbl-illum export radiance``).

The export writes, into one folder, a scene in Radiance's own language (Ward, "The
RADIANCE Lighting Simulation and Rendering System", SIGGRAPH 1994; Larson & Shakespeare,
*Rendering with Radiance*, 1998) that describes the same light transport as ours, so that
``oconv`` and ``rtrace -I`` compute the same illuminance at the same sensor points:

===================  =================================================================
file                 contents
===================  =================================================================
``materials.rad``    one Radiance material per scene material (see :func:`material_primitive`)
``sky.rad``          the sky and ground glow (``brightfunc`` ``skyfunc`` on two ``glow``
                     hemispheres) and the sun (a ``light`` ``source``)
``lbl_sky.cal``      the sky luminance models of :mod:`lbl_illum.daylight.sky` in Radiance's ``.cal``
                     language (only when there is a sky)
``lbl_glazing.cal``  the Fresnel glazing of :mod:`lbl_illum.scene.materials` for ``BRTDfunc``
                     (:data:`GLAZING_CAL`; only when a double pane is exported)
``geometry.rad``     triangles as ``polygon`` s grouped by material, sphere primitives as
                     ``sphere`` s, and, for large scenes, one ``mesh`` primitive
``geometry.obj``,    the large-scene path: the plastic and glass triangles as a Wavefront
``geometry.rtm``     OBJ compiled by ``obj2mesh`` (far faster to ``oconv`` than polygons)
``luminaires.rad``   the luminaires of photometric files: per luminaire a ``brightdata`` of
                     its intensity table on a small ``light`` sphere, as ``ies2rad`` writes
                     them (:func:`luminaire_description`; only when there are luminaires)
``lum_N.dat``,       their intensity tables (Radiance data files [W/sr]) and the angles in
``lbl_luminaires.cal`` each luminaire's frame
``points.pts``       the sensor points, ``x y z nx ny nz`` per line [m]
``README.txt``       the ``oconv`` and ``rtrace`` command lines that reproduce a run
===================  =================================================================

Units.  Lengths are in metres (the scene's lengths after ``Scene.unit_scale``).  Light:
our RGB channels are photometric (a grey (L, L, L) has luminance L cd/m²,
:mod:`lbl_illum.photometry`); Radiance works in radiometric units with a luminous
efficacy of 179 lm/W for its white, so each channel is divided by 179:
``L_radiance [W sr⁻¹ m⁻²] = L [cd/m²] / 179`` and, back, ``E [lux] = 179 · E_radiance``.
Radiance takes the photometric value of an RGB triple with its own weights
(0.265, 0.670, 0.065) where we use Rec. 709's (0.2126, 0.7152, 0.0722); for grey
light, which is all of the sky and sun, the two agree exactly.
"""

from __future__ import annotations

import math
import os
import re
import shutil
import subprocess
import tempfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable, Sequence

import numpy as np

from .._version import __version__
from ..errors import InputError
from .files import atomic_write_text
from ..scene.geometry import SPHERE_SUBDIVISIONS
from ..scene.materials import GLASS_INDEX, Material, pane_transmissivity
from ..daylight.sun import SUN_SOLID_ANGLE
from ..photometry import RADIANCE_WHITE_EFFICACY

__all__ = [
    "RADIANCE_EFFICACY", "RADIANCE_RGB_WEIGHTS", "MESH_THRESHOLD", "GLASS_MODELS", "SKY_MODEL_CODES",
    "RadianceExport", "export_radiance", "radiance_programs", "illuminance_from_rtrace",
    "to_radiance", "from_radiance", "glass_transmissivity", "glass_transmittance", "sun_source_angle",
    "material_primitive", "glass_export", "GLAZING_CAL", "sky_description", "ambient_options", "radiance_name",
    "merge_coplanar",
]

#: Radiance's luminous efficacy of its white light [lm/W] (``WHTEFFICACY`` in color.h).
RADIANCE_EFFICACY = RADIANCE_WHITE_EFFICACY
#: Radiance's RGB → luminance weights (``bright()``: CIE Y of its default RGB primaries).
RADIANCE_RGB_WEIGHTS = (0.265, 0.670, 0.065)
#: Above this many plastic/glass triangles, and when ``obj2mesh`` is found, the geometry
#: goes into one compiled ``mesh`` instead of one ``polygon`` per triangle.
MESH_THRESHOLD = 20_000
#: Ways of writing our glass (:func:`material_primitive`): ``auto`` the equivalent of each
#: glass's model (Fresnel single pane → ``glass``, Fresnel double pane → ``BRTDfunc`` with
#: ``lbl_glazing.cal``, constant → ``BRTDfunc`` with constants); ``glass`` Radiance's
#: ``glass`` for every glass; ``brtdfunc`` constant coefficients (the normal-incidence
#: values) for every glass.
GLASS_MODELS = ("auto", "glass", "brtdfunc")
#: Sky models of :mod:`lbl_illum.daylight.sky` and their selector (A1) in ``lbl_sky.cal``.
SKY_MODEL_CODES = {"uniform": 1, "cie-overcast": 2, "cie-general": 3, "perez": 4}
#: Offset [m] of the two back-to-back copies of a ``light`` or ``mirror`` surface: Radiance
#: draws both one-sided (the back of a light polygon emits nothing, the back of a
#: mirror is black), ours are two-sided.  Larger than Radiance's intersection tolerance
#: (FTINY = 1e-6 scene units).
TWO_SIDED_OFFSET = 1e-5
#: Light triangles of one material are merged into convex polygons (see
#: :func:`merge_coplanar`) up to this many; more are written as they are.
MAX_MERGED_LIGHT_TRIANGLES = 10_000
#: rtrace's default ambient resolution, written out when the record spacing is not known
#: (rpict's default is 64).
RADIANCE_DEFAULT_AR = 256
#: Radiance's largest ambient record radius is 64 cube / ar (ambient.c, ``setambres``).
RADIANCE_MAXARAD_FACTOR = 64.0
#: ``-lw``: Radiance drops rays whose weight falls below this; the default (1e-4) can cut
#: the deep diffuse bounces our ``bounces`` still follows.
LIMIT_WEIGHT = 1e-5

_SCENE_FILES = ("materials.rad", "sky.rad", "geometry.rad")
_OCTREE = "scene.oct"
_POINTS = "points.pts"
_CAL = "lbl_sky.cal"
_GLAZING_CAL = "lbl_glazing.cal"
_LUMINAIRES = "luminaires.rad"
_LUMINAIRE_CAL = "lbl_luminaires.cal"
#: Radius [m] of the ``light`` sphere a luminaire is drawn as (a point for its direct light:
#: 1e-4 of the distance at 5 m).
LUMINAIRE_RADIUS = 0.0005


# ---------------------------------------------------------------------------
# Unit and material conversions
# ---------------------------------------------------------------------------

def to_radiance(value):
    """Photometric channel values [cd/m² or lux] → Radiance's radiometric ones [W/(sr m²) or W/m²]:
    divide by 179 lm/W."""
    return np.asarray(value, dtype=np.float64) / RADIANCE_EFFICACY


def from_radiance(value):
    """Radiance's radiometric channel values → photometric ones: multiply by 179 lm/W."""
    return np.asarray(value, dtype=np.float64) * RADIANCE_EFFICACY


def _pane_reflection(index: float = GLASS_INDEX) -> float:
    """Single-interface normal-incidence reflectance ((n − 1)/(n + 1))² [-]."""
    return ((index - 1.0) / (index + 1.0)) ** 2


def glass_transmittance(transmissivity, index: float = GLASS_INDEX):
    """Normal-incidence transmittance T of Radiance's ``glass`` with transmissivity tn.

    Two Fresnel interfaces of reflectance r = ((n−1)/(n+1))² with internal
    transmissivity tn between them, all inter-reflections summed (glass.c):
    T = (1 − r)² tn / (1 − r² tn²).
    """
    t = np.asarray(transmissivity, dtype=np.float64)
    r = _pane_reflection(index)
    return (1.0 - r) ** 2 * t / (1.0 - r * r * t * t)


def glass_transmissivity(transmittance, index: float = GLASS_INDEX):
    """Transmissivity tn that gives Radiance's ``glass`` the normal-incidence transmittance T.

    The inverse of :func:`glass_transmittance` (one pane of
    :func:`lbl_illum.scene.materials.pane_transmissivity`), the positive root of
    T r² tn² + (1 − r)² tn − T = 0:  tn = (√((1 − r)⁴ + 4 r² T²) − (1 − r)²) / (2 r² T).
    For n = 1.52 this is the formula of Radiance's glass.c and reference manual,
    tn = (√(0.8402528435 + 0.0072522239 T²) − 0.9166530661) / 0.0036261119 / T, here with
    unrounded constants (the rounded ones lose 1e-4 of T at T = 0.01 to cancellation).
    T = 0 gives 0; clear glass (T = 0.88) gives 0.96.
    """
    return pane_transmissivity(transmittance, index, 1)


def sun_source_angle() -> float:
    """Full angle [deg] of a Radiance ``source`` whose solid angle 2π(1 − cos(angle/2))
    is the sun's 6.8e-5 sr of :mod:`lbl_illum.daylight.sun` (0.5323°)."""
    return 2.0 * math.degrees(math.acos(1.0 - SUN_SOLID_ANGLE / (2.0 * math.pi)))


def radiance_name(name: str, taken: set | None = None) -> str:
    """``name`` as a Radiance identifier (no white space, not ``void``), unique in ``taken``
    (which is updated)."""
    base = re.sub(r"[^A-Za-z0-9_.+\-]", "_", name) or "material"
    if base == "void":
        base = "void_"
    out, k = base, 1
    while taken is not None and out in taken:
        k += 1
        out = f"{base}_{k}"
    if taken is not None:
        taken.add(out)
    return out


def _g(x: float) -> str:
    return f"{float(x):.9g}"


def _rgb(values) -> str:
    return " ".join(_g(v) for v in values)


GLAZING_CAL = """\
{ lbl_glazing.cal: the Fresnel glazing of lbl_illum (lbl_illum/scene/materials.py), written by
  lbl-illum export radiance, for
    void BRTDfunc NAME
    10 glz_rr glz_rg glz_rb glz_tr glz_tg glz_tb 0 0 0 lbl_glazing.cal
    0
    14 0 0 0 0 0 0 0 0 0 n tn_r tn_g tn_b panes
  n: refractive index;  tn: internal transmissivity of each pane at normal incidence;
  panes: 1 or 2.  One pane is Radiance's glass (glass.c) exactly: two interfaces, all
  internal reflections summed, s and p polarisations averaged.  Two identical panes sum
  the reflections between them per polarisation.  The ray goes straight through. }

sq(x) = x*x;
glz_n = arg(10);
glz_ci = if(abs(RdotP) - 1e-9, abs(RdotP), 1e-9);
glz_ct = sqrt(1 - (1 - glz_ci*glz_ci)/(glz_n*glz_n));
glz_rs = sq((glz_ci - glz_n*glz_ct)/(glz_ci + glz_n*glz_ct));
glz_rp = sq((glz_ct - glz_n*glz_ci)/(glz_ct + glz_n*glz_ci));
{ internal transmittance along the refracted path: tn^(1/cos theta_t) }
glz_d(tn) = if(tn - 1e-30, exp(log(tn)/glz_ct), 0);
{ one pane of interface reflectance r and internal transmittance d }
pane_t(r, d) = sq(1 - r)*d/(1 - sq(r*d));
pane_r(r, d) = r*(1 + (1 - 2*r)*d*d)/(1 - sq(r*d));
{ two identical panes }
unit_t(r, d) = sq(pane_t(r, d))/(1 - sq(pane_r(r, d)));
unit_r(r, d) = pane_r(r, d) + sq(pane_t(r, d))*pane_r(r, d)/(1 - sq(pane_r(r, d)));
glz_t(r, d) = select(arg(14), pane_t(r, d), unit_t(r, d));
glz_r(r, d) = select(arg(14), pane_r(r, d), unit_r(r, d));
glz_trans(tn) = (glz_t(glz_rs, glz_d(tn)) + glz_t(glz_rp, glz_d(tn)))/2;
glz_refl(tn) = (glz_r(glz_rs, glz_d(tn)) + glz_r(glz_rp, glz_d(tn)))/2;

glz_tr = glz_trans(arg(11));  glz_tg = glz_trans(arg(12));  glz_tb = glz_trans(arg(13));
glz_rr = glz_refl(arg(11));   glz_rg = glz_refl(arg(12));   glz_rb = glz_refl(arg(13));
"""


def glass_export(material: Material, glass: str = "auto") -> str:
    """How :func:`material_primitive` writes a glass: ``"glass"`` (Radiance's ``glass``),
    ``"brtdfunc-cal"`` (``BRTDfunc`` with :data:`GLAZING_CAL`) or ``"brtdfunc"``
    (``BRTDfunc`` with constant coefficients)."""
    if glass not in GLASS_MODELS:
        raise ValueError(f"glass model must be one of {GLASS_MODELS}, got {glass!r}")
    if glass == "glass":
        return "glass"
    if glass == "brtdfunc" or not material.fresnel:
        return "brtdfunc"
    return "glass" if material.panes == 1 else "brtdfunc-cal"


def material_primitive(rad_name: str, material: Material, glass: str = "auto") -> str:
    """Radiance description of one material, named ``rad_name``.

    * ``diffuse`` → ``plastic`` with the reflectance RGB, specularity 0, roughness 0
      (plastic without a specular part is Lambertian);
    * ``glass`` with ``glass = "auto"`` (default), the equivalent of its model:
      Fresnel, one pane → ``glass`` with transmissivity from :func:`glass_transmissivity`
      (and the refractive index as a fourth argument when it is not 1.52); Fresnel, two
      panes → ``BRTDfunc`` whose coefficients are the functions of ``lbl_glazing.cal``
      (:data:`GLAZING_CAL`, written by the export); constant → ``BRTDfunc`` with constant
      specular reflectance and transmittance and no diffuse part.  ``glass = "glass"``
      writes every glass as Radiance's ``glass`` with the same normal-incidence
      transmittance, ``"brtdfunc"`` every glass with constant (normal-incidence)
      coefficients: both only approximate the glass of another model;
    * ``mirror`` → ``mirror`` with the reflectance RGB;
    * ``plastic`` → ``plastic`` with the colour RGB, the specularity and the roughness
      (the same model: :mod:`lbl_illum.scene.materials`); ``metal`` → ``metal`` likewise;
    * ``light`` → ``light`` with radiance = luminance / 179 per channel;
    * ``translucent`` (ρ, τ) → ``trans`` with colour C = ρ + τ, no specular part and
      transmitted share τ/(ρ + τ) (Radiance's trans reflects C (1 − t_d) and transmits
      C t_d diffusely), or, when that share differs between channels, a ``BRTDfunc``
      with diffuse reflectance ρ on both faces and diffuse transmittance τ.
    """
    if material.kind == "diffuse":
        return f"void plastic {rad_name}\n0\n0\n5 {_rgb(material.reflectance)} 0 0\n"
    if material.kind in ("plastic", "metal"):
        return (f"void {material.kind} {rad_name}\n0\n0\n5 {_rgb(material.reflectance)} {_g(material.specularity)} "
                f"{_g(material.roughness)}\n")
    if material.kind == "mirror":
        return f"void mirror {rad_name}\n0\n0\n3 {_rgb(material.reflectance)}\n"
    if material.kind == "translucent":
        rho, tau = np.array(material.reflectance), np.array(material.transmittance)
        C = rho + tau
        share = (tau / np.where(C > 0, C, 1.0))[C > 0]
        if len(share) == 0 or np.ptp(share) <= 1e-9:
            t_d = float(share[0]) if len(share) else 0.0
            return f"void trans {rad_name}\n0\n0\n7 {_rgb(C)} 0 0 {_g(t_d)} 0\n"
        return (f"void BRTDfunc {rad_name}\n10 0 0 0 0 0 0 0 0 0 .\n0\n"
                f"9 {_rgb(rho)} {_rgb(rho)} {_rgb(tau)}\n")
    if material.kind == "light":
        return f"void light {rad_name}\n0\n0\n3 {_rgb(to_radiance(material.luminance))}\n"
    if material.kind == "glass":
        how = glass_export(material, glass)
        if how == "brtdfunc":
            refl = " ".join(_g(v) for v in material.reflectance)
            trans = " ".join(_g(v) for v in material.transmittance)
            return (f"void BRTDfunc {rad_name}\n10 {refl} {trans} 0 0 0 .\n0\n"
                    "9 0 0 0 0 0 0 0 0 0\n")
        index = material.index if material.fresnel else GLASS_INDEX
        if how == "brtdfunc-cal":
            tn = pane_transmissivity(np.array(material.transmittance, np.float64), index, material.panes)
            return (f"void BRTDfunc {rad_name}\n10 glz_rr glz_rg glz_rb glz_tr glz_tg glz_tb 0 0 0 {_GLAZING_CAL}\n"
                    f"0\n14 0 0 0 0 0 0 0 0 0 {_g(index)} {_rgb(tn)} {material.panes}\n")
        tn = glass_transmissivity(material.transmittance, index)
        if index == GLASS_INDEX:
            return f"void glass {rad_name}\n0\n0\n3 {_rgb(tn)}\n"
        return f"void glass {rad_name}\n0\n0\n4 {_rgb(tn)} {_g(index)}\n"
    if material.kind == "opening":      # its faces are portals, not surfaces: nothing to write
        return f"# {rad_name}: an opening (sampled as a portal, seen by no ray): no Radiance material\n"
    raise ValueError(f"unknown material kind {material.kind!r}")


# ---------------------------------------------------------------------------
# Sky and sun
# ---------------------------------------------------------------------------

SKY_CAL = """\
{ lbl_sky.cal: the sky luminance models of lbl_illum (lbl_illum/daylight/sky.py), written by
  lbl-illum export radiance.  Used as  void brightfunc skyfunc 2 lbl_sky lbl_sky.cal 0 N A1 A2 ...
  on two glow hemispheres (sky above, ground below the horizon).

  A1: model, 1 = uniform, 2 = cie-overcast (CIE traditional overcast, Moon & Spencer 1942),
      3 = cie-general (ISO 15469 / CIE S 011), 4 = perez (Perez, Seals & Michalsky 1993)
  A2: uniform: the sky radiance;  cie-overcast: the zenith radiance;
      cie-general: L_z / (f(Z_s) phi(0));  perez: E_dh / integral(lv cos Z)  [W/(sr m2)]
  A3: ground radiance, rho_g E_gh / pi / 179, uniform below the horizon  [W/(sr m2)]
  A4..A8: cie-general and perez: the coefficients a b c d e
  A9..A11: cie-general and perez: unit vector towards the sun (+x east, +y north, +z up)
  Dx, Dy, Dz: the ray direction; Dz = cos Z = sin(altitude).
  No blending of sky and ground at the horizon (unlike gensky's skybright.cal). }

uniform_sky = A2;
cie_overcast_sky = A2 * (1 + 2*Dz) / 3;

{ angle chi between the ray and the sun (rayinit.cal names only A1..A10: arg(11) here) }
clip1(x) = if(x - 1, 1, if(-1 - x, -1, x));
cos_chi = clip1(Dx*arg(9) + Dy*arg(10) + Dz*arg(11));
chi = acos(cos_chi);
{ exp of an argument that may be hugely negative (b / cos Z near the horizon) }
exp_neg(x) = if(x + 700, exp(x), 0);

{ CIE general sky: gradation phi(Z) = 1 + a exp(b / cos Z), exactly 1 at the horizon;
  indicatrix f(chi) = 1 + c (exp(d chi) - exp(d pi/2)) + e cos^2 chi }
cie_gradation = if(Dz, 1 + A4 * exp_neg(A5 / Dz), 1);
cie_indicatrix = 1 + A6 * (exp(A7 * chi) - exp(A7 * 1.5707963267948966)) + A8 * cos_chi * cos_chi;
cie_general_sky = A2 * cie_gradation * cie_indicatrix;

{ Perez all-weather sky: cos Z held at 0.01 or more (as perezlum.cal), negative values set to 0 }
perez_cosz = if(Dz - 0.01, Dz, 0.01);
perez_lv = (1 + A4 * exp_neg(A5 / perez_cosz)) * (1 + A6 * exp(A7 * chi) + A8 * cos_chi * cos_chi);
perez_sky = A2 * if(perez_lv, perez_lv, 0);

sky_radiance = select(A1, uniform_sky, cie_overcast_sky, cie_general_sky, perez_sky);
{ z >= 0 is sky, as in lbl_illum }
lbl_sky = if(-Dz, A3, sky_radiance);
"""


def _sky_comment(sky) -> str:
    """An ASCII line describing the sky for ``sky.rad``."""
    text = f"{sky.name} sky"
    if sky.name == "cie-general":
        text += f" type {sky.sky_type}"
    elif sky.name == "perez":
        text += f" (epsilon {_g(sky.clearness)}, delta {_g(sky.brightness)})"
    text += f", unobstructed horizontal illuminance {_g(sky.horizontal_illuminance)} lux"
    if sky.sun_direction is not None:
        text += f", sun at altitude {_g(sky.sun_altitude)} deg, azimuth {_g(sky.sun_azimuth)} deg"
    return text


def sky_description(sky, sun) -> tuple[str, str | None]:
    """``(sky.rad text, lbl_sky.cal text or None)`` for a :class:`~lbl_illum.daylight.sky.Sky` and
    an optional :class:`~lbl_illum.daylight.sun.Sun`.

    Sky: ``void brightfunc skyfunc`` (``lbl_sky.cal``, :data:`SKY_CAL`: the same formulas as
    :mod:`lbl_illum.daylight.sky`, with the model's scale, coefficients and sun direction as real
    arguments) modifying two ``glow`` s of unit
    colour on ``source`` hemispheres (solid angle 180°) towards +z and −z; the glows have
    no maximum radius, so they are not light sources of the direct calculation — the
    ambient (indirect) calculation samples them, as ours does (the paper's §5).
    Sun: a ``light`` on a ``source`` of the same solid angle as ours (6.8e-5 sr) towards
    the sun, radiance L = E_dn / (179 Ω) per channel, so that its normal irradiance
    × 179 is E_dn.  Omitted when the sun is below the horizon or has E_dn = 0.
    """
    parts = [f"# sky and sun written by lbl-illum {__version__}; radiance = luminance / 179 per channel\n"]
    cal = None
    if sky.name != "none" and not sky.is_dark:
        if sky.name not in SKY_MODEL_CODES:
            raise ValueError(f"no Radiance version of sky model {sky.name!r}")
        code = SKY_MODEL_CODES[sky.name]
        if sky.name in ("cie-general", "perez"):
            scale = sky.luminance_scale
            sun_dir = sky.sun_direction                     # None: a type that ignores the sun
            extra = [*sky.coefficients, *(sun_dir if sun_dir is not None else (0.0, 0.0, 1.0))]
        else:
            scale = sky.zenith_luminance if sky.name == "cie-overcast" else sky.horizontal_illuminance / math.pi
            extra = []
        A2, A3 = to_radiance(scale), to_radiance(sky.ground_luminance)
        args = " ".join(_g(v) for v in (code, A2, A3, *extra))
        parts.append(
            f"# {_sky_comment(sky)}; ground glow {_g(sky.ground_luminance)} cd/m2 "
            f"(reflectance {_g(sky.ground_reflectance)})\n"
            f"void brightfunc skyfunc\n2 lbl_sky {_CAL}\n0\n{3 + len(extra)} {args}\n\n"
            "skyfunc glow sky_glow\n0\n0\n4 1 1 1 0\n\n"
            "sky_glow source sky\n0\n0\n4 0 0 1 180\n\n"
            "skyfunc glow ground_glow\n0\n0\n4 1 1 1 0\n\n"
            "ground_glow source ground\n0\n0\n4 0 0 -1 180\n\n")
        cal = SKY_CAL
    if sun is not None and sun.is_up:
        L = to_radiance(sun.luminance)
        d = sun.direction
        parts.append(
            f"# sun: altitude {_g(sun.altitude)} deg, azimuth {_g(sun.azimuth)} deg, "
            f"direct normal illuminance {_g(sun.direct_normal_illuminance)} lux\n"
            f"void light solar\n0\n0\n3 {_g(L)} {_g(L)} {_g(L)}\n\n"
            f"solar source sun\n0\n0\n4 {_rgb(d)} {_g(sun_source_angle())}\n")
    return "".join(parts), cal


# ---------------------------------------------------------------------------
# Ambient options
# ---------------------------------------------------------------------------

LUMINAIRE_CAL = """\
{ lbl_luminaires.cal: the emission direction of a luminaire's ray in its own frame and its
  photometric angles (lbl_illum/scene/photometric.py), written by lbl_illum.
  A2..A10: the frame's rows x (C0), y (C90), z (up) in scene coordinates; the ray arrives
  along D, so the light leaves along -D.  A1: W/sr per unit of the data file over the
  sphere's projected area. }
lbl_x = -(Dx*A2 + Dy*A3 + Dz*A4);
lbl_y = -(Dx*A5 + Dy*A6 + Dz*A7);
lbl_z = -(Dx*A8 + Dy*A9 + Dz*A10);
lbl_gamma = acos(bound(-1, -lbl_z, 1)) / DEGREE;
lbl_c = mod(atan2(lbl_y, lbl_x) / DEGREE, 360);
lbl_bh = atan2(-lbl_y, -lbl_z) / DEGREE;
lbl_bv = asin(bound(-1, lbl_x, 1)) / DEGREE;
lbl_lum(v) = A1 * v;
"""


def luminaire_table(photometry) -> tuple[list[np.ndarray], np.ndarray]:
    """The intensity table [cd] of a :class:`~lbl_illum.scene.photometric.Photometry` over
    its whole domain, for a Radiance data file: ``(axes, values)``, axes the node angles
    [deg] (type C: C over 0..360 and γ over 0..180, or γ alone for an axial one; type B:
    H over −180..180 and V over −90..90), values (len(axes[0]), ...).  The planes a
    symmetry implies are written out as mirror images of the file's nodes, and where the
    table stops short of the domain a node 1e-3° past its edge and one at the domain's
    edge carry 0, so Radiance's linear interpolation gives what ours does."""
    p = photometry
    pad = 1e-3
    if p.kind == "B":
        h = p.horizontal if p.symmetry != "lateral" else np.union1d(-p.horizontal, p.horizontal)
        h_dom, v_dom = (-180.0, 180.0), (-90.0, 90.0)
    else:
        c = p.horizontal
        if p.symmetry == "quadrant":
            c = np.concatenate([c, 180.0 - c, 180.0 + c, 360.0 - c])
        elif p.symmetry == "c0-c180":
            c = np.concatenate([c, 360.0 - c])
        elif p.symmetry == "c90-c270":
            c = np.concatenate([c, np.mod(180.0 - c, 360.0)])
        h = np.unique(np.round(np.concatenate([c, [0.0, 360.0]]) if p.symmetry != "axial" else c, 9))
        h_dom, v_dom = (0.0, 360.0), (0.0, 180.0)

    def padded(nodes, lo, hi):
        inside = nodes.copy()
        extra = []
        if nodes[0] > lo + pad:
            extra += [lo, nodes[0] - pad]
        if nodes[-1] < hi - pad:
            extra += [nodes[-1] + pad, hi]
        return np.union1d(inside, extra)

    v = padded(p.vertical, *v_dom)
    if p.kind == "B":
        h = padded(h, *h_dom)
    V_in = (v >= p.vertical[0] - 1e-9) & (v <= p.vertical[-1] + 1e-9)
    if p.kind == "C" and p.symmetry == "axial":
        values = np.where(V_in, p.intensity(p.direction(np.zeros(len(v)), v)), 0.0)
        return [v], values
    H, Vg = np.meshgrid(h, v, indexing="ij")
    values = p.intensity(p.direction(H.ravel(), Vg.ravel())).reshape(H.shape)
    values[:, ~V_in] = 0.0
    if p.kind == "B":
        values[(h < -90.0 - 1e-9) | (h > 90.0 + 1e-9), :] = 0.0
    return [h, v], values


def _data_file(axes, values) -> str:
    """A Radiance data file (``brightdata``): the number of dimensions, each axis as
    ``0 0 n`` and its nodes, then the values, the last axis varying fastest."""
    out = [f"{len(axes)}\n"]
    for ax in axes:
        out.append(f"0 0 {len(ax)}\n" + _wrapped(ax) + "\n")
    out.append(_wrapped(np.asarray(values).ravel()) + "\n")
    return "".join(out)


def _wrapped(values, per_line: int = 6) -> str:
    items = [f"{float(x):.9g}" for x in values]
    return "\n".join(" ".join(items[i:i + per_line]) for i in range(0, len(items), per_line))


def luminaire_description(luminaires) -> dict[str, str]:
    """The files of the scene's luminaires (module text): ``luminaires.rad``, one data file
    per luminaire and ``lbl_luminaires.cal``.  Each luminaire is a ``light`` sphere of
    radius :data:`LUMINAIRE_RADIUS` at its photometric centre whose radiance along a ray
    is I(ω) / (π r²) [W sr⁻¹ m⁻²], I from its data file [cd / 179]: what the sphere sends
    along ω is then I(ω), a point source for every receiver beyond a few centimetres (the
    same model as ours)."""
    files = {_LUMINAIRE_CAL: LUMINAIRE_CAL}
    text = [f"# written by lbl-illum {__version__}: luminaires as light spheres of radius "
            f"{LUMINAIRE_RADIUS:g} m with brightdata intensity tables (W/sr = cd / {RADIANCE_EFFICACY:g})\n"]
    for k, lum in enumerate(luminaires):
        axes, values = luminaire_table(lum.photometry)
        data = f"lum_{k}.dat"
        files[data] = _data_file(axes, values)
        args = ("lbl_bh lbl_bv" if lum.photometry.kind == "B" else
                "lbl_gamma" if len(axes) == 1 else "lbl_c lbl_gamma")
        scale = lum.multiplier / (RADIANCE_EFFICACY * math.pi * LUMINAIRE_RADIUS ** 2)
        frame = " ".join(_g(x) for x in np.asarray(lum.frame).ravel())
        name = radiance_name(f"lum_{k}")
        text.append(f"# {lum.name}: {lum.photometry.name}, multiplier {lum.multiplier:g}\n"
                    f"void brightdata {name}_dist\n{3 + len(args.split())} lbl_lum {data} {_LUMINAIRE_CAL} {args}\n"
                    f"0\n10 {_g(scale)} {frame}\n"
                    f"{name}_dist light {name}_light\n0\n0\n3 1 1 1\n"
                    f"{name}_light sphere {name}\n0\n0\n4 {_rgb(lum.position)} {_g(LUMINAIRE_RADIUS)}\n\n")
    files[_LUMINAIRES] = "".join(text)
    return files


def ambient_options(options, max_spacing: float | None = None, cube: float | None = None) -> list[str]:
    """The closest ``rtrace`` options to our quality options.

    ``-ab bounces+1`` (Radiance counts the sky seen from a sensor as a bounce; ours does
    not), ``-aa accuracy``, ``-ad samples``, ``-as 0`` (no super-samples: ours has none),
    ``-lw`` small (do not drop the deep bounces), ``-av`` = ambient / (179 π) with
    ``-aw 0`` when a bounce-limit illuminance is set.  ``-ar`` makes Radiance's largest
    record radius, 64 · cube / ar (ambient.c), equal to our ``max_spacing`` [m] when that
    and the octree's cube size [m] are known; otherwise it is written out as ``-ar 256``
    (:data:`RADIANCE_DEFAULT_AR`, rtrace's default), because rpict's default (64) differs
    and the same options serve both.
    """
    opts = ["-ab", str(options.bounces + 1), "-aa", f"{options.accuracy:g}", "-ad", str(options.samples),
            "-as", "0"]
    if max_spacing and cube:
        opts += ["-ar", str(max(1, math.ceil(RADIANCE_MAXARAD_FACTOR * cube / max_spacing)))]
    else:
        opts += ["-ar", str(RADIANCE_DEFAULT_AR)]
    opts += ["-lw", f"{LIMIT_WEIGHT:g}"]
    if options.ambient > 0:
        av = to_radiance(options.ambient / math.pi)
        opts += ["-av", _g(av), _g(av), _g(av), "-aw", "0"]
    return opts


def illuminance_from_rtrace(output_text: str, weights: Sequence[float] = RADIANCE_RGB_WEIGHTS) -> np.ndarray:
    """(n,) illuminance [lux] from the output of ``rtrace -I -h`` (three irradiance
    channels [W/m²] per line): 179 · (0.265 R + 0.670 G + 0.065 B), Radiance's own
    photometric value.  Give ``weights = lbl_illum.photometry.luminance_weights()`` for
    our Rec. 709 value instead (the same for grey light)."""
    values = np.array(output_text.split(), dtype=np.float64)
    if values.size % 3:
        raise ValueError(f"rtrace output has {values.size} numbers, not a multiple of 3")
    return from_radiance(values.reshape(-1, 3) @ np.asarray(weights, dtype=np.float64))


# ---------------------------------------------------------------------------
# Radiance programs
# ---------------------------------------------------------------------------

_PROGRAMS = ("oconv", "rtrace", "obj2mesh", "getinfo", "lookamb", "rcalc")


def radiance_programs(directory: str | os.PathLike | None = None) -> dict | None:
    """Radiance's programs and an environment to run them in, or None.

    The programs bundled with the ``pyradiance`` wheel (its ``bin`` folder) are used when
    the package is installed (it is located without importing it: its import changes the
    environment); otherwise ``oconv`` and ``rtrace`` on the ``PATH``.  Returns
    ``{"bin": {name: Path}, "env": dict, "root": Path | None}``; ``bin`` has ``oconv``
    and ``rtrace`` and whichever of ``obj2mesh``, ``getinfo``, ``lookamb`` and ``rcalc``
    exist.  ``env["RAYPATH"]`` starts with ``directory`` (so that an export's ``.cal``
    and ``.rtm`` files are found from any working folder), then ``.``, the wheel's
    ``lib`` folder and any RAYPATH already set.
    """
    import importlib.util

    bins, root, lib = {}, None, None
    spec = importlib.util.find_spec("pyradiance")
    if spec is not None and spec.origin is not None:
        root = Path(spec.origin).parent
        bins = {name: root / "bin" / name for name in _PROGRAMS if (root / "bin" / name).is_file()}
        lib = root / "lib"
    if not ("oconv" in bins and "rtrace" in bins):
        root, lib = None, None
        bins = {name: Path(p) for name in _PROGRAMS if (p := shutil.which(name))}
        if not ("oconv" in bins and "rtrace" in bins):
            return None
    env = dict(os.environ)
    path = [str(Path(directory).resolve())] if directory is not None else []
    path.append(".")
    if lib is not None and lib.is_dir():
        path.append(str(lib))
    if env.get("RAYPATH"):
        path.append(env["RAYPATH"])
    elif lib is None:
        path.append("/usr/local/lib/ray")          # Radiance's compiled-in default
    env["RAYPATH"] = os.pathsep.join(path)
    return {"bin": bins, "env": env, "root": root}


# ---------------------------------------------------------------------------
# The export
# ---------------------------------------------------------------------------

@dataclass
class RadianceExport:
    """What :func:`export_radiance` wrote.

    directory : the export folder;  files : every file written (absolute paths)
    scene_files : the ``.rad`` files in ``oconv`` order, relative to ``directory``
    octree : the octree the README's ``oconv`` command makes (relative to ``directory``)
    points : the ``.pts`` file (relative), or None when no points were given
    ambient_options : the ``rtrace`` options equivalent to the scene's quality options
    triangles, spheres : counts exported as triangles (polygons or mesh) and as spheres
    mesh : whether the plastic and glass triangles went into a compiled mesh
    """

    directory: Path
    files: list[Path]
    scene_files: list[str]
    octree: str = _OCTREE
    points: str | None = None
    ambient_options: list[str] = field(default_factory=list)
    triangles: int = 0
    spheres: int = 0
    mesh: bool = False

    def oconv_command(self) -> list[str]:
        """``oconv`` over the scene files; run it in ``directory`` with standard output
        to :attr:`octree`."""
        return ["oconv", *self.scene_files]

    def rtrace_command(self, ambient_options: list[str] | None = None, processes: int = 2) -> list[str]:
        """``rtrace -I -h -n P <ambient options> scene.oct``, to run in ``directory`` with
        the ``.pts`` file on standard input; it prints three irradiance channels [W/m²]
        per point (:func:`illuminance_from_rtrace` converts them to lux).  Without
        ``ambient_options`` the scene's own (:attr:`ambient_options`) are used."""
        opts = self.ambient_options if ambient_options is None else list(ambient_options)
        return ["rtrace", "-I", "-h", "-n", str(processes), *opts, self.octree]


def _rows(fmt: str, values: np.ndarray) -> str:
    """``fmt`` (one row's format) applied to every row of the 2-D ``values``, as one string
    (one ``%`` over all numbers: about twice as fast as a join over rows)."""
    values = np.asarray(values)
    if len(values) == 0:
        return ""
    return (fmt * len(values)) % tuple(values.ravel().tolist())


def _triangle_text(names: list[str], vertices: np.ndarray, material: np.ndarray) -> str:
    """One ``polygon`` per triangle, grouped by material, ids ``<material>.<k>``."""
    out = []
    for m in np.unique(material):
        idx = np.flatnonzero(material == m)
        name = names[m]
        out.append(f"# material {name}: {len(idx)} triangles\n")
        fmt = f"{name} polygon {name}.%d\n0\n0\n9 " + " ".join(["%.9g"] * 9) + "\n"
        out.append(_rows(fmt, np.column_stack([np.arange(len(idx)), vertices[idx].reshape(-1, 9)])))
    return "".join(out)


def _convex_loop(points: np.ndarray, normal: np.ndarray, tol: float) -> list[int] | None:
    """Indices of ``points`` (a closed loop) without its collinear corners, or None when
    the loop is not convex about ``normal`` (or turns back on itself)."""
    n = len(points)
    keep = []
    for i in range(n):
        a, b, c = points[i - 1], points[i], points[(i + 1) % n]
        turn = float(np.dot(np.cross(b - a, c - b), normal))
        size = float(np.linalg.norm(b - a) * np.linalg.norm(c - b))
        if turn < -tol * size:
            return None
        if turn > tol * size:
            keep.append(i)
        elif np.dot(b - a, c - b) < 0:          # collinear but folding back
            return None
    return keep if len(keep) >= 3 else None


def merge_coplanar(vertices: np.ndarray, tol: float = 1e-9) -> list[np.ndarray]:
    """Merge (T, 3, 3) triangles into convex polygons across shared edges.

    Two polygons merge when they share an edge with opposite winding, are coplanar
    (normals within ``tol``, same plane) and their union is convex; repeated until no pair
    merges.  Returns a list of (k, 3) corner loops wound like the triangles.  Used for
    ``light`` surfaces: Radiance's direct calculation over-estimates the light of a
    triangular source near it (a 1 m right triangle 1 m away: +13 % in Radiance 6.0a,
    measured), while the quadrilateral the two triangles of a rectangle make is within
    0.3 %.  Greedy, Python-level: meant for the few triangles of light sources.
    """
    flat = np.asarray(vertices, dtype=np.float64).reshape(-1, 3)
    unique, inverse = np.unique(flat, axis=0, return_inverse=True)
    loops = [list(map(int, t)) for t in inverse.reshape(-1, 3)]
    v = np.asarray(vertices, dtype=np.float64)
    normals = np.cross(v[:, 1] - v[:, 0], v[:, 2] - v[:, 0])
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    scale = float(np.max(np.ptp(flat, axis=0))) if len(flat) else 1.0
    alive = [True] * len(loops)
    owner = {}
    for p, loop in enumerate(loops):
        for i in range(len(loop)):
            owner[(loop[i], loop[(i + 1) % len(loop)])] = p
    merged = True
    while merged:
        merged = False
        for p in range(len(loops)):
            if not alive[p]:
                continue
            loop = loops[p]
            for i in range(len(loop)):
                a, b = loop[i], loop[(i + 1) % len(loop)]
                q = owner.get((b, a))
                if q is None or q == p or not alive[q]:
                    continue
                if np.dot(normals[p], normals[q]) < 1.0 - tol:
                    continue
                other = loops[q]
                if abs(np.dot(unique[other] - unique[loop[0]], normals[p])).max() > tol * scale:
                    continue
                j = other.index(a)
                path = other[j:] + other[:j]            # a, ..., b
                candidate = loop[:i + 1] + path[1:-1] + loop[i + 1:]
                keep = _convex_loop(unique[candidate], normals[p], tol)
                if keep is None:
                    continue
                candidate = [candidate[k] for k in keep]
                for loop_ in (loop, other):
                    for k in range(len(loop_)):
                        owner.pop((loop_[k], loop_[(k + 1) % len(loop_)]), None)
                loops[p], alive[q] = candidate, False
                for k in range(len(candidate)):
                    owner[(candidate[k], candidate[(k + 1) % len(candidate)])] = p
                merged = True
                break
    return [unique[loop] for p, loop in enumerate(loops) if alive[p]]


def _polygon_text(name: str, loops: list[np.ndarray], prefix: str) -> str:
    """One ``polygon`` per corner loop, ids ``<material>.<prefix><k>``."""
    out = [f"# material {name}: {len(loops)} polygons\n"]
    for k, loop in enumerate(loops):
        out.append(f"{name} polygon {name}.{prefix}{k}\n0\n0\n{3 * len(loop)} "
                   + " ".join(_g(x) for x in np.asarray(loop).ravel()) + "\n")
    return "".join(out)


def _two_sided_loops(loops: list[np.ndarray], offset: float) -> list[np.ndarray]:
    """Each loop moved ``offset`` along its normal, then a reversed copy moved ``offset``
    the other way: two one-sided Radiance surfaces back to back."""
    front, back = [], []
    for loop in loops:
        n = np.cross(loop[1] - loop[0], loop[2] - loop[0])
        n /= np.linalg.norm(n)
        front.append(loop + offset * n)
        back.append((loop - offset * n)[::-1])
    return front + back


def _obj_text(names: list[str], vertices: np.ndarray, material: np.ndarray) -> str:
    """Wavefront OBJ of the triangles: shared vertices, faces grouped by ``usemtl``."""
    flat = np.ascontiguousarray(vertices, dtype=np.float64).reshape(-1, 3)
    keys = flat.view(np.dtype((np.void, flat.dtype.itemsize * 3))).ravel()     # rows as bytes: fast unique
    _, first, inverse = np.unique(keys, return_index=True, return_inverse=True)
    unique = flat[first]
    faces = inverse.reshape(-1, 3) + 1
    lines = [f"# written by lbl-illum {__version__}; metres, +z up\n", _rows("v %.9g %.9g %.9g\n", unique)]
    for m in np.unique(material):
        idx = np.flatnonzero(material == m)
        lines.append(f"usemtl {names[m]}\n")
        lines.append(_rows("f %d %d %d\n", faces[idx]))
    return "".join(lines)


def _sphere_groups(tri) -> tuple[list[tuple[int, int]], np.ndarray]:
    """Spheres exported as ``sphere`` primitives: [(sphere id, material id)], and the (T,)
    mask of the triangles they replace.  A sphere whose facets carry more than one
    material keeps its facets."""
    spheres, replaced = [], np.zeros(len(tri), dtype=bool)
    if len(tri.sphere_radius) == 0:
        return spheres, replaced
    for s in np.unique(tri.sphere[tri.sphere >= 0]):
        mask = tri.sphere == s
        mats = np.unique(tri.material[mask])
        if len(mats) == 1:
            spheres.append((int(s), int(mats[0])))
            replaced |= mask
    return spheres, replaced


def _default_max_spacing(scene, points, normals) -> float | None:
    """Our record spacing limit [m]: the scene's ``max_spacing`` if set, else the
    integrator's automatic one for these points (None without points)."""
    if scene.options.max_spacing:
        return scene.options.max_spacing
    if points is None or len(points) == 0:
        return None
    from ..engine.integrator import default_spacing, spacing_rng
    from ..engine.raycast import Tracer

    tracer = Tracer(scene.triangles, scene.material_table.kind, scene.material_table.transmittance)
    return float(default_spacing(tracer, points, normals, spacing_rng(scene.options.seed))[1])


def _bounds(scene) -> np.ndarray:
    """(2, 3) box [m] around all triangles and true spheres (what ``oconv`` encloses)."""
    tri = scene.triangles
    lo, hi = tri.bounds
    if len(tri.sphere_radius):
        r = tri.sphere_radius[:, None]
        lo = np.minimum(lo, (tri.sphere_center - r).min(axis=0))
        hi = np.maximum(hi, (tri.sphere_center + r).max(axis=0))
    return np.stack([lo, hi])


def export_radiance(scene, directory, points=None, normals=None, *, glass: str = "auto",
                    mesh: bool | None = None, mesh_threshold: int = MESH_THRESHOLD,
                    progress: Callable[[str], None] | None = None) -> RadianceExport:
    """Write ``scene`` as a Radiance scene into ``directory`` (see the module docstring).

    points, normals : optional (n, 3) sensor points [m] and normals, written to
        ``points.pts`` and used for the automatic ``-ar``
    glass : ``"auto"`` (default: each glass as the Radiance material equivalent to its
        model — Fresnel single pane ``glass``, Fresnel double pane ``BRTDfunc`` with
        ``lbl_glazing.cal``, constant ``BRTDfunc`` with constants), ``"glass"`` (Radiance's
        ``glass`` for every glass) or ``"brtdfunc"`` (constant normal-incidence coefficients
        for every glass); see :func:`material_primitive`
    mesh : True: compile the plastic and glass triangles with ``obj2mesh`` into one
        ``mesh`` (an error when ``obj2mesh`` is not found); False: polygons; None
        (default): the mesh when there are more than ``mesh_threshold`` of them and
        ``obj2mesh`` is found.  ``light`` and ``mirror`` triangles are always polygons:
        Radiance finds light sources and virtual-source mirrors only among the
        top-level surfaces, not inside meshes
    progress : called with a short description of each stage

    The files are written into a temporary folder beside ``directory`` and then moved
    into it, each by a rename: no file is ever partly written.  Files of ``directory``
    with other names are left alone.
    """
    if glass not in GLASS_MODELS:
        raise InputError(f"glass model must be one of {', '.join(GLASS_MODELS)}, got {glass!r}")
    say = progress or (lambda text: None)
    directory = Path(directory)
    if directory.exists() and not directory.is_dir():
        raise InputError(f"{directory}: not a folder")
    if not directory.resolve().parent.is_dir():
        raise InputError(f"{directory}: folder {directory.parent} does not exist")
    if points is not None:
        points = np.asarray(points, dtype=np.float64).reshape(-1, 3)
        normals = np.asarray(normals, dtype=np.float64).reshape(-1, 3)
        if normals.shape != points.shape:
            raise InputError(f"points and normals differ in shape: {points.shape} and {normals.shape}")
        normals = normals / np.linalg.norm(normals, axis=1, keepdims=True)

    tri = scene.triangles
    taken: set = set()
    names = [radiance_name(m.name, taken) for m in scene.materials]
    kinds = np.array([m.kind for m in scene.materials] or ["diffuse"])
    spheres, replaced = _sphere_groups(tri)
    facets = np.flatnonzero(~replaced)
    kind_of = kinds[tri.material[facets]] if len(facets) else np.zeros(0, dtype=kinds.dtype)
    one_sided = facets[(kind_of == "light") | (kind_of == "mirror")]
    plain = facets[(kind_of != "light") & (kind_of != "mirror")]
    programs = radiance_programs()
    has_obj2mesh = programs is not None and "obj2mesh" in programs["bin"]
    if mesh is None:
        use_mesh = has_obj2mesh and len(plain) > mesh_threshold
    else:
        use_mesh = bool(mesh) and len(plain) > 0
        if use_mesh and not has_obj2mesh:
            raise InputError("export radiance: the mesh path needs Radiance's obj2mesh (pip install pyradiance)")

    say("materials")
    header = f"# written by lbl-illum {__version__}"
    materials_text = header + "; colours are linear RGB, lights in W/(sr m2) = cd/m2 / 179\n\n" + "\n".join(
        f"# [materials.{m.name}] {m.kind}\n" + material_primitive(n, m, glass)
        for n, m in zip(names, scene.materials))
    sky_text, cal_text = sky_description(scene.sky, scene.sun)

    say("geometry")
    geo = [f"{header}; lengths in metres\n"]
    if spheres:
        geo.append(f"# {len(spheres)} sphere primitives (their {SPHERE_SUBDIVISIONS}-fold icosphere facets "
                   "in lbl_illum are inscribed in these)\n")
        for s, m in spheres:
            c, r = tri.sphere_center[s], tri.sphere_radius[s]
            geo.append(f"{names[m]} sphere sphere.{s}\n0\n0\n4 {_rgb(c)} {_g(r)}\n\n")
    if len(one_sided):
        geo.append(f"# light and mirror surfaces, each as two one-sided polygons back to back "
                   f"({TWO_SIDED_OFFSET:g} m apart): ours are two-sided.  Light triangles are merged into "
                   "convex polygons\n")
        for m in np.unique(tri.material[one_sided]):
            ids = one_sided[tri.material[one_sided] == m]
            if kinds[m] == "light" and len(ids) <= MAX_MERGED_LIGHT_TRIANGLES:
                loops = merge_coplanar(tri.vertices[ids])
            else:
                loops = list(tri.vertices[ids])
            geo.append(_polygon_text(names[m], _two_sided_loops(loops, TWO_SIDED_OFFSET), prefix="s"))
    obj_text = None
    if use_mesh:
        obj_text = _obj_text(names, tri.vertices[plain], tri.material[plain])
        geo.append(f"# {len(plain)} triangles compiled by: obj2mesh -a materials.rad geometry.obj geometry.rtm\n"
                   "void mesh geometry_mesh\n1 geometry.rtm\n0\n0\n")
    elif len(plain):
        geo.append(_triangle_text(names, tri.vertices[plain], tri.material[plain]))

    max_spacing = _default_max_spacing(scene, points, normals)
    lo, hi = _bounds(scene)
    if points is not None and len(points):
        lo, hi = np.minimum(lo, points.min(axis=0)), np.maximum(hi, points.max(axis=0))
    cube = float(np.max(hi - lo))
    amb = ambient_options(scene.options, max_spacing, cube)

    files = {"materials.rad": materials_text, "sky.rad": sky_text, "geometry.rad": "".join(geo)}
    scene_files = list(_SCENE_FILES)
    if scene.luminaires:
        files.update(luminaire_description(scene.luminaires))
        scene_files.append(_LUMINAIRES)
    if cal_text is not None:
        files[_CAL] = cal_text
    if any(m.kind == "glass" and glass_export(m, glass) == "brtdfunc-cal" for m in scene.materials):
        files[_GLAZING_CAL] = GLAZING_CAL
    if obj_text is not None:
        files["geometry.obj"] = obj_text
    if points is not None:
        files[_POINTS] = _rows("%.9g %.9g %.9g %.9g %.9g %.9g\n", np.hstack([points, normals]))
    result = RadianceExport(directory=directory.resolve(), files=[], scene_files=scene_files,
                            points=_POINTS if points is not None else None, ambient_options=amb,
                            triangles=int(len(facets)), spheres=len(spheres), mesh=use_mesh)
    files["README.txt"] = _readme(scene, result, max_spacing, cube, glass)

    say("writing")
    parent = directory.resolve().parent
    tmp = Path(tempfile.mkdtemp(prefix=f".{directory.name}.", suffix=".tmp", dir=parent))
    try:
        mask = os.umask(0)
        os.umask(mask)
        os.chmod(tmp, 0o777 & ~mask)                 # a folder as mkdir would make it, not mkdtemp's 0700
        for name, text in files.items():
            atomic_write_text(tmp / name, text)
        if use_mesh:
            say("obj2mesh")
            run = subprocess.run([str(programs["bin"]["obj2mesh"]), "-a", "materials.rad", "geometry.obj",
                                  "geometry.rtm"], cwd=tmp, env=programs["env"], capture_output=True, text=True)
            if run.returncode != 0 or not (tmp / "geometry.rtm").is_file():
                message = (run.stderr.strip().splitlines() or ["failed"])[-1]
                raise InputError(f"export radiance: obj2mesh: {message}")
        written = sorted(p.name for p in tmp.iterdir())
        if not directory.exists():
            os.rename(tmp, directory)
        else:
            for name in written:
                os.replace(tmp / name, directory / name)
            tmp.rmdir()
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    result.files = [result.directory / name for name in written]
    return result


def _glass_note(scene, glass) -> str:
    """What the export made of the scene's glass, for README.txt."""
    words = {"glass": "glass (Fresnel)", "brtdfunc": "BRTDfunc with constant coefficients",
             "brtdfunc-cal": "BRTDfunc with the Fresnel double glazing of lbl_glazing.cal"}
    used = dict.fromkeys(glass_export(m, glass) for m in scene.materials if m.kind == "glass")
    return " or ".join(words[u] for u in used) if used else "none here"


def _readme(scene, ex: RadianceExport, max_spacing, cube, glass) -> str:
    """README.txt: what the files are and the commands that reproduce a run."""
    o = scene.options
    source = scene.path.name if scene.path is not None else "a scene built in code"
    pts = ex.points or "POINTS.pts"
    rt = " ".join(ex.rtrace_command())
    ar_note = (f"-ar makes Radiance's largest record radius (64 x cube / ar, cube ~ {cube:.4g} m) equal to our "
               f"max_spacing {max_spacing:.4g} m." if max_spacing else
               f"-ar is {RADIANCE_DEFAULT_AR} (rtrace's default, written out because rpict's is 64): our "
               "max_spacing is automatic and no points were given.")
    lines = [
        f"Radiance version of {source}, written by lbl-illum {__version__} (lbl-illum export radiance).",
        "",
        "Lengths are in metres.  Light: Radiance radiance [W/(sr m2)] = our luminance [cd/m2] / 179",
        "per RGB channel; illuminance [lux] = 179 x Radiance irradiance [W/m2].",
        "",
        "Files",
        "  materials.rad  materials (diffuse -> plastic, plastic -> plastic, glass -> " + _glass_note(scene, glass)
        + ", mirror -> mirror, light -> light)",
        "  sky.rad        sky and ground glow (brightfunc skyfunc, lbl_sky.cal) and the sun",
        "  geometry.rad   surfaces" + (" (plastic and glass triangles in geometry.rtm)" if ex.mesh else ""),
    ]
    if ex.mesh:
        lines.append("  geometry.obj   the plastic and glass triangles; geometry.rtm is made from it by")
        lines.append("                 obj2mesh -a materials.rad geometry.obj geometry.rtm")
    if ex.points:
        lines.append(f"  {ex.points}     sensor points, x y z nx ny nz per line [m]")
    lines += [
        "",
        "Commands (run in this folder; RAYPATH must contain '.', as Radiance's default does)",
        f"  {' '.join(ex.oconv_command())} > {ex.octree}",
        f"  {rt} < {pts} > irradiance.dat",
        "  rcalc -e '$1=179*(0.265*$1+0.670*$2+0.065*$3)' irradiance.dat > illuminance.txt",
        "",
        f"The rtrace options are the closest to the scene's settings (accuracy {o.accuracy:g}, samples "
        f"{o.samples}, bounces {o.bounces}):",
        "  -ab bounces+1 (Radiance counts the sky seen from the sensor as a bounce), -aa accuracy,",
        "  -ad samples, -as 0, -lw small so that deep bounces are not dropped.",
        f"  {ar_note}",
        "rtrace -I prints three irradiance channels [W/m2] per point; the rcalc line gives lux with",
        "Radiance's weights (0.265, 0.670, 0.065); lbl-illum weights its RGB by Rec. 709",
        "(0.2126, 0.7152, 0.0722): the same number for grey light.",
        "",
        "Known differences: see docs/radiance-export.md in lbl_illum.",
    ]
    return "\n".join(lines) + "\n"

"""Annual glare at view points: the daylight glare probability of every hour of a year
from the cache's daylight coefficients, with the sun and the bright sky patches in view as
its sources (docs/glare.md, "Annual glare").

For a view (eye at P looking along d, a 180° field as evalglare's fisheyes):

* **E_v**, the vertical illuminance at the eye, for every hour: the annual calculation at a
  sensor at P with its normal along d (:func:`lbl_illum.engine.annual.annual_light`:
  sky patches and interreflected sun through the coefficients, the direct sun traced).
* **DGPs**, the simplified DGP of Wienold (2009): 6.22e-5 E_v + 0.184, for every hour.
* **DGP with sources**, Wienold & Christoffersen (2006) with the low-light correction
  (:func:`lbl_illum.glare.metrics.daylight_glare_probability`), the sources found from the
  sky matrix instead of an image (*patch-based source detection*):

  - the sun, when its disk is in front of the eye and not blocked: luminance E_dn T / Ω_sun
    (T the glazing's transmittance along the ray, read from the direct sun at the eye:
    E_sun = E_dn T cos θ), solid angle Ω_sun = 6.8e-5 sr, the position index of its
    direction;
  - every sky patch (and the ground glow) seen from the eye through the glazing whose
    luminance times the glazing's transmittance is at least the threshold (2000 cd/m²,
    evalglare's default): its visible solid angle, its luminance L_p T_p and the position
    index of the mean direction of its visible part.  What each patch shows of itself from
    the eye is traced once (:func:`patch_visibility`, :data:`PATCH_RAYS` rays a patch).

  Bright surfaces (a sunlit floor or sill, a white facade across the street) are not
  sources here: their light is in E_v but not in the contrast term.  The study
  ``lbl-illum validate annual`` measures what that leaves out against DGPs of rendered
  fisheyes at hours with the sun in view.

Per view and year: the hours' DGP, the share of occupied hours in each of Wienold et al.'s
(2019) classes (imperceptible < 0.35 ≤ perceptible < 0.40 ≤ disturbing < 0.45 ≤
intolerable), the glare autonomy (the share of occupied hours below 0.40, without
disturbing or intolerable glare; Jakubiec & Reinhart 2012 with those classes), and the
EN 17037 glare-protection class of the DGP exceeded in 5 % of the occupied hours.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..daylight.skymatrix import SkyPatches
from ..daylight.sun import SUN_SOLID_ANGLE
from ..scene.views import View
from .metrics import (DEFAULT_THRESHOLD, DGP_CATEGORIES, DGP_CONSTANTS, DGP_EV_EXPONENT, LOW_LIGHT_LIMIT,
                      _view_angles, en17037_class, position_index)

__all__ = ["PatchVisibility", "patch_visibility", "AnnualGlare", "annual_glare", "simplified_dgp",
           "GLARE_AUTONOMY_LIMIT", "EN17037_EXCEEDANCE", "PATCH_RAYS"]

#: DGP below which an hour counts for the glare autonomy (the lower limit of disturbing glare).
GLARE_AUTONOMY_LIMIT = 0.40
#: EN 17037 rates the DGP exceeded in this share of the occupied hours.
EN17037_EXCEEDANCE = 0.05
#: Rays traced from the eye into each sky patch (a stratified grid over its altitude and azimuth).
PATCH_RAYS = 64
#: DGPs = a E_v + b (Wienold 2009).
SIMPLIFIED_DGP = (6.22e-5, 0.184)


def simplified_dgp(ev) -> np.ndarray:
    """DGPs = 6.22e-5 E_v + 0.184 (Wienold 2009), at most 1; E_v [lux]."""
    a, b = SIMPLIFIED_DGP
    return np.minimum(a * np.asarray(ev, np.float64) + b, 1.0)


@dataclass(frozen=True)
class PatchVisibility:
    """What the sky patches show of themselves from an eye: per patch (rows of the sky
    matrix), ``solid_angle`` [sr] of the visible part in front of the eye, ``transmittance``
    (mean photometric τ of the glazing along its visible rays) and ``position`` (the
    position index of the visible part's mean direction)."""

    solid_angle: np.ndarray
    transmittance: np.ndarray
    position: np.ndarray


def _patch_rays(patches: SkyPatches, n: int) -> tuple[np.ndarray, np.ndarray]:
    """(P, n, 3) stratified directions within each patch (the ground: the lower hemisphere)
    and (P,) the solid angle each ray stands for."""
    g = max(1, int(round(np.sqrt(n))))
    u = (np.arange(g) + 0.5) / g
    su, sv = np.meshgrid(u, u, indexing="ij")
    su, sv = su.ravel(), sv.ravel()
    b = patches.bounds                                     # altitude from, to, azimuth from, to [°]
    sin_lo, sin_hi = np.sin(np.radians(b[:, 0])), np.sin(np.radians(b[:, 1]))
    z = sin_lo[:, None] + (sin_hi - sin_lo)[:, None] * su[None]          # uniform in solid angle
    az = np.radians(b[:, 2][:, None] + (b[:, 3] - b[:, 2])[:, None] * sv[None])
    r = np.sqrt(np.maximum(0.0, 1.0 - z * z))
    d = np.stack([r * np.sin(az), r * np.cos(az), z], axis=-1)
    return d, patches.solid_angles / (g * g)


def patch_visibility(direct, tracer, eye, view: View, patches: SkyPatches, rays: int = PATCH_RAYS) -> PatchVisibility:
    """The sky patches seen from ``eye`` [m] (the view's position, in metres) through the
    glazing, in front of the view (module text).  ``direct``, ``tracer``: an integrator's
    (shadow rays through glass with τ(θ))."""
    from ..photometry import luminance

    d, omega = _patch_rays(patches, rays)
    P, n = d.shape[:2]
    flat = d.reshape(-1, 3)
    front = flat @ view.unit_direction > 0.0
    T = np.zeros(len(flat))
    use = np.flatnonzero(front)
    if len(use):
        origins = np.repeat(np.asarray(eye, np.float64).reshape(1, 3), len(use), axis=0)
        T[use] = luminance(direct.transmittance(origins, flat[use]))
    T = T.reshape(P, n)
    seen = T > 0.0
    count = seen.sum(axis=1)
    mean_dir = (d * seen[..., None]).sum(axis=1)
    norm = np.linalg.norm(mean_dir, axis=1)
    mean_dir = mean_dir / np.where(norm > 0.0, norm, 1.0)[:, None]
    sigma, tau, above = _view_angles(mean_dir, view)
    pos = np.where(count > 0, position_index(sigma, tau, above), np.inf)
    trans = np.where(count > 0, T.sum(axis=1) / np.maximum(count, 1), 0.0)
    return PatchVisibility(solid_angle=count * omega, transmittance=trans, position=pos)


@dataclass
class AnnualGlare:
    """A view's glare over the rows of a weather file (module text).

    ev : (hours,) [lux];  dgp : (hours,) with the sun and the bright patches as sources;
    dgps : (hours,) the simplified DGP;  sun_in_view : (hours,) bool, the sun's disk seen;
    sources : (hours,) number of sources
    """

    ev: np.ndarray
    dgp: np.ndarray
    dgps: np.ndarray
    sun_in_view: np.ndarray
    sources: np.ndarray

    def summary(self, occupancy) -> dict:
        """Shares of the occupied hours [%] per class, glare autonomy, the DGP exceeded in 5 %
        of them and its EN 17037 class, for ``dgp`` and ``dgps``; hours with the sun in view."""
        w = np.asarray(occupancy, np.float64)
        total = w.sum()
        out = {"occupied_hours": float(total), "sun_in_view_hours": float(w @ self.sun_in_view)}
        for name, values in (("dgp", self.dgp), ("dgps", self.dgps)):
            shares, lower = {}, -np.inf
            for bound, label in DGP_CATEGORIES:
                shares[label] = 100.0 * float(w @ ((values >= lower) & (values < bound))) / total
                lower = bound
            order = np.argsort(values, kind="stable")
            cum = np.cumsum(w[order])
            k = int(np.searchsorted(cum, (1.0 - EN17037_EXCEEDANCE) * total, side="left"))
            exceeded = float(values[order][min(k, len(order) - 1)])
            out[name] = {"classes": shares,
                         "glare_autonomy": 100.0 * float(w @ (values < GLARE_AUTONOMY_LIMIT)) / total,
                         "dgp_exceeded_in_5_percent": exceeded, "en17037": en17037_class(exceeded)}
        return out


def annual_glare(ev, sky_luminance, sun_direction, direct_normal, sun_at_eye, view: View,
                 visibility: PatchVisibility, threshold: float = DEFAULT_THRESHOLD, low_light: bool = True,
                 constants=DGP_CONSTANTS) -> AnnualGlare:
    """The glare of every hour at one view (module text).

    ev : (hours,) vertical illuminance at the eye [lux];  sky_luminance : (patches, hours)
    [cd/m²] the sky matrix without the sun;  sun_direction : (hours, 3);  direct_normal :
    (hours,) [lux];  sun_at_eye : (hours,) the direct sun at the eye [lux] (normal along
    the view direction);  visibility : :func:`patch_visibility` of the eye;  threshold
    [cd/m²] of a source.
    """
    ev = np.asarray(ev, np.float64)
    L = np.asarray(sky_luminance, np.float64) * visibility.transmittance[:, None]
    bright = (L >= threshold) & (visibility.solid_angle[:, None] > 0.0)
    term = ((np.where(bright, L, 0.0) ** 2) * (visibility.solid_angle / np.where(
        np.isfinite(visibility.position), visibility.position, 1.0) ** 2)[:, None]).sum(axis=0)
    sources = bright.sum(axis=0)
    s = np.asarray(sun_direction, np.float64)
    e_sun = np.asarray(sun_at_eye, np.float64)
    cos = s @ view.unit_direction
    seen = (e_sun > 0.0) & (cos > 0.0) & (np.asarray(direct_normal) > 0.0)
    if seen.any():
        L_sun = e_sun[seen] / (cos[seen] * SUN_SOLID_ANGLE)
        sigma, tau, above = _view_angles(s[seen], view)
        p = position_index(sigma, tau, above)
        term[seen] += L_sun ** 2 * SUN_SOLID_ANGLE / p ** 2
        sources[seen] += 1
    c1, c2, c3 = constants
    dgp = c1 * ev + c3
    positive = (term > 0.0) & (ev > 0.0)
    dgp[positive] += c2 * np.log10(1.0 + term[positive] / ev[positive] ** DGP_EV_EXPONENT)
    dgp = np.minimum(dgp, 1.0)
    if low_light:
        dgp *= np.where(ev >= LOW_LIGHT_LIMIT, 1.0, 1.0 / (1.0 + np.exp(4.0 - 0.024 * ev)))
    dark = ev <= 0.0
    dgp[dark] = 0.0
    dgps = simplified_dgp(ev)
    dgps[dark] = 0.0
    return AnnualGlare(ev=ev, dgp=dgp, dgps=dgps, sun_in_view=seen, sources=sources)

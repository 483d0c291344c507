"""Materials of the scene file: what a surface does with the light that reaches it.

=========  ===========================================================  ==============================
type       behaviour                                                    keys
=========  ===========================================================  ==============================
diffuse    Lambertian reflector, radiance L = ρ E / π                   ``reflectance`` ρ (0…1)
glass      thin clear pane: specular transmission and reflection        ``transmittance`` τ_n (0…1),
                                                                        ``reflectance`` (optional),
                                                                        ``portal`` (true/false)
mirror     specular reflector                                           ``reflectance`` (0…1)
light      Lambertian emitter, counted by the direct calculation only  ``luminance`` [cd/m²]
=========  ===========================================================  ==============================

Scalars or ``[r, g, b]`` triples are accepted wherever a value may be coloured.
Glass transmittance is the visible transmittance at normal incidence and is used at
every angle (angle-dependent glazing is a later extension).  When a glass's reflectance
is not given it is that of a thin pane of refractive index 1.52 with the stated
transmittance (two Fresnel interfaces at normal incidence with internal absorption,
the model of Radiance's ``glass``).

``portal = true`` marks a window whose area the indirect calculation samples directly
(the paper's §5: large sources such as the sky seen through a window belong in the
indirect step, sampled well); see :mod:`lbl_illum.integrator`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Mapping

import numpy as np

from .errors import InputError, check_keys, get_rgb

__all__ = ["Material", "MaterialTable", "DIFFUSE", "GLASS", "MIRROR", "LIGHT", "material_from_table"]

DIFFUSE, GLASS, MIRROR, LIGHT = 0, 1, 2, 3
KIND_CODES = {"diffuse": DIFFUSE, "glass": GLASS, "mirror": MIRROR, "light": LIGHT}
_KEYS = {
    "diffuse": ("type", "reflectance"),
    "glass": ("type", "transmittance", "reflectance", "portal"),
    "mirror": ("type", "reflectance"),
    "light": ("type", "luminance"),
}
GLASS_INDEX = 1.52


@dataclass(frozen=True)
class Material:
    """One material.  Colour values are linear RGB with photometric channels."""

    name: str
    kind: str                                   # "diffuse" | "glass" | "mirror" | "light"
    reflectance: tuple = (0.0, 0.0, 0.0)        # ρ (diffuse, mirror, glass surface reflection)
    transmittance: tuple = (0.0, 0.0, 0.0)      # τ (glass)
    luminance: tuple = (0.0, 0.0, 0.0)          # emitted luminance [cd/m²] (light)
    portal: bool = False                        # glass sampled by area in the indirect step

    @property
    def code(self) -> int:
        return KIND_CODES[self.kind]


def thin_pane_reflectance(transmittance: float, index: float = GLASS_INDEX) -> float:
    """Normal-incidence reflectance of a thin pane with the given transmittance.

    With the single-interface reflectance r = ((n-1)/(n+1))² and internal
    transmissivity t, a pane has τ = (1-r)² t / (1 - r² t²) and
    ρ = r + r (1-r)² t² / (1 - r² t²); t is solved from τ (the quadratic of
    Radiance's ``glass`` primitive).
    """
    r = ((index - 1.0) / (index + 1.0)) ** 2
    tau = float(transmittance)
    if tau <= 0.0:
        return r
    a, b, c = tau * r * r, (1.0 - r) ** 2, -tau
    t = (-b + np.sqrt(b * b - 4 * a * c)) / (2 * a)
    if t >= 1.0:                      # clearer than a clear pane can be: keep energy ≤ 1
        return max(0.0, min(r, 1.0 - tau))
    rho = r + r * (1.0 - r) ** 2 * t * t / (1.0 - r * r * t * t)
    return float(min(rho, 1.0 - tau))


def material_from_table(name: str, table: Mapping[str, Any], where: str) -> Material:
    """Build a :class:`Material` from its ``[materials.NAME]`` table, checking every key."""
    kind = table.get("type")
    if kind not in _KEYS:
        raise InputError(f"{where}: 'type' must be one of {', '.join(_KEYS)}, got {kind!r}")
    check_keys(table, _KEYS[kind], where)
    if kind == "diffuse":
        return Material(name, kind, reflectance=get_rgb(table, "reflectance", where, maximum=1.0))
    if kind == "mirror":
        return Material(name, kind, reflectance=get_rgb(table, "reflectance", where, maximum=1.0))
    if kind == "light":
        return Material(name, kind, luminance=get_rgb(table, "luminance", where))
    tau = get_rgb(table, "transmittance", where, maximum=1.0)
    if "reflectance" in table:
        rho = get_rgb(table, "reflectance", where, maximum=1.0)
    else:
        rho = tuple(thin_pane_reflectance(t) for t in tau)
    for t, r in zip(tau, rho):
        if t + r > 1.0 + 1e-12:
            raise InputError(f"{where}: transmittance + reflectance must not exceed 1")
    portal = table.get("portal", False)
    if not isinstance(portal, bool):
        raise InputError(f"{where}: 'portal' must be true or false, got {portal!r}")
    return Material(name, kind, reflectance=rho, transmittance=tau, portal=portal)


@dataclass
class MaterialTable:
    """The materials as arrays indexed by material id, for vectorised shading."""

    kind: np.ndarray            # (m,) int8, one of DIFFUSE, GLASS, MIRROR, LIGHT
    reflectance: np.ndarray     # (m, 3) float64
    transmittance: np.ndarray   # (m, 3) float64
    luminance: np.ndarray       # (m, 3) float64 [cd/m²]
    portal: np.ndarray          # (m,) bool, glass sampled by area in the indirect step

    @classmethod
    def from_materials(cls, materials: list[Material]) -> "MaterialTable":
        return cls(
            kind=np.array([m.code for m in materials], dtype=np.int8),
            reflectance=np.array([m.reflectance for m in materials], dtype=np.float64).reshape(-1, 3),
            transmittance=np.array([m.transmittance for m in materials], dtype=np.float64).reshape(-1, 3),
            luminance=np.array([m.luminance for m in materials], dtype=np.float64).reshape(-1, 3),
            portal=np.array([m.portal for m in materials], dtype=bool),
        )

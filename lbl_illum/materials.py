"""Materials of the scene file: what a surface does with the light that reaches it.

=========  ===========================================================  ==============================
type       behaviour                                                    keys
=========  ===========================================================  ==============================
diffuse    Lambertian reflector, radiance L = ρ E / π                   ``reflectance`` ρ (0…1)
glass      thin pane (or two): specular transmission and reflection,    ``transmittance`` τ_n (0…1),
           straight through, no refraction of the ray                   ``model``, ``panes``,
                                                                        ``refractive_index``,
                                                                        ``reflectance`` (constant model),
                                                                        ``portal`` (true/false)
mirror     specular reflector                                           ``reflectance`` (0…1)
light      Lambertian emitter, counted by the direct calculation only  ``luminance`` [cd/m²]
=========  ===========================================================  ==============================

Scalars or ``[r, g, b]`` triples are accepted wherever a value may be coloured.

**Glazing.**  A glass's ``transmittance`` τ_n is always its visible transmittance at
normal incidence; ``model`` says how it changes with the angle of incidence θ:

* ``"fresnel"`` (the default): the thin-glass model of Radiance's ``glass`` primitive
  (Ward, Radiance reference manual, "Glass"; ``src/rt/glass.c``): each pane is two
  parallel air–glass interfaces of refractive index n (``refractive_index``, default
  1.52) with internal transmissivity t_n at normal incidence, every internal reflection
  summed, for the s and p polarisations separately and averaged (:func:`glazing_optics`).
  ``panes = 2`` stacks two identical panes with the reflections between them summed per
  polarisation (Duffie & Beckman, *Solar Engineering of Thermal Processes*, 4th ed.,
  §5.1–5.3).  t_n is solved from τ_n (:func:`pane_transmissivity`), and the reflectance
  follows from n: giving ``reflectance`` is an error.  τ falls and ρ rises towards
  grazing incidence (τ = ρ + τ → 0, 1 at 90°).
* ``"constant"``: τ_n and ``reflectance`` ρ at every angle (the idealised pane of
  earlier versions); ρ defaults to the normal-incidence reflectance of a single
  Fresnel pane with τ_n (:func:`thin_pane_reflectance`).

``portal = true`` marks a window whose area the indirect calculation samples directly
(the paper's §5: large sources such as the sky seen through a window belong in the
indirect step, sampled well); see :mod:`lbl_illum.integrator` and docs/windows.md.
Glass is a portal by default (``DEFAULT_GLASS_PORTAL``).
"""

from __future__ import annotations

import difflib
from dataclasses import dataclass
from typing import Any, Mapping

import numpy as np

from .errors import InputError, check_keys, get_number, get_rgb, show

__all__ = ["Material", "MaterialTable", "DIFFUSE", "GLASS", "MIRROR", "LIGHT", "GLASS_INDEX", "GLAZING_MODELS",
           "DEFAULT_GLASS_PORTAL", "material_from_table", "thin_pane_reflectance", "fresnel_interfaces",
           "glazing_optics", "pane_transmissivity", "max_transmittance"]

DIFFUSE, GLASS, MIRROR, LIGHT = 0, 1, 2, 3
KIND_CODES = {"diffuse": DIFFUSE, "glass": GLASS, "mirror": MIRROR, "light": LIGHT}
_KEYS = {
    "diffuse": ("type", "reflectance"),
    "glass": ("type", "transmittance", "reflectance", "portal", "model", "panes", "refractive_index"),
    "mirror": ("type", "reflectance"),
    "light": ("type", "luminance"),
}
#: Refractive index of window glass (soda-lime float glass in the visible; Radiance's RINDEX).
GLASS_INDEX = 1.52
#: Values of a glass's ``model``; the first is the default.
GLAZING_MODELS = ("fresnel", "constant")
#: Whether a glass is a window portal when its table does not say (see docs/windows.md
#: for the deep-room measurement behind it).
DEFAULT_GLASS_PORTAL = True
#: Smallest cosine of incidence used by the Fresnel formulas (a ray exactly in the plane
#: of the pane is reflected whole).
_MIN_COS = 1e-9


@dataclass(frozen=True)
class Material:
    """One material.  Colour values are linear RGB with photometric channels.

    For glass, ``transmittance`` is the normal-incidence value; with ``model = "fresnel"``
    ``reflectance`` is the normal-incidence reflectance the model implies (kept for
    reports and exports: the engine computes both at every angle from ``transmittance``,
    ``panes`` and ``index``).
    """

    name: str
    kind: str                                   # "diffuse" | "glass" | "mirror" | "light"
    reflectance: tuple = (0.0, 0.0, 0.0)        # ρ (diffuse, mirror, glass surface reflection)
    transmittance: tuple = (0.0, 0.0, 0.0)      # τ_n (glass, normal incidence)
    luminance: tuple = (0.0, 0.0, 0.0)          # emitted luminance [cd/m²] (light)
    portal: bool = False                        # glass sampled by area in the indirect step
    model: str = "fresnel"                      # glass: "fresnel" | "constant"
    panes: int = 1                              # glass (fresnel): 1 or 2 panes
    index: float = GLASS_INDEX                  # glass (fresnel): refractive index n

    @property
    def code(self) -> int:
        return KIND_CODES[self.kind]

    @property
    def fresnel(self) -> bool:
        """An angle-dependent (Fresnel) glass."""
        return self.kind == "glass" and self.model == "fresnel"


# ---------------------------------------------------------------------------
# Glazing optics
# ---------------------------------------------------------------------------

def fresnel_interfaces(cos_i, index: float = GLASS_INDEX):
    """Reflectance of one air–glass interface for s and p polarised light.

    cos_i : cosine of the angle of incidence (any shape, 0…1);  index : n.
    With cos θ_t = √(1 − (1 − cos²θ_i)/n²) (Snell):
    r_s = ((cos θ_i − n cos θ_t)/(cos θ_i + n cos θ_t))²,
    r_p = ((cos θ_t − n cos θ_i)/(cos θ_t + n cos θ_i))²  (Born & Wolf, *Principles of
    Optics*, §1.5.2; Radiance's ``r1e`` and ``r1m``).  Returns ``(r_s, r_p, cos_t)``.
    """
    c = np.clip(np.asarray(cos_i, np.float64), _MIN_COS, 1.0)
    n = float(index)
    cos_t = np.sqrt(1.0 - (1.0 - c * c) / (n * n))
    r_s = ((c - n * cos_t) / (c + n * cos_t)) ** 2
    r_p = ((cos_t - n * c) / (cos_t + n * c)) ** 2
    return r_s, r_p, cos_t


def _one_pane(r, d):
    """Transmittance and reflectance of a pane with interface reflectance r and internal
    transmittance d along the refracted path, all internal reflections summed:
    τ = (1 − r)² d / (1 − r² d²),  ρ = r (1 + (1 − 2r) d²) / (1 − r² d²)."""
    den = 1.0 - (r * d) ** 2
    den = np.where(den > 0.0, den, 1.0)       # r = d = 1 only: τ = 0, ρ = 1 either way
    tau = (1.0 - r) ** 2 * d / den
    rho = r * (1.0 + (1.0 - 2.0 * r) * d * d) / den
    return tau, np.where((r >= 1.0), 1.0, rho)


def _two_panes(tau, rho):
    """Two identical panes with the reflections between them summed:
    τ₂ = τ² / (1 − ρ²),  ρ₂ = ρ + τ² ρ / (1 − ρ²)."""
    den = np.maximum(1.0 - rho * rho, 1e-300)
    return tau * tau / den, rho + tau * tau * rho / den


def glazing_optics(cos_i, transmissivity, index: float = GLASS_INDEX, panes: int = 1):
    """Transmittance and reflectance of Fresnel glazing at incidence cosine ``cos_i``.

    cos_i : (k,) cosines of incidence (sign ignored);  transmissivity : (k, c) or (c,)
    internal transmissivity t_n of each pane at normal incidence (per channel);
    index : refractive index n;  panes : 1 or 2.  Returns ``(tau, rho)``, each (k, c).

    Per polarisation x ∈ {s, p}: the interface reflectance r_x of
    :func:`fresnel_interfaces`, the internal transmittance d = t_n^(1/cos θ_t) along the
    refracted path, one pane by :func:`_one_pane`, two by :func:`_two_panes`; then the
    mean of s and p (unpolarised daylight).  One pane is Radiance's ``glass`` exactly
    (glass.c); for t_n from :func:`pane_transmissivity`, τ(0°) is the stated τ_n.
    """
    cos_i = np.abs(np.asarray(cos_i, np.float64)).reshape(-1)
    t = np.clip(np.asarray(transmissivity, np.float64), 0.0, 1.0)
    if t.ndim == 1:
        t = np.broadcast_to(t, (len(cos_i), t.shape[0]))
    r_s, r_p, cos_t = fresnel_interfaces(cos_i, index)
    d = t ** (1.0 / cos_t)[:, None]
    tau, rho = np.zeros(t.shape), np.zeros(t.shape)
    for r in (r_s, r_p):
        tx, rx = _one_pane(r[:, None], d)
        if panes == 2:
            tx, rx = _two_panes(tx, rx)
        tau += 0.5 * tx
        rho += 0.5 * rx
    return tau, rho


def max_transmittance(index: float = GLASS_INDEX, panes: int = 1) -> float:
    """Normal-incidence transmittance of non-absorbing glazing (t_n = 1):
    (1 − r)/(1 + r) for one pane, (1 − r)/(1 + 3r) for two, r = ((n − 1)/(n + 1))²
    (Duffie & Beckman §5.1).  n = 1.52: 0.9183 and 0.8490."""
    r = ((index - 1.0) / (index + 1.0)) ** 2
    return (1.0 - r) / (1.0 + (2 * panes - 1) * r)


def pane_transmissivity(transmittance, index: float = GLASS_INDEX, panes: int = 1):
    """Internal transmissivity t_n of each pane that gives the normal-incidence
    transmittance τ_n (array, any shape).

    One pane: the positive root of τ r² t² + (1 − r)² t − τ = 0,
    t = (√((1 − r)⁴ + 4 r² τ²) − (1 − r)²) / (2 r² τ) — for n = 1.52 the formula of
    Radiance's glass.c, tn = (√(0.8402528435 + 0.0072522239 τ²) − 0.9166530661) /
    0.0036261119 / τ, with unrounded constants.  Two panes: τ₂(t) of :func:`glazing_optics`
    at normal incidence is increasing in t; solved by bisection to 1e-15.  τ_n above
    :func:`max_transmittance` gives t_n = 1 (clamped).
    """
    T = np.asarray(transmittance, np.float64)
    r = ((index - 1.0) / (index + 1.0)) ** 2
    if panes == 1:
        a, b = (1.0 - r) ** 2, r * r
        safe = np.where(T > 0.0, T, 1.0)
        tn = (np.sqrt(a * a + 4.0 * b * safe * safe) - a) / (2.0 * b * safe)
        return np.clip(np.where(T > 0.0, tn, 0.0), 0.0, 1.0)
    flat = T.reshape(-1)
    lo, hi = np.zeros(flat.shape), np.ones(flat.shape)
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        tau, _ = glazing_optics(np.ones(len(flat)), mid[:, None], index, panes)
        below = tau[:, 0] < flat
        lo = np.where(below, mid, lo)
        hi = np.where(below, hi, mid)
    return np.where(flat > 0.0, 0.5 * (lo + hi), 0.0).reshape(T.shape)


def thin_pane_reflectance(transmittance: float, index: float = GLASS_INDEX) -> float:
    """Normal-incidence reflectance of a single thin pane with the given transmittance.

    With the single-interface reflectance r = ((n-1)/(n+1))² and internal
    transmissivity t, a pane has τ = (1-r)² t / (1 - r² t²) and
    ρ = r + r (1-r)² t² / (1 - r² t²); t is solved from τ (the quadratic of
    Radiance's ``glass`` primitive).  The default reflectance of a constant-model glass.
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


# ---------------------------------------------------------------------------
# Reading [materials.NAME]
# ---------------------------------------------------------------------------

def material_from_table(name: str, table: Mapping[str, Any], where: str) -> Material:
    """Build a :class:`Material` from its ``[materials.NAME]`` table, checking every key."""
    if "type" not in table:
        raise InputError(f"{where}: missing key 'type' (one of {', '.join(_KEYS)})")
    kind = table["type"]
    if not isinstance(kind, str) or kind not in _KEYS:
        near = difflib.get_close_matches(kind, list(_KEYS), n=1) if isinstance(kind, str) else []
        hint = f" (did you mean '{near[0]}'?)" if near else ""
        raise InputError(f"{where}: 'type' must be one of {', '.join(_KEYS)}, got {show(kind)}{hint}")
    check_keys(table, _KEYS[kind], where)
    if kind == "diffuse":
        return Material(name, kind, reflectance=get_rgb(table, "reflectance", where, maximum=1.0))
    if kind == "mirror":
        return Material(name, kind, reflectance=get_rgb(table, "reflectance", where, maximum=1.0))
    if kind == "light":
        return Material(name, kind, luminance=get_rgb(table, "luminance", where))
    return _glass_from_table(name, table, where)


def _glass_from_table(name: str, table: Mapping[str, Any], where: str) -> Material:
    tau = get_rgb(table, "transmittance", where, maximum=1.0)
    portal = table.get("portal", DEFAULT_GLASS_PORTAL)
    if not isinstance(portal, bool):
        raise InputError(f"{where}: 'portal' must be true or false, got {show(portal)}")
    model = table.get("model", GLAZING_MODELS[0])
    if not isinstance(model, str) or model not in GLAZING_MODELS:
        raise InputError(f"{where}: 'model' must be one of {', '.join(repr(m) for m in GLAZING_MODELS)}, "
                         f"got {show(model)}")
    if model == "constant":
        for key in ("panes", "refractive_index"):
            if key in table:
                raise InputError(f"{where}: '{key}' applies to model = \"fresnel\" only")
        if "reflectance" in table:
            rho = get_rgb(table, "reflectance", where, maximum=1.0)
        else:
            rho = tuple(thin_pane_reflectance(t) for t in tau)
        for t, r in zip(tau, rho):
            if t + r > 1.0 + 1e-12:
                raise InputError(f"{where}: transmittance + reflectance must not exceed 1")
        return Material(name, "glass", reflectance=rho, transmittance=tau, portal=portal, model="constant")
    if "reflectance" in table:
        raise InputError(f"{where}: 'reflectance' applies to model = \"constant\" only (a Fresnel pane's "
                         "reflectance follows from its refractive_index)")
    panes = table.get("panes", 1)
    if isinstance(panes, bool) or panes not in (1, 2):
        raise InputError(f"{where}: 'panes' must be 1 or 2, got {show(panes)}")
    index = get_number(table, "refractive_index", where, default=GLASS_INDEX, minimum=1.0, maximum=4.0,
                       min_inclusive=False)
    top = max_transmittance(index, panes)
    if max(tau) > top + 1e-12:
        raise InputError(f"{where}: 'transmittance' {max(tau):g} is more than {panes} clear "
                         f"pane{'s' if panes == 2 else ''} of refractive index {index:g} transmit "
                         f"({top:.4f}); lower it or use model = \"constant\"")
    tn = pane_transmissivity(np.array(tau), index, panes)
    _, rho = glazing_optics(np.ones(1), tn, index, panes)
    return Material(name, "glass", reflectance=tuple(float(v) for v in rho[0]), transmittance=tau,
                    portal=portal, model="fresnel", panes=int(panes), index=float(index))


# ---------------------------------------------------------------------------
# Arrays for the engine
# ---------------------------------------------------------------------------

@dataclass
class MaterialTable:
    """The materials as arrays indexed by material id, for vectorised shading."""

    kind: np.ndarray            # (m,) int8, one of DIFFUSE, GLASS, MIRROR, LIGHT
    reflectance: np.ndarray     # (m, 3) float64 (glass: normal incidence)
    transmittance: np.ndarray   # (m, 3) float64 (glass: normal incidence)
    luminance: np.ndarray       # (m, 3) float64 [cd/m²]
    portal: np.ndarray          # (m,) bool, glass sampled by area in the indirect step
    fresnel: np.ndarray = None          # (m,) bool, angle-dependent (Fresnel) glass
    panes: np.ndarray = None            # (m,) int8, panes of Fresnel glass
    index: np.ndarray = None            # (m,) float64, refractive index of Fresnel glass
    transmissivity: np.ndarray = None   # (m, 3) float64, t_n of each pane of Fresnel glass

    def __post_init__(self):
        m = len(self.kind)
        if self.fresnel is None:
            self.fresnel = np.zeros(m, bool)
        if self.panes is None:
            self.panes = np.ones(m, np.int8)
        if self.index is None:
            self.index = np.full(m, GLASS_INDEX)
        if self.transmissivity is None:
            self.transmissivity = np.zeros((m, 3))

    @classmethod
    def from_materials(cls, materials: list[Material]) -> "MaterialTable":
        fresnel = np.array([m.fresnel for m in materials], dtype=bool)
        tn = np.zeros((len(materials), 3))
        for i, m in enumerate(materials):
            if m.fresnel:
                tn[i] = pane_transmissivity(np.array(m.transmittance, np.float64), m.index, m.panes)
        return cls(
            kind=np.array([m.code for m in materials], dtype=np.int8),
            reflectance=np.array([m.reflectance for m in materials], dtype=np.float64).reshape(-1, 3),
            transmittance=np.array([m.transmittance for m in materials], dtype=np.float64).reshape(-1, 3),
            luminance=np.array([m.luminance for m in materials], dtype=np.float64).reshape(-1, 3),
            portal=np.array([m.portal for m in materials], dtype=bool),
            fresnel=fresnel,
            panes=np.array([m.panes if m.fresnel else 1 for m in materials], dtype=np.int8),
            index=np.array([m.index if m.fresnel else GLASS_INDEX for m in materials], dtype=np.float64),
            transmissivity=tn,
        )

    @property
    def angular(self) -> bool:
        """Some material's transmittance or reflectance depends on the angle of incidence."""
        return bool(self.fresnel.any())

    def specular(self, mat, cos_i):
        """Specular transmittance and reflectance of materials ``mat`` (k,) hit at
        incidence cosines ``cos_i`` (k,): ``(tau, rho)``, each (k, 3).

        Fresnel glass by :func:`glazing_optics`; constant glass its constants; mirrors
        (0, ρ); other kinds (0, their reflectance), which callers do not use.
        """
        mat = np.asarray(mat, np.int64)
        tau = self.transmittance[mat].copy()
        rho = self.reflectance[mat].copy()
        tau[self.kind[mat] != GLASS] = 0.0
        sel = np.flatnonzero(self.fresnel[mat])
        if len(sel):
            cos_i = np.asarray(cos_i, np.float64)
            groups = np.stack([self.index[mat[sel]], self.panes[mat[sel]]], axis=1)
            for n, p in np.unique(groups, axis=0):          # one pass per kind of glazing
                g = sel[(groups[:, 0] == n) & (groups[:, 1] == p)]
                tau[g], rho[g] = glazing_optics(cos_i[g], self.transmissivity[mat[g]], float(n), int(p))
        return tau, rho

    def glass_transmittance(self, mat, cos_i):
        """(k, 3) transmittance of glass materials ``mat`` at incidence cosines ``cos_i``."""
        return self.specular(mat, cos_i)[0]

"""Record sizing: the radius R_i [m] of each new record, and for elliptical domains its
shape, which with the accuracy a bound the domain a·R_i over which Eq. 5 interpolates
the record (the paper's §3.2; docs/design.md §1; docs/architecture.md, "Record domains" and
departures 2 and 3).

**The split sphere.**  Eq. 3 bounds the change of E with position by the split sphere
of radius R, ε ≤ E (4/(π R) |Δx| + |Δξ|); Eq. 4 generalises it to any geometry with R_0,
the harmonic mean of the distances [m] of the record's hemisphere rays to the surfaces
they hit (:func:`harmonic_mean_distance`; rays to the sky count 1/∞ = 0).

**Light limit.**  The split sphere assumes uniform incident light; daylight through a
window is not.  R_i is also limited by E/|∇_t E| [lux / (lux/m) = m] (Ward & Heckbert
1992) of the light that makes a room non-uniform, sized without the record's own samples
of it (:meth:`RecordSizing.light_limit`): behind the windows Lambert's closed form for
the portals, elsewhere the light the record's rays found when they were traced
(:func:`known_gradient_limit`).

**Hessian domains** (``interpolation = "hessian"``): elliptical domains from the
Hessian of the same light (Schwarzhaupt, Jensen & Jarosz 2012;
:meth:`RecordSizing.hessian_domains`, the kernels in :mod:`lbl_illum.engine.hessian`).

**Clamp.**  R_i is then clamped to [min_spacing, max_spacing + δ(P_i)], δ being the
distance [m] from P_i to the box around the query points (:meth:`RecordSizing.clamp`):
far from every query, a record is seen under a small solid angle and may grow in
proportion (a level-of-detail rule of this project; it keeps a kilometre-wide ground
from costing records, where a limit tied to the scene's bounding box makes records as
large as rooms).

Record sizes depend only on what is known when a record's rays are traced — geometry,
the sky and ground seen directly or through windows — not on the levels below, which
are evaluated later (:mod:`lbl_illum.engine.integrator`, "Order of work").
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .context import LightingContext
from .gather import rows as take
from .gradients import irradiance_gradients
from .hemisphere import orthonormal_basis
from .hessian import MAX_ANISOTROPY, hessian_radii, irradiance_hessian, leak_sectors
from .lambert import portal_irradiance
from ..photometry import luminance

__all__ = ["HESSIAN_FAR", "harmonic_mean_distance", "known_gradient_limit", "RecordSizing"]

#: Rays that reach the sky count as hits this many times the largest record spacing away
#: in the Hessian of a record's hemisphere (:func:`~lbl_illum.engine.hessian.irradiance_hessian`).
HESSIAN_FAR = 1e4


def harmonic_mean_distance(first_t, r, S):
    """(r,) R_0 of Eq. 4: the harmonic mean of each record's S first-hit distances (rays
    to the sky count 1/∞ = 0; a record whose every ray escapes has R_0 = ∞)."""
    inv = np.where(np.isfinite(first_t), 1.0 / np.maximum(first_t, 1e-300), 0.0).reshape(r, S).sum(axis=1)
    with np.errstate(divide="ignore"):
        return np.where(inv > 0, S / np.maximum(inv, 1e-300), np.inf)


def known_gradient_limit(normals, dirs, radiance, first_t, m, n):
    """R_i ≤ E / |∇_t E| (Ward & Heckbert 1992, §3) for the part of each record's
    value known when its rays are traced: sky, ground glow and light seen by
    reflection, through windows included.  That part is what makes daylit rooms
    non-uniform (the split sphere of Eq. 3 assumes uniform light), and it is known
    before the levels below are evaluated.  Records with no known light: no limit.

    normals : (r, 3);  dirs : (r·m·n, 3) the stratified directions of Eq. 2;  radiance :
    (r·m·n, 3) [cd/m²] known along each ray;  first_t : (r·m·n,) [m].  Returns (r,) [m].
    """
    r = len(normals)
    Y = luminance(radiance).reshape(r, m, n)
    E = np.pi / (m * n) * Y.sum(axis=(1, 2))
    limit = np.full(r, np.inf)
    lit = np.flatnonzero(E > 0)       # the gradients of unlit records are not computed
    if len(lit) == 0:
        return limit
    _, trans = irradiance_gradients(normals[lit], dirs.reshape(r, m, n, 3)[lit], Y[lit, ..., None],
                                    first_t.reshape(r, m, n)[lit])     # one channel: luminance
    g = np.linalg.norm(trans[:, 0, :], axis=1)
    with np.errstate(divide="ignore", invalid="ignore"):
        limit[lit] = np.where(g > 0, E[lit] / g, np.inf)
    return limit


@dataclass(frozen=True)
class RecordSizing:
    """How the new records of one diffuse level are sized in one run (the module text).

    context : the scene's lighting context (its portals)
    accuracy : a of the level (0: records that do not interpolate, sized by R_0 alone)
    min_spacing, max_spacing : [m] the clamp on R_i near the query points
    roi : (lo, hi) [m] the box around the run's query points
    portal_luminance : per portal triangle [cd/m²], seen from that box
        (:meth:`LightingContext.portal_luminance`; None without portals)
    interreflected : [lux] the split-flux estimate of the interreflected light still to
        come in the level's values (:meth:`lbl_illum.engine.integrator.RunPlan.interreflected`)
    gradient_limit : limit R_i by E/|∇_t E| of the known light (off only for comparisons)
    hessian : elliptical domains from the Hessian (``interpolation = "hessian"``)

    Every method takes the new records' (r, 3) points ``P`` [m] and shading normals
    ``Ns`` and, where it needs them, their hemispheres: (r·m·n, 3) stratified directions
    ``dirs`` (Eq. 2, M × N = ``m`` × ``n`` cells), (r·m·n, 3) ``radiance`` [cd/m²] known
    along each ray when it was traced and (r·m·n,) ``first_t`` [m] (inf to the sky).
    """

    context: LightingContext
    accuracy: float
    min_spacing: float
    max_spacing: float
    roi: tuple
    portal_luminance: np.ndarray | None
    interreflected: float
    gradient_limit: bool = True
    hessian: bool = False

    def radii(self, P, Ns, dirs, radiance, first_t, m, n):
        """The new records' (R, W, leak): (r,) radii R_i [m] — the harmonic mean distance
        (Eq. 4), limited by the light (:meth:`light_limit`) where the level interpolates,
        clamped (:meth:`clamp`) — and, for elliptical domains, the shape vectors W and
        the leak sectors (:meth:`hessian_domains`; both None for round domains)."""
        if self.hessian and self.accuracy > 0:
            return self.hessian_domains(P, Ns, dirs, radiance, first_t, m, n)
        R0 = harmonic_mean_distance(first_t, len(P), m * n)
        if self.accuracy > 0 and self.gradient_limit:
            R0 = np.minimum(R0, self.light_limit(P, Ns, dirs, radiance, first_t, m, n)[0])
        return self.clamp(R0, P), None, None

    def light_limit(self, P, Ns, dirs, radiance, first_t, m, n):
        """R_i ≤ E/|∇_t E| (Ward & Heckbert 1992) for the light that makes a room's
        illuminance non-uniform, sized without the record's own samples of it.

        A record's domain must not depend on the noise of its own value: where it does,
        records that happened to catch more of a small bright source get smaller domains
        and serve fewer queries than their neighbours that caught less, and interpolation
        reads low (docs/architecture.md, "Record domains").  So for records behind the
        windows (:meth:`lbl_illum.engine.portals.PortalSet.inside`) E and ∇E are Lambert's closed
        form for the portals, unoccluded (:func:`lbl_illum.engine.lambert.portal_irradiance`),
        with the interreflected light the bounces still to come add
        (:attr:`interreflected`) in E; elsewhere — the ground and the buildings outside,
        lit by the open sky, whose estimate from the record's rays is not dominated by a
        few of them — the light its rays found (:func:`known_gradient_limit`).

        Returns ``(limit, terms, behind)``: (r,) [m]; the (r, 6) terms of Lambert's form
        (E, gradient, Hessian; zero rows outside) for the Hessian's domains; (r,) bool, the
        records behind the windows.
        """
        r = len(P)
        portal_set = self.context.portal_set
        behind = portal_set.inside(P) if self.context.portals is not None else np.zeros(r, bool)
        terms = np.zeros((r, 6))
        limit = np.full(r, np.inf)
        if (~behind).any():
            out = np.flatnonzero(~behind)
            sel = np.flatnonzero(np.repeat(~behind, m * n))
            limit[out] = known_gradient_limit(take(Ns, out), take(dirs, sel), take(radiance, sel), first_t[sel], m, n)
        if behind.any():
            inside = np.flatnonzero(behind)
            terms[inside] = self.window_terms(take(P, inside), take(Ns, inside))
            g = np.hypot(terms[behind, 1], terms[behind, 2])
            with np.errstate(divide="ignore", invalid="ignore"):
                limit[behind] = np.where(g > 0, terms[behind, 0] / g, np.inf)
        return limit, terms, behind

    def window_terms(self, P, Ns):
        """(r, 6) the portals' light at the records: Lambert's E [lux] (plus the
        interreflected estimate :attr:`interreflected`), its gradient [lux/m] and Hessian
        [lux/m²] in the tangent plane (:func:`lbl_illum.engine.lambert.portal_irradiance`)."""
        portal_set = self.context.portal_set
        t = portal_irradiance(P, Ns, orthonormal_basis(Ns), self.context.portals.vertices, self.portal_luminance,
                              portal_set.outward)
        t[:, 0] += self.interreflected
        return t

    def hessian_domains(self, P, Ns, dirs, radiance, first_t, m, n):
        """Elliptical record domains (``interpolation = "hessian"``): the Hessian radii of
        Schwarzhaupt, Jensen & Jarosz (2012; :func:`~lbl_illum.engine.hessian.hessian_radii`)
        of the light that shapes the room, sized without the record's own samples of it,
        as :meth:`light_limit` explains: behind the windows the portals' light in closed
        form, its E raised by the interreflected estimate, and the short radius at most
        the harmonic mean distance R_0 of Eq. 4 (the long one 2 R_0), which the closed form
        knows nothing of; elsewhere the Hessian of the light the record's rays found
        (:func:`~lbl_illum.engine.hessian.irradiance_hessian`: luminance scaled to a mean of
        0.99 and raised by 0.01, all 1 where none is known, Radiance 5's rule; rays to the
        sky as hits :data:`HESSIAN_FAR` × max_spacing away).  Both radii are then limited
        by :meth:`light_limit` and clamped (:meth:`clamp`), the long one to at most
        ``MAX_ANISOTROPY`` times the short, and the leak sectors found
        (:func:`~lbl_illum.engine.hessian.leak_sectors`).  Returns (R, W, leak) with R
        the long radius [m], W (r, 3) the shape vectors and leak (r,) the sector masks.
        """
        r, S = len(P), m * n
        accuracy = self.accuracy
        limit, terms, behind = self.light_limit(P, Ns, dirs, radiance, first_t, m, n)
        if (~behind).any():
            out = np.flatnonzero(~behind)
            Y = luminance(radiance).reshape(r, S)[out]
            total = Y.sum(axis=1)
            lit = total > 0.0
            scale = np.where(lit, 0.99 * S / np.where(lit, total, 1.0), 0.0)
            values = np.where(lit[:, None], Y * scale[:, None] + 0.01, 1.0).reshape(-1, m, n)
            terms[out] = irradiance_hessian(Ns[out], dirs.reshape(r, m, n, 3)[out], values,
                                            first_t.reshape(r, m, n)[out], HESSIAN_FAR * self.max_spacing)
        R_s, R_l, axis = hessian_radii(Ns, terms, accuracy)
        R0 = harmonic_mean_distance(first_t, r, S)
        R_s = np.where(behind, np.minimum(R_s, R0), R_s)
        R_l = np.where(behind, np.minimum(R_l, 2.0 * R0), R_l)
        R_s, R_l = np.minimum(R_s, limit), np.minimum(R_l, limit)
        R_s = self.clamp(R_s, P)
        R_l = np.minimum(np.maximum(self.clamp(R_l, P), R_s), MAX_ANISOTROPY * R_s)
        W = axis * np.sqrt(np.maximum((R_l / R_s) ** 2 - 1.0, 0.0))[:, None]
        leak = leak_sectors(Ns, dirs.reshape(r, S, 3), first_t.reshape(r, S), accuracy * R_s, accuracy * R_l,
                            axis, n)
        return R_l, W, leak

    def clamp(self, R0, P):
        """(r,) radii ``R0`` [m] clamped to [min_spacing, max_spacing + δ(P_i)], δ the
        distance [m] from P_i to the box :attr:`roi` around the run's query points (the
        module text, "Clamp"; docs/architecture.md, departures 2 and 3)."""
        lo_box, hi_box = self.roi
        outside = np.maximum(0.0, np.maximum(lo_box - P, P - hi_box))
        far = np.linalg.norm(outside, axis=1)
        return np.clip(R0, self.min_spacing, self.max_spacing + far)

"""The path follower: rays through mirrors, glass and plastic's specular part to where
they end (the paper's §2, ray casting; docs/design.md §3, one batch per stage).

Hemisphere rays of records (grids) and camera rays (images) are followed by the same
loop over depth, at most :data:`MAX_SPECULAR_DEPTH` specular interactions, every stage
on the arrays of all live rays at once:

========================  ==============================================================
stage                     what the ray carries (times the throughput of its chain)
========================  ==============================================================
escaped to the sky        the sky's luminance, or the ground glow below the horizon;
                          for images also the sun's disk (the policy's ``sun_disk``)
hit an emitter            a ``light`` surface's luminance, or a luminaire's opening's
                          I(−d)/A_p(−d) (met before the scene's hit; the openings are
                          not in the scene's geometry) — for images always, for
                          hemisphere rays only after a reflection: one met directly or
                          through glass was counted by the direct step (§5)
diffuse hit               a hit (P, normals, weight = throughput · ρ_d/π) whose luminance
                          is weight · E(P) once the level below is known (plastic's
                          diffuse part too; a plastic hit is also a specular event);
                          on a ``translucent`` surface a second hit on its far side
                          (normals reversed, weight = throughput · τ_d/π): the paper's
                          diffuse transmission, the far side's irradiance from its own
                          records
specular event            mirrors reflect; rough plastic draws a direction from its lobe
                          and its sun highlight is taken by a shadow ray; glass reflects
                          *or* transmits (hemisphere rays: chosen at random in
                          proportion to ρ and τ, weighted to stay unbiased) or reflects
                          *and* transmits (images: both branches followed, as rpict)
========================  ==============================================================

The two places where grids and images legitimately differ are the :class:`PathPolicy`;
nothing else about a path depends on who traced it.  Weak branches play Russian
roulette (Arvo & Kirk 1990) below the policy's throughput floor.  Window-portal
weights of hemisphere rays (multiple importance sampling, Veach 1997 §9.2; see
:mod:`lbl_illum.engine.portal_sampling`) enter through a hook
(:class:`PortalWeights`) called at the first hit and at portal glass.

Units: lengths [m], luminance [cd/m²].
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Protocol

import numpy as np

from .context import LightingContext
from .gather import rows as take
from .raycast import Hits
from ..photometry import luminance
from ..scene.materials import GLASS, LIGHT, PLASTIC, PLASTIC_BRANCH_LIMIT, russian_roulette

__all__ = ["MAX_SPECULAR_DEPTH", "WEIGHT_LIMIT", "PathPolicy", "HEMISPHERE", "CAMERA", "Paths", "PortalWeights", "follow_paths"]

#: Specular (glass, mirror, plastic) interactions a path may follow.
MAX_SPECULAR_DEPTH = 8
#: Throughput floor of image branches (the role of Radiance's ``-lw``): a split at glass
#: doubles a path's rays, and branches below it play Russian roulette.
WEIGHT_LIMIT = 2e-3


@dataclass(frozen=True)
class PathPolicy:
    """How a kind of ray is followed where grids and images legitimately differ.

    glass : ``"choose"`` — one branch at glass, reflection or transmission drawn with
        probabilities p_r, p_t in proportion to the photometric ρ and τ, the throughput
        multiplied by ρ/p_r · (p_r + p_t) or τ/p_t · (p_r + p_t) (unbiased; a hemisphere
        ray stays one ray); ``"split"`` — both branches followed (an image's glass shows
        the reflection and the view through it without noise)
    emitters_always : a ``light`` surface met directly or through glass counts (images);
        otherwise only after a reflection, the direct step having counted it (§5)
    sun_disk : an escaped ray adds the sun's luminance inside its disk (images; for
        hemisphere rays the sun and its images in flat reflectors are direct light)
    roulette : throughput floor of the specular branches below which they play Russian
        roulette, and ``roulette_all``: every branch (images) or plastic's only (grids)
    """

    glass: str
    emitters_always: bool
    sun_disk: bool
    roulette: float
    roulette_all: bool


#: Hemisphere rays of records (grids): choose at glass, emitters only after a reflection.
HEMISPHERE = PathPolicy(glass="choose", emitters_always=False, sun_disk=False, roulette=PLASTIC_BRANCH_LIMIT,
                        roulette_all=False)
#: Camera rays (images): split at glass, every emitter and the sun's disk seen.
CAMERA = PathPolicy(glass="split", emitters_always=True, sun_disk=True, roulette=WEIGHT_LIMIT, roulette_all=True)


class PortalWeights(Protocol):
    """The MIS hook of hemisphere rays drawn beside portal samples."""

    def first_hit(self, ray: np.ndarray, origins: np.ndarray, directions: np.ndarray, hits: Hits) -> np.ndarray | None:
        """At depth 0, for rays ``ray`` (indices among all): set their weights; return the
        rays to keep (bool), or None for all."""

    def through_portal(self, ray: np.ndarray, directions: np.ndarray, hits: Hits, rows: np.ndarray) -> None:
        """At depth 0, the live rays ``rows`` (indices into ``ray``, ``directions`` and
        ``hits`` of that depth) went through portal glass: add its density."""


@dataclass
class Paths:
    """What the follower found for n rays.

    first_t : (n,) distance [m] to each ray's first hit (inf: it escaped)
    radiance : (n, 3) [cd/m²] luminance already known along each ray's chain
    ray, P, Ns, Ng, weight : the diffuse hits — (m,) the ray each belongs to, (m, 3)
        position [m], shading and geometric normals facing the arriving ray, and
        throughput · ρ_d/π [1/sr]
    rays : rays traced
    """

    first_t: np.ndarray
    radiance: np.ndarray
    ray: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))
    P: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    Ns: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    Ng: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    weight: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    rays: int = 0
    #: with ``escapes``: the rays that reached the sky or the ground glow — (e,) the ray,
    #: (e, 3) its direction there and (e, 3) its throughput (what the sky's luminance in
    #: that direction was multiplied by)
    sky_ray: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))
    sky_dir: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    sky_through: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))


def _add(out, index, values, repeated: bool) -> None:
    """out[index] += values; ``repeated``: indices may repeat (split paths), summed."""
    if len(index) == 0:
        return
    if not repeated:
        out[index] += values
        return
    for c in range(3):
        out[:, c] += np.bincount(index, values[:, c], minlength=len(out))


def follow_paths(context: LightingContext, origins, directions, rng: np.random.Generator, policy: PathPolicy,
                 through=None, tmax=None, portal_weights: PortalWeights | None = None, reach=None,
                 progress=None, escapes: bool = False) -> Paths:
    """Follow n rays from ``origins`` [m] in unit ``directions`` until they escape, meet an
    emitter or end at diffuse surfaces, through at most :data:`MAX_SPECULAR_DEPTH`
    specular events (the module docstring gives the stages).

    through : (n, 3) starting throughput (default 1)
    tmax : (n,) the first segment's clipping distance [m] (``inf``: none); beyond it a
        ray sees nothing, as Radiance's ``-va`` (images)
    portal_weights : the MIS hook of hemisphere rays drawn beside portal samples
    reach : (n,) samples on openings: a ray that meets a surface before ``reach`` [m]
        is dropped (its weight set to 0 by ``portal_weights``)
    progress : receives ``update(rays)`` after every depth
    escapes : also return where each ray reached the sky and with what throughput
        (:attr:`Paths.sky_ray`; the daylight coefficients bin them by sky patch)
    """
    mats = context.materials
    tracer = context.tracer
    sky, sun = context.sky, context.sun
    luminous = context.luminous_openings
    split = policy.glass == "split"
    n = len(origins)
    radiance = np.zeros((n, 3))
    first_t = np.full(n, np.inf)
    ray = np.arange(n)
    o = np.asarray(origins, np.float64)
    d = np.asarray(directions, np.float64)
    unit = through is None          # every throughput is 1 until a specular event (then None)
    through = None if unit else np.array(through, np.float64)

    def scaled(index, values):
        """``values`` times the throughput of the rays ``index`` (no product while it is 1)."""
        return values if unit else take(through, index) * values

    reflected = np.zeros(n, bool)   # a reflection happened on the way
    sun_done = np.zeros(n, bool)    # the sun's disk was taken by a highlight's shadow ray
    out = {k: [] for k in ("ray", "P", "Ns", "Ng", "weight", "sky_ray", "sky_dir", "sky_through")}
    rays = 0
    for depth in range(MAX_SPECULAR_DEPTH + 1):
        if len(ray) == 0:
            break
        hits = tracer.intersect(o, d)
        rays += len(ray)
        if progress is not None:
            progress.update(len(ray))
        reached, escaped = hits.hit, ~hits.hit
        if depth == 0:
            first_t[:] = hits.t
            if tmax is not None:
                clip = np.asarray(tmax, np.float64)
                reached = reached & (hits.t <= clip)
                escaped = escaped & ~np.isfinite(clip)
            if portal_weights is not None:
                keep = portal_weights.first_hit(ray, o, d, hits)
                if keep is not None:
                    keep = np.flatnonzero(keep)
                    ray, o, d = ray[keep], take(o, keep), take(d, keep)
                    through = None if unit else take(through, keep)
                    reflected, sun_done = reflected[keep], sun_done[keep]
                    hits = Hits(hits.t[keep], hits.prim[keep])
                    reached, escaped = hits.hit, ~hits.hit
        # -- luminaires' luminous openings met before the scene's hit: emitters under the
        #    rule of light surfaces below; the ray ends there (lbl_illum.engine.luminous_openings)
        if luminous is not None:
            limit = np.minimum(hits.t, clip) if depth == 0 and tmax is not None else hits.t
            seen, L = luminous.seen(o, d, limit, None if policy.emitters_always else reflected, tracer.length_scale)
            if len(seen):
                _add(radiance, ray[seen], scaled(seen, L), split)
                reached, escaped = reached.copy(), escaped.copy()
                reached[seen] = escaped[seen] = False
        # -- escaped to the sky
        esc = np.flatnonzero(escaped)
        if len(esc):
            d_esc = take(d, esc)
            L = sky.luminance(d_esc)
            if policy.sun_disk and sun is not None:
                L[sun.within_disk(d_esc) & ~sun_done[esc]] += sun.luminance
            _add(radiance, ray[esc], scaled(esc, L), split)
            if escapes:
                out["sky_ray"].append(ray[esc])
                out["sky_dir"].append(d_esc)
                out["sky_through"].append(np.ones((len(esc), 3)) if unit else take(through, esc))
        hit = np.flatnonzero(reached)
        if len(hit) == 0:
            break
        P, Ng, Ns = tracer.surface(o, d, hits, hit)
        mat = context.scene.triangles.material[hits.prim[hit]]
        kind = mats.kind[mat]
        # -- diffuse hits end the path (plastic: its diffuse part)
        dif = np.flatnonzero(context.diffuse_reflector[mat])
        if len(dif):
            out["ray"].append(ray[hit[dif]])
            Ns_dif = take(Ns, dif)
            out["P"].append(take(P, dif))
            out["Ns"].append(Ns_dif)
            out["Ng"].append(take(Ng, dif))
            weight = take(context.rho_over_pi, mat[dif])
            if context.plastic_fresnel:           # polished plastic: ρ_d(θ) = (1 − ρ_s(θ)) C
                weight = mats.diffuse_at(mat[dif], np.einsum("ij,ij->i", take(d, hit[dif]), Ns_dif)) / np.pi
            out["weight"].append(scaled(hit[dif], weight))
        # -- diffuse transmission: the far side's irradiance, seen through the surface
        #    (translucent: L = ρ E_near/π + τ E_far/π; the far side's own records hold E_far)
        back = np.flatnonzero(context.diffuse_transmitter[mat])
        if len(back):
            out["ray"].append(ray[hit[back]])
            out["P"].append(P[back])
            out["Ns"].append(-Ns[back])
            out["Ng"].append(-Ng[back])
            weight = context.tau_over_pi[mat[back]]
            out["weight"].append(scaled(hit[back], weight))
        # -- emitters
        is_light = kind == LIGHT
        lit = np.flatnonzero(is_light if policy.emitters_always else is_light & reflected[hit])
        if len(lit):
            _add(radiance, ray[hit[lit]], scaled(hit[lit], mats.luminance[mat[lit]]), split)
        # -- the sun's highlight on rough plastic, by a shadow ray (the lobe's continuation
        #    below does not count the sun's disk again)
        if context.sun_glossy:
            gl = np.flatnonzero(mats.glossy[mat])
            if len(gl):
                _add(radiance, ray[hit[gl]], scaled(hit[gl], context.direct.sun_highlight(
                    d[hit[gl]], P[gl], Ng[gl], Ns[gl], mat[gl], rng)), split)
        # -- specular events continue
        spec = np.flatnonzero(mats.continues[mat])
        if len(spec) == 0 or depth == MAX_SPECULAR_DEPTH:
            break
        s_hit = hit[spec]
        s_mat = mat[spec]
        step = _split if split else _choose
        rows, side, new_d, new_through, was_reflected, transmitted = step(
            mats, policy, take(d, s_hit), take(Ns, spec), take(Ng, spec), s_mat,
            np.ones((len(s_hit), 3)) if unit else take(through, s_hit), rng)
        if portal_weights is not None and depth == 0 and context.portals is not None:
            portal = transmitted[mats.portal[s_mat[transmitted]]]
            if len(portal):
                portal_weights.through_portal(ray, d, hits, s_hit[portal])
        unit = False
        o = tracer.offset(take(P, spec[rows]), side)
        d = new_d
        sun_done = np.where(was_reflected, mats.glossy[s_mat[rows]], sun_done[s_hit][rows])
        reflected = reflected[s_hit][rows] | was_reflected
        ray = ray[s_hit][rows]
        through = new_through
    paths = Paths(first_t, radiance, rays=rays)
    if out["ray"]:
        paths.ray, paths.P, paths.Ns, paths.Ng, paths.weight = (np.concatenate(out[k]) for k in
                                                                 ("ray", "P", "Ns", "Ng", "weight"))
    if out["sky_ray"]:
        paths.sky_ray, paths.sky_dir, paths.sky_through = (np.concatenate(out[k]) for k in
                                                           ("sky_ray", "sky_dir", "sky_through"))
    return paths


def _choose(mats, policy: PathPolicy, d, Ns, Ng, mat, through, rng):
    """One continuation per specular hit: glass reflects or transmits, chosen at random.

    Returns ``(rows, side, directions, throughput, reflected)`` of the branches kept —
    ``rows`` indexing the hits, ``side`` the normal to offset the new origin along,
    ``reflected`` whether the branch is a reflection — and ``transmitted``, the hits
    whose ray was transmitted (kept or not)."""
    tau, rho = mats.specular(mat, np.einsum("ij,ij->i", d, Ns))
    p_t = luminance(tau)
    p_r = luminance(rho)
    total = p_t + p_r
    keep = total > 0
    transmit = rng.random(len(mat)) * np.where(keep, total, 1.0) < p_t
    refl_dir, rho = mats.reflect(mat, d, Ns, rho, rng)
    new_d = np.where(transmit[:, None], d, refl_dir)
    side = np.where(transmit[:, None], -Ng, Ng)
    safe = np.where(keep, total, 1.0)[:, None]
    factor = np.where(transmit[:, None], tau / np.maximum(p_t, 1e-300)[:, None],
                      rho / np.maximum(p_r, 1e-300)[:, None]) * safe
    new_through = through * factor
    alive = keep & (new_through.max(axis=1) > 0.0)
    weak = np.flatnonzero(alive & (mats.kind[mat] == PLASTIC)) if not policy.roulette_all else np.flatnonzero(alive)
    if len(weak):
        alive[weak], new_through[weak] = russian_roulette(new_through[weak], rng, policy.roulette)
    rows = np.flatnonzero(alive)
    return rows, take(side, rows), take(new_d, rows), take(new_through, rows), ~transmit[rows], np.flatnonzero(transmit)


def _split(mats, policy: PathPolicy, d, Ns, Ng, mat, through, rng):
    """Every branch of every specular hit: mirrors and plastic reflect, glass reflects and
    transmits (a hit gives two rows).  Returns what :func:`_choose` does."""
    tau, rho = mats.specular(mat, np.einsum("ij,ij->i", d, Ns))
    reflects = np.flatnonzero(rho.max(axis=1) > 0.0)
    transmits = np.flatnonzero((mats.kind[mat] == GLASS) & (tau.max(axis=1) > 0.0))
    refl, rho_refl = mats.reflect(mat[reflects], d[reflects], Ns[reflects], rho[reflects], rng)
    rows = np.concatenate([reflects, transmits])
    directions = np.concatenate([refl, d[transmits]])
    side = np.concatenate([Ng[reflects], -Ng[transmits]])
    factor = np.concatenate([rho_refl, tau[transmits]])
    was_reflected = np.concatenate([np.ones(len(reflects), bool), np.zeros(len(transmits), bool)])
    new_through = through[rows] * factor
    keep, new_through = russian_roulette(new_through, rng, policy.roulette)
    return rows[keep], side[keep], directions[keep], new_through[keep], was_reflected[keep], transmits

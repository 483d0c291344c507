"""Window-portal samples of a record's hemisphere and their multiple importance sampling
(the paper's §5: large sources such as the sky seen through a window belong in the
indirect step, sampled well; docs/architecture.md, "Window portals and multiple
importance sampling"; docs/windows.md).

A primary evaluation at a point behind the portals (:meth:`PortalSet.inside
<lbl_illum.engine.portals.PortalSet.inside>`) draws, besides its S cosine-distributed
hemisphere rays of Eq. 2, n_p points on the portals (:data:`PORTAL_SAMPLE_FRACTION` · S,
stratified over their area).  The two strategies are combined by the balance heuristic
(Veach, "Robust Monte Carlo Methods for Light Transport Simulation", 1997, §9.2): a
sample in direction ω counts f(ω) / (S p_h + n_p p_p) with p_h = cos θ / π [1/sr] the
hemisphere density and p_p [1/sr] the portal density of ω (:func:`portal_density`).

* :func:`portal_sample_plan` — which points sample the portals, and how many samples each;
* :func:`portal_density` — p_p of a direction: the portal glass its first hit is, the
  openings it crosses before;
* :func:`hemisphere_weight` — the balance-heuristic weight S p_h / (S p_h + n_p p_p);
* :class:`PortalBalanceWeights` — those weights for hemisphere rays, as the hook of
  :func:`lbl_illum.engine.paths.follow_paths` (:class:`~lbl_illum.engine.paths.PortalWeights`);
* :func:`trace_hemisphere_rays` — rays followed with the hemisphere policy and, if asked,
  their portal weights;
* :func:`portal_samples` — the portal samples themselves and the light they bring.

Which portals there are and which way they face is :mod:`lbl_illum.engine.portals`.
Every function takes the scene's :class:`~lbl_illum.engine.context.LightingContext`
(tracer, materials, portals, openings) and nothing of the integrator.

Units: lengths [m], luminance [cd/m²], densities [1/sr].
"""

from __future__ import annotations

import numpy as np

from .context import LightingContext
from .gather import rows as take
from .paths import HEMISPHERE, MAX_SPECULAR_DEPTH, follow_paths
from .raycast import Hits, step_past

__all__ = ["PORTAL_SAMPLE_FRACTION", "TRANSLUCENT_SOLID_ANGLE", "portal_sample_plan", "solid_angle", "portal_density",
           "hemisphere_weight", "PortalBalanceWeights", "trace_hemisphere_rays", "portal_samples"]

#: Portal samples per primary evaluation, as a fraction of its hemisphere samples.
PORTAL_SAMPLE_FRACTION = 0.5
#: [sr] Points that see the translucent portals under more than this solid angle do not
#: sample the portals: the cosine-distributed hemisphere finds a sheet that fills a
#: quarter of the sphere, while area samples spread over a vast sheet (a luminous
#: ceiling) send the levels below to every part of it.
TRANSLUCENT_SOLID_ANGLE = np.pi


def portal_sample_plan(context: LightingContext, P, S: int) -> tuple[np.ndarray | None, int]:
    """Which of the (r, 3) points ``P`` [m] of a primary evaluation with ``S`` hemisphere
    rays sample the portals, and how many portal samples each draws.

    Only points behind at least half of the portals' area sample them
    (:meth:`~lbl_illum.engine.portals.PortalSet.inside`), and of those only the ones that
    see the translucent portals under at most :data:`TRANSLUCENT_SOLID_ANGLE`; each draws
    the stratified grid of the portal sampler nearest :data:`PORTAL_SAMPLE_FRACTION` · S
    points.  Both rules depend on position alone, so every estimate stays unbiased.
    Returns ``(inside, n_p)``: the indices of those points (None without portals) and n_p
    (0 when none samples them).
    """
    if context.portals is None:
        return None, 0
    inside = np.flatnonzero(context.portal_set.inside(P))
    prim = context.portal_prim
    sheets = np.flatnonzero(prim >= 0)[context.translucent_portal[prim[prim >= 0]]]      # portal triangle indices
    if len(inside) and len(sheets):
        inside = inside[solid_angle(P[inside], context.portals.vertices[sheets]) <= TRANSLUCENT_SOLID_ANGLE]
    n_p = 0
    if len(inside):
        gx, gy = context.portals.grid(max(1, int(round(PORTAL_SAMPLE_FRACTION * S))))
        n_p = gx * gy
    return inside, n_p


def solid_angle(points, triangles, block: int = 1 << 20) -> np.ndarray:
    """(n,) solid angle [sr] that the (k, 3, 3) ``triangles`` subtend at ``points`` (n, 3)
    [m], summed (overlaps counted twice): tan(Ω/2) = |a·(b×c)| / (abc + (a·b)c +
    (a·c)b + (b·c)a) for each triangle, a, b, c its corners relative to the point
    (Van Oosterom & Strackee, IEEE Trans. Biomed. Eng. 30, 1983)."""
    points = np.asarray(points, np.float64)
    out = np.zeros(len(points))
    step = max(1, block // max(1, len(triangles)))
    for lo in range(0, len(points), step):
        rel = triangles[None] - points[lo:lo + step, None, None, :]           # (m, k, 3, 3)
        a, b, c = rel[:, :, 0], rel[:, :, 1], rel[:, :, 2]
        la, lb, lc = (np.linalg.norm(x, axis=-1) for x in (a, b, c))
        triple = np.abs(np.einsum("mkc,mkc->mk", a, np.cross(b, c)))
        dot = lambda x, y: np.einsum("mkc,mkc->mk", x, y)          # noqa: E731
        den = la * lb * lc + dot(a, b) * lc + dot(a, c) * lb + dot(b, c) * la
        out[lo:lo + step] = (2.0 * np.arctan2(triple, den)).sum(axis=1)
    return out


def portal_density(context: LightingContext, directions, t, prim=None, origins=None) -> np.ndarray:
    """Solid-angle density [1/sr] of drawing ``directions`` by one portal sample.

    A point drawn on portal triangle k (area density p_A) at distance t seen under
    cosine cos_p is the direction's density p_A t² / cos_p.  The sum covers, for rays
    with first hits at distance ``t``:

    * ``prim`` given: the portal glass triangle each ray's first hit is (entries that
      are no portal add nothing);
    * ``origins`` given: every opening of ``[[portals]]`` the ray crosses before t
      (found with the openings' own tracer, nearest first; an opening counts only
      when nothing lies between it and the point, as for its samples).
    """
    portals = context.portals
    directions = np.asarray(directions, np.float64)
    density = np.zeros(len(directions))
    if prim is not None and len(directions):
        k = context.portal_index[np.asarray(prim, np.int64)]
        glass = np.flatnonzero(k >= 0)
        if len(glass):
            kk = k[glass]
            cos_p = np.abs(np.einsum("ij,ij->i", take(portals.normals, kk), take(directions, glass)))
            density[glass] = portals.pdf_area(kk) * t[glass] ** 2 / np.maximum(cos_p, 1e-300)
    if origins is None or context.openings is None or len(directions) == 0:
        return density
    live = np.arange(len(directions))
    o = np.asarray(origins, np.float64)
    d, tmax, start = directions, np.asarray(t, np.float64), np.zeros(len(directions))
    for _ in range(MAX_SPECULAR_DEPTH):
        hits = context.openings.intersect(o, d)
        crossed = np.flatnonzero(hits.t < tmax)
        live, o, d, tmax, start, tt, prim_o = (live[crossed], take(o, crossed), take(d, crossed), tmax[crossed],
                                               start[crossed], hits.t[crossed], hits.prim[crossed])
        if len(live) == 0:
            break
        kk = context.opening_first + prim_o
        dist = start + tt                                 # from the ray's origin
        cos_p = np.abs(np.einsum("ij,ij->i", portals.normals[kk], d))
        density[live] += portals.pdf_area(kk) * dist ** 2 / np.maximum(cos_p, 1e-300)
        o, step = step_past(o, d, tt, context.openings.length_scale)
        start, tmax = start + step, tmax - step
    return density


def hemisphere_weight(normals, directions, density, S, n_p) -> np.ndarray:
    """Balance-heuristic weight S p_h / (S p_h + n_p p_p) of a ray in direction ω from
    a point drawing S hemisphere rays (p_h = max(0, N·ω)/π) and n_p portal samples of
    portal density p_p = ``density`` (Veach 1997, §9.2).  The same weight serves
    hemisphere rays and portal samples (see :func:`portal_samples`)."""
    p_h = S * np.maximum(np.einsum("ij,ij->i", normals, directions), 0.0) / np.pi
    p_p = n_p * np.asarray(density, np.float64)
    return np.where(p_p > 0.0, p_h / np.maximum(p_h + p_p, 1e-300), 1.0)


class PortalBalanceWeights:
    """The balance-heuristic weights of hemisphere rays drawn beside portal samples
    (:func:`trace_hemisphere_rays`; the :class:`~lbl_illum.engine.paths.PortalWeights`
    hook of :func:`lbl_illum.engine.paths.follow_paths`): the openings a ray crosses
    before its first hit, plus the portal glass it goes through if its first hit is one
    and it is transmitted there.

    n rays from points with (n, 3) ``normals`` drawing ``S`` hemisphere rays and ``n_p``
    portal samples (a number, or one per ray; 0: draws none); ``reach`` (n,) [m], for
    portal samples on openings: the distance to the point drawn, which the ray must
    reach unobstructed.  :attr:`weight` (n,) holds the weights (1 until set).
    """

    def __init__(self, context: LightingContext, n: int, normals, S, n_p, reach=None):
        self.context, self.normals, self.S = context, normals, S
        self.n_p = np.broadcast_to(np.asarray(n_p, np.float64), (n,))     # per ray (0: draws none)
        self.weight = np.ones(n)
        self.reach = reach              # samples on openings: unobstructed up to them
        self.p_open = None

    def first_hit(self, ray, origins, directions, hits):
        keep = None
        if self.reach is not None:
            keep = hits.t > self.reach
            self.weight[~keep] = 0.0
            ray, origins, directions = ray[keep], take(origins, keep), take(directions, keep)
            hits = Hits(hits.t[keep], hits.prim[keep])
        self.p_open = portal_density(self.context, directions, hits.t, origins=origins)
        density = self.p_open
        sheet = np.flatnonzero(hits.hit)
        sheet = sheet[self.context.translucent_portal[hits.prim[sheet]]]
        if len(sheet):              # a translucent portal ends the ray on both its faces
            density = density.copy()
            density[sheet] += portal_density(self.context, take(directions, sheet), hits.t[sheet], prim=hits.prim[sheet])
        self.weight[ray] = hemisphere_weight(take(self.normals, ray), directions, density, self.S, self.n_p[ray])
        return keep

    def through_portal(self, ray, directions, hits, rows):
        d = take(directions, rows)
        density = self.p_open[rows] + portal_density(self.context, d, hits.t[rows], prim=hits.prim[rows])
        r = ray[rows]
        self.weight[r] = hemisphere_weight(take(self.normals, r), d, density, self.S, self.n_p[r])


def trace_hemisphere_rays(context: LightingContext, origins, directions, rng, through=None, portal_mis=None,
                          escapes: bool = False):
    """Follow rays through specular surfaces to the sky, a light or a diffuse surface
    (:func:`~lbl_illum.engine.paths.follow_paths` with the ``HEMISPHERE`` policy).

    ``through`` (n, 3) is each ray's starting throughput (default 1).
    ``portal_mis = (normals, S, n_p)`` marks rays from points that draw S cosine-
    distributed hemisphere rays about ``normals`` (n, 3) and ``n_p`` (a number, or one
    per ray) portal samples:
    every ray gets the weight S p_h / (S p_h + n_p p_p) (see :func:`portal_samples`),
    p_p the portal density of its direction (:func:`portal_density`) — the openings
    it crosses before its first hit, plus the portal glass it goes through if its first
    hit is one and it is transmitted there.  ``portal_mis = (normals, S, n_p, reach)``
    marks portal samples on openings instead, ``reach`` (n,) the distance to the point
    drawn: a ray that meets a surface before it is dropped (weight 0).
    Glass transmits and reflects by its angle of incidence
    (:meth:`~lbl_illum.scene.materials.MaterialTable.specular`).

    Returns ``(first_t, radiance, hits, mis)``: (n,) first-hit distance (inf to the
    sky), (n, 3) radiance already known (sky, lights seen by reflection), the diffuse
    hits as a dict of arrays ``ray, P, Ns, Ng, weight`` (weight = throughput ρ/π),
    and (n,) the MIS weight of each ray (1 unless it went through a portal), which
    the radiance and hit weights do not include.  With ``escapes`` the hits also hold
    ``sky_ray, sky_dir, sky_through``: the rays that reached the sky, where and with what
    throughput (:class:`~lbl_illum.engine.paths.Paths`).
    """
    weights = None if portal_mis is None else PortalBalanceWeights(context, len(origins), *portal_mis)
    paths = follow_paths(context, origins, directions, rng, HEMISPHERE, through=through,
                         portal_weights=weights, escapes=escapes)
    hits = {"ray": paths.ray, "P": paths.P, "Ns": paths.Ns, "Ng": paths.Ng, "weight": paths.weight}
    if escapes:
        hits.update(sky_ray=paths.sky_ray, sky_dir=paths.sky_dir, sky_through=paths.sky_through)
    mis_weight = weights.weight if weights is not None else np.ones(len(origins))
    return paths.first_t, paths.radiance, hits, mis_weight


def portal_samples(context: LightingContext, P, Ns, Ng, S, n_p, rng, origins=None, escapes: bool = False):
    """Light through the portals seen from (P, Ns): the paper's §5 advice that large
    sources belong in the indirect step, sampled well.

    Each point gets ``n_p`` (about ``PORTAL_SAMPLE_FRACTION · S``) points on the
    portals — portal glass and the openings of ``[[portals]]`` — stratified over their
    area.  A sample on portal glass counts only if the first surface its ray meets is
    the portal triangle it was drawn on; through the pane it carries τ(θ) and
    continues like any ray (sky, ground, deeper levels).  A sample on an opening
    counts only if nothing lies between the point and it; its ray goes on from the
    point like any ray, since openings are invisible to every other ray.
    Hemisphere rays and portal samples are combined by the balance heuristic of
    multiple importance sampling (Veach, "Robust Monte Carlo Methods for Light
    Transport Simulation", 1997, §9.2): a sample in direction ω counts
    f(ω) / (S p_h + n_p p_p) with p_h = cos θ / π and p_p the portal density
    (:func:`portal_density`), so cosine sampling carries the light near a window and
    area sampling the small distant windows.  Values are scaled by S/π to join the
    hemisphere sums of Eq. 2, which makes a sample's factor the weight S p_h /
    (S p_h + n_p p_p) of :func:`hemisphere_weight`.

    P, Ns, Ng : (r, 3) points [m], shading and geometric normals;  origins : (r, 3) the
    rays' origins (default: P offset along Ng).

    Returns ``(known, hits, owner)`` like the hemisphere part: (r, 3) radiance sums
    known at trace time, the diffuse hits (``P, Ns, Ng, weight``, the weight including
    the sample's MIS factor) and (m,) the point each hit belongs to.  With ``escapes``
    the hits also hold ``sky_owner, sky_dir, sky_weight``: each sample that reached the
    sky, its point, direction there and throughput times its MIS factor.
    """
    tracer = context.tracer
    r = len(P)
    tri, x, pdf_area, n_p = context.portals.sample_stratified(rng, r, n_p)
    owner = np.repeat(np.arange(r), n_p)
    o = np.repeat(tracer.offset(P, Ng) if origins is None else origins, n_p, axis=0)
    w = x - o
    dist = np.linalg.norm(w, axis=1)
    w /= np.maximum(dist, 1e-300)[:, None]
    cos_r = np.einsum("ij,ij->i", take(Ns, owner), w)
    usable = (cos_r > 0.0) & (dist > 0.0)
    target = context.portal_prim[tri]
    known = np.zeros((r, 3))
    keys = ("P", "Ns", "Ng", "weight")
    parts, owners = [], []
    sky = {"sky_owner": [], "sky_dir": [], "sky_weight": []}

    def add(use, radiance, p_hits, weight):
        for c in range(3):
            known[:, c] += np.bincount(owner[use], radiance[:, c] * weight, minlength=r)
        if len(p_hits["ray"]):
            parts.append({**{key: p_hits[key] for key in keys[:3]},
                          "weight": p_hits["weight"] * np.take(weight, p_hits["ray"])[:, None]})
            owners.append(owner[use][p_hits["ray"]])
        if escapes and len(p_hits["sky_ray"]):
            sky["sky_owner"].append(owner[use][p_hits["sky_ray"]])
            sky["sky_dir"].append(p_hits["sky_dir"])
            sky["sky_weight"].append(p_hits["sky_through"] * weight[p_hits["sky_ray"], None])

    # portal glass and translucent sheets: the triangle drawn on must be the first surface met
    use = np.flatnonzero(usable & (target >= 0))
    if len(use):
        hits = tracer.intersect(take(o, use), take(w, use))
        first = np.flatnonzero(hits.prim == target[use])
        use = use[first]
        if len(use):
            sub = Hits(hits.t[first], hits.prim[first])
            o_use, w_use = take(o, use), take(w, use)
            density = portal_density(context, w_use, sub.t, prim=sub.prim, origins=o_use)
            weight = hemisphere_weight(take(Ns, owner[use]), w_use, density, S, n_p)
            # a translucent sheet: the ray ends there, on the near face (ρ/π) and the far
            # face (τ/π), as any ray that meets it does (paths.py)
            sheet = context.translucent_portal[sub.prim]
            if sheet.any():
                _, radiance, p_hits, _ = trace_hemisphere_rays(context, o[use[sheet]], w[use[sheet]], rng,
                                                               escapes=escapes)
                add(use[sheet], radiance, p_hits, weight[sheet])
            # glass: through the pane at τ(θ), on like any ray
            pane = ~sheet
            if pane.any():
                pane = np.flatnonzero(pane)
                use, weight, sub = use[pane], weight[pane], Hits(sub.t[pane], sub.prim[pane])
                w_use = take(w_use, pane)
                Pp, Ngp, _ = tracer.surface(take(o_use, pane), w_use, sub, np.arange(len(use)))
                cos_p = np.einsum("ij,ij->i", take(tracer.normals, sub.prim), w_use)
                tau = context.materials.glass_transmittance(context.scene.triangles.material[sub.prim], cos_p)
                _, radiance, p_hits, _ = trace_hemisphere_rays(context, tracer.offset(Pp, -Ngp), w_use, rng,
                                                               through=tau, escapes=escapes)
                add(use, radiance, p_hits, weight)
    # openings: unobstructed up to the point drawn, then on like any ray
    use = np.flatnonzero(usable & (target < 0))
    if len(use):
        _, radiance, p_hits, weight = trace_hemisphere_rays(context, take(o, use), take(w, use), rng,
                                                            portal_mis=(take(Ns, owner[use]), S, n_p, dist[use]),
                                                            escapes=escapes)
        add(use, radiance, p_hits, weight)
    if escapes:
        escaped = {key: np.concatenate(v) if v else np.zeros((0, 3) if key != "sky_owner" else 0)
                   for key, v in sky.items()}
        escaped["sky_owner"] = escaped["sky_owner"].astype(np.int64)
    else:
        escaped = {}
    if not parts:
        return known, {**{key: np.zeros((0, 3)) for key in keys}, **escaped}, np.zeros(0, np.int64)
    hits = {key: np.concatenate([part[key] for part in parts]) for key in keys}
    return known, {**hits, **escaped}, np.concatenate(owners)

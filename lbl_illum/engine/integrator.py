"""Wavefront irradiance-cache integrator (the paper's §3 and §3.4; DESIGN.md §3).

Illuminance at a query point P with normal N is the direct part (sun and light
surfaces, :mod:`lbl_illum.engine.direct`) plus the indirect part, interpolated from the
records of diffuse level 0.  A record of level k integrates the hemisphere by Eq. 2;
its rays end

* in the sky or ground glow: luminance of the sky model, times the transmittance of
  any glass crossed;
* on a ``light`` surface (or the sun) reached directly or through glass: nothing —
  the direct calculation counted it (§5);  reached after a specular reflection:
  its luminance;
* on a diffuse surface at Q: ρ/π (E_direct(Q) + E_{k+1}(Q)) where E_{k+1} is
  interpolated from level k+1 — or, at the bounce limit k = bounces, ρ/π · ambient;
* on glass or a mirror: the ray continues specularly (glass chooses reflection or
  transmission at random in proportion to their sizes, keeping the estimate unbiased).

**Order of work.**  Where a record goes, and its R_i, depend only on geometry; its
value needs the level below.  So the levels are *placed* top-down and *evaluated*
bottom-up:

1. Placement of level k, coarse to fine: look the queries up; among those no record
   covers, pick one per cell of a grid (cells keyed by position and dominant normal
   axis), halving the cell each pass; trace all their hemispheres in one batch; make
   them records (P, N, R_i = harmonic mean ray length, clamped); look the rest up
   again; repeat until every query is covered.  The diffuse hits of the new records'
   rays are the queries of level k+1.
2. Evaluation from the deepest level up: direct light at the hits (one batch of
   shadow rays), the level below interpolated from its *complete* record set, the
   records' values by Eq. 2.
3. Every query is answered from the complete record set of its level.

So results do not depend on the order of the queries, and a rerun from a saved cache
is identical.  Python loops only over levels and passes; rays, records and queries are
arrays.

**Record radius.**  R_i is the harmonic mean distance of Eq. 4, limited by
E/|∇_t E| of the light known when the record's rays are traced (sky and ground seen
directly or through windows; see :meth:`Integrator._known_gradient_limit`), then clamped to [min_spacing, max_spacing + δ(P_i)], δ being
the distance from P_i to the box around the query points: far from every query, a
record is seen under a small solid angle and may grow in proportion (a level-of-detail
rule of this project; it keeps a kilometre-wide ground from costing records, where a
limit tied to the scene's bounding box makes records as large as rooms).
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import time
from dataclasses import dataclass, field

import numpy as np
from numba import njit

from .cache import IrradianceCache, LevelRecords
from .direct import DirectLight
from .hemisphere import (MAX_ANISOTROPY, cell_counts, cosine_directions, hessian_radii, irradiance_gradients,
                         irradiance_hessian, leak_sectors, limit_gradients, orthonormal_basis, stratified_directions)
from .lambert import portal_irradiance
from ..scene.materials import GLASS, LIGHT, MIRROR, PLASTIC, PLASTIC_BRANCH_LIMIT, MaterialTable, russian_roulette
from ..options import Options
from .placement import distance_bands, pick_per_cell
from ..photometry import luminance
from .portals import build_portals
from ..scene.geometry import TriangleSampler, Triangles
from .raycast import Hits, Tracer, step_past
from ..scene.scenefile import Scene

__all__ = ["IlluminanceResult", "RunStats", "compute_illuminance", "Integrator", "scene_fingerprint",
           "default_spacing", "spacing_rng"]

#: Specular (glass, mirror) interactions a hemisphere ray may follow.
MAX_SPECULAR_DEPTH = 8
#: Russian roulette of weak paths below the first reflection at accuracy 0: a path whose
#: photometric throughput from its sensor (the product of ρ·(MIS weight) of its hits,
#: :meth:`Integrator._path_roulette`) falls below this is continued with probability
#: throughput / limit and then weighted up, so its expectation is unchanged.
PATH_ROULETTE_LIMIT = 0.1
#: Light-surface shadow rays per query point (hemisphere hits use one).
QUERY_LIGHT_SAMPLES = 16
#: Record spacing defaults: max = D / 2, min = max / 16, D the extent of the queries.
#: (On the office example min = max/64 made 2.4× the records of max/16 at the same
#: error against a converged reference: 12,043 against 5,026 level-2 records.)
MAX_SPACING_FRACTION = 0.5
SPACING_RATIO = 16.0
#: Portal samples per primary evaluation, as a fraction of its hemisphere samples.
PORTAL_SAMPLE_FRACTION = 0.5
#: Rays that reach the sky count as hits this many times the largest record spacing away
#: in the Hessian of a record's hemisphere (:func:`~lbl_illum.engine.hemisphere.irradiance_hessian`).
HESSIAN_FAR = 1e4
#: Passes of placement before all remaining uncovered queries are taken at once.
MAX_PASSES = 64
#: Hemisphere rays traced in one batch: the records of a pass are traced in blocks of at
#: most this many rays, which bounds the temporary arrays of a pass (about 300 bytes a ray).
MAX_BATCH_RAYS = 1 << 20
#: Queries of one level taken at a time.  A level with more queries is placed and
#: evaluated block by block, depth first (:meth:`Integrator._solve_level`): every block
#: that is done holds complete records, so an interruption loses at most the open block
#: of each level, and the memory held for records waiting for their values is bounded.
#: Results depend on it only where a level has more queries than this (docs/cache-files.md).
QUERY_BLOCK = 1 << 16

# random-stream tags
_TAG_HEMISPHERE, _TAG_DIRECT_HITS, _TAG_DIRECT_QUERIES, _TAG_PROBE = 1, 2, 3, 4


@njit(cache=True)
def _add_hit_light(owner, weight, E_hit, known, ray, mis, ray_L):
    """known[owner[h]] += weight[h] E_hit[h];  ray_L[ray[h]] += the same / mis[ray[h]] for
    hits of hemisphere rays (ray ≥ 0; portal samples have -1).  ``ray`` empty: no ray sums."""
    rays = ray.shape[0] > 0
    for h in range(owner.shape[0]):
        i = owner[h]
        r = ray[h] if rays else -1
        scale = 1.0 / max(mis[r], 1e-12) if r >= 0 else 0.0
        for c in range(3):
            v = weight[h, c] * E_hit[h, c]
            known[i, c] += v
            if r >= 0:
                ray_L[r, c] += v * scale


@njit(cache=True)
def _compact(keep, todo, P, N, band):
    """The entries of the uncovered queries' arrays where ``keep`` is true, in one pass."""
    m = 0
    for i in range(keep.shape[0]):
        m += keep[i]
    todo2 = np.empty(m, todo.dtype)
    P2 = np.empty((m, 3))
    N2 = np.empty((m, 3))
    band2 = np.empty(m, band.dtype)
    j = 0
    for i in range(keep.shape[0]):
        if keep[i]:
            todo2[j] = todo[i]
            band2[j] = band[i]
            for c in range(3):
                P2[j, c] = P[i, c]
                N2[j, c] = N[i, c]
            j += 1
    return todo2, P2, N2, band2


def _harmonic_mean_distance(first_t, r, S):
    """(r,) R_0 of Eq. 4: the harmonic mean of each record's S first-hit distances (rays
    to the sky count 1/∞ = 0; a record whose every ray escapes has R_0 = ∞)."""
    inv = np.where(np.isfinite(first_t), 1.0 / np.maximum(first_t, 1e-300), 0.0).reshape(r, S).sum(axis=1)
    with np.errstate(divide="ignore"):
        return np.where(inv > 0, S / np.maximum(inv, 1e-300), np.inf)


@dataclass
class RunStats:
    """What a calculation did."""

    records: list = field(default_factory=list)          # records per level, after the run
    new_records: list = field(default_factory=list)      # primary evaluations per level, this run
    queries: list = field(default_factory=list)          # cache queries per level
    cache_hits: int = 0                                  # queries answered by records that existed
    rays: int = 0                                        # rays traced by this run
    seconds: float = 0.0
    min_spacing: float = 0.0                             # [m]
    max_spacing: float = 0.0                             # [m]

    @property
    def primary_evaluations(self) -> int:
        return int(sum(self.new_records))


@dataclass
class IlluminanceResult:
    """Illuminance at the query points.

    rgb, direct, indirect : (n, 3) [lux];  illuminance : (n,) photometric [lux]
    """

    rgb: np.ndarray
    direct: np.ndarray
    indirect: np.ndarray
    stats: RunStats

    @property
    def illuminance(self) -> np.ndarray:
        return luminance(self.rgb)


#: Version of the rules that make records' values and sizes (part of the fingerprint: a
#: cache file made with other rules is refused).  3: light limits from the portals in
#: closed form inside, zones (docs/architecture.md, "Record domains"); 4: the sun's images
#: in mirrors and panes are direct light (lbl_illum.engine.sunmirrors); 5: and in polished plastic,
#: with the sun's highlight on rough plastic seen by hemisphere rays.
SIZING_VERSION = 5


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
                      + ((m.specularity, m.roughness) if m.kind == "plastic" else ())
                      for m in scene.materials],
        "sky": scene.sky.parameters,
        "sun": None if scene.sun is None else (scene.sun.altitude, scene.sun.azimuth,
                                               scene.sun.direct_normal_illuminance),
        "options": (options.ambient, [options.level_accuracy(k) for k in range(options.bounces + 1)],
                    [options.level_samples(k) for k in range(options.bounces + 1)]),
    }
    desc["sizing"] = SIZING_VERSION
    if options.interpolation == "hessian":      # other record radii
        desc["domains"] = "hessian"
    h.update(json.dumps(desc, sort_keys=True).encode())
    return h.hexdigest()


@dataclass
class _Queries:
    """A level's queries: (n, 3) points [m], shading and geometric normals, and what only
    some levels carry: the sensors' ray origins at level 0 (:meth:`Tracer.sensor_origins`,
    found once for the hemispheres and the direct light) and the path throughput on
    the one-ray paths of accuracy 0 (:meth:`Integrator._path_roulette`)."""

    P: np.ndarray
    Ns: np.ndarray
    Ng: np.ndarray
    origins: np.ndarray | None = None
    importance: np.ndarray | None = None

    def __len__(self) -> int:
        return len(self.P)

    def take(self, index) -> "_Queries":
        """The queries ``index`` (a slice or an index array)."""
        def part(a):
            return None if a is None else a[index]
        return _Queries(self.P[index], self.Ns[index], self.Ng[index], part(self.origins), part(self.importance))


@dataclass
class _Pending:
    """Records of one level made in this run and waiting for their values."""

    records: list = field(default_factory=list)     # record indices per pass
    known: list = field(default_factory=list)       # (r, 3) radiance sums known at trace time
    samples: list = field(default_factory=list)     # rays per record of each pass
    # Diffuse hits, the next level's queries, are kept until the level is evaluated, for
    # every level at once: positions in float64, normals and weights in float32, indices
    # in int32 (68 bytes a hit instead of 112).
    hit_P: list = field(default_factory=list)       # diffuse hits: the next level's queries
    hit_Ns: list = field(default_factory=list)
    hit_Ng: list = field(default_factory=list)
    hit_weight: list = field(default_factory=list)  # throughput · ρ / π
    hit_owner: list = field(default_factory=list)   # index into the concatenated records
    hit_ray: list = field(default_factory=list)     # hemisphere ray of the hit, -1 for portal samples
    hit_importance: list = field(default_factory=list)  # path throughput of hits feeding path levels
    # per hemisphere ray, kept for the irradiance gradients (levels that interpolate)
    ray_L: list = field(default_factory=list)       # (r·S, 3) radiance known at trace time, unweighted
    ray_mis: list = field(default_factory=list)     # (r·S,) MIS weight
    ray_t: list = field(default_factory=list)       # (r·S,) first-hit distance
    ray_dir: list = field(default_factory=list)     # (r·S, 3) direction
    cells: tuple = (1, 1)                            # (M, N) of Eq. 2 at this level

    def cat(self, name, width=3, dtype=np.float64):
        """The parts of ``name`` as one array (concatenated once, then kept)."""
        parts = getattr(self, name)
        if len(parts) != 1:
            joined = np.concatenate(parts) if parts else np.zeros((0, width) if width else 0, dtype)
            setattr(self, name, [joined])
        return getattr(self, name)[0]


def spacing_rng(seed: int) -> np.random.Generator:
    """The random stream of :func:`default_spacing` for a run of ``seed``."""
    return np.random.default_rng(np.random.SeedSequence([seed, _TAG_PROBE]))


def default_spacing(tracer: Tracer, points, normals, rng: np.random.Generator) -> tuple[float, float]:
    """(min, max) record spacing [m] from the extent of the queries.

    D = max(diagonal of the queries' box, 2 × median distance from the queries to the
    surfaces they see, by 16 cosine-distributed rays from each of up to 256 of them);
    max = D/2 (:data:`MAX_SPACING_FRACTION`), min = max/16 (:data:`SPACING_RATIO`).  The
    scene's bounding box plays no part.
    """
    diag = float(np.linalg.norm(points.max(axis=0) - points.min(axis=0)))
    pick = rng.choice(len(points), size=min(len(points), 256), replace=False)
    o = tracer.offset(points[pick], normals[pick])
    o = np.repeat(o, 16, axis=0)
    d = cosine_directions(np.repeat(normals[pick], 16, axis=0), rng)
    t = tracer.intersect(o, d).t
    t = t[np.isfinite(t)]
    probe = float(np.median(t)) if len(t) else 0.0
    D = max(diag, 2.0 * probe)
    if D <= 0.0:
        D = 1.0
    max_spacing = MAX_SPACING_FRACTION * D
    return max_spacing / SPACING_RATIO, max_spacing


class Integrator:
    """Computes illuminance for one scene and one set of options, with a cache.

    ``progress`` (optional) receives ``update(rays)`` after every batch of rays and
    ``describe(text)`` at every stage.
    """

    def __init__(self, scene: Scene, options: Options | None = None, cache: IrradianceCache | None = None,
                 progress=None):
        self.scene = scene
        self.options = options or scene.options
        self.materials: MaterialTable = scene.material_table
        self.tracer = Tracer(scene.triangles, self.materials.kind, self.materials.transmittance)
        self.direct = DirectLight(self.tracer, self.materials, scene.sun)
        self.sky = scene.sky
        self.sun = self.direct.sun
        #: limit each R_i by E/|∇_t E| of its known light (off only for comparisons)
        self.gradient_limit = True
        # window portals (§5; lbl_illum.engine.portals): portal glass first, then openings, which no
        # other ray sees (their own tracer finds the openings a ray crosses, for the MIS weights)
        self.portal_set = None if scene.sky.is_dark else build_portals(scene, self.tracer, self.materials,
                                                                       find=scene.find_openings)
        ps = self.portal_set
        self.portals = ps.sampler if ps is not None else None
        #: per portal triangle: its scene triangle (portal glass), or -1 (an opening)
        self._portal_prim = ps.prim if ps is not None else np.zeros(0, np.int64)
        portal_ids = self._portal_prim[self._portal_prim >= 0]
        self._portal_index = np.full(len(scene.triangles), -1, np.int64)
        self._portal_index[portal_ids] = np.arange(len(portal_ids))
        openings = self.portals.vertices[len(portal_ids):] if ps is not None else np.zeros((0, 3, 3))
        self._openings = None
        if len(openings):
            self._openings = Tracer(Triangles(openings, np.zeros(len(openings), np.int32),
                                              np.full(len(openings), -1, np.int32)),
                                    np.zeros(1, np.int8), np.zeros((1, 3)), threads=self.tracer.threads)
            self._opening_first = len(portal_ids)     # portal index of the first opening triangle
        #: per material: reflects diffusely (ends a path at a diffuse level: a diffuse
        #: surface or the diffuse part of plastic), and ρ_d/π
        self._diffuse_reflector = self.materials.diffuse_reflectance.max(axis=1) > 0.0
        self._rho_over_pi = self.materials.diffuse_reflectance / np.pi
        used = np.unique(scene.triangles.material)
        specular = np.isin(self.materials.kind[used], (MIRROR, GLASS)) & (self.materials.reflectance[used].max(axis=1) > 0)
        specular |= self.materials.specularity[used] > 0.0
        #: some surface reflects specularly (a mirror, glass with reflectance, plastic with s > 0)
        self._reflects = bool(specular.any())
        #: some plastic is hit: its specular branches play Russian roulette
        self._plastic = bool(np.any(self.materials.kind[used] == PLASTIC))
        #: a sun and some rough plastic: paths meeting it see the sun's highlight
        self._sun_glossy = self.direct.sun is not None and bool(np.any(self.materials.glossy[used]))
        #: some polished plastic's diffuse reflectance depends on the angle of incidence
        self._plastic_fresnel = bool(np.any(self.materials.plastic_fresnel[used]))
        #: elliptical record domains from the Hessian (``interpolation = "hessian"``)
        self.hessian = self.options.interpolation == "hessian"
        self.fingerprint = scene_fingerprint(scene, self.options, self.portal_set)
        self.progress = progress
        B = self.options.bounces
        self.accuracies = [self.options.level_accuracy(k) for k in range(B + 1)]
        self.cache = cache
        if cache is not None and cache.fingerprint != self.fingerprint:
            raise ValueError("cache was made for another scene or other settings")

    def _zone(self, P) -> np.ndarray:
        """(n,) uint8 cache zone of each point (:meth:`lbl_illum.engine.portals.PortalSet.zone`; 0 for
        all without portals)."""
        if self.portal_set is None:
            return np.zeros(len(P), np.uint8)
        return self.portal_set.zone(P)

    def portal_notes(self) -> list[str]:
        """What the user should hear of the portals: openings found in the geometry and
        panes left out because no sky lies behind them (:mod:`lbl_illum.engine.portals`)."""
        ps = self.portal_set
        if ps is None:
            return self.direct.notes()
        notes = [f"unglazed opening found, sampled as a portal: {o.describe(self.scene.unit_scale, self.scene.units)} (find_openings = false to turn "
                 "this off)" for o in ps.openings]
        notes += self.direct.notes()
        if ps.dropped:
            notes.append(f"{ps.dropped} glass {'triangle is' if ps.dropped == 1 else 'triangles are'} not sampled as "
                         "a portal: no sky behind them (portal = true on the material samples them anyway)")
        return notes

    # -- bookkeeping ----------------------------------------------------------------
    def _tick(self, text=None):
        if self.progress is not None:
            if text:
                self.progress.describe(text)
            self.progress.update(self.tracer.rays_traced - self._rays_reported)
        self._rays_reported = self.tracer.rays_traced

    def _rng(self, *key):
        return np.random.default_rng(np.random.SeedSequence([self.options.seed, *key]))

    def _level_active(self, k: int) -> bool:
        """Whether records of level k can be non-zero (else they are never made)."""
        sky_light = not self.sky.is_dark
        if k == self.options.bounces:
            # at the bounce limit a record sees the sky, the ambient value, light surfaces
            # by specular reflection (a mirror, the outside of a pane) and the sun's
            # highlight on rough plastic (the sun's images in flat reflectors are direct
            # light at the hits, which the bounce limit does not reach)
            reflected_light = (self.direct.has_lights and self._reflects) or self._sun_glossy
            return sky_light or self.options.ambient > 0 or reflected_light
        return sky_light or not self.direct.is_dark or self.options.ambient > 0

    def _new_cache(self, points) -> IrradianceCache:
        lo = np.minimum(self.scene.triangles.bounds[0], points.min(axis=0))
        hi = np.maximum(self.scene.triangles.bounds[1], points.max(axis=0))
        half = 0.5 * float(np.max(hi - lo)) * 1.01 + 1e-9
        return IrradianceCache(self.fingerprint, self.accuracies, 0.5 * (lo + hi), half, anisotropic=self.hessian)

    # -- spacing ----------------------------------------------------------------------
    def default_spacing(self, points, normals) -> tuple[float, float]:
        """(min, max) record spacing [m] from the extent of the queries
        (:func:`default_spacing`, with this run's seed)."""
        return default_spacing(self.tracer, points, normals, spacing_rng(self.options.seed))

    # -- hemisphere rays ----------------------------------------------------------------
    def trace_paths(self, origins, directions, rng, through=None, portal_mis=None):
        """Follow rays through specular surfaces to the sky, a light or a diffuse surface.

        ``through`` (n, 3) is each ray's starting throughput (default 1).
        ``portal_mis = (normals, S, n_p)`` marks rays from points that draw S cosine-
        distributed hemisphere rays about ``normals`` (n, 3) and ``n_p`` (a number, or one
        per ray) portal samples:
        every ray gets the weight S p_h / (S p_h + n_p p_p) (see :meth:`_portal_samples`),
        p_p the portal density of its direction (:meth:`_portal_density`) — the openings
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
        the radiance and hit weights do not include.
        """
        mats = self.materials
        n = len(origins)
        radiance = np.zeros((n, 3))
        first_t = np.full(n, np.inf)
        ray = np.arange(n)
        o = np.asarray(origins, np.float64)
        d = np.asarray(directions, np.float64)
        unit = through is None          # every throughput is 1 until a specular event
        through = np.ones((n, 3)) if unit else np.array(through, np.float64)
        mis_weight = np.ones(n)
        reflected = np.zeros(n, bool)
        out = {k: [] for k in ("ray", "P", "Ns", "Ng", "weight")}
        if portal_mis is not None:
            mis_normals, S, n_p = portal_mis[:3]
            n_p = np.broadcast_to(np.asarray(n_p, np.float64), (n,))     # per ray (0: draws none)
            reach = portal_mis[3] if len(portal_mis) > 3 else None
        for depth in range(MAX_SPECULAR_DEPTH + 1):
            if len(ray) == 0:
                break
            hits = self.tracer.intersect(o, d)
            if depth == 0:
                first_t[:] = hits.t
                if portal_mis is not None:
                    if reach is not None:               # samples on openings: unobstructed up to them
                        keep = hits.t > reach
                        mis_weight[~keep] = 0.0
                        ray, o, d, through, reflected = ray[keep], o[keep], d[keep], through[keep], reflected[keep]
                        hits = Hits(hits.t[keep], hits.prim[keep])
                    # (ray = its index among the n rays at depth 0)
                    p_open = self._portal_density(d, hits.t, origins=o)
                    mis_weight[ray] = self._hemisphere_weight(mis_normals[ray], d, p_open, S, n_p[ray])
            esc = np.flatnonzero(~hits.hit)
            if len(esc):
                # (the sun seen after a reflection adds nothing here: the direct light
                # counts it as the sun's image in flat mirrors and panes, lbl_illum.engine.sunmirrors)
                radiance[ray[esc]] += through[esc] * self.sky.luminance(d[esc])
            hit = np.flatnonzero(hits.hit)
            if len(hit) == 0:
                break
            P, Ng, Ns = self.tracer.surface(o, d, hits, hit)
            mat = self.scene.triangles.material[hits.prim[hit]]
            kind = mats.kind[mat]
            # diffuse surfaces end the path (plastic: its diffuse part; its specular part
            # continues below, so a plastic hit is both)
            dif = np.flatnonzero(self._diffuse_reflector[mat])
            if len(dif):
                out["ray"].append(ray[hit[dif]])
                out["P"].append(P[dif])
                out["Ns"].append(Ns[dif])
                out["Ng"].append(Ng[dif])
                weight = self._rho_over_pi[mat[dif]]
                if self._plastic_fresnel:           # polished plastic: ρ_d(θ) = (1 − ρ_s(θ)) C
                    weight = mats.diffuse_at(mat[dif], np.einsum("ij,ij->i", d[hit[dif]], Ns[dif])) / np.pi
                out["weight"].append(weight if unit else through[hit[dif]] * weight)
            lit = np.flatnonzero((kind == LIGHT) & reflected[hit])
            if len(lit):
                radiance[ray[hit[lit]]] += through[hit[lit]] * mats.luminance[mat[lit]]
            # the sun's highlight on rough plastic, by a shadow ray (its lobe's continuation
            # below counts no sun; polished plastic shows the sun as a virtual sun instead)
            if self._sun_glossy:
                gl = np.flatnonzero(mats.glossy[mat])
                if len(gl):
                    radiance[ray[hit[gl]]] += through[hit[gl]] * self.direct.sun_highlight(
                        d[hit[gl]], P[gl], Ng[gl], Ns[gl], mat[gl], rng)
            # specular surfaces continue (plastic: by reflection, into its lobe if rough)
            spec = np.flatnonzero(mats.continues[mat])
            if len(spec) == 0 or depth == MAX_SPECULAR_DEPTH:
                break
            s_hit = hit[spec]
            s_mat = mat[spec]
            ds = d[s_hit]
            ns = Ns[spec]
            tau, rho = mats.specular(s_mat, np.einsum("ij,ij->i", ds, ns))
            p_t = luminance(tau)
            p_r = luminance(rho)
            total = p_t + p_r
            keep = total > 0
            transmit = rng.random(len(spec)) * np.where(keep, total, 1.0) < p_t
            refl_dir, rho = mats.reflect(s_mat, ds, ns, rho, rng)
            new_d = np.where(transmit[:, None], ds, refl_dir)
            side = np.where(transmit[:, None], -Ng[spec], Ng[spec])
            safe = np.where(keep, total, 1.0)[:, None]
            factor = np.where(transmit[:, None], tau / np.maximum(p_t, 1e-300)[:, None],
                              rho / np.maximum(p_r, 1e-300)[:, None]) * safe
            new_through = through[s_hit] * factor
            alive = keep & (new_through.max(axis=1) > 0.0)
            if self._plastic:                       # weak branches from plastic: Russian roulette
                weak = np.flatnonzero(alive & (mats.kind[s_mat] == PLASTIC))
                if len(weak):
                    alive[weak], new_through[weak] = russian_roulette(new_through[weak], rng, PLASTIC_BRANCH_LIMIT)
            if portal_mis is not None and depth == 0 and self.portals is not None:
                through_portal = np.flatnonzero(transmit & mats.portal[s_mat])
                if len(through_portal):
                    sel = s_hit[through_portal]
                    density = p_open[sel] + self._portal_density(d[sel], hits.t[sel], prim=hits.prim[sel])
                    mis_weight[ray[sel]] = self._hemisphere_weight(mis_normals[ray[sel]], d[sel], density, S,
                                                                   n_p[ray[sel]])
            unit = False
            ray = ray[s_hit][alive]
            o = self.tracer.offset(P[spec][alive], side[alive])
            d = new_d[alive]
            through = new_through[alive]
            reflected = (reflected[s_hit] | ~transmit)[alive]
        hits_out = {k: (np.concatenate(v) if v else None) for k, v in out.items()}
        if hits_out["ray"] is None:
            hits_out = {"ray": np.zeros(0, np.int64), "P": np.zeros((0, 3)), "Ns": np.zeros((0, 3)),
                        "Ng": np.zeros((0, 3)), "weight": np.zeros((0, 3))}
        return first_t, radiance, hits_out, mis_weight

    # -- placement (top-down) ---------------------------------------------------------
    def _evaluate_hemispheres(self, k, q: _Queries, pending: _Pending, rng):
        """Trace the hemispheres of new records at the queries ``q``; return their radii
        R_i (clamped), the shapes W_i of elliptical domains and the leak sectors (both None
        for round domains)."""
        P, Ns, Ng = q.P, q.Ns, q.Ng
        samples = self.options.level_samples(k)
        m, n = cell_counts(samples)
        S = m * n
        r = len(P)
        dirs = stratified_directions(Ns, m, n, rng).reshape(-1, 3)
        # level 0 holds the sensor points, which need not lie on a surface
        if q.origins is not None:
            base = q.origins
        else:
            base = self.tracer.sensor_origins(P, Ng) if k == 0 else self.tracer.offset(P, Ng)
        origins = np.repeat(base, S, axis=0)
        n_p = 0
        # portal samples add rays per record; on the one-ray paths of accuracy 0 below
        # the first level they would make every path branch, so those go without (with
        # point samples, accuracy 0 gives the first reflection its full samples: portals)
        path_level = k > 0 and samples == 1
        inside = None
        if self.portals is not None and not path_level:
            # only points behind the portals sample them (lbl_illum.engine.portals)
            inside = np.flatnonzero(self.portal_set.inside(P))
            if len(inside):
                gx, gy = self.portals.grid(max(1, int(round(PORTAL_SAMPLE_FRACTION * S))))
                n_p = gx * gy
        per_ray = np.repeat(np.where(np.isin(np.arange(r), inside), n_p, 0), S) if n_p else None
        mis = (np.repeat(Ns, S, axis=0), S, per_ray) if n_p else None
        first_t, radiance, hits, ray_mis = self.trace_paths(origins, dirs, rng, portal_mis=mis)
        known = (radiance * ray_mis[:, None]).reshape(r, S, 3).sum(axis=1)
        owner_local = hits["ray"] // S
        ray_base = sum(len(x) for x in pending.ray_t)
        hit_ray = hits["ray"] + ray_base
        hemi_ray, hemi_weight = hits["ray"], hits["weight"]           # unweighted by MIS
        hit_weight = hits["weight"] * ray_mis[hits["ray"], None]
        if self.cache.levels[k].accuracy > 0:
            pending.ray_L.append(radiance.astype(np.float32))
            pending.ray_mis.append(ray_mis.astype(np.float32))
            pending.ray_t.append(first_t.astype(np.float32))
            pending.ray_dir.append(dirs.astype(np.float32))
            pending.cells = (m, n)
        if n_p:
            p_known, p_hits, p_owner = self._portal_samples(P[inside], Ns[inside], Ng[inside], S, n_p, rng,
                                                            base[inside])
            known[inside] += p_known
            p_owner = inside[p_owner]
            hits = {key: np.concatenate([hits[key], p_hits[key]]) for key in ("P", "Ns", "Ng")}
            hit_weight = np.concatenate([hit_weight, p_hits["weight"]])
            owner_local = np.concatenate([owner_local, p_owner])
            hit_ray = np.concatenate([hit_ray, np.full(len(p_owner), -1, np.int64)])
        if k == self.options.bounces:
            if self.options.ambient > 0 and len(owner_local):
                for c in range(3):
                    known[:, c] += self.options.ambient * np.bincount(owner_local, hit_weight[:, c], minlength=r)
                if pending.ray_L:   # the ambient value is part of each ray's radiance
                    np.add.at(pending.ray_L[-1], hemi_ray, hemi_weight * self.options.ambient)
        else:
            if self._path_level(k + 1):
                keep, hit_weight, child = self._path_roulette(
                    q.importance if q.importance is not None else np.ones(r), owner_local, hit_weight, rng)
                hits = {key: hits[key][keep] for key in ("P", "Ns", "Ng")}
                owner_local, hit_ray = owner_local[keep], hit_ray[keep]
                pending.hit_importance.append(child)
            base = sum(len(x) for x in pending.samples)      # records traced before these
            pending.hit_P.append(hits["P"])
            pending.hit_Ns.append(hits["Ns"].astype(np.float32))
            pending.hit_Ng.append(hits["Ng"].astype(np.float32))
            pending.hit_weight.append(hit_weight.astype(np.float32))
            pending.hit_owner.append((owner_local + base).astype(np.int32))
            pending.hit_ray.append(hit_ray.astype(np.int32))
        pending.known.append(known)
        pending.samples.append(np.full(r, S))
        if self.hessian and self.cache.levels[k].accuracy > 0:
            return self._hessian_domains(k, P, Ns, dirs, radiance, first_t, m, n)
        R0 = _harmonic_mean_distance(first_t, r, S)
        if self.cache.levels[k].accuracy > 0 and self.gradient_limit:
            R0 = np.minimum(R0, self._light_limit(k, P, Ns, dirs, radiance, first_t, m, n)[0])
        return self._clamp_radius(R0, P), None, None

    def _path_level(self, k) -> bool:
        """Level k follows one ray per record (accuracy 0 below the first reflection)."""
        return (k <= self.options.bounces and self.cache.levels[k].accuracy == 0.0
                and self.options.level_samples(k) == 1)

    @staticmethod
    def _path_roulette(importance, owner, weight, rng):
        """Russian roulette (Arvo & Kirk 1990) of the hits that start one-ray paths.

        A hit's path throughput is its record's ``importance`` (r,) times π·Y(w), w its
        (m, 3) weight (throughput · ρ/π · MIS weight, what it adds to its record per unit
        of irradiance, Eq. 2 without the 1/S of the record's samples).  Hits below
        :data:`PATH_ROULETTE_LIMIT` go on with probability throughput / limit, weighted up
        by its inverse.  Without it, a path trapped where every ray meets several plastic
        surfaces with a specular part (each hit is both a diffuse hit and a continuation:
        the inside of a closed brass doorknob) multiplies at every level.

        Returns ``(keep (m,) bool, weight (k, 3), importance (k,))`` of the hits kept.
        """
        child = importance[owner] * np.pi * luminance(weight)
        keep, scaled = russian_roulette(child[:, None] * np.ones((1, 3)), rng, PATH_ROULETTE_LIMIT)
        factor = scaled[keep, 0] / child[keep]
        return keep, weight[keep] * factor[:, None].astype(weight.dtype), child[keep] * factor

    def _light_limit(self, k, P, Ns, dirs, radiance, first_t, m, n):
        """R_i ≤ E/|∇_t E| (Ward & Heckbert 1992) for the light that makes a room's
        illuminance non-uniform, sized without the record's own samples of it.

        A record's domain must not depend on the noise of its own value: where it does,
        records that happened to catch more of a small bright source get smaller domains
        and serve fewer queries than their neighbours that caught less, and interpolation
        reads low (docs/architecture.md, "Record domains").  So for records behind the
        windows (:meth:`lbl_illum.engine.portals.PortalSet.inside`) E and ∇E are Lambert's closed
        form for the portals, unoccluded (:func:`lbl_illum.engine.lambert.portal_irradiance`),
        with the interreflected light the bounces still to come add
        (:meth:`_interreflected`) in E; elsewhere — the ground and the buildings outside,
        lit by the open sky, whose estimate from the record's rays is not dominated by a
        few of them — the light its rays found (:meth:`_known_gradient_limit`).

        Returns ``(limit, terms, behind)``: (r,) [m]; the (r, 6) terms of Lambert's form
        (E, gradient, Hessian; zero rows outside) for the Hessian's domains; (r,) bool, the
        records behind the windows.
        """
        r = len(P)
        behind = self.portal_set.inside(P) if self.portals is not None else np.zeros(r, bool)
        terms = np.zeros((r, 6))
        limit = np.full(r, np.inf)
        if (~behind).any():
            out = np.flatnonzero(~behind)
            sel = (np.repeat(~behind, m * n))
            limit[out] = self._known_gradient_limit(Ns[out], dirs[sel], radiance[sel], first_t[sel], m, n)
        if behind.any():
            terms[behind] = self._window_terms(P[behind], Ns[behind], k)
            g = np.hypot(terms[behind, 1], terms[behind, 2])
            with np.errstate(divide="ignore", invalid="ignore"):
                limit[behind] = np.where(g > 0, terms[behind, 0] / g, np.inf)
        return limit, terms, behind

    def _window_terms(self, P, Ns, k):
        """(r, 6) the portals' light at records of level k: Lambert's E (plus the
        interreflected estimate of :meth:`_interreflected`), its gradient and Hessian in
        the tangent plane (:func:`lbl_illum.engine.lambert.portal_irradiance`)."""
        t = portal_irradiance(P, Ns, orthonormal_basis(Ns), self.portals.vertices, self._portal_luminance,
                              self.portal_set.outward)
        t[:, 0] += self._interreflected(k)
        return t

    def _interreflected(self, k) -> float:
        """Estimate [lux] of the interreflected light in the value of a level-k record
        inside: the split-flux average (Sumpner's law of the integrating sphere) over the
        B − k bounces still to come, E = Φ ρ / A · (1 − ρ^(B−k)) / (1 − ρ), with Φ the
        flux through the portals, A the area and ρ the mean diffuse reflectance of the
        surfaces inside (:meth:`_inside_stats`).  It depends on the scene alone.  The
        interreflected light varies little over a record's domain; counting it in E keeps
        a window's gradient from shrinking the domains deep in a room, where most of the
        light is interreflected."""
        n = self.options.bounces - k
        rho = self._inside_rho
        if n <= 0 or rho <= 0:
            return 0.0
        first = self._inside_first_bounce
        return first * (1.0 - rho ** n) / (1.0 - rho) if rho < 1.0 else first * n

    def _inside_stats(self) -> tuple[float, float]:
        """(Φ ρ / A [lux], ρ) of the inside zone (:meth:`_interreflected`): Φ = π Σ L_k A_k
        over the portal triangles (luminance seen through each, :meth:`_portal_sources`),
        A and ρ the area and the area-weighted diffuse reflectance of the triangles wholly
        inside (:meth:`lbl_illum.engine.portals.PortalSet.zone`)."""
        tri = self.scene.triangles
        inside = (self._zone(tri.vertices.reshape(-1, 3)).reshape(-1, 3) == 1).all(axis=1)
        area = tri.areas[inside]
        A = float(area.sum())
        if A <= 0.0:
            return 0.0, 0.0
        rho = float((area * luminance(self.materials.diffuse_reflectance)[tri.material[inside]]).sum() / A)
        flux = float(np.pi * (self._portal_luminance * self.portals.area).sum())
        return flux * rho / A, rho

    def _hessian_domains(self, k, P, Ns, dirs, radiance, first_t, m, n):
        """Elliptical record domains (``interpolation = "hessian"``): the Hessian radii of
        Schwarzhaupt, Jensen & Jarosz (2012; :func:`~lbl_illum.engine.hemisphere.hessian_radii`)
        of the light that shapes the room, sized without the record's own samples of it,
        as :meth:`_light_limit` explains: behind the windows the portals' light in closed
        form, its E raised by the interreflected estimate, and the short radius at most
        the harmonic mean distance R_0 of Eq. 4 (the long one 2 R_0), which the closed form
        knows nothing of; elsewhere the Hessian of the light the record's rays found
        (:func:`~lbl_illum.engine.hemisphere.irradiance_hessian`: luminance scaled to a mean of
        0.99 and raised by 0.01, all 1 where none is known, Radiance 5's rule).  Both
        radii are then limited by :meth:`_light_limit` and clamped, and the leak sectors
        found (:func:`~lbl_illum.engine.hemisphere.leak_sectors`).  Returns (R, W, leak) with R
        the long radius.
        """
        r, S = len(P), m * n
        accuracy = self.cache.levels[k].accuracy
        limit, terms, behind = self._light_limit(k, P, Ns, dirs, radiance, first_t, m, n)
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
        R0 = _harmonic_mean_distance(first_t, r, S)
        R_s = np.where(behind, np.minimum(R_s, R0), R_s)
        R_l = np.where(behind, np.minimum(R_l, 2.0 * R0), R_l)
        R_s, R_l = np.minimum(R_s, limit), np.minimum(R_l, limit)
        R_s = self._clamp_radius(R_s, P)
        R_l = np.minimum(np.maximum(self._clamp_radius(R_l, P), R_s), MAX_ANISOTROPY * R_s)
        W = axis * np.sqrt(np.maximum((R_l / R_s) ** 2 - 1.0, 0.0))[:, None]
        leak = leak_sectors(Ns, dirs.reshape(r, S, 3), first_t.reshape(r, S), accuracy * R_s, accuracy * R_l,
                            axis, n)
        return R_l, W, leak

    def _known_gradient_limit(self, normals, dirs, radiance, first_t, m, n):
        """R_i ≤ E / |∇_t E| (Ward & Heckbert 1992, §3) for the part of each record's
        value known when its rays are traced: sky, ground glow and light seen by
        reflection, through windows included.  That part is what makes daylit rooms
        non-uniform (the split sphere of Eq. 3 assumes uniform light), and it is known
        before the levels below are evaluated.  Records with no known light: no limit.
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

    def _portal_sources(self):
        """Per portal triangle, the luminance seen through it from the centre of the query
        points' box: the sky (or ground glow) in the direction of the triangle's centroid,
        times the glass's transmittance at that incidence (1 for an opening)."""
        centre = 0.5 * (self._roi[0] + self._roi[1])
        d = self.portals.vertices.mean(axis=1) - centre
        d /= np.maximum(np.linalg.norm(d, axis=1), 1e-300)[:, None]
        L = luminance(self.sky.luminance(d))
        glass = self._portal_prim >= 0
        if glass.any():
            prim = self._portal_prim[glass]
            cos = np.abs(np.einsum("ij,ij->i", self.tracer.normals[prim], d[glass]))
            tau = self.materials.glass_transmittance(self.scene.triangles.material[prim], cos)
            L[glass] *= luminance(tau)
        return L

    def _portal_density(self, directions, t, prim=None, origins=None):
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
        directions = np.asarray(directions, np.float64)
        density = np.zeros(len(directions))
        if prim is not None and len(directions):
            k = self._portal_index[np.asarray(prim, np.int64)]
            glass = np.flatnonzero(k >= 0)
            if len(glass):
                kk = k[glass]
                cos_p = np.abs(np.einsum("ij,ij->i", self.portals.normals[kk], directions[glass]))
                density[glass] = self.portals.pdf_area(kk) * t[glass] ** 2 / np.maximum(cos_p, 1e-300)
        if origins is None or self._openings is None or len(directions) == 0:
            return density
        live = np.arange(len(directions))
        o = np.asarray(origins, np.float64)
        d, tmax, start = directions, np.asarray(t, np.float64), np.zeros(len(directions))
        for _ in range(MAX_SPECULAR_DEPTH):
            hits = self._openings.intersect(o, d)
            crossed = hits.t < tmax
            live, o, d, tmax, start, tt, prim_o = (live[crossed], o[crossed], d[crossed], tmax[crossed],
                                                   start[crossed], hits.t[crossed], hits.prim[crossed])
            if len(live) == 0:
                break
            kk = self._opening_first + prim_o
            dist = start + tt                                 # from the ray's origin
            cos_p = np.abs(np.einsum("ij,ij->i", self.portals.normals[kk], d))
            density[live] += self.portals.pdf_area(kk) * dist ** 2 / np.maximum(cos_p, 1e-300)
            o, step = step_past(o, d, tt, self._openings.length_scale)
            start, tmax = start + step, tmax - step
        return density

    def _hemisphere_weight(self, normals, directions, density, S, n_p):
        """Balance-heuristic weight S p_h / (S p_h + n_p p_p) of a ray in direction ω from
        a point drawing S hemisphere rays (p_h = max(0, N·ω)/π) and n_p portal samples of
        portal density p_p = ``density`` (Veach 1997, §9.2).  The same weight serves
        hemisphere rays and portal samples (see :meth:`_portal_samples`)."""
        p_h = S * np.maximum(np.einsum("ij,ij->i", normals, directions), 0.0) / np.pi
        p_p = n_p * np.asarray(density, np.float64)
        return np.where(p_p > 0.0, p_h / np.maximum(p_h + p_p, 1e-300), 1.0)

    def _portal_samples(self, P, Ns, Ng, S, n_p, rng, origins=None):
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
        (:meth:`_portal_density`), so cosine sampling carries the light near a window and
        area sampling the small distant windows.  Values are scaled by S/π to join the
        hemisphere sums of Eq. 2, which makes a sample's factor the weight S p_h /
        (S p_h + n_p p_p) of :meth:`_hemisphere_weight`.

        Returns ``(known, hits, owner)`` like the hemisphere part.
        """
        r = len(P)
        tri, x, pdf_area, n_p = self.portals.sample_stratified(rng, r, n_p)
        owner = np.repeat(np.arange(r), n_p)
        o = np.repeat(self.tracer.offset(P, Ng) if origins is None else origins, n_p, axis=0)
        w = x - o
        dist = np.linalg.norm(w, axis=1)
        w /= np.maximum(dist, 1e-300)[:, None]
        cos_r = np.einsum("ij,ij->i", Ns[owner], w)
        usable = (cos_r > 0.0) & (dist > 0.0)
        target = self._portal_prim[tri]
        known = np.zeros((r, 3))
        keys = ("P", "Ns", "Ng", "weight")
        parts, owners = [], []

        def add(use, radiance, p_hits, weight):
            for c in range(3):
                known[:, c] += np.bincount(owner[use], radiance[:, c] * weight, minlength=r)
            if len(p_hits["ray"]):
                parts.append({**{key: p_hits[key] for key in keys[:3]},
                              "weight": p_hits["weight"] * weight[p_hits["ray"], None]})
                owners.append(owner[use][p_hits["ray"]])

        # portal glass: through the pane drawn on, if it is the first surface met
        use = np.flatnonzero(usable & (target >= 0))
        if len(use):
            hits = self.tracer.intersect(o[use], w[use])
            first = hits.prim == target[use]
            use = use[first]
            if len(use):
                sub = Hits(hits.t[first], hits.prim[first])
                Pp, Ngp, _ = self.tracer.surface(o[use], w[use], sub, np.arange(len(use)))
                cos_p = np.einsum("ij,ij->i", self.tracer.normals[sub.prim], w[use])
                tau = self.materials.glass_transmittance(self.scene.triangles.material[sub.prim], cos_p)
                density = self._portal_density(w[use], sub.t, prim=sub.prim, origins=o[use])
                weight = self._hemisphere_weight(Ns[owner[use]], w[use], density, S, n_p)
                _, radiance, p_hits, _ = self.trace_paths(self.tracer.offset(Pp, -Ngp), w[use], rng, through=tau)
                add(use, radiance, p_hits, weight)
        # openings: unobstructed up to the point drawn, then on like any ray
        use = np.flatnonzero(usable & (target < 0))
        if len(use):
            _, radiance, p_hits, weight = self.trace_paths(o[use], w[use], rng,
                                                           portal_mis=(Ns[owner[use]], S, n_p, dist[use]))
            add(use, radiance, p_hits, weight)
        if not parts:
            return known, {key: np.zeros((0, 3)) for key in keys}, np.zeros(0, np.int64)
        hits = {key: np.concatenate([part[key] for part in parts]) for key in keys}
        return known, hits, np.concatenate(owners)

    def _trace_records(self, k, q: _Queries, pending: _Pending, key: int):
        """:meth:`_evaluate_hemispheres` for new records of level k at the queries ``q``, in
        blocks of at most ``MAX_BATCH_RAYS`` rays; block b's random stream is keyed by
        ``key`` plus the index of its first record, so one block draws what the whole batch did."""
        per = max(1, MAX_BATCH_RAYS // max(1, self.options.level_samples(k)))
        if len(q) <= per:
            return self._evaluate_hemispheres(k, q, pending, self._rng(_TAG_HEMISPHERE, k, key))
        parts = []
        for start in range(0, len(q), per):
            block = slice(start, start + per)
            rng = self._rng(_TAG_HEMISPHERE, k, key + start)
            parts.append(self._evaluate_hemispheres(k, q.take(block), pending, rng))
            self._tick()
        return tuple(None if part[0] is None else np.concatenate(part) for part in zip(*parts))

    def _clamp_radius(self, R0, P):
        lo_box, hi_box = self._roi
        outside = np.maximum(0.0, np.maximum(lo_box - P, P - hi_box))
        far = np.linalg.norm(outside, axis=1)
        return np.clip(R0, self.min_spacing, self.max_spacing + far)

    def place_level(self, k, q: _Queries, stats: RunStats):
        """Make the records of level k that the queries ``q`` need.

        Returns ``(pending, own_record)``; ``own_record`` maps each query to its own
        record when the level does not interpolate (accuracy 0), else it is None.
        """
        lv = self.cache.levels[k]
        pending = _Pending()
        nq = len(q)
        stats.queries[k] += nq
        if nq == 0:
            return pending, None
        q = _Queries(q.P, np.asarray(q.Ns, np.float64), np.asarray(q.Ng, np.float64), q.origins, q.importance)
        P, Ns = q.P, q.Ns
        if lv.accuracy == 0.0:
            R, W, leak = self._trace_records(k, q, pending, lv.count)
            idx = lv.add(P, Ns, R, W=W, leak=leak)
            pending.records.append(idx)
            stats.new_records[k] += nq
            self._tick()
            return pending, idx
        zone = self._zone(P)
        if lv.count:
            todo = np.flatnonzero(~lv.covers(P, Ns, zone))
        else:
            todo = np.arange(nq)
        stats.cache_hits += nq - len(todo)
        # the uncovered queries, compacted after every pass
        tP, tN = P[todo], Ns[todo]
        band = distance_bands(tP, *self._roi, self.max_spacing)
        cell = 2.0 * lv.accuracy * self.max_spacing
        passes = 0
        while len(todo):
            passes += 1
            if passes >= MAX_PASSES:
                local = np.arange(len(todo))
            else:
                local = pick_per_cell(tP, tN, band, cell)
            pP, pN = tP[local], tN[local]
            R, W, leak = self._trace_records(k, q.take(todo[local]), pending, lv.count)
            pZ = zone[todo[local]]
            pending.records.append(lv.add(pP, pN, R, W=W, leak=leak, zone=pZ))
            stats.new_records[k] += len(local)
            keep = np.ones(len(todo), bool)
            keep[local] = False
            if keep.any():
                # only this pass's records can cover what was uncovered before it
                fresh = LevelRecords(lv.accuracy, lv.node_center[0], lv.node_half[0], capacity=len(local),
                                     anisotropic=lv.anisotropic)
                fresh.add(pP, pN, R, W=W, leak=leak, zone=pZ)
                idx = np.flatnonzero(keep)
                keep[idx[fresh.covers(tP[idx], tN[idx], zone[todo[idx]])]] = False
            todo, tP, tN, band = _compact(keep, todo, tP, tN, band)
            cell *= 0.5
            self._tick()
        return pending, None

    # -- evaluation (bottom-up) --------------------------------------------------------
    def _answer(self, k, P, Ns, own_record):
        """Irradiance of level k at queries, from its complete record set."""
        lv = self.cache.levels[k]
        if own_record is not None:
            return lv.E[own_record].astype(np.float64)
        E, _, count = lv.lookup(P, Ns, gradients=self.options.interpolation != "paper", zone=self._zone(P))
        return E

    def evaluate_level(self, k, pending: _Pending, next_answer):
        """Give the records of ``pending`` their values (Eq. 2)."""
        if not pending.records:
            return
        lv = self.cache.levels[k]
        records = np.concatenate(pending.records)
        known = pending.cat("known")
        S = pending.cat("samples", width=0, dtype=np.int64)
        ray_L = pending.cat("ray_L").astype(np.float64) if pending.ray_L else None
        if k < self.options.bounces:
            hP = pending.cat("hit_P")
            hNs = pending.cat("hit_Ns", dtype=np.float32).astype(np.float64)
            hNg = pending.cat("hit_Ng", dtype=np.float32).astype(np.float64)
            weight = pending.cat("hit_weight", dtype=np.float32)
            owner = pending.cat("hit_owner", width=0, dtype=np.int32)
            if len(owner):
                E_hit = self.direct.illuminance(hP, hNs, hNg, self._rng(_TAG_DIRECT_HITS, k, lv.count))
                if next_answer is not None:
                    E_hit += next_answer
                ray = pending.cat("hit_ray", width=0, dtype=np.int32) if ray_L is not None else None
                mis = pending.cat("ray_mis", width=0, dtype=np.float32) if ray_L is not None else None
                # each hit adds weight · E to its record and, without its MIS weight, to
                # its hemisphere ray's own radiance (for the gradients)
                _add_hit_light(owner, weight, E_hit, known,
                               np.zeros(0, np.int32) if ray is None else ray,
                               np.ones(0, np.float32) if mis is None else mis,
                               np.zeros((0, 3)) if ray_L is None else ray_L)
                self._tick()
        lv.E[records] = (np.pi / S)[:, None] * known
        if ray_L is not None:
            m, n = pending.cells
            r = len(records)
            dirs = pending.cat("ray_dir").reshape(r, m, n, 3)
            ray_t = pending.cat("ray_t", width=0, dtype=np.float32).reshape(r, m, n)
            ray_L = ray_L.reshape(r, m, n, 3)
            per = max(1, MAX_BATCH_RAYS // (m * n))       # bounds the temporaries, as in placement
            for start in range(0, r, per):
                part = slice(start, start + per)
                rec = records[part]
                rot, trans = irradiance_gradients(lv.N[rec].astype(np.float64), dirs[part], ray_L[part], ray_t[part])
                lv.Gr[rec], lv.Gt[rec] = limit_gradients(
                    lv.E[rec], rot, trans, lv.accuracy * lv.R[rec].astype(np.float64), lv.accuracy)

    # -- cache files ---------------------------------------------------------------------
    #: the cache file of :meth:`attach_cache_file` (None: the cache is kept in memory only)
    cache_file = None

    def attach_cache_file(self, path, rebuild: bool = False) -> None:
        """Keep the cache in the file ``path`` (docs/cache-files.md).

        Its records are read now (unless it does not exist, or ``rebuild`` is true) and
        the cache is written back at the end of every :meth:`compute` — merged, under the
        file's lock, with records other processes added meanwhile.  A damaged file, or
        one made for another scene or other settings, is refused with an
        :class:`~lbl_illum.errors.InputError`; with ``rebuild`` it is replaced instead.
        A :meth:`compute` that is interrupted (Ctrl-C, SIGTERM, an error) writes the
        records of the levels it has evaluated (see :meth:`compute`).  Records read
        replace those the integrator held.
        """
        from ..io.cachefile import CacheFile, record_settings

        cache_file = CacheFile(path, rebuild)
        cache = cache_file.read(self.fingerprint, record_settings(self.scene, self.options))
        self.cache_file = cache_file
        if cache is not None:
            self.cache = cache

    def _open_block(self, k) -> None:
        """Remember level k's records and octree root as a block of its queries begins."""
        lv = self.cache.levels[k]
        self._open[k] = (lv.count, lv.node_center[0].copy(), float(lv.node_half[0]))

    def _close_block(self, k) -> None:
        """Level k's block is evaluated: its records are complete."""
        self._open.pop(k, None)

    def _drop_unevaluated(self, start) -> bool:
        """After an interruption: drop the records of the open blocks (placed, without
        values), each level going back to the records and octree root it had when its
        open block began, and the records of levels that do not interpolate (accuracy 0:
        one record per query, never reused) back to ``start`` — (count, center, half) per
        level at the start of the run.  Returns whether a level that interpolates kept
        records this run made."""
        for k, lv in enumerate(self.cache.levels):
            state = start[k] if lv.accuracy == 0.0 else self._open.get(k)
            if state is not None and lv.count > state[0]:
                lv.truncate(*state)
        self._open = {}
        return any(lv.count > start[k][0] and lv.accuracy > 0 for k, lv in enumerate(self.cache.levels))

    def _solve_level(self, k, q: _Queries, stats: RunStats):
        """Make level k's records for the queries ``q`` and give them values.

        The queries are taken in blocks of ``QUERY_BLOCK``.  For each: place the records
        it needs (:meth:`place_level`), solve level k+1 for their hemisphere hits
        (recursively, depth first), then evaluate them from level k+1's records
        (:meth:`evaluate_level`).  Returns, for a level that does not interpolate, each
        query's own record (else None).
        """
        B = self.options.bounces
        own_parts = []
        n = len(q)
        blocks = max(1, -(-n // QUERY_BLOCK))
        for b in range(blocks):
            part = slice(b * QUERY_BLOCK, (b + 1) * QUERY_BLOCK)
            self._open_block(k)
            where = f", block {b + 1} of {blocks}" if blocks > 1 else ""
            self._tick(f"placing level {k} ({len(q.P[part])} queries{where})")
            pending, own = self.place_level(k, q.take(part), stats)
            own_parts.append(own)
            hP = pending.cat("hit_P")
            deeper = len(hP) > 0 and k + 1 <= B and self._level_active(k + 1)
            child = pending.cat("hit_importance", width=0) if pending.hit_importance else None
            hits = _Queries(hP, pending.cat("hit_Ns"), pending.cat("hit_Ng"), importance=child)
            own_next = self._solve_level(k + 1, hits, stats) if deeper else None
            self._tick(f"evaluating level {k}{where}")
            next_answer = self._answer(k + 1, hP, pending.cat("hit_Ns"), own_next) if deeper else None
            self.evaluate_level(k, pending, next_answer)
            self._close_block(k)
        if any(own is None for own in own_parts):
            return None
        return np.concatenate(own_parts)

    # -- the whole calculation -----------------------------------------------------------
    def compute(self, points, normals) -> IlluminanceResult:
        """Illuminance at (n, 3) ``points`` [m] with (n, 3) unit ``normals``.

        Interruptions.  Each level's queries are taken in blocks (``QUERY_BLOCK``); a
        block's records are placed, the level below is solved for their hits, and then
        they get their values (:meth:`_solve_level`).  When the calculation stops early
        (KeyboardInterrupt, SIGTERM with a cache file attached, any exception) the blocks
        that are done hold complete records and the open block of each level holds
        records without values.  Those are dropped (each level returns to the records and
        octree it had when its open block began), the rest is kept and, with a cache file
        attached (:meth:`attach_cache_file`), written before the exception goes on; the
        exception then carries ``saved_cache`` (the file) and ``saved_records`` (records
        per level in it).  A second run over the same points with the same file and seed
        finds every query of a finished block covered and places the open blocks exactly
        as the first run did (their records and random streams are the same), and so
        gives bit-identical results to a run that was never interrupted.
        """
        from ..io.cachefile import deferred_interrupts, record_settings, sigterm_as_interrupt

        t0 = time.perf_counter()
        self._rays_reported = rays_before = self.tracer.rays_traced
        points = np.ascontiguousarray(points, np.float64).reshape(-1, 3)
        normals = np.asarray(normals, np.float64).reshape(-1, 3)
        normals = normals / np.linalg.norm(normals, axis=1, keepdims=True)
        B = self.options.bounces
        stats = RunStats(new_records=[0] * (B + 1), queries=[0] * (B + 1))
        if self.cache is None:
            self.cache = self._new_cache(points)
        if self.cache.settings is None:
            self.cache.settings = record_settings(self.scene, self.options)
        # the spacing probe traces rays: skip it when no level can hold light (nothing
        # indirect is computed) or when both limits are given
        probe = (len(points) > 0 and self._level_active(0)
                 and not (self.options.min_spacing and self.options.max_spacing))
        auto_min, auto_max = self.default_spacing(points, normals) if probe else (1.0, 1.0)
        self.max_spacing = self.options.max_spacing if self.options.max_spacing else auto_max
        self.min_spacing = self.options.min_spacing if self.options.min_spacing else min(
            auto_min, self.max_spacing)
        self.min_spacing = min(self.min_spacing, self.max_spacing)
        stats.min_spacing, stats.max_spacing = self.min_spacing, self.max_spacing
        self._roi = (points.min(axis=0), points.max(axis=0)) if len(points) else (np.zeros(3), np.zeros(3))
        self._portal_luminance = self._portal_sources() if self.portals is not None else None
        self._inside_first_bounce, self._inside_rho = self._inside_stats() if self.portals is not None else (0.0, 0.0)

        # what each level held before this run, to return to if it is interrupted
        start = [(lv.count, lv.node_center[0].copy(), float(lv.node_half[0])) for lv in self.cache.levels]
        self._open = {}
        with sigterm_as_interrupt() if self.cache_file is not None else contextlib.nullcontext():
            try:
                # placement top-down and evaluation bottom-up, block by block
                own0 = None
                solved = len(points) > 0 and self._level_active(0)
                # the sensors' ray origins, found once for their direct light and their
                # hemispheres (without direct light, level 0 finds those of its new records)
                origins = None if self.direct.is_dark else self.tracer.sensor_origins(points, normals)
                if solved:
                    own0 = self._solve_level(0, _Queries(points, normals, normals, origins), stats)

                # answers at the query points
                self._tick("direct light at the points")
                direct = self.direct.illuminance(points, normals, normals, self._rng(_TAG_DIRECT_QUERIES),
                                                 light_samples=QUERY_LIGHT_SAMPLES, origins=origins)
                if solved:
                    indirect = self._answer(0, points, normals, own0)
                else:
                    indirect = np.zeros_like(direct)
            except BaseException as exc:
                with deferred_interrupts():
                    gained = self._drop_unevaluated(start)
                    if self.cache_file is not None and gained:
                        exc.saved_records = self.cache_file.write(self.cache)
                        exc.saved_cache = str(self.cache_file.path)
                raise
            if self.cache_file is not None:
                self._tick("writing the cache file")
                self.cache_file.write(self.cache)
        self._tick("done")
        stats.records = self.cache.record_counts
        stats.rays = self.tracer.rays_traced - rays_before
        stats.seconds = time.perf_counter() - t0
        return IlluminanceResult(direct + indirect, direct, indirect, stats)


def compute_illuminance(scene: Scene, points, normals, options: Options | None = None,
                        cache: IrradianceCache | None = None, progress=None, cache_file=None,
                        rebuild_cache: bool = False) -> IlluminanceResult:
    """Illuminance [lux] at sensor ``points`` [m] facing ``normals``: direct + indirect.

    ``cache_file`` (a path) keeps the records in a file: read first, written at the end
    and on interruption, merged with other processes' records
    (:meth:`Integrator.attach_cache_file`; ``rebuild_cache`` replaces a file made for
    other settings instead of refusing it).

    Example
    -------
    >>> from lbl_illum import load_scene, compute_illuminance, read_points
    >>> scene = load_scene("examples/office/scene.toml")          # doctest: +SKIP
    >>> pts, nrm = read_points("examples/office/grid.pts", scene.unit_scale)  # doctest: +SKIP
    >>> compute_illuminance(scene, pts, nrm).illuminance.mean()   # doctest: +SKIP
    """
    integ = Integrator(scene, options, cache, progress)
    if cache_file is not None:
        integ.attach_cache_file(cache_file, rebuild=rebuild_cache)
    return integ.compute(points, normals)

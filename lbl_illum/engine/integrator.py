"""Wavefront irradiance-cache integrator (the paper's §3 and §3.4; docs/design.md §3).

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

**Record radius** (:mod:`lbl_illum.engine.sizing`).  R_i is the harmonic mean distance
of Eq. 4, limited by E/|∇_t E| of the light that makes a room non-uniform (known when
the record's rays are traced), then clamped to [min_spacing, max_spacing + δ(P_i)], δ
being the distance from P_i to the box around the query points.

**Portal samples** (:mod:`lbl_illum.engine.portal_sampling`).  Records behind the
windows also sample the portals' area, combined with their hemisphere rays by multiple
importance sampling (the paper's §5).
"""

from __future__ import annotations

import contextlib
import time
from dataclasses import dataclass, field

import numpy as np
from numba import njit

from .cache import IrradianceCache, LevelRecords
from .compiled import finish_first_run
from .context import LightingContext
from .fingerprint import record_settings, scene_fingerprint
from .gather import rows as take
from .gradients import irradiance_gradients, limit_gradients
from .hemisphere import cell_counts, cosine_directions, stratified_directions
from ..scene.materials import roulette_factors
from ..options import Options
from .placement import distance_bands, pick_per_cell
from ..photometry import luminance
from .portal_sampling import portal_sample_plan, portal_samples, trace_hemisphere_rays
from .raycast import Tracer
from .sizing import RecordSizing
from ..scene.scenefile import Scene

__all__ = ["IlluminanceResult", "RunPlan", "RunStats", "Integrator", "scene_fingerprint",
           "default_spacing", "spacing_rng"]

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
        """The queries ``index`` (a slice or an integer index array)."""
        def part(a):
            if a is None:
                return None
            return a[index] if isinstance(index, slice) or a.ndim == 1 else take(a, index)
        return _Queries(part(self.P), part(self.Ns), part(self.Ng), part(self.origins), part(self.importance))


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
    # daylight coefficients (Integrator.coefficients): the rays that reached the sky, by
    # record (index into the concatenated records), sky patch and weight; whether the next
    # level was solved for the hits, and each hit's own record there (a level without
    # interpolation) or None
    sky_owner: list = field(default_factory=list)
    sky_patch: list = field(default_factory=list)
    sky_weight: list = field(default_factory=list)
    next_solved: bool = False
    next_own: np.ndarray | None = None

    def cat(self, name, width=3, dtype=np.float64):
        """The parts of ``name`` as one array (concatenated once, then kept)."""
        parts = getattr(self, name)
        if len(parts) != 1:
            joined = np.concatenate(parts) if parts else np.zeros((0, width) if width else 0, dtype)
            setattr(self, name, [joined])
        return getattr(self, name)[0]


def _block_share(done: int, blocks: int) -> float:
    """Share of a level's work in its first ``done`` of ``blocks`` blocks (the first block
    half of it when there are several: :meth:`RunPlan.fraction_done`)."""
    if blocks == 1 or done == 0:
        return float(done)
    return 0.5 + 0.5 * (done - 1) / (blocks - 1)


@dataclass
class RunPlan:
    """What one :meth:`Integrator.compute` hands its stages, and nothing keeps after it.

    The integrator holds what is fixed for a scene and a set of options (its lighting
    context, options, cache); what depends on a run's query points is here: the record
    spacing limits (found from the points unless the options or the caller give them),
    the box around the points, the portals' luminance seen from it and the split-flux
    estimate of the interreflected light inside, the open query block of each level (for
    interruptions) and the run's statistics.
    """

    bounces: int
    min_spacing: float                    #: lower clamp on R_i [m]
    max_spacing: float                    #: upper clamp on R_i [m] (near the queries)
    roi: tuple                            #: (lo, hi) [m], the box around the query points
    portal_luminance: np.ndarray | None   #: per portal triangle [cd/m²] (LightingContext.portal_luminance)
    inside: tuple                         #: (Φρ/A [lux], ρ) of the inside (LightingContext.inside_stats)
    stats: RunStats
    rays_reported: int = 0                #: rays already reported to the progress display
    open_blocks: dict = field(default_factory=dict)   #: level → its state when its open block began
    #: per level being solved, [blocks done, blocks] (:meth:`fraction_done`)
    block_stack: list = field(default_factory=list)

    def fraction_done(self) -> float:
        """Share (0…1) of the run's work done, for the progress display: an estimate, not a
        measure.  Each level's query blocks are counted, and within a block the blocks of
        the levels below that it solves first.  The first block of a level with several
        weighs half the level, the others share the other half: it makes the records the
        later ones find (on the office at ``high`` the first of level 1's 10 blocks took
        about 70 % of the time)."""
        done, scale = 0.0, 1.0
        for finished, blocks in self.block_stack:
            b = min(int(finished), blocks - 1)
            lo, hi = _block_share(b, blocks), _block_share(b + 1, blocks)
            done += scale * (lo + (hi - lo) * (finished - b))
            scale *= hi - lo
        return min(done, 1.0)

    def interreflected(self, k: int) -> float:
        """Estimate [lux] of the interreflected light in the value of a level-k record
        inside: the split-flux average (Sumpner's law of the integrating sphere) over the
        B − k bounces still to come, E = Φ ρ / A · (1 − ρ^(B−k)) / (1 − ρ), with Φ the
        flux through the portals, A the area and ρ the mean diffuse reflectance of the
        surfaces inside (:meth:`LightingContext.inside_stats`).  The interreflected light
        varies little over a record's domain; counting it in E keeps a window's gradient
        from shrinking the domains deep in a room, where most of the light is
        interreflected."""
        n = self.bounces - k
        first, rho = self.inside
        if n <= 0 or rho <= 0:
            return 0.0
        return first * (1.0 - rho ** n) / (1.0 - rho) if rho < 1.0 else first * n


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
                 progress=None, context: LightingContext | None = None):
        if context is not None and context.scene is not scene:
            raise ValueError("the lighting context was made for another scene")
        #: the scene's tracer, materials, light sources and portals (shared, never changed)
        self.context = context if context is not None else LightingContext.of(scene)
        self.options = options or scene.options
        #: limit each R_i by E/|∇_t E| of its known light (off only for comparisons)
        self.gradient_limit = True
        #: elliptical record domains from the Hessian (``interpolation = "hessian"``)
        self.hessian = self.options.interpolation == "hessian"
        self.fingerprint = scene_fingerprint(scene, self.options, self.context.portal_set)
        self.progress = progress
        B = self.options.bounces
        self.accuracies = [self.options.level_accuracy(k) for k in range(B + 1)]
        self.cache = cache
        if cache is not None and cache.fingerprint != self.fingerprint:
            raise ValueError("cache was made for another scene or other settings")
        #: who keeps the records beyond the run (None: memory only).  A keeper has
        #: ``guard()`` (a context around a run: how it may be stopped), ``hold()`` (a context
        #: in which stopping waits), ``save(cache)`` (returns the records per level kept)
        #: and ``name``; a cache file is one (:func:`lbl_illum.io.cachefile.attach_cache_file`).
        self.keeper = None
        #: daylight coefficients carried beside the records' irradiance (None: not), a
        #: :class:`lbl_illum.engine.coefficients.CoefficientRecords`
        self.coefficients = None
        #: keys put between the seed and each random stream's own key: empty for a whole
        #: run; a part of a run cut into parts (:mod:`lbl_illum.distributed`) has its own
        self.stream: tuple = ()

    # -- the lighting context, read-only ------------------------------------------------
    scene = property(lambda self: self.context.scene, doc="The scene (lengths in metres).")
    materials = property(lambda self: self.context.materials, doc="The scene's material table.")
    tracer = property(lambda self: self.context.tracer, doc="The scene's ray tracer.")
    direct = property(lambda self: self.context.direct, doc="The sun and light surfaces (direct light).")
    sky = property(lambda self: self.context.sky, doc="The sky model.")
    sun = property(lambda self: self.context.sun, doc="The sun (None without one).")
    portal_set = property(lambda self: self.context.portal_set, doc="Window portals and openings (or None).")
    portals = property(lambda self: self.context.portals, doc="The portal triangles' sampler (or None).")

    def portal_notes(self) -> list[str]:
        """What the user should hear of the portals and the direct light (:meth:`LightingContext.notes`)."""
        return self.context.notes()

    # -- bookkeeping ----------------------------------------------------------------
    def _tick(self, run: RunPlan, text=None, done: float | None = None):
        if self.progress is not None:
            if text:
                self.progress.describe(text)
            self.progress.update(self.tracer.rays_traced - run.rays_reported)
            if hasattr(self.progress, "fraction"):
                self.progress.fraction(run.fraction_done() if done is None else done)
        run.rays_reported = self.tracer.rays_traced

    def _rng(self, *key):
        return np.random.default_rng(np.random.SeedSequence([self.options.seed, *self.stream, *key]))

    def _level_active(self, k: int) -> bool:
        """Whether records of level k can be non-zero (else they are never made)."""
        return self.context.level_active(k, self.options.bounces, self.options.ambient)

    def _new_cache(self, points) -> IrradianceCache:
        bounds = self.scene.triangles.bounds
        lo = np.minimum(bounds[0], points.min(axis=0))
        hi = np.maximum(bounds[1], points.max(axis=0))
        half = 0.5 * float(np.max(hi - lo)) * 1.01 + 1e-9
        return IrradianceCache(self.fingerprint, self.accuracies, 0.5 * (lo + hi), half, anisotropic=self.hessian)

    def empty_cache(self, points) -> IrradianceCache:
        """A cache without records for this scene and these options whose root cube holds
        the scene and ``points`` (n, 3) [m]: the one :meth:`compute` starts from when it
        has none (a run cut into parts starts every part from it)."""
        return self._new_cache(np.asarray(points, np.float64).reshape(-1, 3))

    # -- spacing ----------------------------------------------------------------------
    def default_spacing(self, points, normals) -> tuple[float, float]:
        """(min, max) record spacing [m] from the extent of the queries
        (:func:`default_spacing`, with this run's seed)."""
        return default_spacing(self.tracer, points, normals, spacing_rng(self.options.seed))

    # -- hemisphere rays ----------------------------------------------------------------
    def trace_paths(self, origins, directions, rng, through=None, portal_mis=None, escapes=False):
        """Follow rays through specular surfaces to the sky, a light or a diffuse surface,
        with the portal weights of ``portal_mis`` if given:
        :func:`lbl_illum.engine.portal_sampling.trace_hemisphere_rays` on this integrator's
        lighting context, which says what the arguments and the returned
        ``(first_t, radiance, hits, mis)`` are."""
        return trace_hemisphere_rays(self.context, origins, directions, rng, through=through,
                                     portal_mis=portal_mis, escapes=escapes)

    # -- placement (top-down) ---------------------------------------------------------
    def _evaluate_hemispheres(self, k, q: _Queries, pending: _Pending, rng, run: RunPlan):
        """Trace the hemispheres of new records at the queries ``q``; return their radii
        R_i (clamped), the shapes W_i of elliptical domains and the leak sectors (both None
        for round domains), as :meth:`lbl_illum.engine.sizing.RecordSizing.radii` sizes them."""
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
        # portal samples add rays per record; on the one-ray paths of accuracy 0 below
        # the first level they would make every path branch, so those go without (with
        # point samples, accuracy 0 gives the first reflection its full samples: portals);
        # only points behind the portals sample them (lbl_illum.engine.portal_sampling)
        path_level = k > 0 and samples == 1
        inside, n_p = (None, 0) if path_level else portal_sample_plan(self.context, P, S)
        if n_p:
            draws = np.zeros(r, np.int64)
            draws[inside] = n_p
            per_ray = np.repeat(draws, S)
        else:
            per_ray = None
        mis = (np.repeat(Ns, S, axis=0), S, per_ray) if n_p else None
        dc = self.coefficients
        first_t, radiance, hits, ray_mis = self.trace_paths(origins, dirs, rng, portal_mis=mis, escapes=dc is not None)
        known = (radiance * ray_mis[:, None]).reshape(r, S, 3).sum(axis=1)
        first = sum(len(x) for x in pending.samples)      # records traced before these
        if dc is not None:
            sky = hits["sky_ray"]
            dc.add_sky(pending, first + sky // S, hits["sky_dir"], hits["sky_through"] * ray_mis[sky, None])
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
            p_known, p_hits, p_owner = portal_samples(self.context, take(P, inside), take(Ns, inside),
                                                      take(Ng, inside), S, n_p, rng, take(base, inside),
                                                      escapes=dc is not None)
            known[inside] += p_known
            if dc is not None:
                dc.add_sky(pending, first + inside[p_hits["sky_owner"]], p_hits["sky_dir"], p_hits["sky_weight"])
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
            pending.hit_P.append(hits["P"])
            pending.hit_Ns.append(hits["Ns"].astype(np.float32))
            pending.hit_Ng.append(hits["Ng"].astype(np.float32))
            pending.hit_weight.append(hit_weight.astype(np.float32))
            pending.hit_owner.append((owner_local + first).astype(np.int32))
            pending.hit_ray.append(hit_ray.astype(np.int32))
        pending.known.append(known)
        pending.samples.append(np.full(r, S))
        return self._sizing(k, run).radii(P, Ns, dirs, radiance, first_t, m, n)

    def _sizing(self, k, run: RunPlan) -> RecordSizing:
        """How this run sizes the new records of level k (:class:`~lbl_illum.engine.sizing.RecordSizing`)."""
        return RecordSizing(self.context, self.cache.levels[k].accuracy, run.min_spacing, run.max_spacing, run.roi,
                            run.portal_luminance, run.interreflected(k), self.gradient_limit, self.hessian)

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
        keep, low, factor = roulette_factors(child, rng, PATH_ROULETTE_LIMIT)
        scale = np.ones(len(child))
        scale[low] = factor
        scale = scale[keep]
        return keep, weight[keep] * scale[:, None].astype(weight.dtype), child[keep] * scale

    def _trace_records(self, k, q: _Queries, pending: _Pending, key: int, run: RunPlan):
        """:meth:`_evaluate_hemispheres` for new records of level k at the queries ``q``, in
        blocks of at most ``MAX_BATCH_RAYS`` rays; block b's random stream is keyed by
        ``key`` plus the index of its first record, so one block draws what the whole batch did."""
        per = max(1, MAX_BATCH_RAYS // max(1, self.options.level_samples(k)))
        if len(q) <= per:
            return self._evaluate_hemispheres(k, q, pending, self._rng(_TAG_HEMISPHERE, k, key), run)
        parts = []
        for start in range(0, len(q), per):
            block = slice(start, start + per)
            rng = self._rng(_TAG_HEMISPHERE, k, key + start)
            parts.append(self._evaluate_hemispheres(k, q.take(block), pending, rng, run))
            self._tick(run)
        return tuple(None if part[0] is None else np.concatenate(part) for part in zip(*parts))

    def place_level(self, k, q: _Queries, run: RunPlan):
        """Make the records of level k that the queries ``q`` need.

        Returns ``(pending, own_record)``; ``own_record`` maps each query to its own
        record when the level does not interpolate (accuracy 0), else it is None.
        """
        lv = self.cache.levels[k]
        pending = _Pending()
        stats = run.stats
        nq = len(q)
        stats.queries[k] += nq
        if nq == 0:
            return pending, None
        q = _Queries(q.P, np.asarray(q.Ns, np.float64), np.asarray(q.Ng, np.float64), q.origins, q.importance)
        P, Ns = q.P, q.Ns
        if lv.accuracy == 0.0:
            R, W, leak = self._trace_records(k, q, pending, lv.count, run)
            idx = lv.add(P, Ns, R, W=W, leak=leak)
            pending.records.append(idx)
            stats.new_records[k] += nq
            self._tick(run)
            return pending, idx
        zone = self.context.zone(P)
        if lv.count:
            todo = np.flatnonzero(~lv.covers(P, Ns, zone))
        else:
            todo = np.arange(nq)
        stats.cache_hits += nq - len(todo)
        # the uncovered queries, compacted after every pass
        tP, tN = take(P, todo), take(Ns, todo)
        band = distance_bands(tP, *run.roi, run.max_spacing)
        cell = 2.0 * lv.accuracy * run.max_spacing
        passes = 0
        while len(todo):
            passes += 1
            if passes >= MAX_PASSES:
                local = np.arange(len(todo))
            else:
                local = pick_per_cell(tP, tN, band, cell)
            pP, pN = take(tP, local), take(tN, local)
            R, W, leak = self._trace_records(k, q.take(todo[local]), pending, lv.count, run)
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
                keep[idx[fresh.covers(take(tP, idx), take(tN, idx), zone[todo[idx]])]] = False
            todo, tP, tN, band = _compact(keep, todo, tP, tN, band)
            cell *= 0.5
            self._tick(run)
        return pending, None

    def _answer_points(self, points, normals, origins, own0, taper):
        """(direct, indirect) (n, 3) [lux] at the query points: the direct light by shadow
        rays, the indirect from level 0's complete record set (or each point's own record,
        ``own0``; ``own0 is False``: level 0 was not solved, no indirect light)."""
        direct = self.direct.illuminance(points, normals, normals, self._rng(_TAG_DIRECT_QUERIES),
                                         light_samples=QUERY_LIGHT_SAMPLES, origins=origins)
        if own0 is False:
            return direct, np.zeros_like(direct)
        return direct, self._answer(0, points, normals, own0, taper)

    def answer(self, points, normals, taper: bool = False) -> tuple[np.ndarray, np.ndarray]:
        """(direct, indirect) (n, 3) [lux] at (n, 3) ``points`` [m] facing unit ``normals``
        from the records the cache holds, making none: the last step of :meth:`compute`
        (the same random stream for the direct light), for points whose records a run cut
        into parts made (:mod:`lbl_illum.distributed`).  A level 0 without interpolation
        (point samples) answers nothing here: its indirect part is zero."""
        points = np.ascontiguousarray(points, np.float64).reshape(-1, 3)
        normals = np.asarray(normals, np.float64).reshape(-1, 3)
        normals = normals / np.linalg.norm(normals, axis=1, keepdims=True)
        origins = None if self.direct.is_dark else self.tracer.sensor_origins(points, normals)
        interpolates = len(points) > 0 and self._level_active(0) and self.cache.levels[0].accuracy > 0
        return self._answer_points(points, normals, origins, None if interpolates else False, taper)

    # -- evaluation (bottom-up) --------------------------------------------------------
    def _answer(self, k, P, Ns, own_record, taper=False):
        """Irradiance of level k at queries, from its complete record set."""
        lv = self.cache.levels[k]
        if own_record is not None:
            return lv.E[own_record].astype(np.float64)
        E, _, count = lv.lookup(P, Ns, gradients=self.options.interpolation != "paper" and not taper,
                                zone=self.context.zone(P), taper=taper)
        return E

    def evaluate_level(self, k, pending: _Pending, next_answer, run: RunPlan, hit_Ns=None):
        """Give the records of ``pending`` their values (Eq. 2).  ``hit_Ns``: the hits'
        shading normals in float64, if the caller has them already."""
        if not pending.records:
            return
        lv = self.cache.levels[k]
        records = np.concatenate(pending.records)
        known = pending.cat("known")
        S = pending.cat("samples", width=0, dtype=np.int64)
        ray_L = pending.cat("ray_L").astype(np.float64) if pending.ray_L else None
        if k < self.options.bounces:
            hP = pending.cat("hit_P")
            hNs = hit_Ns if hit_Ns is not None else pending.cat("hit_Ns", dtype=np.float32).astype(np.float64)
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
                self._tick(run)
        lv.E[records] = (np.pi / S)[:, None] * known
        if self.coefficients is not None:
            self.coefficients.evaluate(k, records, S, pending)
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
                rot, trans = irradiance_gradients(take(lv.N, rec).astype(np.float64), dirs[part], ray_L[part],
                                                  ray_t[part])
                lv.Gr[rec], lv.Gt[rec] = limit_gradients(
                    lv.E[rec], rot, trans, lv.accuracy * lv.R[rec].astype(np.float64), lv.accuracy)

    def _open_block(self, k, run: RunPlan) -> None:
        """Remember level k's records and octree root as a block of its queries begins."""
        lv = self.cache.levels[k]
        run.open_blocks[k] = (lv.count, lv.node_center[0].copy(), float(lv.node_half[0]))

    @staticmethod
    def _close_block(k, run: RunPlan) -> None:
        """Level k's block is evaluated: its records are complete."""
        run.open_blocks.pop(k, None)

    def _drop_unevaluated(self, start, run: RunPlan) -> bool:
        """After an interruption: drop the records of the open blocks (placed, without
        values), each level going back to the records and octree root it had when its
        open block began, and the records of levels that do not interpolate (accuracy 0:
        one record per query, never reused) back to ``start`` — (count, center, half) per
        level at the start of the run.  Returns whether a level that interpolates kept
        records this run made."""
        for k, lv in enumerate(self.cache.levels):
            state = start[k] if lv.accuracy == 0.0 else run.open_blocks.get(k)
            if state is not None and lv.count > state[0]:
                lv.truncate(*state)
        run.open_blocks.clear()
        return any(lv.count > start[k][0] and lv.accuracy > 0 for k, lv in enumerate(self.cache.levels))

    def _solve_level(self, k, q: _Queries, run: RunPlan):
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
        run.block_stack.append([0.0, blocks])
        for b in range(blocks):
            run.block_stack[-1][0] = float(b)
            part = slice(b * QUERY_BLOCK, (b + 1) * QUERY_BLOCK)
            self._open_block(k, run)
            where = f", block {b + 1} of {blocks}" if blocks > 1 else ""
            self._tick(run, f"placing level {k} ({len(q.P[part])} queries{where})")
            pending, own = self.place_level(k, q.take(part), run)
            own_parts.append(own)
            hP = pending.cat("hit_P")
            deeper = len(hP) > 0 and k + 1 <= B and self._level_active(k + 1)
            child = pending.cat("hit_importance", width=0) if pending.hit_importance else None
            hits = _Queries(hP, pending.cat("hit_Ns"), pending.cat("hit_Ng"), importance=child)
            own_next = self._solve_level(k + 1, hits, run) if deeper else None
            run.block_stack[-1][0] = b + 1.0           # the block's levels below are solved
            self._tick(run, f"evaluating level {k}{where}")
            # the hits' normals in float64 once, for the lookup and for their direct light
            hNs = pending.cat("hit_Ns").astype(np.float64) if deeper else None
            next_answer = self._answer(k + 1, hP, hNs, own_next) if deeper else None
            pending.next_solved, pending.next_own = deeper, own_next
            self.evaluate_level(k, pending, next_answer, run, hNs)
            self._close_block(k, run)
        run.block_stack.pop()
        if any(own is None for own in own_parts):
            return None
        return np.concatenate(own_parts)

    # -- the whole calculation -----------------------------------------------------------
    def compute(self, points, normals, spacing: tuple[float, float] | None = None,
                taper: bool = False, *, roi: tuple | None = None, solve_only: bool = False) -> IlluminanceResult:
        """Illuminance at (n, 3) ``points`` [m] with (n, 3) unit ``normals``.

        ``taper``: the points' indirect light is the weighted mean of the records' values
        with weights 1 − ε_i/a, which fall to zero at the edge of each record's domain
        (:func:`lbl_illum.engine.octree.lookup`), without extrapolating them by their
        gradients: what the renderer asks for its pixels.  In an image the paper's weights
        step where a domain ends (round blotches on a wall), and each record's own
        gradient, a Monte Carlo estimate, carries it away from its neighbours' (a pattern
        of scales where the nearest record dominates); the ramp without gradients leaves a
        continuous mean.  On the office at ``high`` the pixels differ from the image with
        gradients and the paper's weights by +0.24 % in the median.  Sensors with their own
        records (``point_samples``) are not interpolated either way.

        ``spacing = (min, max)`` [m] are this run's record spacing limits where the options
        leave them unset (the renderer's limits from the view); by default they come from
        the extent of the points (:func:`default_spacing`).  Everything that depends on
        the run is gathered into a :class:`RunPlan` handed to every stage; the integrator
        itself keeps only its cache.

        Interruptions.  Each level's queries are taken in blocks (``QUERY_BLOCK``); a
        block's records are placed, the level below is solved for their hits, and then
        they get their values (:meth:`_solve_level`).  When the calculation stops early
        (KeyboardInterrupt, SIGTERM with a cache file attached, any exception) the blocks
        that are done hold complete records and the open block of each level holds
        records without values.  Those are dropped (each level returns to the records and
        octree it had when its open block began), the rest is kept and, with a cache file
        attached (:attr:`keeper`, :func:`lbl_illum.io.cachefile.attach_cache_file`), written before the exception goes on; the
        exception then carries ``saved_cache`` (the file) and ``saved_records`` (records
        per level in it).  A second run over the same points with the same file and seed
        finds every query of a finished block covered and places the open blocks exactly
        as the first run did (their records and random streams are the same), and so
        gives bit-identical results to a run that was never interrupted.

        For runs cut into parts (:mod:`lbl_illum.distributed`): ``roi = (lo, hi)`` [m] is
        the box of the whole run's points, which sizes the records instead of the box of
        ``points``; ``solve_only`` makes the records the points need and stops there: no
        direct light at the points, and the result's indirect part holds only what a level
        0 without interpolation gives (each point's own record), else zeros — the points
        are answered later from the complete record set (:meth:`answer`).
        """
        t0 = time.perf_counter()
        finish_first_run()      # a first run's kernels, compiled on two cores
        rays_before = self.tracer.rays_traced
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
        given_min, given_max = self.options.min_spacing, self.options.max_spacing
        if spacing is not None:
            given_min, given_max = given_min or spacing[0], given_max or spacing[1]
        probe = len(points) > 0 and self._level_active(0) and not (given_min and given_max)
        auto_min, auto_max = self.default_spacing(points, normals) if probe else (1.0, 1.0)
        max_spacing = given_max if given_max else auto_max
        min_spacing = min(given_min if given_min else auto_min, max_spacing)
        stats.min_spacing, stats.max_spacing = min_spacing, max_spacing
        if roi is None:
            roi = (points.min(axis=0), points.max(axis=0)) if len(points) else (np.zeros(3), np.zeros(3))
        portal_luminance = self.context.portal_luminance(roi) if self.portals is not None else None
        inside = self.context.inside_stats(portal_luminance) if self.portals is not None else (0.0, 0.0)
        run = RunPlan(B, min_spacing, max_spacing, roi, portal_luminance, inside, stats, rays_reported=rays_before)

        # what each level held before this run, to return to if it is interrupted
        start = [(lv.count, lv.node_center[0].copy(), float(lv.node_half[0])) for lv in self.cache.levels]
        keeper = self.keeper
        with keeper.guard() if keeper is not None else contextlib.nullcontext():
            try:
                # placement top-down and evaluation bottom-up, block by block
                own0 = None
                solved = len(points) > 0 and self._level_active(0)
                # the sensors' ray origins, found once for their direct light and their
                # hemispheres (without direct light, level 0 finds those of its new records)
                origins = None if self.direct.is_dark else self.tracer.sensor_origins(points, normals)
                if solved:
                    own0 = self._solve_level(0, _Queries(points, normals, normals, origins), run)

                # answers at the query points
                if solve_only:
                    direct = np.zeros((len(points), 3))
                    indirect = self._answer(0, points, normals, own0) if own0 is not None else np.zeros_like(direct)
                else:
                    self._tick(run, "direct light at the points", done=1.0)
                    direct, indirect = self._answer_points(points, normals, origins, own0 if solved else False, taper)
            except BaseException as exc:
                with keeper.hold() if keeper is not None else contextlib.nullcontext():
                    gained = self._drop_unevaluated(start, run)
                    if keeper is not None and gained:
                        exc.saved_records = keeper.save(self.cache)
                        exc.saved_cache = keeper.name
                raise
            if keeper is not None:
                self._tick(run, "writing the cache file", done=1.0)
                keeper.save(self.cache)
        self._tick(run, "done", done=1.0)
        stats.records = self.cache.record_counts
        stats.rays = self.tracer.rays_traced - rays_before
        stats.seconds = time.perf_counter() - t0
        return IlluminanceResult(direct + indirect, direct, indirect, stats)

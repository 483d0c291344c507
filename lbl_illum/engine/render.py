"""Luminance images through the irradiance cache (the paper's §2 and §3; docs/design.md §3).

A pixel's value is the luminance [cd/m²] seen along its camera rays, averaged over
``pixel_samples`` jittered rays per pixel.  Each camera ray is followed by ray casting
(Whitted, "An improved illumination model for shaded display", CACM 1980; the paper's
§2) until it ends:

========================  ==============================================================
the ray meets             it carries (times the throughput of the specular chain)
========================  ==============================================================
nothing (escapes)         the sky's luminance, or the ground glow below the horizon;
                          plus the sun's luminance E_dn/Ω inside its 6.8e-5 sr disk
a ``light`` surface       the surface's luminance (two-sided Lambertian emitter)
a luminaire's opening     I(−d)/A_p(−d) [cd/m²], its file's intensity over the opening's
                          projected area (:mod:`lbl_illum.engine.luminous_openings`)
a ``diffuse`` surface     L = ρ/π · E(P, N): E is the *full* illuminance at the hit P on
                          the side N facing the ray — direct light from the sun and the
                          light surfaces by shadow rays plus the indirect part
                          interpolated from the cache (the paper's secondary method,
                          Eq. 5) or computed as new records (Eq. 2) where none is valid
a ``mirror``              the ray reflects about the surface normal; throughput × ρ
``glass`` (thin panes)    the ray splits: transmitted straight on (× τ) and reflected
                          (× ρ), both followed (as Radiance's ``rpict`` does); τ and ρ at
                          the ray's angle of incidence (:mod:`lbl_illum.scene.materials`)
``plastic``               both: a diffuse hit with ρ_d (as a diffuse surface), and the
                          specular part continued — polished: the mirror direction × ρ_s(θ);
                          rough: one direction drawn from Ward's lobe × ρ_s × its weight,
                          plus the sun's highlight by a shadow ray (below)
========================  ==============================================================

Emitters are counted wherever a camera path meets them — directly, through glass or
in a mirror: the cache's §5 rule (a hemisphere ray that meets a light adds nothing,
the direct step counted it) is about the *illuminance* at a diffuse point and is kept
inside E; a camera ray is not part of any illuminance integral.

**One batch per stage.**  All pixels × samples are traced at once (docs/design.md §3):
camera rays → specular continuations, depth by depth (at most
``MAX_SPECULAR_DEPTH`` = 8 interactions, as the integrator's hemisphere rays) → the
diffuse hits of every path, which go to :meth:`Integrator.compute` together.  That one
call places the level-0 records the view needs (the records its visible surfaces
need, and the deeper levels *those* need — nothing else), evaluates the levels
bottom-up and answers every hit from the complete record sets, exactly as for sensor
points.  So records made for a view serve an illuminance run of the same scene and
settings, and the other way round.

**Branching and the throughput floor.**  A split at glass doubles the rays of a path.
Branches whose photometric throughput falls below ``WEIGHT_LIMIT`` (2e-3, the role of
Radiance's ``-lw``) play Russian roulette: kept with probability w / ``WEIGHT_LIMIT`` and then
weighted ``WEIGHT_LIMIT`` / w, so the estimate stays unbiased (Arvo & Kirk, "Particle
transport and image synthesis", SIGGRAPH 1990) while the ray count stays bounded.

**Settings for images.**

* ``point_samples`` is ignored: it gives every query its own primary evaluation,
  which for an image means ``point_samples`` rays for each pixel.  A cache made with
  ``point_samples`` therefore has another fingerprint and cannot be shared with an
  image (use the same options without it).
* Record spacing.  Unless ``min_spacing``/``max_spacing`` are given, the integrator
  derives both from the extent of its queries (D = the diagonal of their box; max =
  D/2, min = max/16).  A view through a window sees ground tens of metres away, which
  would make that box — and every record inside the room — as large as the site.  For
  images D is therefore the diagonal of the box between the 5th and 95th percentiles
  of the diffuse hits along each axis (:func:`view_spacing`), the same rule made robust
  to the few far pixels.  The spacing is not part of the cache's fingerprint, so this
  does not stop records from being shared.

**Plastic** (Radiance's ``plastic``; :mod:`lbl_illum.scene.materials` gives the model).  A
hit adds a diffuse hit of weight throughput · ρ_d/π — its diffuse part goes through the
cache like any diffuse surface — *and* continues as a specular path
(:func:`lbl_illum.engine.paths.follow_paths` with the camera's policy, :meth:`~lbl_illum.scene.materials.MaterialTable.reflect`).  On rough
plastic the sun, a 6.8e-5 sr disk that a lobe sample would rarely meet, is taken
directly instead: L += ρ_s f_s(v, s) cos θ_s E_dn T(s) for one direction s drawn
uniformly in the disk, T the transmittance of a shadow ray toward it (what Radiance's
``dirnorm`` adds for a light source; it widens α² by Ω/4π for flat surfaces in place of
sampling the disk).  The ray continued from that plastic then does not count the sun
disk if it escapes — straight on, or through glass, which the shadow ray also crosses —
so the sun is counted once; after any further reflection it counts again, as no shadow
ray covered that path.  Light surfaces met by the continued ray count (unbiased; Radiance
takes them by shadow rays as well and discards them in its specular samples).

**Light sources seen directly.**  Beside the pixels the result marks the *source*
pixels (:func:`first_hit_sources`): those where a camera ray's first hit is not an
ordinary surface of the scene but light arriving from a source — the ray escapes (sky,
ground glow, sun disk; through an unglazed ``opening`` too), meets ``glass`` (a window:
what the pixel shows lies beyond it), a ``translucent`` window (a portal), a ``light``
surface or a luminaire's opening.  Diffuse, plastic and mirror surfaces are the room's
own.  False colour sets its default scale from the other pixels (the room, not the
window; :func:`lbl_illum.viz.falsecolor.default_maximum`).  Finding them costs one
closest-hit query per camera ray, counted in ``stats.rays``.

Units: lengths [m], luminance [cd/m²], illuminance [lux]; pixels are linear RGB with
photometric channels (docs/design.md §2), row 0 the top of the image (:mod:`lbl_illum.scene.views`).
"""

from __future__ import annotations

import dataclasses
import time
from dataclasses import dataclass, field

import numpy as np

from .cache import IrradianceCache
from .context import LightingContext
from ..errors import InputError
from .integrator import Integrator
from .paths import CAMERA, WEIGHT_LIMIT, follow_paths
from .raycast import Hits
from ..options import Options
from ..photometry import luminance
from ..scene.materials import GLASS, LIGHT
from ..scene.scenefile import Scene
from ..scene.views import View, sample_offsets

__all__ = ["RenderResult", "RenderStats", "render_image", "trace_view_paths", "first_hit_sources", "image_options",
           "view_spacing", "WEIGHT_LIMIT"]

#: Percentiles of the diffuse hits' coordinates whose box sets an image's record spacing.
SPACING_PERCENTILES = (5.0, 95.0)
#: Camera rays added to each pixel on an edge between surfaces (:func:`edge_pixels`), and
#: what makes an edge: planes turned by more than EDGE_ANGLE [degrees], or apart by more
#: than EDGE_DEPTH of the distance to the camera.
EDGE_SAMPLES = 8
EDGE_ANGLE = 10.0
EDGE_DEPTH = 1e-3
#: Random-stream tags (the integrator uses 1-4).
_TAG_PIXELS, _TAG_PATHS, _TAG_EDGES = 11, 12, 13


# ---------------------------------------------------------------------------
# Results
# ---------------------------------------------------------------------------

@dataclass
class RenderStats:
    """What a render did.

    records, new_records, queries : per diffuse level, as :class:`~lbl_illum.engine.integrator.RunStats`
    (``records`` after the render; ``new_records`` made for this image).
    """

    width: int = 0
    height: int = 0
    pixel_samples: int = 1
    edge_pixels: int = 0          # pixels on an edge between surfaces, given EDGE_SAMPLES more rays
    camera_rays: int = 0          # camera rays and their specular continuations
    diffuse_hits: int = 0         # path ends on diffuse surfaces (cache queries at level 0)
    rays: int = 0                 # every ray of the render: camera, records, shadow rays
    records: list = field(default_factory=list)
    new_records: list = field(default_factory=list)
    queries: list = field(default_factory=list)
    cache_hits: int = 0
    min_spacing: float = 0.0      # [m]
    max_spacing: float = 0.0      # [m]
    trace_seconds: float = 0.0    # camera paths
    shade_seconds: float = 0.0    # illuminance at the diffuse hits (records included)
    seconds: float = 0.0

    @property
    def records_made(self) -> int:
        """Records computed for this image, all levels."""
        return int(sum(self.new_records))

    def as_dict(self) -> dict:
        doc = dataclasses.asdict(self)
        doc["records_made"] = self.records_made
        return doc


@dataclass
class RenderResult:
    """A luminance image.

    rgb : (h, w, 3) float32 — linear RGB with photometric channels [cd/m²]; row 0 on top
    valid : (h, w) bool — pixels with at least one ray (False outside a fisheye's circle,
        where ``rgb`` is 0)
    view, stats, options : what was rendered, how, with what settings
    cache : the irradiance cache after the render (pass it on to share its records)
    source : (h, w) bool — pixels where at least one camera ray's first hit is a light
        source seen directly (:func:`first_hit_sources`: sky, sun, glass, a translucent
        window, a light surface, a luminaire's opening); ``valid & ~source`` are the
        pixels that show the room's own surfaces.  None: not known (all count as the room)
    """

    rgb: np.ndarray
    valid: np.ndarray
    view: View
    stats: RenderStats
    options: Options
    cache: IrradianceCache | None = None
    source: np.ndarray | None = None

    @property
    def luminance(self) -> np.ndarray:
        """(h, w) float32 photometric luminance [cd/m²] (Rec. 709 weights, docs/design.md §2)."""
        return luminance(self.rgb).astype(np.float32)


# ---------------------------------------------------------------------------
# Settings
# ---------------------------------------------------------------------------

def image_options(options: Options) -> Options:
    """The options an image uses: ``options`` without ``point_samples`` (see the module text)."""
    return dataclasses.replace(options, point_samples=None) if options.point_samples is not None else options


def view_spacing(points: np.ndarray) -> tuple[float, float] | None:
    """(min, max) record spacing [m] for the diffuse hits ``points`` (n, 3) [m] of a view.

    The integrator's rule (max = D/2, min = max/16) with D the diagonal of the box
    between the ``SPACING_PERCENTILES`` (5th, 95th) of the points along each axis: the
    surfaces most of the image shows, not the far ground a few pixels see through a
    window.  None when the points span no box (then the integrator's default applies).
    """
    from .integrator import MAX_SPACING_FRACTION, SPACING_RATIO

    points = np.asarray(points, np.float64).reshape(-1, 3)
    if len(points) < 2:
        return None
    lo, hi = np.percentile(points, SPACING_PERCENTILES, axis=0)
    D = float(np.linalg.norm(hi - lo))
    if not D > 0.0:
        return None
    max_spacing = MAX_SPACING_FRACTION * D
    return max_spacing / SPACING_RATIO, max_spacing


# ---------------------------------------------------------------------------
# Camera paths
# ---------------------------------------------------------------------------

def _scatter_add(out: np.ndarray, index: np.ndarray, values: np.ndarray) -> None:
    """out[index] += values for (m, 3) values, with repeated indices summed."""
    if len(index) == 0:
        return
    for c in range(3):
        out[:, c] += np.bincount(index, values[:, c], minlength=len(out))


def trace_view_paths(integ: Integrator, origins: np.ndarray, directions: np.ndarray, rng: np.random.Generator,
                     tmax: np.ndarray | None = None, progress=None):
    """Follow camera rays through mirrors, glass and the specular part of plastic to the
    sky, an emitter or a diffuse surface (plastic's diffuse part among them): the path
    follower with the camera's policy (:data:`lbl_illum.engine.paths.CAMERA`: split at
    glass, every emitter and the sun's disk seen).

    Parameters
    ----------
    integ : the integrator whose lighting context (tracer, materials, sky, sun) is used
    origins, directions : (n, 3) [m] and unit camera rays
    rng : random numbers for Russian roulette of weak branches, the lobes of rough
        plastic and their sun highlights
    tmax : (n,) aft clipping distance [m] of each camera ray (``inf``: none); beyond
        it the ray sees nothing (black), as Radiance's ``-va``

    Returns
    -------
    radiance : (n, 3) [cd/m²] luminance already known: sky, ground glow, sun disk,
        light surfaces and sun highlights on rough plastic seen along the paths, times
        their throughput
    hits : dict of arrays ``ray`` (m,) camera-ray index, ``P`` (m, 3) [m], ``N`` (m, 3)
        unit normal facing the arriving ray, ``weight`` (m, 3) = throughput · ρ_d/π [1/sr]:
        the diffuse hits, whose luminance is weight · E(P, N)
    rays : rays traced
    """
    paths = follow_paths(integ.context, origins, directions, rng, CAMERA, tmax=tmax, progress=progress)
    return paths.radiance, {"ray": paths.ray, "P": paths.P, "N": paths.Ns, "weight": paths.weight}, paths.rays


def first_hit_sources(context: LightingContext, origins: np.ndarray, directions: np.ndarray,
                      tmax: np.ndarray | None = None, hits=None) -> np.ndarray:
    """(n,) bool: the camera rays whose first hit is a light source seen directly.

    A ray sees a source when it escapes (the sky, the ground glow or the sun's disk,
    through an unglazed opening too), or its first hit is ``glass`` (a window), a
    ``translucent`` window (a portal, :mod:`lbl_illum.engine.portals`), a ``light``
    surface, or a luminaire's opening met before the scene's hit — the ends and the
    glass of :func:`lbl_illum.engine.paths.follow_paths`' first depth.  A diffuse,
    plastic or mirror surface is not a source; nor is a ray that ``tmax`` (n,) [m]
    clips (it sees nothing).  One closest-hit query per ray (``origins`` [m],
    unit ``directions``), unless its ``hits`` are given.
    """
    tracer = context.tracer
    o, d = np.asarray(origins, np.float64), np.asarray(directions, np.float64)
    hits = tracer.intersect(o, d) if hits is None else hits
    clip = np.full(len(o), np.inf) if tmax is None else np.asarray(tmax, np.float64)
    reached = np.flatnonzero(hits.hit & (hits.t <= clip))
    source = ~hits.hit & ~np.isfinite(clip)
    prim = hits.prim[reached]
    kind = context.materials.kind[context.scene.triangles.material[prim]]
    source[reached] = (kind == GLASS) | (kind == LIGHT) | context.translucent_portal[prim]
    luminous = context.luminous_openings
    if luminous is not None:
        seen, _ = luminous.seen(o, d, np.minimum(hits.t, clip), None, tracer.length_scale)
        source[seen] = True
    return source


def surface_keys(context: LightingContext, hits, tmax: np.ndarray | None = None) -> tuple[np.ndarray, ...]:
    """What each camera ray's first hit shows, for :func:`edge_pixels`: ``(material, normal,
    offset, distance)`` — (n,) int material index (−1: the ray escapes or ``tmax`` clips
    it), (n, 3) the triangle's unit normal, (n,) its plane's offset n · P [m] and the hit
    distance t [m]."""
    n = len(hits.hit)
    reached = hits.hit if tmax is None else hits.hit & (hits.t <= tmax)
    material = np.full(n, -1, np.int64)
    normal = np.zeros((n, 3))
    offset = np.zeros(n)
    prim = hits.prim[reached]
    material[reached] = context.scene.triangles.material[prim]
    normal[reached] = context.tracer.normals[prim]
    offset[reached] = np.einsum("ij,ij->i", normal[reached], context.tracer._v0[prim])
    return material, normal, offset, np.where(reached, hits.t, 0.0)


def edge_pixels(material: np.ndarray, normal: np.ndarray, offset: np.ndarray, distance: np.ndarray) -> np.ndarray:
    """(h, w) bool: pixels on an edge between surfaces, from :func:`surface_keys` of their
    camera rays shaped (h, w, s) (and (h, w, s, 3) for ``normal``).

    Two rays see different surfaces when their materials differ (a miss counts as a
    material), their planes turn by more than EDGE_ANGLE, or one plane lies in front of
    the other by more than EDGE_DEPTH of the distance (a desk before the floor, a
    partition before a wall of the same finish).  A pixel is on an edge when its own
    rays differ, or its first ray differs from the first ray of a pixel beside it or
    below it (both pixels are marked).  Triangles of one flat surface are one surface.
    """
    def differ(a, b):
        m = material[a] != material[b]
        same = ~m & (material[a] >= 0)
        cos = np.einsum("...k,...k->...", normal[a], normal[b])
        depth = np.abs(offset[a] - offset[b]) > EDGE_DEPTH * np.maximum(distance[a], distance[b]) + 1e-9
        return m | (same & ((cos < np.cos(np.radians(EDGE_ANGLE))) | depth))

    h, w, s = material.shape
    edge = np.zeros((h, w), bool)
    for k in range(1, s):
        edge |= differ((slice(None), slice(None), 0), (slice(None), slice(None), k))
    across = differ((slice(None), slice(0, w - 1), 0), (slice(None), slice(1, w), 0))
    edge[:, :-1] |= across
    edge[:, 1:] |= across
    down = differ((slice(0, h - 1), slice(None), 0), (slice(1, h), slice(None), 0))
    edge[:-1] |= down
    edge[1:] |= down
    return edge


# ---------------------------------------------------------------------------
# The image
# ---------------------------------------------------------------------------

def render_image(scene: Scene, view: View, width: int, height: int, options: Options | None = None,
           pixel_samples: int = 1, cache: IrradianceCache | None = None, progress=None,
           integrator: Integrator | None = None, shade=None) -> RenderResult:
    """Render the luminance image [cd/m²] of ``view``, ``width`` × ``height`` pixels.

    Parameters
    ----------
    scene : the scene (lengths in metres)
    view : the camera (:class:`~lbl_illum.scene.views.View`); ``width`` and ``height`` are used
        as given (:meth:`View.resolution` gives rpict's square pixels)
    options : quality options (default ``scene.options``); ``point_samples`` is ignored
        (:func:`image_options`)
    pixel_samples : jittered rays per pixel (stratified within the pixel, one random
        shift per pixel: :meth:`View.pixel_coordinates`); the pixel is their mean
    cache : records to start from and add to, made for the same scene and settings
        (an illuminance run's ``integrator.cache``, or :meth:`IrradianceCache.load`)
    progress : object with ``update(rays)`` and ``describe(text)`` (a tqdm adapter)
    integrator : an :class:`~lbl_illum.engine.integrator.Integrator` to use instead of a new
        one (its cache is used and grows); ``options`` and ``cache`` must then be None
    shade : what gives the illuminance at the diffuse hits in place of
        ``integrator.compute``: called as ``shade(points, normals, spacing, taper)``, it
        returns an :class:`~lbl_illum.engine.integrator.IlluminanceResult` (a run on a
        cluster, :func:`lbl_illum.distributed.rounds.solve_points`)

    Returns
    -------
    RenderResult with ``rgb`` (h, w, 3) float32 [cd/m²], ``valid`` (h, w), ``source`` (h, w)
    (:func:`first_hit_sources`), stats and the cache.
    """
    t0 = time.perf_counter()
    for name, value in (("width", width), ("height", height), ("pixel_samples", pixel_samples)):
        if isinstance(value, bool) or int(value) != value or value < 1:
            raise InputError(f"{name} must be a positive whole number, got {value!r}")
    width, height, pixel_samples = int(width), int(height), int(pixel_samples)
    if integrator is not None:
        if options is not None or cache is not None:
            raise ValueError("give options and cache through the integrator, not beside it")
        integ = integrator
        if integ.options.point_samples is not None:
            raise InputError("render: the integrator uses point_samples, which images do not "
                             "(make it with image_options(options))")
    else:
        opts = image_options(options or scene.options)
        integ = Integrator(scene, opts, cache, progress)
    if progress is not None and integ.progress is None:
        integ.progress = progress
    opts = integ.options
    stats = RenderStats(width=width, height=height, pixel_samples=pixel_samples)
    rays_before = integ.tracer.rays_traced

    # 1. camera rays and their specular chains, all pixels and samples at once
    if progress is not None:
        progress.describe(f"tracing {width} x {height} x {pixel_samples} camera rays")
    rng_pixels = np.random.default_rng(np.random.SeedSequence([opts.seed, _TAG_PIXELS]))
    origins, directions, valid = view.rays(width, height, rng_pixels, pixel_samples)
    pixel = np.repeat(np.arange(height * width), pixel_samples)
    first = integ.tracer.intersect(origins, directions)
    aft = view.aft_distances(directions) if view.aft > 0 else None
    keys = surface_keys(integ.context, first, aft)
    keys[0][~valid] = -2
    edge = np.flatnonzero(edge_pixels(*(k.reshape(height, width, pixel_samples, *k.shape[1:]) for k in keys)))
    stats.edge_pixels = len(edge)
    if len(edge):
        # pixels on an edge between surfaces: EDGE_SAMPLES more rays, stratified over the pixel
        rng_edges = np.random.default_rng(np.random.SeedSequence([opts.seed, _TAG_EDGES]))
        offsets = (sample_offsets(EDGE_SAMPLES)[None] + rng_edges.random((len(edge), 1, 2))) % 1.0
        row, col = np.divmod(edge, width)
        x = (col[:, None] + offsets[..., 0]) / width
        y = ((height - 1 - row)[:, None] + offsets[..., 1]) / height
        o2, d2, v2 = view.image_rays(x.reshape(-1), y.reshape(-1))
        more = integ.tracer.intersect(o2, d2)
        origins, directions, valid = np.vstack([origins, o2]), np.vstack([directions, d2]), np.r_[valid, v2]
        pixel = np.r_[pixel, np.repeat(edge, EDGE_SAMPLES)]
        first = Hits(np.concatenate([first.t, more.t]), np.concatenate([first.prim, more.prim]))
    live = np.flatnonzero(valid)
    tmax = view.aft_distances(directions[live]) if view.aft > 0 else None
    rng_paths = np.random.default_rng(np.random.SeedSequence([opts.seed, _TAG_PATHS]))
    known, hits, camera_rays = trace_view_paths(integ, origins[live], directions[live], rng_paths, tmax,
                                                progress)
    sees_source = np.zeros(len(valid), bool)
    sees_source[live] = first_hit_sources(integ.context, origins[live], directions[live], tmax,
                                          hits=Hits(first.t[live], first.prim[live]))
    stats.camera_rays = camera_rays
    stats.diffuse_hits = len(hits["ray"])
    t1 = time.perf_counter()
    stats.trace_seconds = t1 - t0

    # 2. the full illuminance at every diffuse hit, in one call through the cache
    radiance = known
    if len(hits["ray"]):
        # record spacing from the view where the options give none (view_spacing)
        spacing = view_spacing(hits["P"]) if opts.min_spacing is None and opts.max_spacing is None else None
        if shade is None:
            result = integ.compute(hits["P"], hits["N"], spacing=spacing, taper=True)
        else:                       # its rays are counted where they were traced, in its stats
            here = integ.tracer.rays_traced
            result = shade(hits["P"], hits["N"], spacing, True)
            rays_before += integ.tracer.rays_traced - here - result.stats.rays
        _scatter_add(radiance, hits["ray"], hits["weight"] * result.rgb)
        rs = result.stats
        stats.records, stats.new_records, stats.queries = list(rs.records), list(rs.new_records), list(rs.queries)
        stats.cache_hits = rs.cache_hits
        stats.min_spacing, stats.max_spacing = rs.min_spacing, rs.max_spacing
    elif integ.cache is not None:
        stats.records = integ.cache.record_counts
        stats.new_records = [0] * len(stats.records)
    stats.shade_seconds = time.perf_counter() - t1

    # 3. pixel = mean of its valid samples
    full = np.zeros((height * width, 3))
    _scatter_add(full, pixel[live], radiance)
    count = np.bincount(pixel, weights=valid, minlength=height * width).reshape(height, width)
    rgb = full.reshape(height, width, 3) / np.maximum(count, 1)[..., None]
    stats.rays = integ.tracer.rays_traced - rays_before
    stats.seconds = time.perf_counter() - t0
    if progress is not None:
        progress.describe("done")
    source = (np.bincount(pixel, weights=sees_source, minlength=height * width) > 0).reshape(height, width)
    return RenderResult(rgb.astype(np.float32), count > 0, view, stats, opts, integ.cache, source)

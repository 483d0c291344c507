"""What a worker runs: the scene it builds once, and the two tasks of a run cut into parts.

A worker is told *how* to make a scene (a :class:`SceneRecipe`: the scene file's path,
read on the worker, and the sky that replaces the file's, if any), builds its lighting
context — the Embree tracer, the material table, the light sources, the portals
(:class:`~lbl_illum.engine.context.LightingContext`) — once, and keeps it for every task
of that scene (:func:`scene_context`; the worker plugin of :mod:`.plugin` builds it when
the worker joins).  The driver's own process uses the same registry when it runs the
tasks itself (``--workers 0``), so both paths run the same code.

The tasks are pure functions of their arguments: the same record set, points, random
stream and plan give the same bits wherever they run, however often they run (a task
of a lost worker runs again elsewhere).

* :func:`solve_chunk` — make and evaluate the records a chunk of points needs, starting
  from the round's record set; return only the new records.
* :func:`answer_chunk` — the direct light and the interpolated indirect light at a
  chunk's points from the complete record set (no records made).
"""

from __future__ import annotations

import copy
import dataclasses
import hashlib
import pickle
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..engine.context import LightingContext
from ..engine.integrator import Integrator
from ..errors import InputError
from ..io.cachefile import CacheData, cache_from_data
from ..options import Options
from .records import record_delta

__all__ = ["SceneRecipe", "ChunkRecords", "scene_context", "remember", "forget", "solve_chunk", "answer_chunk",
           "direct_sun_chunk", "scene_check", "STREAM_TAG"]

#: First key of a part's random streams (:attr:`Integrator.stream`), then the chunk index:
#: no whole run's stream (seed, tag, ...) starts with it (the engine's tags are below 20).
STREAM_TAG = 1021


@dataclass(frozen=True)
class SceneRecipe:
    """How a worker makes the scene of a run: the scene file (an absolute path the worker
    reads: a shared file system, as Radiance's ambient files on NFS); with
    ``replace_sky``, the sky and sun that replace the file's (the daylight factor's CIE
    overcast sky, the annual study's design sky); ``shades``, ``(materials, factor)``
    the glazing closed by a window group's shades
    (:func:`lbl_illum.engine.annual.shaded_scene`)."""

    path: str
    sky: object = None
    sun: object = None
    replace_sky: bool = False
    shades: tuple | None = None

    @property
    def key(self) -> str:
        """A name for the recipe, the same in every process."""
        return hashlib.sha256(pickle.dumps((self.path, self.sky, self.sun, self.replace_sky,
                                            self.shades))).hexdigest()[:16]

    def build(self):
        """(scene, lighting context): the file read and the context built here."""
        from ..scene.scenefile import load_scene

        scene = load_scene(self.path)
        if self.replace_sky:
            scene = dataclasses.replace(scene, sky=self.sky, sun=self.sun)
        if self.shades is not None:
            from ..engine.annual import shaded_scene

            scene = shaded_scene(scene, *self.shades)
        return scene, LightingContext.of(scene)


#: recipe key -> (scene, context), or the InputError met building it; one per process
_BUILT: dict = {}


def remember(recipe: SceneRecipe, scene, context) -> None:
    """Give this process the scene and context of ``recipe`` built elsewhere (the driver's,
    when it runs the tasks itself)."""
    _BUILT[recipe.key] = (scene, context)


def forget(recipe: SceneRecipe) -> None:
    """Drop the scene of ``recipe`` from this process (the plugin's teardown), and the last
    record set's cache (:func:`cache_of`)."""
    _BUILT.pop(recipe.key, None)
    with _LAST_SET_LOCK:
        _LAST_SET[:] = [None, None]


def scene_context(recipe: SceneRecipe):
    """(scene, context) of ``recipe`` in this process, built the first time it is asked
    for; a scene that could not be read is the same :class:`InputError` every time."""
    built = _BUILT.get(recipe.key)
    if built is None:
        try:
            built = recipe.build()
        except InputError as exc:
            built = exc
        except OSError as exc:
            built = InputError(f"{Path(recipe.path).name}: {exc.strerror or exc}")
        _BUILT[recipe.key] = built
    if isinstance(built, InputError):
        raise InputError(str(built))
    return built


def scene_check(recipe: SceneRecipe, options: Options) -> str:
    """The fingerprint of the scene and settings this process sees (what the driver
    compares with its own), or ``"error: ..."`` when it cannot read the scene."""
    try:
        scene, context = scene_context(recipe)
        return Integrator(scene, options, context=context).fingerprint
    except InputError as exc:
        return f"error: {exc}"


@dataclass
class ChunkRecords:
    """What :func:`solve_chunk` returns: the new records (a :class:`CacheData` of only
    them, :func:`~.records.record_delta`), the points' own indirect light when level 0
    does not interpolate (n, 3) [lux] (else None), the daylight-coefficient vectors of the
    points' own records (annual runs, else None) and what the part did."""

    delta: CacheData
    own_indirect: np.ndarray | None
    vectors: np.ndarray | None
    new_records: list = field(default_factory=list)
    queries: list = field(default_factory=list)
    cache_hits: int = 0
    rays: int = 0
    seconds: float = 0.0


#: The last record set a task of this process started from and the cache built from it
#: (octrees and lookup layouts made), which the next task of the same round copies.
_LAST_SET: list = [None, None]
_LAST_SET_LOCK = threading.Lock()        # a worker may run tasks on several threads


def cache_of(base: CacheData):
    """A cache of the records of ``base``, the task's own to add to: built once per record
    set in this process (:func:`~lbl_illum.io.cachefile.cache_from_data`, then the lookup
    layouts), copied for each task (for 10^6 records the copy takes 0.3 s, the building
    1.1 s).  A copy holds the same arrays, octree and layout as a new build, so the task's
    results are the same bits either way."""
    with _LAST_SET_LOCK:
        if _LAST_SET[0] is not base:
            _LAST_SET[:] = [None, None]             # the previous round's set is dropped first
            cache = cache_from_data(base)
            for lv in cache.levels:
                if lv.count and lv.accuracy > 0:
                    lv.freeze()
            _LAST_SET[:] = [base, cache]
        return copy.deepcopy(_LAST_SET[1])


def _integrator(recipe, options, base: CacheData, stream) -> Integrator:
    scene, context = scene_context(recipe)
    integ = Integrator(scene, options, cache_of(base), context=context)
    integ.stream = stream
    return integ


def solve_chunk(recipe: SceneRecipe, options: Options, base: CacheData, points, normals, chunk: int,
                spacing: tuple, roi: tuple, taper: bool = False, coefficients: dict | None = None) -> ChunkRecords:
    """Make the records that the (n, 3) ``points`` [m] facing ``normals`` need, starting
    from the record set ``base`` (the round's), with the random streams of part ``chunk``,
    the whole run's record ``spacing`` (min, max) [m] and box ``roi`` (lo, hi) [m]
    (:meth:`Integrator.compute` with ``solve_only``).  ``coefficients``
    (``{"mf": .., "suns": ..}``): the records carry daylight coefficients
    (:class:`~lbl_illum.engine.coefficients.CoefficientRecords`) as well."""
    t0 = time.perf_counter()
    integ = _integrator(recipe, options, base, (STREAM_TAG, int(chunk)))
    dc = None
    if coefficients is not None:
        from ..engine.coefficients import CoefficientRecords

        dc = CoefficientRecords(integ, coefficients["mf"], coefficients["suns"])
        for k, values in enumerate(coefficients_of(base)):
            if values is not None:
                dc.values[k] = values.copy()
    result = integ.compute(points, normals, spacing=spacing, taper=taper, roi=roi, solve_only=True)
    own = integ.cache.levels[0].accuracy == 0.0
    vectors = None
    if dc is not None:
        vectors = dc.photometric(dc.at_points(points, normals, np.arange(len(points)) if own else None))
    stats = result.stats
    return ChunkRecords(record_delta(integ.cache, base, dc), result.indirect if own else None, vectors,
                        list(stats.new_records), list(stats.queries), int(stats.cache_hits), int(stats.rays),
                        time.perf_counter() - t0)


def coefficients_of(data: CacheData) -> list:
    """Per level, the daylight-coefficient vectors a record set carries (``L{k}_C``), or None."""
    return [data.arrays.get(f"L{k}_C") for k in range(len(data.header["levels"]))]


def answer_chunk(recipe: SceneRecipe, options: Options, final: CacheData, points, normals, chunk: int,
                 taper: bool = False):
    """(direct, indirect, rays): (n, 3) [lux] at the points from the complete record set
    ``final`` with the random stream of part ``chunk`` (:meth:`Integrator.answer`)."""
    integ = _integrator(recipe, options, final, (STREAM_TAG, int(chunk)))
    before = integ.tracer.rays_traced
    direct, indirect = integ.answer(points, normals, taper=taper)
    return direct, indirect, integ.tracer.rays_traced - before


def direct_sun_chunk(recipe: SceneRecipe, sun: tuple, points, normals):
    """(direct, rays): the (n, hours) float32 direct sun [lux] at a chunk's points, ``sun``
    being ``(directions (hours, 3), direct normal illuminance (hours,) [lux])``
    (:func:`~lbl_illum.engine.sun_hours.direct_sun_matrix`: shadow rays, no random numbers)."""
    from ..engine.sun_hours import direct_sun_matrix

    _, context = scene_context(recipe)
    before = context.tracer.rays_traced
    direct = direct_sun_matrix(context.direct, context.tracer, points, normals, *sun)
    return direct, context.tracer.rays_traced - before

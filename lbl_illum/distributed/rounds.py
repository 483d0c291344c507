"""A run cut into work units that share one irradiance cache in rounds (docs/distributed.md).

**Decomposition, fixed by the work.**  The query points (sensors, or an image's diffuse
hits) are cut into chunks of :attr:`Decomposition.chunk` points in their order, and the
chunks into rounds of 1, 2, 4, … chunks, at most :attr:`Decomposition.most` a round
(:meth:`Decomposition.rounds`).  Nothing here depends on the number of workers.

**A round.**  Every task of a round starts from the same record set, the one the driver
holds when the round begins (sent once to every worker); it makes and evaluates the
records its chunk needs (:func:`~.worker.solve_chunk`: the integrator's placement and
evaluation, level by level, with the whole run's record spacing and box and the random
streams of its chunk index) and returns only its new records.  The driver merges them
in chunk order (:func:`~.records.merge_round`), writes the set to the cache file if one
is kept, and starts the next round from it.  The first round's single chunk fills the
deep levels that every later chunk looks up; the rounds then widen as the cache fills.

**Answers.**  Once every round is merged, each chunk's points are answered from the
complete record set (:func:`~.worker.answer_chunk`: direct light by shadow rays with the
chunk's stream, the indirect part interpolated), so neighbouring chunks — an image's
rows — see the same records.

**Why the bits do not depend on the workers.**  A task's result is a function of the
round's record set, its chunk and its chunk index; the record set after a round is a
function of the set before it and the tasks' results in chunk order.  By induction
every round's set, and so every answer, is the same whether the tasks run on 1 or 100
workers, are run twice after a lost worker, or run one after the other in this process
(``--workers 0``).  The run differs from an ordinary run of the same points (which has
one random stream and one growing cache), as a run with another seed does.

**Interruption.**  Each merged round is written to the cache file before the next
begins; Ctrl-C or SIGTERM stops the run with the merged rounds kept.  Run again with
the same file, the finished rounds find their chunks covered and add nothing, the
interrupted round starts from the set it started from before, and the results are the
same bits as an uninterrupted run's (when level 0 interpolates; with point samples each
sensor's own record is evaluated again from the larger record set below it).
"""

from __future__ import annotations

import contextlib
import pickle
import time
from dataclasses import dataclass, field

import numpy as np

from ..engine.integrator import IlluminanceResult, Integrator, RunStats
from ..io.cachefile import CacheFile, record_settings, sigterm_as_interrupt
from .plan import ANSWER_WEIGHT, CHUNK_POINTS, ROUND_CHUNKS, Decomposition
from .records import record_set, merge_round, save_round
from .worker import SceneRecipe, answer_chunk, solve_chunk

__all__ = ["Decomposition", "RoundCost", "RunCosts", "solve_points", "CHUNK_POINTS", "ROUND_CHUNKS"]

#: The stages of a round whose seconds :class:`RoundCost` keeps.
STAGES = ("send", "wall", "tasks", "merge", "save")


@dataclass
class RoundCost:
    """What a round cost the driver against its work: ``seconds`` of each stage —
    ``send`` (the record set to every worker), ``wall`` (from the first task sent to the
    last result back), ``tasks`` (the tasks' own seconds, summed), ``merge`` (the new
    records into the set), ``save`` (the cache file); ``records`` sent, ``bytes`` of the
    set sent, ``new`` records merged."""

    chunks: int
    records: int
    bytes: int
    new: int = 0
    seconds: dict = field(default_factory=lambda: dict.fromkeys(STAGES, 0.0))


@dataclass
class RunCosts:
    """The rounds' costs and the answer pass's (``answer_wall``, ``answer_send``) [s]."""

    rounds: list = field(default_factory=list)
    answer_send: float = 0.0
    answer_wall: float = 0.0

    def as_dict(self) -> dict:
        return {"rounds": [dict(vars(r)) for r in self.rounds], "answer_send": self.answer_send,
                "answer_wall": self.answer_wall}


def run_spacing(integ: Integrator, points, normals, spacing=None) -> tuple[float, float]:
    """The whole run's record spacing (min, max) [m], as :meth:`Integrator.compute` finds it
    for all the points at once (the options', else ``spacing``, else the probe of
    :meth:`Integrator.default_spacing`)."""
    opts = integ.options
    given_min, given_max = opts.min_spacing, opts.max_spacing
    if spacing is not None:
        given_min, given_max = given_min or spacing[0], given_max or spacing[1]
    auto_min, auto_max = (1.0, 1.0) if (given_min and given_max) or not len(points) else \
        integ.default_spacing(points, normals)
    max_spacing = given_max if given_max else auto_max
    return min(given_min if given_min else auto_min, max_spacing), max_spacing


def _tick(progress, text=None, done=None, rays=0):
    if progress is None:
        return
    if text:
        progress.describe(text)
    if rays:
        progress.update(rays)
    if done is not None and hasattr(progress, "fraction"):
        progress.fraction(done)


def solve_points(cluster, recipe: SceneRecipe, integ: Integrator, points, normals, spacing=None,
                 taper: bool = False, plan: Decomposition = Decomposition(), cache_file=None, rebuild: bool = False,
                 progress=None, coefficients: dict | None = None, answer: bool = True):
    """Illuminance at (n, 3) ``points`` [m] facing ``normals`` by rounds of chunks (module
    text) on ``cluster`` (:mod:`.cluster`).

    recipe : how a worker makes the scene (the same scene as ``integ``'s)
    integ : the driver's integrator: its options, fingerprint and spacing probe (its
        cache, if any, is the first round's record set)
    spacing, taper : as :meth:`Integrator.compute` (an image's)
    cache_file, rebuild : keep the records in this file (read first, written after each
        round; docs/cache-files.md)
    coefficients : ``{"mf", "suns"}``: records carry daylight coefficients (annual runs)
    answer : answer the points (else the result holds only what the rounds give: the
        points' own records' indirect light with point samples, else zeros)

    Returns ``(result, costs, vectors)``: an :class:`IlluminanceResult` whose stats sum
    the tasks', the :class:`RunCosts`, and the points' coefficient vectors (or None).
    """
    t0 = time.perf_counter()
    points = np.ascontiguousarray(points, np.float64).reshape(-1, 3)
    normals = np.asarray(normals, np.float64).reshape(-1, 3)
    normals = normals / np.linalg.norm(normals, axis=1, keepdims=True)
    opts = integ.options
    B = opts.bounces
    stats = RunStats(new_records=[0] * (B + 1), queries=[0] * (B + 1))
    keeper = CacheFile(cache_file, rebuild) if cache_file is not None else None
    settings = record_settings(integ.scene, opts)
    start = keeper.read(integ.fingerprint, settings) if keeper is not None else None
    if start is None:
        start = integ.cache if integ.cache is not None else integ.empty_cache(points)
    if start.settings is None:
        start.settings = settings
    dc = None
    if coefficients is not None:
        from ..engine.coefficients import CoefficientRecords

        dc = CoefficientRecords(Integrator(integ.scene, opts, context=integ.context), coefficients["mf"],
                                coefficients["suns"])
    base = record_set(start, dc)
    stats.min_spacing, stats.max_spacing = run_spacing(integ, points, normals, spacing)
    spacing = (stats.min_spacing, stats.max_spacing)
    roi = (points.min(axis=0), points.max(axis=0)) if len(points) else (np.zeros(3), np.zeros(3))
    chunks = plan.chunks(len(points))
    rounds = plan.rounds(len(chunks))
    total = len(chunks) * (1.0 + ANSWER_WEIGHT)
    finished = [0.0]
    costs = RunCosts()
    own = [None] * len(chunks)
    vectors = [None] * len(chunks)
    saved = None

    def done(weight):
        def tick(i, result):
            finished[0] += weight
            rays = result.rays if hasattr(result, "rays") else result[2]
            _tick(progress, done=finished[0] / total, rays=rays)
        return tick

    guard = sigterm_as_interrupt() if keeper is not None else contextlib.nullcontext()
    try:
        with guard:
            for r, members in enumerate(rounds):
                _tick(progress, f"round {r + 1} of {len(rounds)}: {len(members)} chunk{'s' * (len(members) > 1)} "
                      f"of {plan.chunk} points on {cluster.name}")
                cost = RoundCost(len(members), int(sum(base.record_counts)), _size(base))
                t = time.perf_counter()
                shared = cluster.share(base)
                cost.seconds["send"] = time.perf_counter() - t
                calls = [(recipe, opts, shared, points[chunks[c]], normals[chunks[c]], c, spacing, roi, taper,
                          coefficients) for c in members]
                t = time.perf_counter()
                parts = cluster.run(solve_chunk, calls, done(1.0))
                cost.seconds["wall"] = time.perf_counter() - t
                t = time.perf_counter()
                merged = merge_round(base, [p.delta for p in parts])
                cost.seconds["merge"] = time.perf_counter() - t
                cost.new = int(sum(merged.record_counts) - sum(base.record_counts))
                cost.seconds["tasks"] = float(sum(p.seconds for p in parts))
                for c, p in zip(members, parts):
                    own[c], vectors[c] = p.own_indirect, p.vectors
                    stats.new_records = [a + b for a, b in zip(stats.new_records, p.new_records)]
                    stats.queries = [a + b for a, b in zip(stats.queries, p.queries)]
                    stats.cache_hits += p.cache_hits
                    stats.rays += p.rays
                base = merged
                if keeper is not None and cost.new:
                    t = time.perf_counter()
                    saved = save_round(keeper.path, base, merge=not keeper.rebuild)
                    keeper.rebuild = False
                    cost.seconds["save"] = time.perf_counter() - t
                costs.rounds.append(cost)
            answers = []
            if answer:
                _tick(progress, f"answering {len(points)} points from {sum(base.record_counts):,} records")
                t = time.perf_counter()
                shared = cluster.share(base)
                costs.answer_send = time.perf_counter() - t
                t = time.perf_counter()
                answers = cluster.run(answer_chunk, [(recipe, opts, shared, points[s], normals[s], c, taper)
                                                     for c, s in enumerate(chunks)], done(ANSWER_WEIGHT))
                costs.answer_wall = time.perf_counter() - t
    except KeyboardInterrupt as exc:
        if saved is not None:
            exc.saved_records, exc.saved_cache = saved, keeper.name
        raise
    direct = np.concatenate([a[0] for a in answers]) if answers else np.zeros((len(points), 3))
    indirect = np.concatenate([a[1] for a in answers]) if answers else np.zeros((len(points), 3))
    stats.rays += int(sum(a[2] for a in answers))
    if any(o is not None for o in own):
        indirect = indirect + np.concatenate(own)
    # as an ordinary run counts them: a level without interpolation holds this run's records
    stats.records = [made if info["accuracy"] == 0 else count for made, info, count
                     in zip(stats.new_records, base.header["levels"], base.record_counts)]
    stats.seconds = time.perf_counter() - t0
    _tick(progress, "done", done=1.0)
    joined = np.concatenate(vectors) if coefficients is not None and vectors else None
    return IlluminanceResult(direct + indirect, direct, indirect, stats), costs, joined


def _size(data) -> int:
    """Bytes of a record set as sent (its arrays and header, pickled)."""
    return int(sum(a.nbytes for a in data.arrays.values()) + len(pickle.dumps(data.header)))

"""A year of daylight on a cluster: the daylight coefficients by rounds of sensor chunks,
the direct sun by sensor chunks × the year's hours (:func:`annual_solver`).

:func:`lbl_illum.engine.annual.annual_light` places the records under its design sky
(the CIE overcast sky) with daylight coefficients carried beside their irradiance
(:mod:`lbl_illum.engine.coefficients`).  On a cluster the records come from the rounds of
:mod:`.rounds`, each record travelling with its coefficient vector (``L{k}_C``), and each
chunk's sensors take their vectors from their own records (point samples, every preset)
or, when level 0 interpolates, from the records their task holds.  The direct sun at
each chunk's sensors for every hour (shadow rays, no random numbers) is a second set of
tasks, one per sensor chunk and batch of :data:`HOUR_BATCH` hours, sent before the
rounds at a lower priority: they need no records, and fill the workers that the first
rounds (one chunk, then two) leave idle.  The combination with the sky matrix, hour by
hour, is the driver's, as in one process.  As for grids, the results depend on the chunks and rounds, not on the workers.
"""

from __future__ import annotations

import numpy as np

from ..engine.coefficients import CoefficientRecords
from ..engine.integrator import Integrator
from .plan import Decomposition
from .rounds import solve_points
from .worker import SceneRecipe, direct_sun_chunk

__all__ = ["annual_solver", "HOUR_BATCH"]

#: Hours of the year a direct-sun task takes (a quarter of 8,760): sensor chunks x hour
#: batches are its work units.
HOUR_BATCH = 2190


def annual_solver(cluster, scene_file: str, plan: Decomposition = Decomposition(), progress=None, shades=None,
                  costs: list | None = None):
    """The ``solve`` of :func:`~lbl_illum.engine.annual.annual_light` on ``cluster``
    (:mod:`.cluster`) for the scene read from ``scene_file`` (absolute path; ``shades``:
    ``(materials, factor)`` of a window group closed, as the scene was made).  Each call
    appends its :class:`~.rounds.RunCosts` to ``costs`` if given."""

    def solve(design, integ: Integrator, matrix, suns, points, normals):
        recipe = SceneRecipe(scene_file, design.sky, design.sun, True,
                             None if shades is None else (tuple(shades[0]), float(shades[1])))
        cluster.prepare(recipe, integ.options, integ.fingerprint, design, integ.context)
        hours = matrix.shape[1]
        batches = [slice(h, min(h + HOUR_BATCH, hours)) for h in range(0, hours, HOUR_BATCH)]
        chunks = plan.chunks(len(points))
        try:
            # the direct sun needs no records: its tasks (sensor chunks x hour batches) go first,
            # at a lower priority, and fill the workers the narrow first rounds leave idle
            sun_dirs, sun_dn = np.asarray(matrix.sun_direction), np.asarray(matrix.direct_normal_illuminance)
            sun = [cluster.share((sun_dirs[b], sun_dn[b])) for b in batches]
            pending = cluster.submit(direct_sun_chunk, [(recipe, sun[j], points[s], normals[s])
                                                        for s in chunks for j in range(len(batches))], priority=-1)
            result, run_costs, vectors = solve_points(cluster, recipe, integ, points, normals, plan=plan,
                                                      progress=progress, answer=False,
                                                      coefficients={"mf": matrix.patches.mf, "suns": suns})
            if costs is not None:
                costs.append(run_costs)
            if progress is not None:
                progress.describe("direct sun, hour by hour")
            parts = cluster.collect(pending)
        finally:
            cluster.release(recipe)
        n = len(batches)
        rows = [np.concatenate([p[0] for p in parts[c * n:(c + 1) * n]], axis=1) for c in range(len(chunks))]
        direct = np.concatenate(rows) if rows else np.zeros((0, hours), np.float32)
        stats = result.stats
        stats.rays += int(sum(p[1] for p in parts))
        dc = CoefficientRecords(Integrator(design, integ.options, context=integ.context), matrix.patches.mf, suns)
        return stats, vectors, direct, dc.channels * dc.sources * 4

    return solve

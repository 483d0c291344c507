"""The worker plugin that builds a scene once per worker (Dask's ``WorkerPlugin``).

Registered by the driver for each scene of a study (:meth:`.cluster.DaskCluster.prepare`),
it runs :func:`.worker.scene_context` on every worker when registered and on every
worker that joins later (one that replaces a lost worker too), so that the tasks find
the scene's tracer, materials, light sources and portals built.  A scene the worker
cannot read is kept as its error, which the driver's check reports.
"""

from __future__ import annotations

from distributed.diagnostics.plugin import WorkerPlugin

from .worker import SceneRecipe, forget, scene_context

__all__ = ["ScenePlugin"]


class ScenePlugin(WorkerPlugin):
    """Build the scene of ``recipe`` on the worker when it starts (:func:`scene_context`)."""

    def __init__(self, recipe: SceneRecipe):
        self.recipe = recipe

    def setup(self, worker) -> None:
        try:
            scene_context(self.recipe)
        except Exception:   # noqa: BLE001 — kept as the recipe's error, reported by the driver's check
            pass

    def teardown(self, worker) -> None:
        forget(self.recipe)

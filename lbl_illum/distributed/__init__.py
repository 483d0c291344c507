"""Studies on a Dask cluster with one shared irradiance cache (docs/distributed.md).

The work of a run is cut into fixed units (chunks of sensor points or of an image's
diffuse hits, and for a year the direct sun by the same chunks) that share the cache in
rounds: every task of a round starts from the same record set, returns only its new
records, and the driver merges them in chunk order.  The results depend on that
decomposition only, never on the number of workers, on which worker ran what, or on
whether a cluster is used at all (``InProcess`` runs the same rounds in this process).
"""

from .._public import public_surface

#: The public names of this package, by module (imported when first used).
__all__, __getattr__, __dir__ = public_surface(globals(), {
    "cluster": ("InProcess", "DaskCluster", "open_cluster", "project_identity"),
    "plan": ("Decomposition", "CHUNK_POINTS", "ROUND_CHUNKS"),
    "rounds": ("solve_points", "RoundCost", "RunCosts"),
    "records": ("merge_round", "record_delta", "record_set"),
    "worker": ("SceneRecipe",),
    "annual": ("annual_solver",),
})

"""Studies on a Dask cluster with one shared irradiance cache (docs/distributed.md).

The work of a run is cut into fixed units (sensor chunks, image rows, sensor chunks of a
year) that go through the cache in rounds; the results depend on that decomposition
only, never on the number of workers or on whether a cluster is used at all.
"""

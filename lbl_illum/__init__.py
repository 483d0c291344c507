"""lbl_illum — illuminance in daylit rooms by the irradiance cache of Ward, Rubinstein & Clear (1988).

The public surface::

    scene = load_scene("examples/office/scene.toml")
    points, normals = read_points("examples/office/grid.pts", scene.unit_scale)
    result = compute_illuminance(scene, points, normals, Options(accuracy=0.1))
    result.illuminance            # (n,) lux
"""

from __future__ import annotations

from ._public import public_surface
from ._version import __version__
from .errors import InputError
from .options import Options

# The engine (numba, Embree) and the scene loader are imported when first used, so that
# ``lbl-illum --help`` and the command's argument checks start in a fraction of a second.
_lazy, __getattr__, __dir__ = public_surface(globals(), {
    "engine.cache": ("IrradianceCache",),
    "engine.integrator": ("IlluminanceResult", "Integrator"),
    "scene.scenefile": ("Scene", "load_scene"),
    "io.points": ("read_points", "write_results"),
})
__all__ = sorted(["__version__", "InputError", "Options", "compute_illuminance", *_lazy])


def compute_illuminance(scene: Scene, points, normals, options: Options | None = None,
                        cache: IrradianceCache | None = None, progress=None, cache_file=None,
                        rebuild_cache: bool = False) -> IlluminanceResult:
    """Illuminance [lux] at sensor ``points`` [m] facing ``normals``: direct + indirect.

    ``cache_file`` (a path) keeps the records in a file: read first, written at the end
    and on interruption, merged with other processes' records
    (:func:`lbl_illum.io.cachefile.attach_cache_file`; ``rebuild_cache`` replaces a file
    made for other settings instead of refusing it).

    Example
    -------
    >>> from lbl_illum import load_scene, compute_illuminance, read_points
    >>> scene = load_scene("examples/office/scene.toml")          # doctest: +SKIP
    >>> pts, nrm = read_points("examples/office/grid.pts", scene.unit_scale)  # doctest: +SKIP
    >>> compute_illuminance(scene, pts, nrm).illuminance.mean()   # doctest: +SKIP
    """
    from .engine.integrator import Integrator

    integ = Integrator(scene, options, cache, progress)
    if cache_file is not None:
        from .io.cachefile import attach_cache_file

        attach_cache_file(integ, cache_file, rebuild=rebuild_cache)
    return integ.compute(points, normals)

"""lbl_illum — illuminance in daylit rooms by the irradiance cache of Ward, Rubinstein & Clear (1988).

The public surface::

    scene = load_scene("examples/office/scene.toml")
    points, normals = read_points("examples/office/grid.pts", scene.unit_scale)
    result = compute_illuminance(scene, points, normals, Options(accuracy=0.1))
    result.illuminance            # (n,) lux
"""

from ._version import __version__  # noqa: E402
from .engine.cache import IrradianceCache  # noqa: E402
from .errors import InputError  # noqa: E402
from .engine.integrator import IlluminanceResult, Integrator, compute_illuminance  # noqa: E402
from .options import Options  # noqa: E402
from .scene.scenefile import Scene, load_scene  # noqa: E402
from .io.points import read_points, write_results  # noqa: E402

__all__ = ["__version__", "IrradianceCache", "InputError", "IlluminanceResult", "Integrator",
           "compute_illuminance", "Options", "Scene", "load_scene", "read_points", "write_results"]

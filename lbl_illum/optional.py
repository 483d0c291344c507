"""Optional dependencies, guarded in one place.

Each optional package names the extra that installs it.  :func:`check` is what a command
calls before any work (it finds the package without importing it, so it costs nothing);
:func:`require` imports it where it is used; :func:`available` answers without an error.
A missing package is one :class:`~lbl_illum.errors.InputError` line saying what needs it
and the ``pip install`` that adds it.
"""

from __future__ import annotations

import importlib
import importlib.util
from types import ModuleType

from .errors import InputError

__all__ = ["EXTRAS", "available", "check", "require"]

#: import name -> (pip install argument, what it is for)
EXTRAS = {
    "matplotlib": ("'lbl_illum[plots]'", "plots, false-colour images and validation reports"),
    "pyvista": ("'lbl_illum[view]'", "3-D views"),
    "pvlib": ("'lbl_illum[solar]'", "the NREL SPA solar position"),
    "pyradiance": ("'lbl_illum[radiance]'", "Radiance's programs"),
    "OpenImageIO": ("OpenImageIO", "image files"),
    "honeybee_radiance": ("'lbl_illum[honeybee]'", "Honeybee models (.hbjson)"),
    "distributed": ("'lbl_illum[distributed]'", "studies on a Dask cluster"),
}


def available(module: str) -> bool:
    """The package ``module`` can be imported here (found on the path; not imported)."""
    try:
        return importlib.util.find_spec(module) is not None
    except (ImportError, ValueError):
        return False


def _message(module: str, what: str | None) -> str:
    pip, purpose = EXTRAS[module]
    head = f"{what} needs {module}" if what else f"{module} is needed for {purpose}"
    return f"{head}; install it with pip install {pip}"


def check(module: str, what: str | None = None) -> None:
    """Refuse, before any work, what needs ``module`` when it is not installed.

    ``what`` names the feature in the message (default: the package's use in :data:`EXTRAS`),
    e.g. ``"--falsecolor IMAGE.png"``.
    """
    if not available(module):
        raise InputError(_message(module, what))


def require(module: str, what: str | None = None) -> ModuleType:
    """The imported package ``module``, or the same one-line error as :func:`check`."""
    try:
        return importlib.import_module(module)
    except ImportError:
        raise InputError(_message(module, what)) from None

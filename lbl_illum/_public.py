"""The public surface of a layer package, in one place.

Each layer (``scene``, ``daylight``, ``engine``, ``io``, ``workplane``, ``viz``, ``glare``) names
in its ``__init__`` the few things a script, a notebook or a validation study may use, module
by module; everything else is internal and may change.  The names are imported when first
used (PEP 562), so ``import lbl_illum.scene`` costs nothing and the layers can import each
other's modules without import cycles.
"""

from __future__ import annotations

import importlib


def public_surface(namespace: dict, exports: dict[str, tuple[str, ...]]):
    """``(__all__, __getattr__, __dir__)`` for the package whose ``globals()`` is
    ``namespace`` and whose public names are ``exports`` (module name inside the package ->
    names it defines)."""
    package = namespace["__name__"]
    where = {name: module for module, names in exports.items() for name in names}
    if len(where) != sum(len(names) for names in exports.values()):
        raise ValueError(f"{package}: a public name is listed twice")

    def __getattr__(name: str):
        module = where.get(name)
        if module is None:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        value = getattr(importlib.import_module(f"{package}.{module}"), name)
        namespace[name] = value          # later lookups skip this function
        return value

    def __dir__():
        return sorted(set(namespace) | set(where))

    return sorted(where), __getattr__, __dir__

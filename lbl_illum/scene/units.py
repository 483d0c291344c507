"""Length units of scene files.  The engine works in metres (docs/design.md §2)."""

from __future__ import annotations

from ..errors import InputError

#: Metres per unit, for every unit a scene file may state.
METRES_PER_UNIT = {
    "m": 1.0,
    "cm": 0.01,
    "mm": 0.001,
    "km": 1000.0,
    "ft": 0.3048,
    "in": 0.0254,
}


def metres_per_unit(unit: str, where: str = "scene") -> float:
    """Scale factor from ``unit`` to metres; unknown units are an :class:`InputError`."""
    try:
        return METRES_PER_UNIT[unit]
    except (KeyError, TypeError):
        raise InputError(f"{where}: unknown unit {unit!r} (valid: {', '.join(METRES_PER_UNIT)})") from None

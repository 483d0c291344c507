"""Input errors and the small helpers that validate hand-written tables.

Every problem with what a user wrote is raised as :class:`InputError`, whose
message is one line naming the file and the line or key at fault.  The
command line prints that line and exits with status 2; it never shows a
traceback for bad input.
"""

from __future__ import annotations

import difflib
import math
from typing import Any, Iterable, Mapping

__all__ = ["InputError", "check_keys", "get_number", "get_rgb", "get_vector", "show", "plural"]

#: Longest value quoted in a message (longer ones are cut, ``...`` marking the cut), so that
#: a wrong value as large as a whole table still gives a one-line message.
SHOW_LENGTH = 60


class InputError(ValueError):
    """Bad input: the message is a single line naming file and line or key."""


def show(value: Any, length: int = SHOW_LENGTH) -> str:
    """``repr(value)`` for a message: one line (``repr`` escapes line breaks), at most
    ``length`` characters."""
    text = repr(value)
    return text if len(text) <= length else text[: length - 3] + "..."


def check_keys(table: Mapping[str, Any], allowed: Iterable[str], where: str,
               required: Iterable[str] = ()) -> None:
    """Refuse unknown keys (suggesting the nearest valid one) and missing ones.

    ``where`` names the table for the message, e.g. ``"scene.toml: [sky]"``.
    """
    allowed = list(allowed)
    for key in table:
        if key not in allowed:
            near = difflib.get_close_matches(str(key), allowed, n=1)
            hint = f" (did you mean '{near[0]}'?)" if near else (
                f" (valid keys: {', '.join(allowed)})" if allowed else "")
            raise InputError(f"{where}: unknown key {show(str(key))}{hint}")
    for key in required:
        if key not in table:
            raise InputError(f"{where}: missing key '{key}'")


def _finite_number(value: Any, where: str, key: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise InputError(f"{where}: '{key}' must be a number, got {show(value)}")
    try:
        number = float(value)
    except OverflowError:           # an integer beyond the float range (TOML allows none past 64 bits)
        number = math.inf
    if not math.isfinite(number):
        raise InputError(f"{where}: '{key}' must be finite, got {show(value)}")
    return number


def get_number(table: Mapping[str, Any], key: str, where: str, default: Any = None,
               minimum: float | None = None, maximum: float | None = None,
               min_inclusive: bool = True) -> float:
    """A finite number from ``table[key]`` (or ``default``) within a range."""
    if key not in table:
        if default is None:
            raise InputError(f"{where}: missing key '{key}'")
        return default
    value = _finite_number(table[key], where, key)
    if minimum is not None and (value < minimum or (not min_inclusive and value == minimum)):
        op = ">=" if min_inclusive else ">"
        raise InputError(f"{where}: '{key}' must be {op} {minimum:g}, got {value:g}")
    if maximum is not None and value > maximum:
        raise InputError(f"{where}: '{key}' must be <= {maximum:g}, got {value:g}")
    return value


def get_rgb(table: Mapping[str, Any], key: str, where: str, default: Any = None,
            minimum: float = 0.0, maximum: float | None = None) -> tuple[float, float, float]:
    """A scalar or ``[r, g, b]`` value, returned as an RGB triple."""
    if key not in table:
        if default is None:
            raise InputError(f"{where}: missing key '{key}'")
        value = default
    else:
        value = table[key]
    if isinstance(value, (list, tuple)):
        if len(value) != 3:
            raise InputError(f"{where}: '{key}' must be a number or [r, g, b], got {show(value)}")
        rgb = tuple(_finite_number(v, where, key) for v in value)
    else:
        v = _finite_number(value, where, key)
        rgb = (v, v, v)
    for v in rgb:
        if v < minimum:
            raise InputError(f"{where}: '{key}' must be >= {minimum:g}, got {v:g}")
        if maximum is not None and v > maximum:
            raise InputError(f"{where}: '{key}' must be <= {maximum:g}, got {v:g}")
    return rgb  # type: ignore[return-value]


def get_vector(table: Mapping[str, Any], key: str, where: str, length: int = 3) -> tuple[float, ...]:
    """A list of ``length`` finite numbers."""
    if key not in table:
        raise InputError(f"{where}: missing key '{key}'")
    value = table[key]
    if not isinstance(value, (list, tuple)) or len(value) != length:
        raise InputError(f"{where}: '{key}' must be a list of {length} numbers, got {show(value)}")
    return tuple(_finite_number(v, where, key) for v in value)


def plural(n: int, word: str) -> str:
    """'1 point', '3 points'."""
    return f"{n} {word}" if n == 1 else f"{n} {word}s"

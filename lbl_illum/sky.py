"""Sky luminance distributions (DESIGN.md §2), one class per model, with a registry.

Directions are unit vectors in the scene frame (+z up, +y north, +x east).  Above
the horizon each model gives the sky luminance; below it every model gives the
ground glow of Radiance's ``gensky`` convention, a uniform luminance
``ρ_g E_gh / π`` where ``E_gh`` is the unobstructed horizontal illuminance from sky
and sun together and ``ρ_g`` the ground reflectance.  Unlike ``gensky`` the sky
and the ground are not blended near the horizon.

=================  =====================================================  ===================
type               luminance above the horizon (γ = altitude)              reference
=================  =====================================================  ===================
``uniform``        L = E_h / π                                             —
``cie-overcast``   L(γ) = L_z (1 + 2 sin γ) / 3,   E_h = 7 π L_z / 9       Moon & Spencer 1942,
                                                                            CIE traditional
                                                                            overcast sky
``none``           0 (and no ground glow)                                  —
=================  =====================================================  ===================
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Mapping

import numpy as np

from .errors import InputError, check_keys, get_number

__all__ = ["Sky", "UniformSky", "CIEOvercastSky", "NoSky", "SKY_MODELS", "sky_from_table"]


@dataclass(frozen=True)
class Sky:
    """Base class.  ``horizontal_illuminance`` is the sky's own unobstructed E_h [lux]."""

    horizontal_illuminance: float = 0.0
    ground_reflectance: float = 0.2
    #: unobstructed horizontal illuminance of the sun, added to the ground glow [lux]
    sun_horizontal_illuminance: float = 0.0

    name = "base"

    @property
    def is_dark(self) -> bool:
        """True when no direction carries light."""
        return self.horizontal_illuminance <= 0.0 and self.ground_luminance <= 0.0

    @property
    def ground_luminance(self) -> float:
        """Uniform luminance below the horizon, ρ_g E_gh / π [cd/m²]."""
        return self.ground_reflectance * (self.horizontal_illuminance + self.sun_horizontal_illuminance) / np.pi

    def sky_luminance(self, sin_altitude: np.ndarray) -> np.ndarray:
        """Luminance above the horizon as a function of sin(altitude) [cd/m²]."""
        raise NotImplementedError

    def luminance(self, directions: np.ndarray) -> np.ndarray:
        """(n, 3) RGB luminance [cd/m²] seen along (n, 3) unit ``directions``."""
        z = np.asarray(directions, dtype=np.float64)[:, 2]
        lum = np.where(z >= 0.0, self.sky_luminance(np.clip(z, 0.0, 1.0)), self.ground_luminance)
        return np.repeat(lum[:, None], 3, axis=1)


@dataclass(frozen=True)
class UniformSky(Sky):
    """Uniform sky: the same luminance E_h/π in every direction above the horizon."""

    name = "uniform"

    def sky_luminance(self, sin_altitude):
        return np.full(np.shape(sin_altitude), self.horizontal_illuminance / np.pi)


@dataclass(frozen=True)
class CIEOvercastSky(Sky):
    """CIE traditional overcast sky, L(γ) = L_z (1 + 2 sin γ)/3 with E_h = 7π L_z/9."""

    name = "cie-overcast"

    @property
    def zenith_luminance(self) -> float:
        return 9.0 * self.horizontal_illuminance / (7.0 * np.pi)

    def sky_luminance(self, sin_altitude):
        return self.zenith_luminance * (1.0 + 2.0 * np.asarray(sin_altitude)) / 3.0


@dataclass(frozen=True)
class NoSky(Sky):
    """No sky and no ground glow: an interior lit only by its own sources."""

    name = "none"

    @property
    def ground_luminance(self) -> float:
        return 0.0

    def sky_luminance(self, sin_altitude):
        return np.zeros(np.shape(sin_altitude))


SKY_MODELS = {cls.name: cls for cls in (UniformSky, CIEOvercastSky, NoSky)}


def sky_from_table(table: Mapping[str, Any] | None, where: str, sun_horizontal_illuminance: float = 0.0) -> Sky:
    """Build the sky of a ``[sky]`` table (no table: no sky)."""
    if table is None:
        return NoSky()
    kind = table.get("type", "cie-overcast")
    if kind not in SKY_MODELS:
        raise InputError(f"{where}: 'type' must be one of {', '.join(SKY_MODELS)}, got {kind!r}")
    if kind == "none":
        check_keys(table, ("type",), where)
        return NoSky()
    check_keys(table, ("type", "horizontal_illuminance", "ground_reflectance"), where)
    return SKY_MODELS[kind](
        horizontal_illuminance=get_number(table, "horizontal_illuminance", where, default=10000.0, minimum=0.0),
        ground_reflectance=get_number(table, "ground_reflectance", where, default=0.2, minimum=0.0, maximum=1.0),
        sun_horizontal_illuminance=sun_horizontal_illuminance,
    )

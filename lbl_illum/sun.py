"""The sun: a distant disk source of solid angle 6.8e-5 sr (DESIGN.md §2).

Position by altitude (degrees above the horizon) and azimuth (degrees clockwise
from north, east = 90°) in the scene frame (+z up, +y north, +x east); strength by
its direct normal illuminance E_dn [lux].  Its luminance is E_dn / Ω.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Mapping

import numpy as np

from .errors import check_keys, get_number
from .hemisphere import orthonormal_basis

__all__ = ["Sun", "SUN_SOLID_ANGLE", "sun_from_table"]

#: Solid angle of the solar disk [sr].
SUN_SOLID_ANGLE = 6.8e-5
#: cos of the disk's angular radius δ, from Ω = 2π (1 − cos δ).
SUN_COS_HALF_ANGLE = 1.0 - SUN_SOLID_ANGLE / (2.0 * np.pi)


@dataclass(frozen=True)
class Sun:
    altitude: float                     # [°] above the horizon
    azimuth: float                      # [°] clockwise from north
    direct_normal_illuminance: float    # E_dn [lux]
    warnings: tuple = field(default=(), compare=False)

    @property
    def direction(self) -> np.ndarray:
        """(3,) unit vector towards the sun's centre."""
        alt, az = np.radians(self.altitude), np.radians(self.azimuth)
        return np.array([np.cos(alt) * np.sin(az), np.cos(alt) * np.cos(az), np.sin(alt)])

    @property
    def is_up(self) -> bool:
        return self.altitude > 0.0 and self.direct_normal_illuminance > 0.0

    @property
    def horizontal_illuminance(self) -> float:
        """Unobstructed horizontal illuminance E_dn sin(altitude) [lux]."""
        return self.direct_normal_illuminance * max(0.0, np.sin(np.radians(self.altitude)))

    @property
    def luminance(self) -> float:
        """Luminance of the disk, E_dn / Ω [cd/m²]."""
        return self.direct_normal_illuminance / SUN_SOLID_ANGLE

    def sample_directions(self, u: np.ndarray, v: np.ndarray) -> np.ndarray:
        """(n, 3) directions uniform over the disk from (n,) uniform numbers ``u``, ``v``."""
        cos_t = 1.0 - np.asarray(u) * (1.0 - SUN_COS_HALF_ANGLE)
        sin_t = np.sqrt(np.maximum(0.0, 1.0 - cos_t * cos_t))
        phi = 2.0 * np.pi * np.asarray(v)
        t, b = orthonormal_basis(self.direction[None, :])
        return (sin_t * np.cos(phi))[:, None] * t + (sin_t * np.sin(phi))[:, None] * b + cos_t[:, None] * self.direction

    def within_disk(self, directions: np.ndarray) -> np.ndarray:
        """(n,) bool: which unit directions fall inside the solar disk."""
        return directions @ self.direction >= SUN_COS_HALF_ANGLE


def sun_from_table(table: Mapping[str, Any] | None, where: str) -> Sun | None:
    """Build the sun of a ``[sun]`` table; ``None`` when there is no table."""
    if table is None:
        return None
    check_keys(table, ("altitude", "azimuth", "direct_normal_illuminance"), where,
               required=("altitude", "azimuth", "direct_normal_illuminance"))
    alt = get_number(table, "altitude", where, minimum=-90.0, maximum=90.0)
    az = get_number(table, "azimuth", where)
    edn = get_number(table, "direct_normal_illuminance", where, minimum=0.0)
    warnings = ()
    if alt <= 0.0 and edn > 0.0:
        warnings = (f"{where}: the sun is below the horizon (altitude {alt:g}°): no direct sun",)
    return Sun(alt, az % 360.0, edn, warnings)

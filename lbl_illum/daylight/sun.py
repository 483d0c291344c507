"""The sun: a distant disk source of solid angle 6.8e-5 sr (docs/design.md §2).

Position by altitude (degrees above the horizon) and azimuth (degrees clockwise
from north, east = 90°) in the scene frame (+z up, +y north, +x east), given or computed
for a site and time (:mod:`lbl_illum.daylight.solar`); strength by its direct normal illuminance
E_dn [lux].  Its luminance is E_dn / Ω.  A sun with E_dn = 0 adds no light: it only
positions a sky that depends on the sun (:mod:`lbl_illum.daylight.sky`).
"""

from __future__ import annotations

import datetime as _dt
from dataclasses import dataclass, field
from typing import Any, Mapping

import numpy as np

from ..errors import InputError, check_keys, get_number
from ..scene.geometry import orthonormal_basis
from .sky import MAX_EXTRATERRESTRIAL_ILLUMINANCE
from .solar import Site, parse_time, solar_position, to_utc

__all__ = ["Sun", "SUN_SOLID_ANGLE", "sun_from_table", "sun_position_at"]

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
    #: the UTC time the position was computed for (None: position given)
    time: _dt.datetime | None = field(default=None, compare=False)

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
        cos_t = 1.0 - np.asarray(u, np.float64) * (1.0 - SUN_COS_HALF_ANGLE)
        sin_t = np.sqrt(np.maximum(0.0, 1.0 - cos_t * cos_t))
        phi = 2.0 * np.pi * np.asarray(v, np.float64)
        t, b = orthonormal_basis(self.direction[None, :])
        # (sin θ cos φ, sin θ sin φ, cos θ) in the frame (t, b, sun): one product with the
        # frame's rows instead of three (n, 3) temporaries
        local = np.empty((len(cos_t), 3))
        np.multiply(sin_t, np.cos(phi), out=local[:, 0])
        np.multiply(sin_t, np.sin(phi), out=local[:, 1])
        local[:, 2] = cos_t
        return local @ np.vstack([t[0], b[0], self.direction])

    def within_disk(self, directions: np.ndarray) -> np.ndarray:
        """(n,) bool: which unit directions fall inside the solar disk."""
        return directions @ self.direction >= SUN_COS_HALF_ANGLE


def sun_position_at(time: Any, site: Site | None, where: str, key: str = "time",
                    site_where: str = "[site]") -> tuple[float, float, _dt.datetime]:
    """(altitude, azimuth) [°] of the sun at a scene file's ``time`` at ``site``, and the
    UTC time.  A time without an offset is local standard time and needs the site's
    ``time_zone``."""
    if site is None:
        raise InputError(f"{where}: '{key}' needs a {site_where} table with latitude, longitude and time_zone")
    local, offset = parse_time(time, where, key)
    if offset is None:
        if site.time_zone is None:
            raise InputError(f"{where}: '{key}' {time!s} is local standard time: {site_where} needs 'time_zone' "
                             "(hours east of UTC), or give the time in UTC (\"...Z\")")
        offset = site.time_zone
    utc = to_utc(local, offset)
    pos = solar_position(utc, site.latitude, site.longitude, site.elevation)
    return float(pos.altitude), float(pos.azimuth) % 360.0, utc


def sun_from_table(table: Mapping[str, Any] | None, where: str, site: Site | None = None,
                   default_direct_normal: float | None = None, site_where: str = "[site]") -> Sun | None:
    """Build the sun of a ``[sun]`` table; ``None`` when there is no table.

    The position is ``altitude`` and ``azimuth``, or ``time`` at ``site`` (see
    :func:`sun_position_at`).  ``direct_normal_illuminance`` is required unless
    ``default_direct_normal`` (the value of a Perez sky) stands in for it.
    """
    if table is None:
        return None
    check_keys(table, ("altitude", "azimuth", "time", "direct_normal_illuminance"), where)
    if "time" in table and ("altitude" in table or "azimuth" in table):
        raise InputError(f"{where}: give the sun's position by 'altitude' and 'azimuth' or by 'time', not both")
    utc = None
    if "time" in table:
        alt, az, utc = sun_position_at(table["time"], site, where, site_where=site_where)
    else:
        for key in ("altitude", "azimuth"):
            if key not in table:
                raise InputError(f"{where}: missing key '{key}' (or give a 'time' with a [site])")
        alt = get_number(table, "altitude", where, minimum=-90.0, maximum=90.0)
        az = get_number(table, "azimuth", where)
    if "direct_normal_illuminance" in table or default_direct_normal is None:
        # no beam at the ground is brighter than the sun above the atmosphere at perihelion
        edn = get_number(table, "direct_normal_illuminance", where, minimum=0.0,
                         maximum=MAX_EXTRATERRESTRIAL_ILLUMINANCE)
    else:
        edn = float(default_direct_normal)
    warnings = ()
    if alt <= 0.0 and edn > 0.0:
        warnings = (f"{where}: the sun is below the horizon (altitude {alt:.4g}°): no direct sun",)
    return Sun(alt, az % 360.0, edn, warnings, utc)

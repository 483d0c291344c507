"""Daylight: sky luminance distributions (uniform, CIE overcast and clear, Perez all-weather),
the sun as a 6.8e-5 sr disk, solar position and the hours of a weather file."""

from .._public import public_surface

#: The public names of this layer, by module (imported when first used).
__all__, __getattr__, __dir__ = public_surface(globals(), {
    "sky": ("Sky", "NoSky", "UniformSky", "CIEOvercastSky", "CIEGeneralSky", "PerezSky", "perez_sky",
            "perez_sky_from_weather"),
    "sun": ("Sun", "SUN_SOLID_ANGLE", "sun_position_at"),
    "solar": ("Site", "SolarPosition", "solar_position", "WeatherFile", "WeatherRecord", "read_epw"),
})

"""Daylight: sky luminance distributions (uniform, CIE overcast and clear, Perez all-weather),
the sun as a 6.8e-5 sr disk, solar position, the hours of a weather file (EPW, .wea) and
annual sky matrices (patch luminance per hour, the role of Radiance's gendaymtx)."""

from .._public import public_surface

#: The public names of this layer, by module (imported when first used).
__all__, __getattr__, __dir__ = public_surface(globals(), {
    "sky": ("Sky", "NoSky", "UniformSky", "CIEOvercastSky", "CIEGeneralSky", "PerezSky", "perez_sky",
            "perez_sky_from_weather"),
    "sun": ("Sun", "SUN_SOLID_ANGLE", "sun_position_at"),
    "solar": ("Site", "SolarPosition", "solar_position", "WeatherFile", "WeatherRecord", "read_epw"),
    "weather": ("HourlyWeather", "read_weather", "read_wea"),
    "skymatrix": ("SkyMatrix", "SkyPatches", "sky_matrix", "sky_patches", "patch_index", "gendaymtx_solar_position"),
})

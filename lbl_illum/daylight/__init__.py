"""Daylight: sky luminance distributions (uniform, CIE overcast and clear, Perez all-weather),
the sun as a 6.8e-5 sr disk, solar position and the hours of a weather file."""

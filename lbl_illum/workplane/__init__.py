"""Workplanes: sensor grids over floors and named surfaces, and the figures designers read
off a grid (mean, minimum, uniformity, shares above thresholds, daylight factor)."""

from .._public import public_surface

#: The public names of this layer, by module (imported when first used).
__all__, __getattr__, __dir__ = public_surface(globals(), {
    "grid": ("Grid", "workplane_grid", "en12464_spacing"),
    "metrics": ("daylight_factor", "unobstructed_horizontal_illuminance", "area_figures", "grid_summary"),
})

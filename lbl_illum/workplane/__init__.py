"""Workplanes: sensor grids over floors and named surfaces, and the figures designers read
off a grid (mean, minimum, uniformity, shares above thresholds, daylight factor, and the
annual metrics: DA, cDA, UDI, sDA, ASE, LEED points, EN 17037 levels)."""

from .._public import public_surface

#: The public names of this layer, by module (imported when first used).
__all__, __getattr__, __dir__ = public_surface(globals(), {
    "grid": ("Grid", "workplane_grid", "en12464_spacing"),
    "metrics": ("daylight_factor", "unobstructed_horizontal_illuminance", "area_figures", "grid_summary"),
    "annual": ("annual_metrics", "annual_summary", "write_point_table", "lm83_occupancy", "read_schedule",
               "WindowGroup", "operate_shades", "leed_points", "en17037_daylight_hours", "en17037_provision"),
})

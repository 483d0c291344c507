"""The irradiance-cache calculation of Ward, Rubinstein & Clear (1988) on arrays of rays:
the ray tracer, the paths through specular surfaces, direct light, window portals and
openings and their samples (``portal_sampling``), hemisphere sampling with gradients and
the Hessian, the records' radii (``sizing``), the records and their octree, placement,
the level solver (``integrator``) and luminance images (``render``).
Lengths are metres, illuminance lux, luminance cd/m²."""

from .._public import public_surface

#: The public names of this layer, by module (imported when first used).
__all__, __getattr__, __dir__ = public_surface(globals(), {
    "context": ("LightingContext",),
    "integrator": ("Integrator", "IlluminanceResult", "RunStats", "QUERY_LIGHT_SAMPLES"),
    "cache": ("IrradianceCache", "LevelRecords"),
    "raycast": ("Tracer", "thread_count", "SELF_HIT_EPSILON", "ON_SURFACE_FRACTION"),
    "paths": ("follow_paths", "PathPolicy", "HEMISPHERE", "CAMERA"),
    "hemisphere": ("cell_counts", "stratified_directions"),
    "gradients": ("irradiance_gradients", "limit_gradients"),
    "render": ("RenderResult", "render_image", "image_options"),
    "coefficients": ("CoefficientRecords",),
    "annual": ("AnnualLight", "annual_light", "hour_scene", "shaded_scene", "sun_positions"),
    "sun_hours": ("direct_sun_matrix",),
})

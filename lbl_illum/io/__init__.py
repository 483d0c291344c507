"""Files in and out: sensor points and result tables, luminance images (HDR, EXR, TIFF,
PNG), whole-or-nothing writes and the lock of shared cache files, and the Radiance
export with rtrace cross-checks."""

from .._public import public_surface

#: The public names of this layer, by module (imported when first used).
__all__, __getattr__, __dir__ = public_surface(globals(), {
    "points": ("read_points", "write_points", "read_results", "write_results"),
    "files": ("atomic_write_bytes", "atomic_write_text", "atomic_write_npy"),
    "images": ("read_image", "write_image", "write_png", "preview_pixels"),
    "cachefile": ("attach_cache_file", "load_cache", "save_cache"),
    "radiance": ("export_radiance", "to_radiance", "ambient_options", "illuminance_from_rtrace", "radiance_programs",
                 "material_primitive", "radiance_name", "RADIANCE_EFFICACY", "RADIANCE_RGB_WEIGHTS"),
    "honeybee_results": ("write_res_folder", "write_annual_folder"),
})

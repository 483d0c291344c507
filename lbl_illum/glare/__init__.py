"""Glare: discomfort-glare figures of 180° fisheye luminance images (vertical illuminance
at the eye, glare sources, position index, DGP, DGI, UGR, the EN 17037 class), as
Radiance's evalglare computes them; see docs/glare.md."""

from .._public import public_surface

#: The public names of this layer, by module (imported when first used).
__all__, __getattr__, __dir__ = public_surface(globals(), {
    "metrics": ("GlareResult", "GlareSource", "FisheyeGeometry", "evaluate_glare", "glare_from_image",
                "fisheye_geometry", "find_glare_sources", "position_index", "daylight_glare_probability",
                "low_light_factor", "en17037_class", "dgp_category", "check_fisheye", "DGP_CONSTANTS",
                "EVALGLARE_DGP_CONSTANTS", "EN17037_LIMITS", "DEFAULT_THRESHOLD", "SEARCH_ANGLE", "PEAK_LUMINANCE"),
    "annual": ("AnnualGlare", "annual_glare", "patch_visibility", "PatchVisibility", "simplified_dgp"),
})

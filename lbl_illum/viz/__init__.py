"""Pictures for reports: false-colour plans of grids, false-colour luminance images with a
legend, and 3-D views of a scene with its sensor points."""

from .._public import public_surface

#: The public names of this layer, by module (imported when first used).
__all__, __getattr__, __dir__ = public_surface(globals(), {
    "plots": ("plan_plot",),
    "falsecolor": ("falsecolor_pixels", "write_falsecolor"),
})

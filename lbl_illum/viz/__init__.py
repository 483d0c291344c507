"""Pictures for reports: false-colour plans of grids, false-colour luminance images with a
legend, and 3-D views of a scene with its sensor points."""

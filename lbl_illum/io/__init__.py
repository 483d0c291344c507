"""Files in and out: sensor points and result tables, luminance images (HDR, EXR, TIFF,
PNG), whole-or-nothing writes and the lock of shared cache files, and the Radiance
export with rtrace cross-checks."""

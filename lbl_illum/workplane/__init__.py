"""Workplanes: sensor grids over floors and named surfaces, and the figures designers read
off a grid (mean, minimum, uniformity, shares above thresholds, daylight factor)."""

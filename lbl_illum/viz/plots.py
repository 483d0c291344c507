"""False-colour plans of sensor grids (matplotlib, drawn off screen with the Agg canvas).

A plan shows, seen from above with x east and y north in metres:

* the values at the points as false colour, interpolated linearly over a triangulation
  of each area's points (triangles much longer than the grid's own cells are left
  out, so colour does not bridge a notch of an L-shaped room or a column);
* isolines at round values, and dashed isolines at the thresholds;
* the room's outline (the section of the walls at the grid height, from
  :func:`lbl_illum.workplane.grid.plan_outline`) and the windows;
* a colour bar with the quantity and unit, a scale bar and the area names.

Files are written whole or not at all (rendered in memory, then an atomic rename);
bad input raises :class:`~lbl_illum.errors.InputError` before anything is written.
"""

from __future__ import annotations

import io
import math
import os
from pathlib import Path

import numpy as np

from ..errors import InputError
from ..io.files import atomic_write_bytes
from ..optional import check

__all__ = ["plan_plot", "check_plot_path", "PLOT_FORMATS", "nice_length"]

PLOT_FORMATS = (".png", ".pdf", ".svg")
#: A triangle of the colour triangulation is dropped when its longest edge exceeds this
#: multiple of the median longest edge of its area (the grid's cell diagonal).
MAX_EDGE_RATIO = 1.5


def check_plot_path(path: str | os.PathLike, formats=PLOT_FORMATS) -> Path:
    """Refuse a plot file whose extension is unknown or whose folder does not exist, and
    a missing matplotlib."""
    path = Path(path)
    if path.suffix.lower() not in formats:
        raise InputError(f"{path.name}: a plot must end in {', '.join(formats)}")
    if str(path.parent) and not path.parent.is_dir():
        raise InputError(f"{path}: folder {path.parent} does not exist")
    check("matplotlib", f"{path.name}: plots")
    return path


def nice_length(extent: float) -> float:
    """A round length (1, 2 or 5 × 10^k) close to a quarter of ``extent``, for a scale bar."""
    target = max(extent, 1e-9) / 4.0
    k = math.floor(math.log10(target))
    for m in (5.0, 2.0, 1.0):
        if m * 10.0 ** k <= target:
            return m * 10.0 ** k
    return 10.0 ** k


def _masked_triangulation(xy: np.ndarray):
    """A Delaunay triangulation of (n, 2) points without its overlong triangles (None if
    the points span no area)."""
    from matplotlib.tri import Triangulation

    if len(xy) < 3 or np.linalg.matrix_rank(xy - xy.mean(axis=0), tol=1e-9) < 2:
        return None
    try:
        tri = Triangulation(xy[:, 0], xy[:, 1])
    except (ValueError, RuntimeError):
        return None
    corners = xy[tri.triangles]
    longest = np.max(np.linalg.norm(corners - np.roll(corners, 1, axis=1), axis=2), axis=1)
    tri.set_mask(longest > MAX_EDGE_RATIO * np.median(longest))
    return tri


def plan_plot(path: str | os.PathLike, points: np.ndarray, values: np.ndarray | None = None, *,
              areas: np.ndarray | None = None, outline: np.ndarray | None = None,
              windows: np.ndarray | None = None, quantity: str = "Illuminance", unit: str = "lux",
              thresholds=(), title: str | None = None, dpi: int = 150) -> None:
    """Draw a plan of a grid into ``path`` (.png, .pdf or .svg).

    points : (n, 2 or 3) plan positions [m];  values : (n,) finite, or None to draw the
    points only;  areas : (n,) area names;  outline, windows : (k, 2, 2) plan segments [m];
    quantity, unit : colour-bar label, e.g. ``"Daylight factor"``, ``"%"``;
    thresholds : values drawn as dashed isolines.
    """
    path = check_plot_path(path)
    xy = np.asarray(points, dtype=np.float64)
    if xy.ndim != 2 or xy.shape[1] not in (2, 3) or len(xy) == 0:
        raise InputError(f"{path.name}: no points to plot")
    xy = xy[:, :2]
    if not np.isfinite(xy).all():
        raise InputError(f"{path.name}: point positions must be finite")
    if values is not None:
        values = np.asarray(values, dtype=np.float64).ravel()
        if values.shape != (len(xy),):
            raise InputError(f"{path.name}: {values.size} values for {len(xy)} points")
        if not np.isfinite(values).all():
            raise InputError(f"{path.name}: values must be finite")
    names = (np.asarray(areas, dtype=object).ravel() if areas is not None
             else np.full(len(xy), "", dtype=object))
    if names.shape != (len(xy),):
        raise InputError(f"{path.name}: {names.size} area names for {len(xy)} points")
    walls, glazing = (np.zeros((0, 2, 2)) if s is None else np.asarray(s, dtype=np.float64).reshape(-1, 2, 2)
                      for s in (outline, windows))
    segments = [walls, glazing]

    from matplotlib.collections import LineCollection
    from matplotlib.figure import Figure
    from matplotlib.lines import Line2D
    from matplotlib.ticker import MaxNLocator
    from mpl_toolkits.axes_grid1.anchored_artists import AnchoredSizeBar

    lo, hi = _limits(xy, segments)
    width, height = hi - lo
    fig = Figure(figsize=(7.5, max(3.5, min(11.0, 6.0 * height / max(width, 1e-9) + 1.5))), dpi=dpi,
                 layout="constrained")
    ax = fig.add_subplot()
    ax.set_aspect("equal")
    ax.set_xlim(lo[0], hi[0])
    ax.set_ylim(lo[1], hi[1])
    ax.set_xlabel("x (east) [m]")
    ax.set_ylabel("y (north) [m]")
    handles = []
    if values is not None:
        vmin, vmax = float(values.min()), float(values.max())
        if vmax <= vmin:
            vmin, vmax = vmin - 0.5 * max(abs(vmin), 1.0), vmax + 0.5 * max(abs(vmax), 1.0)
        levels = [x for x in MaxNLocator(nbins=8).tick_values(vmin, vmax) if vmin < x < vmax]
        for name in dict.fromkeys(names.tolist()):
            sel = names == name
            tri = _masked_triangulation(xy[sel])
            if tri is None:
                continue
            ax.tripcolor(tri, values[sel], shading="gouraud", cmap="viridis", vmin=vmin, vmax=vmax)
            if levels:
                cs = ax.tricontour(tri, values[sel], levels=levels, colors="0.15", linewidths=0.6)
                ax.clabel(cs, fontsize=7, fmt="%g")
            inside = [t for t in thresholds if vmin < t < vmax]
            if inside:
                ax.tricontour(tri, values[sel], levels=sorted(inside), colors="crimson", linewidths=1.4,
                              linestyles="dashed")
        sc = ax.scatter(xy[:, 0], xy[:, 1], c=values, cmap="viridis", vmin=vmin, vmax=vmax, s=9,
                        edgecolors="0.2", linewidths=0.3, zorder=3)
        fig.colorbar(sc, ax=ax, shrink=0.85, label=f"{quantity} [{unit}]")
        for t in thresholds:
            handles.append(Line2D([], [], color="crimson", ls="--", lw=1.4, label=f"{t:g} {unit}"))
    else:
        ax.scatter(xy[:, 0], xy[:, 1], s=9, color="0.1", zorder=3)
        handles.append(Line2D([], [], ls="", marker="o", ms=3, color="0.1", label=f"{len(xy)} points"))
    if len(walls):
        ax.add_collection(LineCollection(walls, colors="black", linewidths=1.6, zorder=4))
        handles.append(Line2D([], [], color="black", lw=1.6, label="walls (section at the grid)"))
    if len(glazing):
        ax.add_collection(LineCollection(glazing, colors="deepskyblue", linewidths=3.0, zorder=5))
        handles.append(Line2D([], [], color="deepskyblue", lw=3.0, label="glazing"))
    for name in dict.fromkeys(names.tolist()):
        if name:
            centre = np.median(xy[names == name], axis=0)
            ax.text(centre[0], centre[1], name, ha="center", va="center", fontsize=9, zorder=6,
                    bbox=dict(boxstyle="round,pad=0.2", fc="white", ec="0.4", alpha=0.85))
    bar = nice_length(width)
    ax.add_artist(AnchoredSizeBar(ax.transData, bar, f"{bar:g} m", "lower right", pad=0.4, borderpad=0.5,
                                  sep=3, frameon=True, size_vertical=0.012 * height))
    if handles:
        ax.legend(handles=handles, loc="upper left", fontsize=7, framealpha=0.85)
    ax.set_title(title or (f"{quantity} [{unit}]" if values is not None else "Sensor grid"), fontsize=10)
    buf = io.BytesIO()
    fig.savefig(buf, format=path.suffix.lower()[1:])
    atomic_write_bytes(path, buf.getvalue())


def _limits(xy: np.ndarray, segments: list[np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """Plot limits: the points, and the outline near them (within a quarter of the grid's
    extent, at least 1 m), with a small border."""
    lo, hi = xy.min(axis=0), xy.max(axis=0)
    grow = max(1.0, 0.25 * float((hi - lo).max()))
    region_lo, region_hi = lo - grow, hi + grow
    for seg in segments:
        if len(seg):
            ends = np.clip(seg.reshape(-1, 2), region_lo, region_hi)
            lo, hi = np.minimum(lo, ends.min(axis=0)), np.maximum(hi, ends.max(axis=0))
    pad = max(0.3, 0.04 * float((hi - lo).max()))
    return lo - pad, hi + pad

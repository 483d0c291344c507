"""False-colour plans of sensor grids (matplotlib, drawn off screen with the Agg canvas).

A plan shows, seen from above with x east and y north in metres:

* the values as false colour over the room's floor out to the walls: the rooms are the
  closed regions of the outline that hold points (:func:`_plan_rooms`); inside a
  triangulation of each area's points the values are interpolated linearly (triangles
  much longer than the grid's own cells are left out), between the outer points and the
  walls each spot takes the value of the nearest point in its room (:func:`_plan_field`).
  Colour does not enter a notch of an L-shaped room, a column or furniture cut at the
  grid height.  Where the outline does not close around the points (no outline, gaps in
  the walls' section), colour stops at the points' triangulation;
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
import textwrap
from pathlib import Path

import numpy as np

from ..errors import InputError
from ..io.files import atomic_write_bytes
from ..optional import check

__all__ = ["plan_plot", "check_plot_path", "PLOT_FORMATS", "PLAN_SCALES", "nice_length"]

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


#: Gaps in the walls' section narrower than this [m] are closed when the rooms are found
#: (section segments of adjacent triangles that miss each other, a window frame's inset).
WALL_GAP = 0.05
#: Cells of the colour raster along the longer side of the rooms' extent.
RASTER_CELLS = 400
#: Colour reaches at most this many grid spacings (the median distance between a point and
#: its nearest neighbour), and at least ``REACH_MIN`` [m], from the nearest point of its room
#: (a room corner behind a 1 m wall margin is 1.41 m away): a grid over part of a room (a
#: task area), or rooms without points beyond a door opening, are not coloured throughout.
REACH_SPACINGS = 2.0
REACH_MIN = 1.5


def _inside(rooms: list, xy: np.ndarray) -> np.ndarray:
    """(n,) index of the first room holding each of the (n, 2) positions [m], -1 for none."""
    import shapely

    room = np.full(len(xy), -1)
    for k, polygon in enumerate(rooms):
        room[(room < 0) & shapely.contains_xy(polygon, xy[:, 0], xy[:, 1])] = k
    return room


def _plan_rooms(xy: np.ndarray, walls: np.ndarray, glazing: np.ndarray) -> list:
    """The rooms of a plan: shapely polygons [m] of the closed regions of the outline that
    hold some of the (n, 2) points ``xy`` [m].

    walls, glazing : (k, 2, 2) plan segments [m].  Every segment, widened by
    ``WALL_GAP / 2`` on each side (gaps narrower than ``WALL_GAP`` close), cuts the plane;
    a region that holds points and does not reach the border of a box 1 m around all of
    it is a room, grown back by ``WALL_GAP / 2`` to the segments' lines.  Holes of a room
    (a column, furniture cut at the grid height) stay out of it, except a hole bounded by
    glazing alone (a roof light seen from above).  Rooms are kept apart even when a single
    wall line parts them.  Empty when no point lies in a closed region: no outline, or an
    outline with gaps (a door opening to the outside, a missing wall).
    """
    import shapely

    walls, glazing = (s[np.isfinite(s).all(axis=(1, 2))] for s in (walls.reshape(-1, 2, 2), glazing.reshape(-1, 2, 2)))
    segments = np.concatenate([walls, glazing])
    if len(segments) == 0 or len(xy) == 0:
        return []
    half = 0.5 * WALL_GAP
    ends = np.concatenate([segments.reshape(-1, 2), xy])
    box = shapely.box(*(ends.min(axis=0) - 1.0), *(ends.max(axis=0) + 1.0))
    rooms = []
    try:
        solid = shapely.union_all(shapely.buffer(shapely.linestrings(segments), half))
        glass = shapely.buffer(shapely.union_all(shapely.linestrings(glazing)), WALL_GAP) if len(glazing) else None
        for region in shapely.get_parts(shapely.difference(box, solid)):
            if region.intersects(box.exterior) or not shapely.contains_xy(region, xy[:, 0], xy[:, 1]).any():
                continue
            for room in shapely.get_parts(shapely.buffer(region, half, join_style="mitre")):
                holes = [ring for ring in room.interiors if glass is None or not glass.covers(ring)]
                rooms.append(shapely.Polygon(room.exterior, holes))
    except shapely.errors.GEOSException:        # a degenerate outline: the plan colours as without one
        return []
    # a region under a roof light holding points lies in the room whose hole it filled
    return [room for room in rooms
            if not any(other is not room and other.contains(room.representative_point()) for other in rooms)]


def _plan_field(xy: np.ndarray, values: np.ndarray, names: np.ndarray, rooms: list,
                lo: np.ndarray, hi: np.ndarray, cells: int = RASTER_CELLS):
    """The values on a raster over the rooms: ``(field, extent, own)``.

    xy : (n, 2) points [m];  values : (n,) in the plan's unit;  names : (n,) area names;
    rooms : polygons from :func:`_plan_rooms`;  lo, hi : (2,) corners [m] the raster stays
    within;  cells : raster cells along the longer side.  field : (ny, nx) masked array of
    values, row 0 to the south, square cells;  extent : (x0, x1, y0, y1) [m] of the raster;
    own : (n,) room index of each point, -1 outside every room.

    A cell whose centre lies in a room takes the linear interpolation of its area's values
    over the area's triangulation where a triangle with all three corners in the same room
    covers it; elsewhere (between the outer points and the walls, around a column) the value
    at the nearest point of the triangulation's outer edges in its room — linear along the
    edge, constant straight out from it: no gradient is invented beyond the points, and the
    margin shades along the wall as the outer row of points does instead of stepping from
    one point's value to the next (where an area has no such edge, a single row of points,
    the nearest point's value).  A cell belongs to the area of its nearest point.  Cells
    outside every room, in its holes, or farther than max(``REACH_MIN``, ``REACH_SPACINGS`` ×
    grid spacing) from every point of their room are masked.
    """
    import shapely
    from matplotlib.tri import LinearTriInterpolator

    own = _inside(rooms, xy)
    bounds = shapely.total_bounds(rooms)
    r_lo, r_hi = np.maximum(bounds[:2], lo), np.minimum(bounds[2:], hi)
    step = max(float((r_hi - r_lo).max()), 1e-6) / cells
    n = np.maximum(np.ceil((r_hi - r_lo) / step).astype(int), 1)
    cx, cy = np.meshgrid(r_lo[0] + (np.arange(n[0]) + 0.5) * step, r_lo[1] + (np.arange(n[1]) + 0.5) * step)
    centres = np.column_stack([cx.ravel(), cy.ravel()])
    cell_room = _inside(rooms, centres)
    placed = np.flatnonzero(own >= 0)
    spacing = 0.0
    if len(placed) > 1:
        tree = shapely.STRtree(shapely.points(xy[placed]))
        _, gaps = tree.query_nearest(shapely.points(xy[placed]), return_distance=True, exclusive=True,
                                     all_matches=False)
        spacing = float(np.median(gaps)) if len(gaps) else 0.0
    reach = max(REACH_MIN, REACH_SPACINGS * spacing)
    near = np.full(len(centres), -1)
    for k in range(len(rooms)):
        mine, inside = np.flatnonzero(own == k), np.flatnonzero(cell_room == k)
        if len(mine) == 0 or len(inside) == 0:
            continue
        (cell, point), dist = shapely.STRtree(shapely.points(xy[mine])).query_nearest(
            shapely.points(centres[inside]), return_distance=True, all_matches=False)
        ok = dist <= reach
        near[inside[cell[ok]]] = mine[point[ok]]
    hit = np.flatnonzero(near >= 0)
    field = np.full(len(centres), np.nan)
    field[hit] = values[near[hit]]
    for name in dict.fromkeys(names[placed].tolist()):
        sel = np.flatnonzero(names == name)
        tri = _masked_triangulation(xy[sel])
        if tri is None:
            continue
        mine = hit[names[near[hit]] == name]
        t = tri.get_trifinder()(centres[mine, 0], centres[mine, 1])
        corners = own[sel][tri.triangles[t]]
        outside = mine[~((t >= 0) & (corners == cell_room[mine][:, None]).all(axis=1))]
        mine = mine[(t >= 0) & (corners == cell_room[mine][:, None]).all(axis=1)]
        linear = np.ma.filled(LinearTriInterpolator(tri, values[sel])(centres[mine, 0], centres[mine, 1]), np.nan)
        field[mine[np.isfinite(linear)]] = linear[np.isfinite(linear)]
        _extend_from_edges(field, centres, cell_room, outside, tri, values[sel], own[sel])
    extent = (r_lo[0], r_lo[0] + n[0] * step, r_lo[1], r_lo[1] + n[1] * step)
    return np.ma.masked_invalid(field.reshape(n[1], n[0])), extent, own


def _outer_edges(tri, own) -> np.ndarray:
    """(k, 2) point indices of the edges that border only one of the triangles used for
    colour (unmasked, all three corners in one room, ``own`` (n,) the room of each
    point): the outline of each room's triangulation, notches and holes included."""
    keep = ~tri.mask if tri.mask is not None else np.ones(len(tri.triangles), bool)
    t = tri.triangles[keep]
    t = t[(own[t] == own[t[:, :1]]).all(axis=1)]
    edges = np.sort(np.concatenate([t[:, [0, 1]], t[:, [1, 2]], t[:, [2, 0]]]), axis=1)
    unique, count = np.unique(edges, axis=0, return_counts=True)
    return unique[count == 1]


def _extend_from_edges(field, centres, cell_room, cells, tri, values, own, chunk: int = 4096) -> None:
    """field[cells] = the value at the nearest point of the triangulation's outer edges
    whose two ends lie in the cell's room, linear along that edge (cells with no such
    edge keep their value)."""
    edges = _outer_edges(tri, own)
    if len(edges) == 0 or len(cells) == 0:
        return
    xy = np.column_stack([tri.x, tri.y])
    a, b = xy[edges[:, 0]], xy[edges[:, 1]]
    ab = b - a
    length2 = np.maximum(np.einsum("ij,ij->i", ab, ab), 1e-18)
    room = own[edges[:, 0]]
    for lo in range(0, len(cells), chunk):
        c = cells[lo:lo + chunk]
        p = centres[c]
        t = np.clip(np.einsum("cej,ej->ce", p[:, None] - a[None], ab) / length2, 0.0, 1.0)
        gap = p[:, None] - (a[None] + t[..., None] * ab[None])
        d2 = np.einsum("cej,cej->ce", gap, gap)
        d2[room[None] != cell_room[c][:, None]] = np.inf
        best = np.argmin(d2, axis=1)
        rows = np.arange(len(c))
        ok = np.isfinite(d2[rows, best])
        tb = t[rows, best]
        va = values[edges[best, 0]]
        value = va + tb * (values[edges[best, 1]] - va)
        field[c[ok]] = value[ok]


#: Colour scales of a plan.
PLAN_SCALES = ("linear", "log")


def plan_plot(path: str | os.PathLike, points: np.ndarray, values: np.ndarray | None = None, *,
              areas: np.ndarray | None = None, outline: np.ndarray | None = None,
              windows: np.ndarray | None = None, quantity: str = "Illuminance", unit: str = "lux",
              thresholds=(), title: str | None = None, summary: str | None = None, scale: str = "linear",
              value_range: tuple[float, float] | None = None, isolines: bool = True, dpi: int = 150) -> None:
    """Draw a plan of a grid into ``path`` (.png, .pdf or .svg).

    points : (n, 2 or 3) plan positions [m];  values : (n,) finite, or None to draw the
    points only;  areas : (n,) area names;  outline, windows : (k, 2, 2) plan segments [m];
    quantity, unit : colour-bar label, e.g. ``"Daylight factor"``, ``"%"``;
    thresholds : values drawn as isolines, one line style each;  title : the sheet's title;
    summary : a line of figures printed under it;  scale : ``"linear"`` or ``"log"`` (a
    sunlit room: sun patches of 47,000 lux no longer turn the rest into one colour);
    value_range : (min, max) of the colours (default: the values');  isolines : False leaves out
    the isolines at round values (a pass/fail map: only its thresholds).  Nothing is drawn over
    the room: the scale bar and the north arrow (+y) sit in a band below the plan, the
    legend beside it.

    The colour covers each room of the outline out to its walls (:func:`_plan_rooms`,
    :func:`_plan_field`): inside the triangulation of an area's points the values are
    interpolated linearly, as the isolines; beyond the outer points (the wall margin,
    around a column) each spot takes the value of the nearest point of its room, a constant
    extrapolation that invents no gradient.  An area with points outside every closed room
    (no outline, an outline that does not close around them) is coloured over its points'
    triangulation only, as the isolines are; the plan is drawn all the same.
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
    if scale not in PLAN_SCALES:
        raise InputError(f"{path.name}: the colour scale must be one of {', '.join(PLAN_SCALES)}, got {scale!r}")
    if value_range is not None and not (np.all(np.isfinite(value_range)) and value_range[0] < value_range[1]):
        raise InputError(f"{path.name}: the colour range must be two finite numbers, the first below the second")
    if scale == "log" and value_range is not None and value_range[0] <= 0.0:
        raise InputError(f"{path.name}: a log colour scale needs a range above 0, got {value_range[0]:g}")

    from matplotlib.collections import LineCollection
    from matplotlib.colors import LogNorm, Normalize
    from matplotlib.figure import Figure
    from matplotlib.lines import Line2D
    from matplotlib.ticker import LogLocator, MaxNLocator
    from mpl_toolkits.axes_grid1.anchored_artists import AnchoredSizeBar

    lo, hi = _limits(xy, segments)
    plan = (lo, hi)                         # the plan without the band below
    width, height = hi - lo
    band = max(0.5, 0.1 * height)           # below the plan: scale bar and north arrow
    lo = lo - np.array([0.0, band])
    height += band
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
        vmin, vmax = value_range if value_range is not None else (float(values.min()), float(values.max()))
        if scale == "log":
            positive = values[values > 0.0]
            floor = float(positive.min()) if len(positive) else 1.0
            vmin, vmax = max(vmin, floor), max(vmax, floor * 10.0)
        if vmax <= vmin:
            vmin, vmax = vmin - 0.5 * max(abs(vmin), 1.0), vmax + 0.5 * max(abs(vmax), 1.0)
        norm = LogNorm(vmin, vmax, clip=True) if scale == "log" else Normalize(vmin, vmax, clip=True)
        shown = np.clip(values, vmin, vmax)
        locator = LogLocator(subs=(1.0, 2.0, 5.0)) if scale == "log" else MaxNLocator(nbins=8)
        levels = [x for x in locator.tick_values(vmin, vmax) if vmin < x < vmax]
        styles = ("dashed", "dashdot", "dotted", (0, (5, 1, 1, 1, 1, 1)))
        own = np.full(len(xy), -1)
        rooms = _plan_rooms(xy, walls, glazing)
        if rooms:
            field, extent, own = _plan_field(xy, shown, names, rooms, *plan)
            ax.imshow(field, extent=extent, origin="lower", cmap="viridis", norm=norm, interpolation="nearest",
                      aspect="equal")
        for name in dict.fromkeys(names.tolist()):
            sel = names == name
            tri = _masked_triangulation(xy[sel])
            if tri is None:
                continue
            if (own[sel] < 0).any():        # outside a closed room: colour over the triangulation only
                ax.tripcolor(tri, shown[sel], shading="gouraud", cmap="viridis", norm=norm)
            if levels and isolines:
                cs = ax.tricontour(tri, shown[sel], levels=levels, colors="0.15", linewidths=0.6)
                ax.clabel(cs, fontsize=7, fmt="%g")
            for i, t in enumerate(thresholds):
                if vmin < t < vmax:
                    ax.tricontour(tri, shown[sel], levels=[t], colors="crimson", linewidths=1.4,
                                  linestyles=[styles[i % len(styles)]])
        sc = ax.scatter(xy[:, 0], xy[:, 1], c=shown, cmap="viridis", norm=norm, s=9,
                        edgecolors="0.2", linewidths=0.3, zorder=3)
        bar_ = fig.colorbar(sc, ax=ax, shrink=0.85, label=f"{quantity} [{unit}]" + (", log scale" if scale == "log" else ""))
        if scale == "log":          # plain numbers at 1-2-5 steps, not powers of ten
            from matplotlib.ticker import FuncFormatter

            bar_.set_ticks([t for t in locator.tick_values(vmin, vmax) if vmin <= t <= vmax])
            bar_.ax.yaxis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:,.0f}" if v >= 10 else f"{v:g}"))
            bar_.ax.minorticks_off()
        for i, t in enumerate(thresholds):
            handles.append(Line2D([], [], color="crimson", ls=styles[i % len(styles)], lw=1.4, label=f"{t:g} {unit}"))
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
    ax.add_artist(AnchoredSizeBar(ax.transData, bar, f"{bar:g} m", "lower right", pad=0.3, borderpad=0.3,
                                  sep=3, frameon=False, size_vertical=0.012 * height))
    # north arrow (+y is north) in the band's left end
    tip = np.array([lo[0] + 0.06 * width, lo[1] + 0.85 * band])
    ax.annotate("N", xy=tip, xytext=(tip[0], lo[1] + 0.15 * band), ha="center", va="bottom", fontsize=9,
                fontweight="bold", arrowprops=dict(arrowstyle="-|>", color="black", lw=1.2))
    if handles:
        fig.legend(handles=handles, loc="outside lower center", ncols=min(4, len(handles)), fontsize=7,
                   frameon=False)
    heading = textwrap.fill(title or (f"{quantity} [{unit}]" if values is not None else "Sensor grid"), 60)
    ax.set_title(heading + (f"\n{textwrap.fill(summary, 72)}" if summary else ""), fontsize=9)
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

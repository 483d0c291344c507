"""Pictures of annual daylight metrics for a report (matplotlib, off screen with Agg).

* :func:`da_plan`: a plan of daylight autonomy DA [% of occupied hours] with the 50 %
  isoline, the sDA pass line;
* :func:`sda_plan`: the points that pass sDA (DA ≥ 50 %) and those that fail, with the
  boundary between them;
* :func:`ase_plan`: a plan of the occupied hours of direct sun ≥ 1000 lux, with the
  250-hour isoline of ASE1000,250;
* :func:`day_hour_plot`: a day × hour map (365 × 24) of the mean illuminance of an area,
  colour bar in lux, with the occupied hours outlined.

The plans are :func:`lbl_illum.viz.plots.plan_plot` given the per-point values (the
definitions are in :mod:`lbl_illum.workplane.annual`).  Files are written whole or not at
all (rendered in memory, then an atomic rename); bad input raises
:class:`~lbl_illum.errors.InputError` before anything is written.
"""

from __future__ import annotations

import io
import os

import numpy as np

from ..errors import InputError
from ..io.files import atomic_write_bytes
from .plots import PLAN_SCALES, check_plot_path, plan_plot

__all__ = ["da_plan", "sda_plan", "ase_plan", "day_hour_plot", "day_hour_grid", "MONTHS"]

#: Month labels of the day axis.
MONTHS = ("Jan", "Feb", "Mar", "Apr", "May", "Jun", "Jul", "Aug", "Sep", "Oct", "Nov", "Dec")
_MONTH_LENGTHS = (31, 28, 31, 30, 31, 30, 31, 31, 30, 31, 30, 31)


def da_plan(path: str | os.PathLike, points, da, *, threshold: float = 300.0, areas=None, outline=None,
            windows=None, title: str | None = None, summary: str | None = None, dpi: int = 150) -> None:
    """A plan of DA [% of occupied hours] from 0 to 100 %, the 50 % isoline dashed (the
    points inside it pass sDA).  points : (P, 2 or 3) [m];  da : (P,) [%];  the other
    arguments as :func:`~lbl_illum.viz.plots.plan_plot`."""
    plan_plot(path, points, da, areas=areas, outline=outline, windows=windows,
              quantity=f"Daylight autonomy DA{threshold:g}", unit="%", thresholds=[50.0],
              title=title or f"Daylight autonomy DA{threshold:g} [% of occupied hours]", summary=summary,
              value_range=(0.0, 100.0), dpi=dpi)


def sda_plan(path: str | os.PathLike, points, da, *, threshold: float = 300.0, areas=None, outline=None,
             windows=None, title: str | None = None, summary: str | None = None, dpi: int = 150) -> None:
    """Pass (1) where DA ≥ 50 % of the occupied hours, fail (0) elsewhere; the isoline at ½
    is the boundary.  The title gives sDA, the percent of points that pass."""
    da = np.asarray(da, dtype=np.float64).ravel()
    passed = (da >= 50.0).astype(np.float64)
    share = 100.0 * passed.sum() / max(passed.size, 1)
    plan_plot(path, points, passed, areas=areas, outline=outline, windows=windows,
              quantity=f"DA{threshold:g} >= 50 %", unit="1 pass, 0 fail", thresholds=[0.5],
              title=title or (f"sDA{threshold:g}/50% = {share:.0f} % of points: DA{threshold:g} >= 50 % "
                              "(1, yellow) or not (0), the boundary dashed"),
              summary=summary, value_range=(0.0, 1.0), isolines=False, dpi=dpi)


def ase_plan(path: str | os.PathLike, points, hours, *, areas=None, outline=None, windows=None,
             title: str | None = None, summary: str | None = None, dpi: int = 150) -> None:
    """A plan of the occupied hours of direct sun ≥ 1000 lux [h], the 250 h isoline dashed
    (points beyond it fail ASE1000,250)."""
    hours = np.asarray(hours, dtype=np.float64).ravel()
    top = max(500.0, float(hours.max()) if hours.size else 0.0)
    share = 100.0 * (hours > 250.0).sum() / max(hours.size, 1)
    plan_plot(path, points, hours, areas=areas, outline=outline, windows=windows,
              quantity="Direct sun >= 1000 lux", unit="h", thresholds=[250.0],
              title=title or f"Direct sun >= 1000 lux [occupied h]: ASE1000,250 = {share:.0f} %",
              summary=summary, value_range=(0.0, top), dpi=dpi)


def day_hour_plot(path: str | os.PathLike, illuminance, *, areas=None, area: str | None = None, occupancy=None,
                  title: str | None = None, scale: str = "linear", value_range: tuple[float, float] | None = None,
                  dpi: int = 150) -> None:
    """A day × hour map of mean illuminance [lux]: days of the year along x, hours of the day
    (local standard time, row hour H drawn from H − 1 to H) along y.

    illuminance : (P, 8760) [lux] (or (8760,) already averaged);  areas, area : average
    over the points whose name is ``area`` (None: all points);  occupancy : (8760,) weights,
    whose occupied hours are outlined, each day from its first to its last occupied hour;
    scale : ``"linear"`` or ``"log"`` (hours without light left blank);  value_range :
    (min, max) of the colours [lux].
    """
    path = check_plot_path(path)
    grid, label, count = day_hour_grid(illuminance, areas, area, where=path.name)
    if scale not in PLAN_SCALES:
        raise InputError(f"{path.name}: the colour scale must be one of {', '.join(PLAN_SCALES)}, got {scale!r}")
    if value_range is not None and not (np.all(np.isfinite(value_range)) and value_range[0] < value_range[1]):
        raise InputError(f"{path.name}: the colour range must be two finite numbers, the first below the second")
    occ = None
    if occupancy is not None:
        occ = np.asarray(occupancy, dtype=np.float64).ravel()
        if occ.shape != (8760,):
            raise InputError(f"{path.name}: occupancy needs 8760 values, got {occ.size}")

    from matplotlib.colors import LogNorm, Normalize
    from matplotlib.figure import Figure
    from matplotlib.lines import Line2D

    vmin, vmax = value_range if value_range is not None else (float(grid.min()), float(grid.max()))
    if scale == "log":
        positive = grid[grid > 0.0]
        vmin = max(vmin, float(positive.min()) if positive.size else 1.0, 1e-3)
        vmax = max(vmax, vmin * 10.0)
        shown = np.ma.masked_less_equal(grid, 0.0)
        norm = LogNorm(vmin, vmax, clip=True)
    else:
        if vmax <= vmin:
            vmax = vmin + 1.0
        shown, norm = grid, Normalize(vmin, vmax, clip=True)
    fig = Figure(figsize=(9.0, 4.2), dpi=dpi, layout="constrained")
    ax = fig.add_subplot()
    ax.set_facecolor("0.85")
    image = ax.imshow(shown, origin="lower", extent=(0, 365, 0, 24), aspect="auto", cmap="viridis", norm=norm,
                      interpolation="nearest")
    bar = fig.colorbar(image, ax=ax, label="Mean illuminance [lux]" + (", log scale" if scale == "log" else ""),
                       pad=0.01)
    if scale == "log":                  # plain numbers at 1-2-5 steps, as the plans
        from matplotlib.ticker import FuncFormatter, LogLocator

        bar.set_ticks([t for t in LogLocator(subs=(1.0, 2.0, 5.0)).tick_values(vmin, vmax) if vmin <= t <= vmax])
        bar.ax.yaxis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:,.0f}" if v >= 10 else f"{v:g}"))
        bar.ax.minorticks_off()
    starts = np.concatenate([[0], np.cumsum(_MONTH_LENGTHS)[:-1]])
    ax.set_xticks(starts + np.array(_MONTH_LENGTHS) / 2.0, MONTHS)
    ax.set_xticks(starts, minor=True)
    ax.tick_params(axis="x", which="major", length=0)
    ax.tick_params(axis="x", which="minor", length=5)
    ax.set_yticks(range(0, 25, 3))
    ax.set_ylabel("hour (local standard time)")
    ax.set_xlabel("day of the year")
    handles = []
    if occ is not None and occ.any():
        first, last = _daily_span(occ.reshape(365, 24))
        days = np.arange(366)
        for edge in (first, last):
            ax.step(days, np.append(edge, edge[-1]), where="post", color="white", lw=1.0, ls="--")
        handles.append(Line2D([], [], color="white", lw=1.0, ls="--", label="occupied hours"))
    if handles:
        legend = ax.legend(handles=handles, loc="upper right", fontsize=7, facecolor="0.3", edgecolor="none")
        for text in legend.get_texts():
            text.set_color("white")
    points = f"{count} point" + ("s" if count != 1 else "")
    ax.set_title(title or f"Mean illuminance of {label} ({points}), day x hour", fontsize=9)
    buf = io.BytesIO()
    fig.savefig(buf, format=path.suffix.lower()[1:])
    atomic_write_bytes(path, buf.getvalue())


def day_hour_grid(illuminance, areas=None, area: str | None = None, where: str = "day x hour map"):
    """(grid, label, points): the (24, 365) mean illuminance [lux] of the points of ``area``
    (all points when None), ``grid[i, d]`` the row of hour-ending i + 1 of day d + 1.

    illuminance : (P, 8760) or (8760,);  areas : (P,) names.  Bad input is an
    :class:`InputError` starting with ``where``.
    """
    E = np.asarray(illuminance)                     # float32 stays float32: no copy of a year
    if E.ndim == 1:
        E = E[None, :]
    if E.ndim != 2 or E.shape[1] != 8760 or len(E) == 0 or not np.issubdtype(E.dtype, np.number):
        raise InputError(f"{where}: a day x hour map needs 8760 hourly values per point, got shape {E.shape}")
    label = "all points"
    if area is not None:
        names = np.asarray(areas, dtype=object).ravel() if areas is not None else np.full(len(E), "", dtype=object)
        if names.shape != (len(E),):
            raise InputError(f"{where}: {names.size} area names for {len(E)} points")
        if not (names == area).any():
            raise InputError(f"{where}: no point in area {area!r}")
        E, label = E[names == area], f"area {area}"
    grid = E.mean(axis=0, dtype=np.float64).reshape(365, 24).T
    if not np.isfinite(grid).all():
        raise InputError(f"{where}: illuminance must be finite")
    return grid, label, len(E)


def _daily_span(occ: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(365,) start and end [h] of each day's occupied hours (first occupied row's start,
    last occupied row's end; NaN for a day without any)."""
    on = occ > 0.0
    any_ = on.any(axis=1)
    first = np.where(any_, np.argmax(on, axis=1), np.nan).astype(float)
    last = np.where(any_, 24 - np.argmax(on[:, ::-1], axis=1), np.nan).astype(float)
    return first, last

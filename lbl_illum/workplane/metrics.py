"""Figures of a grid of results: mean, extremes, uniformity and threshold shares.

For values E_1 … E_n at the points of an area (illuminance [lux] or daylight factor [%]):

==================  ===============================  ================================
key                 value                            note
==================  ===============================  ================================
``points``          n
``mean``            Ē = (1/n) Σ E_i                  arithmetic mean over the points
``min``, ``max``    E_min, E_max
``uniformity``      U₀ = E_min / Ē                   EN 12464-1:2011 §4.4; None if Ē = 0
``min_max``         E_min / E_max                    "diversity"; None if E_max = 0
``at_or_above``     {t: share of points E_i ≥ t}     0 … 1, one entry per threshold
==================  ===============================  ================================

The mean is the plain mean over the points, which is the area-weighted mean when the
points sit at the centres of equal cells (the grids of :mod:`lbl_illum.workplane.grid`).

Pure numpy: no scene, no files.  Non-finite values are refused (``ValueError``).

The daylight factor is DF = 100 · E / E_h [%], with E_h the illuminance on an
unobstructed horizontal plane from the sky alone (CIE 1970, *Daylight*, CIE 16;
EN 17037:2018 §3).  :func:`unobstructed_horizontal_illuminance` computes E_h from any
sky model by integrating its luminance over the upper hemisphere rather than taking
the value the sky was scaled to, so a model and its stated E_h are checked against each
other on every run.

References: EN 12464-1:2011 *Light and lighting — Lighting of work places — Part 1:
Indoor work places*, §4.4 (uniformity U₀ = E_min / Ē on the calculation grid);
EN 17037:2018 *Daylight in buildings*, Annex A (share of the area reaching a target
daylight factor or illuminance).
"""

from __future__ import annotations

from typing import Iterable, Sequence

import numpy as np

__all__ = ["area_figures", "grid_summary", "readable", "summary_line", "threshold_key", "unobstructed_horizontal_illuminance",
           "daylight_factor", "SKY_QUADRATURE"]

#: Nodes of the hemisphere quadrature of :func:`unobstructed_horizontal_illuminance`:
#: Gauss–Legendre in sin(altitude), midpoint rule in azimuth.
SKY_QUADRATURE = (64, 128)


def unobstructed_horizontal_illuminance(luminance, nodes: tuple[int, int] = SKY_QUADRATURE) -> float:
    """E_h = ∫ L(ω) cos θ dω over the upper hemisphere [lux], θ the zenith angle.

    luminance : callable taking (n, 3) unit directions (+z up) and returning (n,)
    photometric luminance [cd/m²].  With μ = cos θ = sin(altitude) and azimuth φ,
    E_h = ∫_0^{2π} ∫_0^1 L(μ, φ) μ dμ dφ, computed with ``nodes[0]`` Gauss–Legendre nodes
    in μ and ``nodes[1]`` equal steps in φ (exact for luminances polynomial in μ up to
    degree 2·nodes[0] − 2 and for trigonometric polynomials in φ of degree below
    nodes[1]: the CIE overcast sky, E_h = 7π L_z / 9, comes out to round-off).
    """
    m, n = nodes
    x, w = np.polynomial.legendre.leggauss(m)
    mu, w = 0.5 * (x + 1.0), 0.5 * w
    phi = 2.0 * np.pi * (np.arange(n) + 0.5) / n
    r = np.sqrt(1.0 - mu * mu)
    dirs = np.stack(np.broadcast_arrays(r[:, None] * np.cos(phi), r[:, None] * np.sin(phi), mu[:, None]),
                    axis=-1).reshape(-1, 3)
    L = np.asarray(luminance(dirs), dtype=np.float64).reshape(m, n)
    return float(np.sum(w[:, None] * mu[:, None] * L) * (2.0 * np.pi / n))


def daylight_factor(illuminance, horizontal_illuminance: float) -> np.ndarray:
    """DF = 100 · E / E_h [%] for (n,) illuminances E [lux] and E_h [lux] > 0."""
    if not np.isfinite(horizontal_illuminance) or horizontal_illuminance <= 0.0:
        raise ValueError(f"the unobstructed horizontal illuminance must be > 0, got {horizontal_illuminance!r}")
    return 100.0 * np.asarray(illuminance, dtype=np.float64) / float(horizontal_illuminance)


def threshold_key(t: float) -> str:
    """The JSON key of a threshold: ``300`` → ``"300"``, ``2.5`` → ``"2.5"``."""
    return f"{float(t):g}"


def area_figures(values: Sequence[float] | np.ndarray, thresholds: Iterable[float] = ()) -> dict:
    """The figures of one set of values (see the module docstring), as a JSON-ready dict.

    values : (n,) finite numbers, n ≥ 1 (any unit; the figures keep it)
    thresholds : values t for the shares of points at or above t
    """
    v = np.asarray(values, dtype=np.float64).ravel()
    if v.size == 0:
        raise ValueError("no values to summarise")
    if not np.isfinite(v).all():
        raise ValueError(f"{int((~np.isfinite(v)).sum())} values are not finite")
    mean, lo, hi = float(v.mean()), float(v.min()), float(v.max())
    return {
        "points": int(v.size),
        "mean": mean,
        "min": lo,
        "max": hi,
        "uniformity": lo / mean if mean > 0.0 else None,
        "min_max": lo / hi if hi > 0.0 else None,
        "at_or_above": {threshold_key(t): float(np.mean(v >= float(t))) for t in thresholds},
    }


def grid_summary(values, thresholds: Iterable[float] = (), areas=None, quantity: str = "illuminance",
                 unit: str = "lux") -> dict:
    """Figures over all points (``overall``) and per named area (``areas``).

    values : (n,) finite numbers;  areas : (n,) area names or None.  Points with the
    empty name belong to no named area; ``areas`` is empty when no point has a name.
    """
    v = np.asarray(values, dtype=np.float64).ravel()
    thresholds = [float(t) for t in thresholds]
    if not all(np.isfinite(thresholds)):
        raise ValueError("thresholds must be finite")
    doc = {"quantity": quantity, "unit": unit, "thresholds": thresholds,
           "overall": area_figures(v, thresholds), "areas": {}}
    if areas is not None:
        names = np.asarray(areas, dtype=object).ravel()
        if names.shape != v.shape:
            raise ValueError(f"{names.size} area names for {v.size} values")
        for name in dict.fromkeys(names.tolist()):
            if name:
                doc["areas"][name] = area_figures(v[names == name], thresholds)
    return doc


def _g(x) -> str:
    return "-" if x is None else f"{x:.3g}"


def readable(x: float) -> str:
    """A value as a person reads it in a summary: whole and grouped by thousands from
    1,000 up (``10,930``, not ``1.093e+04``), four significant digits below (``424.2``,
    ``0.0423``)."""
    x = float(x)
    if abs(x) >= 999.5 and abs(x) < 1e15:
        return f"{x:,.0f}"
    return f"{x:.4g}"


def summary_line(doc: dict, extremes: bool = True) -> str:
    """One line of the overall figures, e.g.
    ``mean 512 lux, min 120, max 2400, U0 0.234, min/max 0.05, >=300 lux 62%``
    (without the first three when ``extremes`` is False)."""
    o, unit = doc["overall"], doc["unit"]
    sep = "" if unit == "%" else " "
    parts = [f"mean {readable(o['mean'])}{sep}{unit}", f"min {readable(o['min'])}",
             f"max {readable(o['max'])}"] if extremes else []
    parts += [f"U0 {_g(o['uniformity'])}", f"min/max {_g(o['min_max'])}"]
    parts += [f">={key}{sep}{unit} {100.0 * share:.0f}%" for key, share in o["at_or_above"].items()]
    return ", ".join(parts)

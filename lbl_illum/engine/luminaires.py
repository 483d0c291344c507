"""Direct illuminance from luminaires described by photometric files.

A luminaire whose file gives no luminous opening is a point source at its photometric
centre p with intensity I(ω) [cd] from its file (:mod:`lbl_illum.scene.photometric`): a
receiver at x of unit normal n gets

    E = I(u) · max(0, n · (−u)) / d² · T(x → p),   u = (x − p)/d,  d = |x − p|,

the inverse-square law with Lambert's cosine (IES Lighting Handbook, 10th ed., ch. 6,
"point method"), T the transmittance of the segment (0 behind an opaque surface, the
panes' τ(θ) through glass; :meth:`lbl_illum.engine.direct.DirectLight.transmittance`).
One shadow ray per receiver and luminaire gives it exactly: nothing is sampled, so there
is no noise.  The same holds at every hit of the indirect calculation, which is how a
luminaire's light feeds the cache.

A luminaire with a luminous opening (a rectangle, a disk, a box or a cylinder) is the same
point source for receivers far from it (beyond 8 times the opening's largest size for a
flat opening, 100 times for a box or a cylinder, whose faces lie off the photometric
centre); nearer, it is a set of cells over the opening, cell j a point source of
intensity I(ω) a_j(ω)/A_p(ω) at its centre with a shadow ray of its own, the same sum
over cells (:mod:`lbl_illum.engine.luminous_openings`; docs/luminaires.md gives the
accuracy: within 1 % of the configuration-factor closed forms from one opening size
away).  A spherical opening stays a point.

Units: lengths [m], intensity [cd], illuminance [lux].
"""

from __future__ import annotations

import numpy as np

from .luminous_openings import LuminousOpenings, cell_counts, opening_cells

__all__ = ["LuminaireLight", "MAX_PAIRS", "NEAR_DISTANCE", "NEAR_SHARE"]

#: Most receiver × luminaire pairs evaluated at once (memory: about 100 bytes each).
MAX_PAIRS = 1 << 21
#: A luminaire whose light meets a surface nearer than this [m] ...
NEAR_DISTANCE = 0.25
#: ... for more than this share of its flux is reported (inside a wall or a ceiling?).
NEAR_SHARE = 0.5
#: Directions (a spiral over the sphere) the check traces per luminaire.
CHECK_RAYS = 4096


class LuminaireLight:
    """The scene's luminaires as sources of direct light: points, or cells over their
    luminous openings near them (module text); ``openings`` the openings that camera rays
    and specular paths see (None when every luminaire is a point)."""

    def __init__(self, luminaires):
        self.luminaires = list(luminaires)
        self.positions = np.array([lum.position for lum in self.luminaires], np.float64).reshape(-1, 3)
        self._shares = None
        #: the luminous openings seen by camera rays and specular paths (None: all points)
        self.openings = LuminousOpenings(self.luminaires)
        if self.openings.empty:
            self.openings = None

    def __len__(self) -> int:
        return len(self.luminaires)

    def blocked_shares(self, tracer) -> np.ndarray:
        """Per luminaire, the share of its flux whose first surface is nearer than
        :data:`NEAR_DISTANCE`: :data:`CHECK_RAYS` directions spread evenly over the sphere
        (a Fibonacci spiral), each weighted by the intensity along it; computed once."""
        if self._shares is not None:
            return self._shares
        k = np.arange(CHECK_RAYS) + 0.5
        z = 1.0 - 2.0 * k / CHECK_RAYS
        phi = np.pi * (1.0 + 5.0 ** 0.5) * k
        r = np.sqrt(1.0 - z * z)
        d = np.column_stack([r * np.cos(phi), r * np.sin(phi), z])
        shares = np.zeros(len(self.luminaires))
        for i, lum in enumerate(self.luminaires):
            I = lum.intensity(d)
            total = I.sum()
            if total <= 0.0:
                continue
            hits = tracer.intersect(np.repeat(lum.position[None], CHECK_RAYS, axis=0), d)
            shares[i] = I[hits.t < NEAR_DISTANCE].sum() / total
        self._shares = shares
        return shares

    def notes(self, tracer, units_scale: float = 1.0, units: str = "m") -> list[str]:
        """A note per luminaire most of whose light meets a surface at once (module text)."""
        out = []
        for lum, share in zip(self.luminaires, self.blocked_shares(tracer)):
            if share > NEAR_SHARE:
                at = ", ".join(f"{x / units_scale:g}" for x in lum.position)
                out.append(f"luminaire '{lum.name}' ({lum.photometry.name}) at ({at}) {units}: {100 * share:.0f} % "
                           f"of its light meets a surface within {NEAR_DISTANCE / units_scale:g} {units}; "
                           "is it inside a wall or a ceiling, or aimed into one?")
        return out

    def illuminance(self, points, normals, origins, transmittance) -> np.ndarray:
        """(n, 3) direct illuminance [lux] at ``points`` (normals ``normals``), shadow rays
        from ``origins`` (module text): one per luminaire, or one per cell of its opening
        for the receivers near it.  White light: the three channels are equal."""
        points = np.asarray(points, np.float64)
        n = len(points)
        E = np.zeros((n, 3))
        if n == 0 or not self.luminaires:
            return E
        block = max(1, MAX_PAIRS // len(self.luminaires))
        for lo in range(0, n, block):
            sl = slice(lo, lo + block)
            E[sl] = self._block(points[sl], np.asarray(normals[sl], np.float64),
                                np.asarray(origins[sl], np.float64), transmittance)
        return E

    def _block(self, points, normals, origins, transmittance):
        n = len(points)
        E = np.zeros((n, 3))
        pending = _Pending(E, origins, transmittance)
        for lum in self.luminaires:
            opening = lum.photometry.opening
            k = cell_counts(opening, (points - lum.position) @ lum.frame.T) if opening.shape != "point" else None
            if k is None or not np.any(k):
                pending.add(None, _pairs(lum.position, points, normals, origins, lambda e, rows: lum.intensity(e)))
                continue
            far = np.flatnonzero(k == 0)
            pending.add(far, _pairs(lum.position, points[far], normals[far], origins[far],
                                    lambda e, rows: lum.intensity(e)))
            for kk in np.unique(k[k > 0]):
                cells = opening_cells(opening, int(kk))
                m = len(cells)
                sources = lum.position + cells.centres @ lum.frame
                near = np.flatnonzero(k == kk)
                step = max(1, MAX_PAIRS // (2 * m))
                for lo in range(0, len(near), step):
                    rows = np.repeat(near[lo:lo + step], m)
                    j = np.tile(np.arange(m), len(rows) // m)

                    def emit(e, sel, j=j, cells=cells):
                        return lum.intensity(e) * cells.shares(opening, j[sel], e @ lum.frame.T)

                    pending.add(rows, _pairs(sources[j], points[rows], normals[rows], origins[rows], emit))
        pending.flush()
        return E


def _pairs(sources, points, normals, origins, emit):
    """Receivers (``points``, ``normals``, shadow rays from ``origins``) × point sources at
    ``sources`` ((3,) one for all, or (n, 3) one each): ``(rows, directions, lengths, g)``
    of the pairs that may be lit — g = emit(e, rows) · cos θ_r / d² [lux] (before the
    shadow ray), e the unit emission directions, and the shadow rays toward the source,
    stopped just short of it — or None."""
    w = sources - points
    d2 = np.einsum("ij,ij->i", w, w)
    ok = d2 > 0.0
    d = np.sqrt(np.where(ok, d2, 1.0))
    u = w / d[:, None]                                  # toward the source
    cos_r = np.einsum("ij,ij->i", normals, u)
    keep = np.flatnonzero(ok & (cos_r > 0.0))
    if len(keep) == 0:
        return None
    g = emit(-u[keep], keep) * cos_r[keep] / d2[keep]
    lit = g > 0.0
    keep, g = keep[lit], g[lit]
    if len(keep) == 0:
        return None
    ray = (sources if sources.ndim == 1 else sources[keep]) - origins[keep]
    length = np.linalg.norm(ray, axis=1)
    good = length > 0.0
    keep, g, ray, length = keep[good], g[good], ray[good], length[good]
    return keep, ray / length[:, None], length * (1.0 - 1e-6) - 1e-9, g


class _Pending:
    """Pairs gathered for one batch of shadow rays, traced when :data:`MAX_PAIRS` are
    waiting and at the end; their light is added to E [lux]."""

    def __init__(self, E, origins, transmittance):
        self.E, self.origins, self.transmittance = E, origins, transmittance
        self.parts, self.count = [], 0

    def add(self, rows, pairs) -> None:
        """``pairs`` from :func:`_pairs` for the receivers ``rows`` (None: all of them)."""
        if pairs is None:
            return
        keep, dirs, lengths, g = pairs
        self.parts.append((keep if rows is None else rows[keep], dirs, lengths, g))
        self.count += len(keep)
        if self.count >= MAX_PAIRS:
            self.flush()

    def flush(self) -> None:
        if not self.parts:
            return
        owner, dirs, lengths, g = (np.concatenate(x) for x in zip(*self.parts))
        self.parts, self.count = [], 0
        T = self.transmittance(self.origins[owner], dirs, lengths)
        for c in range(3):
            self.E[:, c] += np.bincount(owner, g * T[:, c], minlength=len(self.E))

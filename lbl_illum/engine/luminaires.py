"""Direct illuminance from luminaires described by photometric files.

A luminaire is a point source at its photometric centre p with intensity I(ω) [cd] from
its file (:mod:`lbl_illum.scene.photometric`): a receiver at x of unit normal n gets

    E = I(u) · max(0, n · (−u)) / d² · T(x → p),   u = (x − p)/d,  d = |x − p|,

the inverse-square law with Lambert's cosine (IES Lighting Handbook, 10th ed., ch. 6,
"point method"), T the transmittance of the segment (0 behind an opaque surface, the
panes' τ(θ) through glass; :meth:`lbl_illum.engine.direct.DirectLight.transmittance`).
One shadow ray per receiver and luminaire gives it exactly: nothing is sampled, so there
is no noise.  The same holds at every hit of the indirect calculation, which is how a
luminaire's light feeds the cache.  The far-field law holds where d is several times the
luminous opening's size (5 times for an error of about 1 % on a disk, IES LM-63's
"five times rule"); nearer, see docs/luminaires.md.

Units: lengths [m], intensity [cd], illuminance [lux].
"""

from __future__ import annotations

import numpy as np

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
    """The scene's luminaires as point sources of direct light (module text)."""

    def __init__(self, luminaires):
        self.luminaires = list(luminaires)
        self.positions = np.array([lum.position for lum in self.luminaires], np.float64).reshape(-1, 3)
        self._shares = None

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
        from ``origins`` (module text).  White light: the three channels are equal."""
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
        owner, dirs, lengths, values = [], [], [], []
        for lum in self.luminaires:
            w = lum.position - points
            d2 = np.einsum("ij,ij->i", w, w)
            ok = d2 > 0.0
            d = np.sqrt(np.where(ok, d2, 1.0))
            u = w / d[:, None]                                  # toward the luminaire
            cos_r = np.einsum("ij,ij->i", normals, u)
            keep = np.flatnonzero(ok & (cos_r > 0.0))
            if len(keep) == 0:
                continue
            g = lum.intensity(-u[keep]) * cos_r[keep] / d2[keep]
            lit = g > 0.0
            keep, g = keep[lit], g[lit]
            if len(keep) == 0:
                continue
            ray = lum.position - origins[keep]
            length = np.linalg.norm(ray, axis=1)
            good = length > 0.0
            keep, g, ray, length = keep[good], g[good], ray[good], length[good]
            owner.append(keep)
            dirs.append(ray / length[:, None])
            lengths.append(length * (1.0 - 1e-6) - 1e-9)
            values.append(g)
        E = np.zeros((n, 3))
        if not owner:
            return E
        owner = np.concatenate(owner)
        T = transmittance(origins[owner], np.concatenate(dirs), np.concatenate(lengths))
        g = np.concatenate(values)
        for c in range(3):
            E[:, c] = np.bincount(owner, g * T[:, c], minlength=n)
        return E

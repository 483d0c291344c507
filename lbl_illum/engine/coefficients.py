"""Daylight coefficients carried by the irradiance cache's records (DAYSIM's idea on the
paper's cache: Reinhart & Walkenhorst 2001; Tregenza & Waters 1983 for the coefficients).

Every record of every diffuse level holds, besides its irradiance under the sky that
placed it, a vector D_i of coefficients: the irradiance [lux] it receives per unit of
each source, through every bounce below it.  The sources are

* the sky patches p of a Tregenza/Reinhart sky of subdivision MF (row 0 the ground glow,
  :func:`lbl_illum.daylight.skymatrix.sky_patches`), per unit luminance [cd/m²];
* J sun positions (unit vectors, the caller's: :func:`lbl_illum.engine.annual.sun_positions`),
  per unit direct normal illuminance [lux], for the sun's *interreflected* light only (its
  direct light at the sensors is computed exactly for each hour,
  :mod:`lbl_illum.engine.sun_hours`).

For an hour with patch luminances L and the sun shared among the sun positions around
it (weights s), E = D_sky · L + D_sun · s E_dn.

**How a record's vector is made** — the same rays as its irradiance (Eq. 2), in the same
order, so that the vectors and the irradiance are one calculation:

* a hemisphere ray or portal sample that reaches the sky in direction ω with
  throughput t (glass crossed, MIS weight) adds π/S · t to the coefficient of the patch
  containing ω (the ground patch below the horizon);
* a ray that ends at a diffuse hit h with weight w_h (throughput · ρ/π · MIS) adds
  π/S · w_h · E_h, where E_h is the vector of the light arriving at h: the next level's
  vectors interpolated at h with the paper's weights (Eq. 5, the records the irradiance
  lookup uses, without the gradient terms: they are estimated for one sky only) plus the
  direct sun at h by a shadow ray per hit and sun position.  Inside the building only
  the rays through the portals are traced (:meth:`CoefficientRecords.sun_at`); below the
  sensors' records, :data:`SUN_HITS` of each record's hits are, by systematic sampling
  along its rays, weighted by the inverse of their chance (unbiased).  Interpolating the
  direct sun from the next level's records instead read 15–40 % high at the hits: the
  gradient limit makes sunlit records large and shaded ones small, so the sunlit domains
  reach into the shade.

Linear algebra does the rest: the coefficients of the deepest level first, each level's
from the one below (the paper's §3.4 order).  Electric light, the ``ambient`` value and
the sun's specular images are not daylight coefficients and are left out.

Channels: one when every material is grey (its red, green and blue equal), else three
(the sky's and sun's light are white; a coloured surface reflects each channel apart).
Each vector is stored as float32 (channels, sources): 884 bytes a record for the
Tregenza sky and 75 sun positions at one channel.
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

from ..daylight.skymatrix import patch_index, sky_patches
from ..photometry import luminance_weights
from .compiled import RowKernel
from .sun_hours import sun_visibility

__all__ = ["CoefficientRecords", "grey_scene"]

#: Records a lookup keeps per query (the largest weights if more serve it).
PAIRS = 16
#: Hits whose next-level records, or whose direct sun, are found at a time (bounds the
#: temporaries: 128 bytes a hit for the records, about 30 per hit and sun for the sun).
HIT_BLOCK = 1 << 18
#: Hits per record whose direct sun is traced (systematic sampling of its rays): a
#: record of levels 1 and 2, of the levels below them (DEEP_SUN_HITS; their light reaches
#: the sensors after two reflections more), and a sensor's own record of level 0 — all of
#: its hits while the sensors' hits number at most SENSOR_SUN_BUDGET, else an equal share
#: of that budget and at least SENSOR_SUN_HITS.
SUN_HITS = 8
DEEP_SUN_HITS = 4
SENSOR_SUN_HITS = 128
SENSOR_SUN_BUDGET = 200_000
_TAG_SUN_HITS = 11
_TAG_PORTAL_CHECK = 12
#: Shadow rays per inside point towards suns whose rays cross no portal: a point that
#: sees the sky along one is traced towards every sun (:meth:`CoefficientRecords._probe`).
PORTAL_PROBES = 4
#: Slack of the ray–portal test, in the triangle's barycentric coordinates (conservative).
PORTAL_SLACK = 1e-6


def grey_scene(context) -> bool:
    """Whether every material of the scene reflects and transmits its three channels alike."""
    m = context.materials
    arrays = [context.rho_over_pi, context.tau_over_pi, m.reflectance, m.transmittance]
    if m.transmissivity is not None:
        arrays.append(m.transmissivity)
    return all(np.allclose(a, a[:, :1], rtol=1e-9, atol=0.0) for a in arrays if len(a))


@njit(cache=True, nogil=True)
def _gather(owner, weight, pair_record, pair_weight, values, known):
    """known[owner[h], c, :] += weight[h, c] Σ_t pair_weight[h, t] values[pair_record[h, t], c, :]."""
    C = values.shape[1]
    K = values.shape[2]
    for h in range(owner.shape[0]):
        o = owner[h]
        for t in range(pair_record.shape[1]):
            j = pair_record[h, t]
            if j < 0:
                break
            for c in range(C):
                f = np.float32(pair_weight[h, t] * weight[h, c])
                if f == 0.0:
                    continue
                for p in range(K):
                    known[o, c, p] += f * values[j, c, p]


def _through_portals(origins, suns, cos, tri, out):
    """out[i, j] = cos[i, j] > 0 and the ray from origins[i] towards suns[j] crosses one of
    the (k, 3, 3) triangles ``tri`` (Möller & Trumbore 1997, edges grown by PORTAL_SLACK)."""
    for i in prange(origins.shape[0]):
        ox, oy, oz = origins[i, 0], origins[i, 1], origins[i, 2]
        for j in range(suns.shape[0]):
            found = 0
            if cos[i, j] > 0.0:
                dx, dy, dz = suns[j, 0], suns[j, 1], suns[j, 2]
                for k in range(tri.shape[0]):
                    e1x = tri[k, 1, 0] - tri[k, 0, 0]
                    e1y = tri[k, 1, 1] - tri[k, 0, 1]
                    e1z = tri[k, 1, 2] - tri[k, 0, 2]
                    e2x = tri[k, 2, 0] - tri[k, 0, 0]
                    e2y = tri[k, 2, 1] - tri[k, 0, 1]
                    e2z = tri[k, 2, 2] - tri[k, 0, 2]
                    px = dy * e2z - dz * e2y
                    py = dz * e2x - dx * e2z
                    pz = dx * e2y - dy * e2x
                    det = e1x * px + e1y * py + e1z * pz
                    if det == 0.0:
                        continue
                    inv = 1.0 / det
                    tx, ty, tz = ox - tri[k, 0, 0], oy - tri[k, 0, 1], oz - tri[k, 0, 2]
                    u = (tx * px + ty * py + tz * pz) * inv
                    if u < -PORTAL_SLACK or u > 1.0 + PORTAL_SLACK:
                        continue
                    qx = ty * e1z - tz * e1y
                    qy = tz * e1x - tx * e1z
                    qz = tx * e1y - ty * e1x
                    v = (dx * qx + dy * qy + dz * qz) * inv
                    if v < -PORTAL_SLACK or u + v > 1.0 + PORTAL_SLACK:
                        continue
                    if (e2x * qx + e2y * qy + e2z * qz) * inv > 0.0:
                        found = 1
                        break
            out[i, j] = found


_through_portals_kernel = RowKernel(_through_portals, rows=(0, 2, 4))


class CoefficientRecords:
    """The daylight-coefficient vectors of an integrator's records (module text).

    integrator : the :class:`~lbl_illum.engine.integrator.Integrator` whose records carry
        them (its cache must start empty); this sets ``integrator.coefficients``
    mf : sky subdivision (1: Tregenza)
    sun_directions : (J, 3) unit vectors of the sun positions (may be empty)
    """

    def __init__(self, integrator, mf: int = 1, sun_directions=None):
        self.integrator = integrator
        context = integrator.context
        self.context = context
        self.mf = int(mf)
        self.patches = len(sky_patches(self.mf))
        s = np.zeros((0, 3)) if sun_directions is None else np.asarray(sun_directions, np.float64).reshape(-1, 3)
        self.suns = s
        self.sources = self.patches + len(s)
        self.grey = grey_scene(context)
        self.channels = 1 if self.grey else 3
        levels = integrator.options.bounces + 1
        self.values = [np.zeros((0, self.channels, self.sources), np.float32) for _ in range(levels)]
        integrator.coefficients = self

    # -- bookkeeping ------------------------------------------------------------------
    def _channels(self, a):
        """(m, 3) per channel → (m, C) float32."""
        a = np.asarray(a)
        return (a[:, :1] if self.grey else a).astype(np.float32)

    def _grow(self, k, count):
        v = self.values[k]
        if len(v) < count:
            grown = np.zeros((max(count, 2 * len(v)), self.channels, self.sources), np.float32)
            grown[:len(v)] = v
            self.values[k] = grown

    def add_sky(self, pending, owner, directions, weight) -> None:
        """Rays of the records of ``pending`` that reached the sky: (e,) record (index into
        the concatenated records), (e, 3) direction, (e, 3) throughput times MIS weight."""
        if len(owner) == 0:
            return
        pending.sky_owner.append(np.asarray(owner, np.int64))
        pending.sky_patch.append(patch_index(directions, self.mf))
        pending.sky_weight.append(self._channels(weight))

    def pairs(self, k, P, Ns, own):
        """The records of level k serving points ``P`` (normals ``Ns``) and their weights
        (:meth:`~lbl_illum.engine.cache.LevelRecords.lookup_weights`); ``own`` (a level
        without interpolation): each point's own record."""
        if own is not None:
            return np.asarray(own, np.int32)[:, None], np.ones((len(own), 1), np.float32)
        lv = self.integrator.cache.levels[k]
        return lv.lookup_weights(P, Ns, zone=self.context.zone(P), pairs=PAIRS)

    def sun_at(self, points, normals, origins=None, inside=None) -> np.ndarray:
        """(n, C, J) float32 direct sun [lux per lux of direct normal illuminance] at
        points facing ``normals``, one shadow ray per point and sun position.

        Points ``inside`` ((n,) bool; default: cache zone 1, behind every portal plane) are
        traced only towards the suns whose rays cross a portal (:func:`_through_portals`)
        unless one of :data:`PORTAL_PROBES` rays towards other suns finds the sky (the
        cache's zone is a box: the ground just beside a building is in it)."""
        n, J = len(points), len(self.suns)
        if J == 0 or n == 0:
            return np.zeros((n, self.channels, J), np.float32)
        if origins is None:
            origins = self.context.tracer.sensor_origins(points, normals)
        pairs = None
        cos = normals @ self.suns.T
        if self.context.portal_set is not None:
            is_in = self.context.zone(points) == 1 if inside is None else np.asarray(inside, bool)
            inside = np.flatnonzero(is_in)
            if len(inside):
                through = np.empty((len(inside), J), np.uint8)
                tri = np.ascontiguousarray(self.context.portals.vertices, np.float64)
                _through_portals_kernel(np.ascontiguousarray(origins[inside]), self.suns, cos[inside], tri, through,
                                        work=len(inside) * J * len(tri))
                leaks = self._probe(origins[inside], cos[inside], through)
                filtered = inside[~leaks]
                trace = cos > 0.0
                trace[filtered] &= through[~leaks].astype(bool)
                pairs = np.nonzero(trace)
        v = sun_visibility(self.context.direct, self.context.tracer, points, normals, self.suns,
                           origins=origins, rgb=not self.grey, pairs=pairs)
        return v if not self.grey else v[:, None, :]

    def _probe(self, origins, cos, through) -> np.ndarray:
        """(m,) bool: which points see the sun other than through the portals, by
        :data:`PORTAL_PROBES` shadow rays each towards suns facing them whose rays cross
        no portal, drawn at random.  A point that sees a share f of those suns is missed
        with chance (1 − f)^PORTAL_PROBES (f = 1/2, a wall's outer face: 1 in 256)."""
        other = (cos > 0.0) & (through == 0)
        count = other.sum(axis=1)
        rows = np.flatnonzero(count > 0)
        if len(rows) == 0:
            return np.zeros(len(origins), bool)
        rng = self.integrator._rng(_TAG_PORTAL_CHECK, len(origins))
        rank = np.cumsum(other[rows], axis=1)                            # 1… count along each row
        pick = np.floor(rng.random((len(rows), PORTAL_PROBES)) * count[rows, None]).astype(np.int64) + 1
        sun = np.stack([np.argmax(rank >= pick[:, t, None], axis=1) for t in range(PORTAL_PROBES)], axis=1)
        point = np.repeat(rows, PORTAL_PROBES)
        T = self.context.direct.transmittance(origins[point], self.suns[sun.ravel()])
        leaks = np.zeros(len(origins), bool)
        leaks[point[T.max(axis=1) > 0.0]] = True
        return leaks

    # -- evaluation -------------------------------------------------------------------
    def evaluate(self, k, records, S, pending) -> None:
        """Give the records ``records`` of level k, with ``S`` hemisphere rays each, their
        vectors (module text), after their irradiance (:meth:`Integrator.evaluate_level`)."""
        r = len(records)
        C, K, P = self.channels, self.sources, self.patches
        known = np.zeros((r, C, K), np.float32)
        if pending.sky_owner:
            owner = np.concatenate(pending.sky_owner)
            key = owner * P + np.concatenate(pending.sky_patch)
            weight = np.concatenate(pending.sky_weight)
            for c in range(C):
                known[:, c, :P] += np.bincount(key, weight[:, c], minlength=r * P).reshape(r, P)
        B = self.integrator.options.bounces
        if k < B and pending.hit_owner:
            owner = pending.cat("hit_owner", width=0, dtype=np.int32)
            weight = self._channels(pending.cat("hit_weight", dtype=np.float32))
            if len(owner) and len(self.suns):
                self._add_sun(k, owner, weight, pending, known, records)
            if len(owner) and pending.next_solved:
                hP = pending.cat("hit_P")
                hNs = pending.cat("hit_Ns", dtype=np.float32)
                own = pending.next_own
                for lo in range(0, len(owner), HIT_BLOCK):       # the pairs of a block at a time
                    part = slice(lo, lo + HIT_BLOCK)
                    record, w = self.pairs(k + 1, hP[part], hNs[part].astype(np.float64),
                                           None if own is None else own[part])
                    _gather(owner[part], weight[part], record, w, self.values[k + 1], known)
        known *= (np.pi / np.asarray(S, np.float64))[:, None, None].astype(np.float32)
        lv = self.integrator.cache.levels[k]
        self._grow(k, lv.count)
        self.values[k][records] = known

    def _add_sun(self, k, owner, weight, pending, known, records) -> None:
        """known[owner, :, sun j] += weight · (direct sun at the hit from sun j), by a
        shadow ray per hit and sun position: for every hit of the sensors' own records
        (within :data:`SENSOR_SUN_BUDGET`), below them for :data:`SUN_HITS` or
        :data:`DEEP_SUN_HITS` hits per record by systematic sampling, each weighted by the
        inverse of its chance (module text); :data:`HIT_BLOCK` / (J / 8) hits at a time."""
        P_ = self.patches
        chosen = np.arange(len(owner))
        scale = np.ones(len(owner), np.float32)
        limit = SUN_HITS if k <= 2 else DEEP_SUN_HITS
        if k == 0:
            limit = 0 if len(owner) <= SENSOR_SUN_BUDGET else max(SENSOR_SUN_HITS, SENSOR_SUN_BUDGET // len(records))
        if limit:
            # systematic sampling of each record's hits in ray order (its hemisphere's
            # strata): hit r of n is taken when floor(r q + u) steps, q = min(1, SUN_HITS/n)
            order = np.argsort(owner, kind="stable")
            counts = np.bincount(owner)
            start = np.concatenate([[0], np.cumsum(counts)[:-1]])
            rank = np.empty(len(owner), np.int64)
            rank[order] = np.arange(len(owner)) - start[owner[order]]
            q = np.minimum(1.0, limit / counts[owner])
            rng = self.integrator._rng(_TAG_SUN_HITS, k, int(owner.min()), len(owner))
            u = rng.random(len(counts))[owner]
            chosen = np.flatnonzero(np.floor((rank + 1) * q + u) > np.floor(rank * q + u))
            scale = (1.0 / q[chosen]).astype(np.float32)
        hP = pending.cat("hit_P")
        hNs = pending.cat("hit_Ns", dtype=np.float32)
        hNg = pending.cat("hit_Ng", dtype=np.float32)
        zone = self.integrator.cache.levels[k].zone[records] if self.context.portal_set is not None else None
        block = max(1, HIT_BLOCK // max(1, len(self.suns) // 8))
        for lo in range(0, len(chosen), block):
            pick = chosen[lo:lo + block]
            P, Ns, Ng = hP[pick], hNs[pick].astype(np.float64), hNg[pick].astype(np.float64)
            # inside: a hit of the inside zone from a record of the inside (the outer face of a
            # wall in a window's plane is in the zone, but only rays from outside reach it)
            inside = None if zone is None else (self.context.zone(P) == 1) & (zone[owner[pick]] == 1)
            sun = self.sun_at(P, Ns, self.context.tracer.offset(P, Ng), inside)     # (h, C, J)
            lit = np.flatnonzero(sun.max(axis=(1, 2)) > 0.0)
            w = weight[pick[lit]] * scale[lo:lo + block][lit, None]
            for c in range(self.channels):
                np.add.at(known[:, c, P_:], owner[pick[lit]], sun[lit, c, :] * w[:, c, None])

    def at_points(self, points, normals, own) -> np.ndarray:
        """(n, C, K) vectors of level 0 at the sensors (``own``: their own records)."""
        record, w = self.pairs(0, points, normals, own)
        known = np.zeros((len(points), self.channels, self.sources), np.float32)
        ones = np.ones((len(points), self.channels), np.float32)
        _gather(np.arange(len(points), dtype=np.int32), ones, record, w, self.values[0], known)
        return known

    def photometric(self, vectors) -> np.ndarray:
        """(n, K) photometric coefficients of (n, C, K) vectors: Y of the channels."""
        if self.grey:
            return vectors[:, 0, :]
        return np.einsum("c,nck->nk", luminance_weights().astype(np.float32), vectors)

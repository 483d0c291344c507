"""The irradiance cache: one record set per diffuse level (§3.4), each with its octree (§3.3).

A record holds a primary evaluation of the indirect irradiance (Eq. 2): position
P_i [m], unit normal N_i, irradiance E_i (RGB, photometric channels) [lux] and
R_i [m], the harmonic mean distance of its hemisphere rays (Eq. 4) clamped to the
spacing limits.  Level k holds the values that serve queries made after k diffuse
reflections; a value computed after k bounces never stands in for one after fewer.

Records and octree nodes are growable structure-of-arrays buffers; the compiled
kernels of :mod:`lbl_illum.engine.octree` insert them, lay them out for lookups and look
them up.  A cache is plain data: it can be saved and loaded, and a lookup's answer
depends only on its query and the records, not on the other queries of the batch
or the number of threads.

The cache file format, its checks and merging live in :mod:`lbl_illum.io.cachefile`;
:meth:`IrradianceCache.save` and :meth:`IrradianceCache.load` go through it.
"""

from __future__ import annotations

import os

import numpy as np

from . import octree
from .compiled import kernel_threads

__all__ = ["LevelRecords", "IrradianceCache"]


def _zones(zone, n: int) -> np.ndarray:
    """(n,) uint8 query zones (0 for all when ``zone`` is None)."""
    if zone is None:
        return np.zeros(n, np.uint8)
    return np.ascontiguousarray(zone, np.uint8).reshape(n)


class LevelRecords:
    """The records of one diffuse level and their octree.

    accuracy : the level's ``a`` (0: no interpolation, records answer only their own query)
    center, half : the root cube [m]
    capacity : records to allocate room for

    Record arrays, indexed by record and growable (rows past ``count`` are spare
    capacity): ``P`` (n, 3) float64 [m], ``N`` (n, 3) float32, ``R`` (n,) float32 [m],
    fixed once added; ``E`` (n, 3) float32 [lux], ``Gr`` (n, 3, 3) float32 [lux/rad],
    ``Gt`` (n, 3, 3) float32 [lux/m] and ``W`` (n, 3), writable views of one (n, 8, 3) block (write into
    them, or use :meth:`set_values`; the next lookup uses the new values); and
    ``leak`` (n,) uint32, the sectors in which a record may not be used (see
    :func:`lbl_illum.engine.hessian.leak_sectors`; ``W`` and ``leak`` are used only by an
    ``anisotropic`` level); ``zone`` (n,) uint8, the zone of each record (a record serves only
    queries of its own zone: inside the windows of a building, or not; see
    :meth:`lbl_illum.engine.portals.PortalSet.zone`); ``record_node`` (n,) int32, the octree node holding each record.  Octree nodes:
    ``node_center`` (m, 3) [m], ``node_half`` (m,) [m], ``node_child`` (m, 8) int32.
    Lookups use the :class:`octree.Layout` made by :meth:`freeze`, redone after insertions.

    Memory per record: 128 bytes in the record arrays (144 with elliptical domains), 44
    in the lookup layout (P, N, R in layout order and the permutation), about 3.4 for its
    boxes and 64 per octree node (a node per 12 to 40 records): about 190 (206) bytes, plus the spare capacity (arrays
    grow by half when full).  :meth:`nbytes` lists them.
    """

    #: Below this many queries a lookup runs on one thread: waking numba's thread pool
    #: costs milliseconds on a busy machine, about as long as 2,000 queries take.
    PARALLEL_MIN_QUERIES = 4096
    #: From this many queries on, they are visited in Morton order (in packets of
    #: neighbours, see :mod:`lbl_illum.engine.octree`); the sort costs about 20 ns a query.
    SORT_MIN_QUERIES = 1024

    def __init__(self, accuracy: float, center: np.ndarray, half: float, capacity: int = 1024,
                 anisotropic: bool = False):
        self.accuracy = float(accuracy)
        #: records have elliptical domains and leak sectors (``W``, ``leak``)
        self.anisotropic = bool(anisotropic)
        self.count = 0
        capacity = max(1, int(capacity))
        self.P = np.zeros((capacity, 3), np.float64)
        self.N = np.zeros((capacity, 3), np.float32)
        self.R = np.zeros(capacity, np.float32)
        # E, Gr (3 rows), Gt (3 rows) and, for elliptical domains, W per record
        self._values = np.zeros((capacity, 8 if anisotropic else 7, 3), np.float32)
        self.leak = np.zeros(capacity if anisotropic else 0, np.uint32)
        self.zone = np.zeros(capacity, np.uint8)
        self.record_node = np.full(capacity, -1, np.int32)
        self._tree_version = 0
        self._frozen = None
        self._reset_tree(np.asarray(center, np.float64), float(half), 64)

    # -- storage ---------------------------------------------------------------
    def _reset_tree(self, center, half, capacity):
        self.node_center = np.zeros((capacity, 3), np.float64)
        self.node_half = np.zeros(capacity, np.float64)
        self.node_child = np.full((capacity, 8), -1, np.int32)
        self.node_center[0] = center
        self.node_half[0] = half
        self.n_nodes = 1
        self._tree_version += 1
        self._frozen = None

    # E, Gr, Gt (and W) are views of one (capacity, 7 or 8, 3) block, so that a lookup reads
    # a record's value, gradients (and shape) from 84 (96) adjacent bytes
    @property
    def E(self) -> np.ndarray:
        """(capacity, 3) float32 irradiance [lux] (a writable view)."""
        return self._values[:, 0, :]

    @property
    def Gr(self) -> np.ndarray:
        """(capacity, 3, 3) float32 rotational gradient [lux/rad], one row per channel (a writable view)."""
        return self._values[:, 1:4, :]

    @property
    def Gt(self) -> np.ndarray:
        """(capacity, 3, 3) float32 translational gradient [lux/m], one row per channel (a writable view)."""
        return self._values[:, 4:7, :]

    @property
    def W(self) -> np.ndarray:
        """(capacity, 3) float32 shape vector of an elliptical domain [1] (a writable view).

        Along the short axis u (unit, tangent) with radii R_s ≤ R: W = u sqrt((R/R_s)² − 1),
        so that |P − P_i|²/R² + ((P − P_i)·W)²/R² is the squared elliptical distance
        (:func:`lbl_illum.engine.octree.lookup`); zero for a round domain.  Only an
        ``anisotropic`` level has it.
        """
        if not self.anisotropic:
            raise AttributeError("round record domains have no shape vector W")
        return self._values[:, 7, :]

    def _grow_records(self, needed):
        cap = len(self.R)
        if needed <= cap:
            return
        new = max(needed, cap + cap // 2)
        for name in ("P", "N", "R", "_values", "leak", "zone", "record_node"):
            old = getattr(self, name)
            if len(old) == 0:
                continue
            arr = np.zeros((new,) + old.shape[1:], old.dtype)
            arr[: self.count] = old[: self.count]
            setattr(self, name, arr)

    def _grow_nodes(self):
        cap = len(self.node_half)
        new = cap + cap // 2
        for name, fill in (("node_center", 0), ("node_half", 0), ("node_child", -1)):
            old = getattr(self, name)
            arr = np.full((new,) + old.shape[1:], fill, old.dtype)
            arr[:cap] = old
            setattr(self, name, arr)

    def _contains(self, points):
        c, h = self.node_center[0], self.node_half[0]
        return np.all(np.abs(points - c) <= h, axis=1)

    def _rebuild(self, center, half):
        """Re-insert every record under a new root cube."""
        self._reset_tree(center, half, max(64, self.n_nodes))
        self._insert(0, self.count)

    def _insert(self, start, stop):
        self._tree_version += 1
        self._frozen = None                   # the old layout is stale: free it now
        while start < stop:
            self.n_nodes, start = octree.insert_records(
                start, stop, self.P, self.R, self.accuracy if self.accuracy > 0 else 1.0, self.record_node,
                self.node_center, self.node_half, self.node_child, self.n_nodes)
            if start < stop:
                self._grow_nodes()

    def add(self, P, N, R, E=None, Gr=None, Gt=None, W=None, leak=None, zone=None) -> np.ndarray:
        """Append records (E and the gradients default to zero, to be set once evaluated;
        W and ``leak``, the domain's shape and leak sectors, to a round domain; ``zone`` to
        0); return their indices."""
        P = np.asarray(P, np.float64).reshape(-1, 3)
        k = len(P)
        start = self.count
        self._grow_records(start + k)
        self.P[start:start + k] = P
        self.N[start:start + k] = N
        self.R[start:start + k] = R
        self.E[start:start + k] = 0.0 if E is None else E
        self.Gr[start:start + k] = 0.0 if Gr is None else Gr
        self.Gt[start:start + k] = 0.0 if Gt is None else Gt
        if self.anisotropic:
            self.W[start:start + k] = 0.0 if W is None else W
            self.leak[start:start + k] = 0 if leak is None else leak
        self.zone[start:start + k] = 0 if zone is None else zone
        self.count = start + k
        if k and self.accuracy > 0:
            if not np.all(self._contains(P)):
                lo = np.minimum(self.P[: self.count].min(axis=0), self.node_center[0] - self.node_half[0])
                hi = np.maximum(self.P[: self.count].max(axis=0), self.node_center[0] + self.node_half[0])
                self._rebuild(0.5 * (lo + hi), 0.5 * float(np.max(hi - lo)) * 1.01 + 1e-9)
            else:
                self._insert(start, self.count)
        return np.arange(start, start + k)

    def set_values(self, indices, E, Gr=None, Gt=None) -> None:
        """Set the irradiance (and, if given, the gradients) of records ``indices``.

        The same as writing ``E[indices]``, ``Gr[indices]``, ``Gt[indices]``: lookups
        read the values through the layout's permutation, so no layout is rebuilt.
        """
        self.E[indices] = E
        if Gr is not None:
            self.Gr[indices] = Gr
        if Gt is not None:
            self.Gt[indices] = Gt

    def truncate(self, count: int, center=None, half=None) -> None:
        """Keep only the first ``count`` records (drop those added later, e.g. by a run that
        was interrupted before it evaluated them), with the octree rebuilt under the root
        cube (``center``, ``half``) [m] (default: the current one).  A record's octree node
        depends only on the root cube, its position and its radius, so the tree and the
        lookup layout become those the kept records had before the others came."""
        count = int(count)
        if count > self.count:
            raise ValueError(f"cannot truncate {self.count} records to {count}")
        center = self.node_center[0].copy() if center is None else np.asarray(center, np.float64)
        half = float(self.node_half[0]) if half is None else float(half)
        self.count = count
        self.record_node[:] = -1
        self._reset_tree(center, half, 64)
        if count and self.accuracy > 0:
            self._insert(0, count)

    # -- queries -----------------------------------------------------------------
    def lookup(self, P, N, gradients: bool = False, zone=None, taper: bool = False):
        """Interpolated irradiance at queries (Eq. 5); with ``gradients`` each record's
        value is first extrapolated to the query by its gradients (Ward & Heckbert 1992).
        ``zone`` (n,) uint8 (default 0): each query is served by the records of its zone.
        ``taper``: weights that fall to zero at the edge of each record's domain (for images;
        :func:`lbl_illum.engine.octree.lookup`).

        Returns ``(E, weight_sum, count)``: (n, 3) float64, (n,) float64, (n,) int32;
        ``count == 0`` marks a query no record covers.  Each answer depends only on its
        own query and the records, not on the other queries or the thread count.
        """
        P = np.ascontiguousarray(P, np.float64).reshape(-1, 3)
        N = np.ascontiguousarray(N, np.float64).reshape(-1, 3)
        n = len(P)
        out_E = np.zeros((n, 3))
        out_w = np.zeros(n)
        out_n = np.zeros(n, np.int32)
        if n and self.count and self.accuracy > 0:
            layout = self.freeze()
            if n >= self.SORT_MIN_QUERIES:
                order = octree.query_order(P, self.node_center[0], self.node_half[0])
            else:
                order = np.arange(n)
            parallel = n >= self.PARALLEL_MIN_QUERIES and kernel_threads() > 1
            octree.lookup(P, N, _zones(zone, n), order, layout, self._values, self.leak, gradients, self.anisotropic, self.accuracy,
                          out_E, out_w, out_n, parallel, taper)
        return out_E, out_w, out_n

    def lookup_weights(self, P, N, zone=None, taper: bool = False, pairs: int = 16):
        """The records that serve each query and their normalised weights (Eq. 5), for
        interpolating other values than E with the record set (the daylight coefficients
        of :mod:`lbl_illum.engine.coefficients`): ``(record, weight)``, (n, pairs) int32
        (-1 after the last) and float32 summing to 1 over a covered query's row (0 for a
        query no record covers).  A query that more than ``pairs`` records serve keeps the
        ones of largest weight (on the office example at ``draft`` a hit's lookup finds 2.3
        on average and 9 at most)."""
        P = np.ascontiguousarray(P, np.float64).reshape(-1, 3)
        N = np.ascontiguousarray(N, np.float64).reshape(-1, 3)
        n = len(P)
        record = np.full((n, pairs), -1, np.int32)
        weight = np.zeros((n, pairs))
        if n and self.count and self.accuracy > 0:
            layout = self.freeze()
            order = octree.query_order(P, self.node_center[0], self.node_half[0]) if n >= self.SORT_MIN_QUERIES \
                else np.arange(n)
            parallel = n >= self.PARALLEL_MIN_QUERIES and kernel_threads() > 1
            out_E, out_w, out_n = np.zeros((n, 3)), np.zeros(n), np.zeros(n, np.int32)
            octree.lookup(P, N, _zones(zone, n), order, layout, self._values, self.leak, False, self.anisotropic,
                          self.accuracy, out_E, out_w, out_n, parallel, taper, pairs=(record, weight))
        total = weight.sum(axis=1, keepdims=True)
        return record, (weight / np.where(total > 0.0, total, 1.0)).astype(np.float32)

    def covers(self, P, N, zone=None) -> np.ndarray:
        """(n,) bool: whether any record serves each query — ``lookup(P, N, zone=zone)[2] > 0``,
        found faster when most queries meet few records (:func:`octree.covered`)."""
        P = np.ascontiguousarray(P, np.float64).reshape(-1, 3)
        N = np.ascontiguousarray(N, np.float64).reshape(-1, 3)
        out = np.zeros(len(P), bool)
        if len(P) and self.count and self.accuracy > 0:
            parallel = len(P) >= self.PARALLEL_MIN_QUERIES and kernel_threads() > 1
            octree.covered(P, N, _zones(zone, len(P)), self.freeze(), self._values, self.leak, self.anisotropic, self.accuracy, out,
                           parallel)
        return out

    def freeze(self) -> octree.Layout:
        """The lookup layout of :func:`octree.freeze`, rebuilt only after insertions."""
        if self._frozen is None or self._frozen[0] != self._tree_version:
            self._frozen = None
            layout = octree.Layout(*octree.freeze(
                self.count, self.n_nodes, self.record_node, self.node_child, self.node_center, self.node_half,
                self.P, self.N, self.R, self.zone, self.accuracy))
            self._frozen = (self._tree_version, layout)
        return self._frozen[1]

    def nbytes(self) -> dict:
        """Bytes held per array (records, octree nodes, lookup layout), by name, counted
        as allocated (spare capacity included)."""
        out = {name: getattr(self, name).nbytes for name in
               ("P", "N", "R", "leak", "zone", "record_node", "node_center", "node_half", "node_child")}
        out["E, Gr, Gt, W"] = self._values.nbytes
        if self._frozen is not None:
            for name, arr in self._frozen[1]._asdict().items():
                if isinstance(arr, np.ndarray):
                    out[f"layout.{name}"] = arr.nbytes
        return out

    def arrays(self) -> dict:
        """Copies of the record arrays that a cache file holds (``count`` rows each)."""
        n = self.count
        names = ("P", "N", "E", "R", "Gr", "Gt", "zone") + (("W", "leak") if self.anisotropic else ())
        return {name: getattr(self, name)[:n].copy() for name in names}


class IrradianceCache:
    """Records of every diffuse level of one scene and one set of settings.

    fingerprint : identifies the scene and the settings the records depend on
    accuracies : ``a`` per level (``accuracies[k]``)
    center, half : octree root cube of new levels [m]
    settings : readable summary of what the fingerprint covers (:func:`record_settings`),
        written to the file's header; None if unknown
    """

    def __init__(self, fingerprint: str, accuracies, center, half, anisotropic: bool = False,
                 settings: dict | None = None):
        self.fingerprint = fingerprint
        self.center = np.asarray(center, np.float64)
        self.half = float(half)
        self.anisotropic = bool(anisotropic)
        self.settings = settings
        self.levels = [LevelRecords(a, self.center, self.half, anisotropic=anisotropic) for a in accuracies]

    @property
    def record_counts(self) -> list[int]:
        return [lv.count for lv in self.levels]

    # -- files (lbl_illum.io.cachefile) ---------------------------------------------------
    def to_data(self):
        """The file's contents: header and record arrays (:func:`lbl_illum.io.cachefile.cache_data`)."""
        from ..io.cachefile import cache_data

        return cache_data(self)

    @classmethod
    def from_data(cls, data) -> "IrradianceCache":
        """A cache holding the records of a file's contents (:func:`lbl_illum.io.cachefile.cache_from_data`)."""
        from ..io.cachefile import cache_from_data

        return cache_from_data(data)

    def save(self, path: str | os.PathLike, merge: bool = True) -> list[int]:
        """Write the cache to ``path``, merged with what the file holds
        (:func:`lbl_illum.io.cachefile.save_cache`); the records per level it now holds."""
        from ..io.cachefile import save_cache

        return save_cache(self, path, merge)

    @classmethod
    def load(cls, path: str | os.PathLike, fingerprint: str | None = None,
             settings: dict | None = None) -> "IrradianceCache":
        """Read a cache file (:func:`lbl_illum.io.cachefile.load_cache`)."""
        from ..io.cachefile import load_cache

        return load_cache(path, fingerprint, settings)

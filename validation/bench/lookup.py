"""Speed and size of the irradiance-cache lookups (``LevelRecords``), measured in one run.

What is measured, for N records of one level at accuracy ``a`` (default 0.15) in two
layouts and N = 10^3 ... 10^6:

* ``floor``: records on the unit square z = 0 with normals +z, queries on the same
  square (a floor of sensors);
* ``volume``: records in the unit cube with normals within 2° of +z, queries in the
  same cube with normals drawn the same way.

The radii are R = R0 · 2^u, u uniform in [-1/2, 1/2], with R0 scaled as N^(-1/d) so a
query finds about ``--hits`` records (Eqs. 5 and 6; the mean found is printed).
Records are inserted in batches of 10,000 in random spatial order (the worst case for
the layout of values indexed by record).  Queries are uniform and in random order.

Columns:

* ``insert/s``: records per second of ``LevelRecords.add`` (batches of 10,000);
* ``freeze s``: seconds to lay the tree out for lookups after the last insertion;
* ``B/rec``: bytes of every array the level holds (records, octree nodes, lookup
  layout) per record, counted as allocated (with the spare capacity the batches of
  insertion leave); the breakdown is printed for the largest N and is in the JSON;
* ``q/s 1t``, ``q/s 1t grad``: queries per second on one thread (``numba.set_num_threads(1)``),
  without and with gradients (Ward & Heckbert 1992), in one call of ``--queries``
  queries, timed by this process's CPU time (``time.process_time``: a shared machine
  that takes the core away does not count);
* ``q/s 2t``: the same on two threads, timed by the wall clock, and ``x2t`` its
  ratio to the one-thread rate timed by the wall clock back to back;
* ``q/s small``: queries per second in calls of 1,000 queries each (two threads),
  the size of many of the engine's lookups.

Speed is the best of ``--repeat`` runs after one untimed warm-up.  Absolute figures
depend on the machine and its load; compare runs made back to back.  The plot (with
``--out``) shows the seconds per query against N with a log N reference.

Usage (from the repository root)::

    python validation/bench/lookup.py [--sizes 1e3,1e4,1e5,1e6] [--queries 262144]
        [--accuracy 0.15] [--hits 20] [--repeat 5] [--out DIR]
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from pathlib import Path

import numba
import numpy as np

from lbl_illum.engine import LevelRecords
from lbl_illum.io import atomic_write_bytes, atomic_write_text

#: Records per ``add`` call while filling a level.
INSERT_BATCH = 10_000
#: Queries per call in the small-call measurement.
SMALL_CALL = 1_000
#: Half-angle of the cone of normals in the volumetric layout [rad].
CONE = math.radians(2.0)


def _cone_normals(rng, n):
    """Unit vectors uniform in solid angle within CONE of +z."""
    cos_t = 1.0 - rng.uniform(0.0, 1.0 - math.cos(CONE), n)
    sin_t = np.sqrt(1.0 - cos_t ** 2)
    phi = rng.uniform(0.0, 2.0 * math.pi, n)
    return np.column_stack([sin_t * np.cos(phi), sin_t * np.sin(phi), cos_t])


def make_case(kind, n, a, hits, n_queries, seed):
    """Records (P, N, R, E, Gr, Gt) and queries (qP, qN) of one layout."""
    rng = np.random.default_rng(seed)
    if kind == "floor":
        P = np.column_stack([rng.uniform(0, 1, (n, 2)), np.zeros(n)])
        N = np.tile([0.0, 0.0, 1.0], (n, 1))
        reach = math.sqrt(hits / (math.pi * n))                  # π (aR)² n = hits
        qP = np.column_stack([rng.uniform(0, 1, (n_queries, 2)), np.zeros(n_queries)])
        qN = np.tile([0.0, 0.0, 1.0], (n_queries, 1))
    else:
        P = rng.uniform(0, 1, (n, 3))
        N = _cone_normals(rng, n)
        reach = (2.0 * hits * 3.0 / (4.0 * math.pi * n)) ** (1 / 3)   # Eq. 6 rejects about half the sphere
        qP = rng.uniform(0, 1, (n_queries, 3))
        qN = _cone_normals(rng, n_queries)
    R = (reach / a) * 2.0 ** rng.uniform(-0.5, 0.5, n)
    E = rng.uniform(100.0, 1000.0, (n, 3))
    Gr = rng.normal(scale=20.0, size=(n, 3, 3))
    Gt = rng.normal(scale=1.0, size=(n, 3, 3)) * (100.0 / R[:, None, None])
    return (P, N.astype(np.float32), R.astype(np.float32), E.astype(np.float32), Gr.astype(np.float32),
            Gt.astype(np.float32)), (qP, qN)


def array_bytes(obj, seen=None) -> dict:
    """Bytes of the numpy arrays reachable from ``obj``'s attributes, by attribute name
    (each buffer counted once, views of a counted buffer not again)."""
    seen = set() if seen is None else seen
    out = {}

    def walk(name, value):
        if isinstance(value, np.ndarray):
            base = value
            while isinstance(base.base, np.ndarray):
                base = base.base
            if id(base) not in seen:
                seen.add(id(base))
                out[name] = out.get(name, 0) + base.nbytes
        elif isinstance(value, (tuple, list)):
            for i, v in enumerate(value):
                walk(f"{name}[{i}]", v)
        elif isinstance(value, dict):
            for k, v in value.items():
                walk(f"{name}.{k}", v)
        elif hasattr(value, "__dict__") and not isinstance(value, type) and not callable(value):
            for k, v in vars(value).items():
                walk(f"{name}.{k}", v)
        elif hasattr(value, "_fields"):
            for k in value._fields:
                walk(f"{name}.{k}", getattr(value, k))

    for key, value in vars(obj).items():
        walk(key, value)
    return out


def freeze(lv):
    """Lay the level out for lookups (the public method if there is one)."""
    if hasattr(lv, "freeze"):
        lv.freeze()
    else:                                           # layout of the first version
        lv._frozen_tree()


def rate(lv, qP, qN, gradients, threads, repeat, call=None, clock=time.perf_counter) -> float:
    """Queries per second of ``lv.lookup``: best of ``repeat`` after a warm-up, timed
    by ``clock`` (``time.process_time`` counts only this process's CPU time)."""
    numba.set_num_threads(threads)
    n = len(qP)
    call = call or n
    lv.lookup(qP[:min(n, 2 * SMALL_CALL)], qN[:min(n, 2 * SMALL_CALL)], gradients=gradients)
    best = math.inf
    for _ in range(repeat):
        t0 = clock()
        for s in range(0, n, call):
            lv.lookup(qP[s:s + call], qN[s:s + call], gradients=gradients)
        best = min(best, clock() - t0)
    return n / best


def run_case(kind, n, args, threads):
    records, (qP, qN) = make_case(kind, n, args.accuracy, args.hits, args.queries, args.seed)
    P, N, R, E, Gr, Gt = records
    lv = LevelRecords(args.accuracy, center=np.full(3, 0.5), half=0.5 * 1.01)
    t0 = time.perf_counter()
    for s in range(0, n, INSERT_BATCH):
        lv.add(P[s:s + INSERT_BATCH], N[s:s + INSERT_BATCH], R[s:s + INSERT_BATCH], E[s:s + INSERT_BATCH],
               Gr[s:s + INSERT_BATCH], Gt[s:s + INSERT_BATCH])
    t_insert = time.perf_counter() - t0
    t0 = time.perf_counter()
    freeze(lv)
    t_freeze = time.perf_counter() - t0
    _, _, count = lv.lookup(qP, qN)
    breakdown = lv.nbytes() if hasattr(lv, "nbytes") else array_bytes(lv)
    capacity = len(lv.R)
    row = {
        "layout": kind, "records": n, "capacity": capacity, "mean_hits": float(count.mean()),
        "covered": float(np.mean(count > 0)), "insert_per_s": n / t_insert, "freeze_s": t_freeze,
        "bytes_per_record": sum(breakdown.values()) / n, "bytes": breakdown,
        "qps_1t": rate(lv, qP, qN, False, 1, args.repeat, clock=time.process_time),
        "qps_1t_grad": rate(lv, qP, qN, True, 1, args.repeat, clock=time.process_time),
    }
    if threads >= 2:
        wall_1t = rate(lv, qP, qN, False, 1, args.repeat)
        row["qps_2t"] = rate(lv, qP, qN, False, 2, args.repeat)
        row["qps_2t_grad"] = rate(lv, qP, qN, True, 2, args.repeat)
        row["speedup_2t"] = row["qps_2t"] / wall_1t
    row["qps_small"] = rate(lv, qP[: 64 * SMALL_CALL], qN[: 64 * SMALL_CALL], False, threads, args.repeat,
                            call=SMALL_CALL)
    numba.set_num_threads(threads)
    return row


def _fmt(x, digits=3):
    if x is None:
        return "-"
    if abs(x) >= 1e5:
        return f"{x / 1e6:.2f}M"
    if abs(x) >= 1e3:
        return f"{x / 1e3:.1f}k"
    return f"{x:.{digits}g}"


def table(rows) -> str:
    cols = [("layout", "layout"), ("records", "N"), ("mean_hits", "hits"), ("insert_per_s", "insert/s"),
            ("freeze_s", "freeze s"), ("bytes_per_record", "B/rec"), ("qps_1t", "q/s 1t"),
            ("qps_1t_grad", "q/s 1t grad"), ("qps_2t", "q/s 2t"), ("speedup_2t", "x2t"),
            ("qps_small", "q/s small")]
    lines = ["| " + " | ".join(h for _, h in cols) + " |", "|" + "---|" * len(cols)]
    for r in rows:
        cells = [r["layout"], f"{r['records']:.0e}"] + [_fmt(r.get(k)) for k, _ in cols[2:]]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def plot(rows, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, (ax, bx) = plt.subplots(1, 2, figsize=(11, 4.2))
    for kind, marker in (("floor", "o"), ("volume", "s")):
        sub = [r for r in rows if r["layout"] == kind]
        if not sub:
            continue
        n = np.array([r["records"] for r in sub], float)
        for key, style, label in (("qps_1t", "-", "1 thread"), ("qps_1t_grad", "--", "1 thread, gradients"),
                                  ("qps_2t", ":", "2 threads")):
            if key in sub[0]:
                ax.loglog(n, [1e9 / r[key] for r in sub], style, marker=marker, label=f"{kind}, {label}")
        ref = 1e9 / sub[0]["qps_1t"] * np.log(n) / np.log(n[0])
        ax.loglog(n, ref, color="0.6", lw=0.8, ls="-.", label=f"{kind}: ∝ log N through N = {n[0]:.0e}")
        bx.semilogx(n, [r["bytes_per_record"] for r in sub], marker=marker, label=kind)
    ax.set_xlabel("records N")
    ax.set_ylabel("ns per query")
    ax.set_title("Lookup cost (1 thread: CPU time; 2 threads: wall clock)")
    ax.legend(fontsize=7)
    bx.axhline(200, color="0.6", lw=0.8, ls="--", label="target 200 B")
    bx.set_xlabel("records N")
    bx.set_ylabel("bytes per record")
    bx.set_title("Memory held per record")
    bx.legend(fontsize=7)
    fig.tight_layout()
    tmp = path.with_name(path.name + ".tmp.png")
    fig.savefig(tmp, dpi=110)
    plt.close(fig)
    atomic_write_bytes(path, tmp.read_bytes())
    tmp.unlink()


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter,
                                 epilog=__doc__.split("\n\n", 1)[1].split("\nUsage")[0])
    ap.add_argument("--sizes", default="1e3,1e4,1e5,1e6", help="record counts N, comma separated")
    ap.add_argument("--layouts", default="floor,volume", help="floor, volume or both (comma separated)")
    ap.add_argument("--queries", type=int, default=262_144, help="queries per timed call")
    ap.add_argument("--accuracy", type=float, default=0.15, help="the level's accuracy a")
    ap.add_argument("--hits", type=float, default=20.0, help="records a query should find on average")
    ap.add_argument("--repeat", type=int, default=5, help="timed runs per figure (the best is kept)")
    ap.add_argument("--threads", type=int, default=2, help="most threads used (1 or 2)")
    ap.add_argument("--seed", type=int, default=1, help="random seed of records and queries")
    ap.add_argument("--out", type=Path, help="folder for lookup.json and lookup.png")
    args = ap.parse_args(argv)
    try:
        sizes = [int(float(s)) for s in args.sizes.split(",")]
        if any(s < 1 for s in sizes):
            raise ValueError
    except ValueError:
        print(f"lookup.py: --sizes {args.sizes!r}: expected positive numbers, comma separated", file=sys.stderr)
        return 2
    layouts = [s.strip() for s in args.layouts.split(",")]
    if not set(layouts) <= {"floor", "volume"}:
        print(f"lookup.py: --layouts {args.layouts!r}: expected floor, volume or both", file=sys.stderr)
        return 2
    for key in ("queries", "repeat", "threads", "accuracy", "hits"):
        if not getattr(args, key) > 0:
            print(f"lookup.py: --{key} {getattr(args, key)}: must be positive", file=sys.stderr)
            return 2
    if args.out is not None and args.out.exists() and not args.out.is_dir():
        print(f"lookup.py: --out {args.out}: not a folder", file=sys.stderr)
        return 2
    threads = max(1, min(args.threads, numba.config.NUMBA_NUM_THREADS))
    from tqdm import tqdm
    rows = []
    t0 = time.perf_counter()
    cases = [(k, n) for k in layouts for n in sizes]
    warm = argparse.Namespace(**{**vars(args), "queries": 4 * SMALL_CALL, "repeat": 1})
    for kind in layouts:                            # numba loads or compiles the kernels: untimed
        run_case(kind, 2000, warm, threads)
    for kind, n in tqdm(cases, unit="case", file=sys.stderr, delay=1.0):
        rows.append(run_case(kind, n, args, threads))
    print(table(rows))
    big = max(rows, key=lambda r: r["records"])
    print(f"\nbytes at N = {big['records']:.0e} ({big['layout']}), per record: "
          + ", ".join(f"{k} {v / big['records']:.1f}" for k, v in sorted(big["bytes"].items(), key=lambda kv: -kv[1])))
    if args.out is not None:
        args.out.mkdir(parents=True, exist_ok=True)
        meta = {"accuracy": args.accuracy, "hits": args.hits, "queries": args.queries, "repeat": args.repeat,
                "threads": threads, "insert_batch": INSERT_BATCH, "small_call": SMALL_CALL}
        atomic_write_text(args.out / "lookup.json", json.dumps({"settings": meta, "rows": rows}, indent=1))
        plot(rows, args.out / "lookup.png")
    print(f"lookup bench: {len(rows)} cases in {time.perf_counter() - t0:.0f} s; at N = {big['records']:.0e} "
          f"{big['qps_1t'] / 1e6:.2f} M queries/s on 1 thread, {big['bytes_per_record']:.0f} B/record"
          + (f"; results in {args.out}" if args.out else ""))
    return 0


if __name__ == "__main__":
    sys.exit(main())

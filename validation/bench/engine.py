"""Speed of the irradiance-cache engine against raw Embree, measured in one run.

What is measured, on one scene and sensor grid (default: the office example at its
default settings):

1. **Engine.**  Wall seconds of ``Integrator(scene, options).compute(points, normals)``
   after one untimed warm-up (numba loads or compiles its octree kernels on first use,
   embree builds its BVH on first trace), the rays it traced, its records per diffuse
   level, and its throughput: engine rays/s = ``stats.rays / stats.seconds``.
2. **Raw Embree.**  The same number of rays as the engine traced (at most 4 M), of the
   same kind -- incoherent rays leaving random points of the room's surfaces, offset
   1e-4 m along the surface normal, cosine-distributed about it -- traced straight
   through ``embreex`` with nothing around it: closest hit (``output=1``) on one thread
   and on a thread pool (embreex releases the GIL), and the ``OCCLUDED`` query on two
   threads.  Chunks are 32768 rays, as in :mod:`lbl_illum.engine.raycast`.
3. **Ratio** engine rays/s / raw Embree rays/s (closest hit, 2 threads).  It says
   how much of the engine's time is spent tracing rays; the target is >= 0.5, i.e.
   at most half of the time in Python, numpy and numba around the ray casts.
4. **Profile.**  One more engine run under :mod:`cProfile`; the top functions by
   cumulative time, restricted to ``lbl_illum`` (numba kernels marked) and embreex.

Why ratios taken in one run: the machines that run this are shared and their speed
drifts by tens of percent from minute to minute, so an absolute number of seconds says
little and a time limit in a test fails at random.  Engine and raw Embree measured
back to back in one process see the same machine, and their ratio is what is compared
between versions of the code.  Speed is never asserted in the tests.

Usage (from the repository root)::

    python validation/bench/engine.py [--scene examples/office/scene.toml]
        [--points examples/office/grid.pts] [--preset NAME] [--repeat N] [--json out.json]

5. **Cores.**  The engine once more on one core (numba's kernels and the ray-casting
   pool limited to one thread) and the speed-up of two (all) cores over one.
"""

from __future__ import annotations

import argparse
import cProfile
import json
import os
import pstats
import sys
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np
from embreex import rtcore_scene
from embreex.mesh_construction import TriangleMesh

import numba

from lbl_illum import Options, load_scene, read_points
from lbl_illum.options import PRESETS
from lbl_illum.engine import Integrator, thread_count

ROOT = Path(__file__).resolve().parents[2]
DEFAULT_SCENE = ROOT / "examples" / "office" / "scene.toml"
DEFAULT_POINTS = ROOT / "examples" / "office" / "grid.pts"

#: Rays per embree call, as in lbl_illum.engine.raycast.CHUNK_RAYS.
CHUNK_RAYS = 32768
#: Most raw rays traced per measurement (memory and time bound).
MAX_RAW_RAYS = 4_000_000
#: Offset of raw ray origins along the surface normal [m].
RAW_OFFSET = 1e-4
#: Growth of the sensor points' box that selects the "room" triangles [m].
ROOM_MARGIN = 3.0
#: Sensor points of the warm-up run.
WARMUP_POINTS = 4
#: Target of engine rays/s / raw embree rays/s (closest hit, 2 threads).
TARGET_RATIO = 0.5
#: Rows of the profile summary.
PROFILE_ROWS = 12
SEED = 12345


# ---------------------------------------------------------------------------
# Command line and inputs
# ---------------------------------------------------------------------------

def parse_args(argv=None) -> argparse.Namespace:
    parser = argparse.ArgumentParser(
        prog="engine.py",
        description="Engine rays/s against raw embree rays/s on the same scene, in one run.")
    parser.add_argument("--scene", default=str(DEFAULT_SCENE), help="scene file (default: the office example)")
    parser.add_argument("--points", default=str(DEFAULT_POINTS), help="sensor points .pts (default: office grid)")
    parser.add_argument("--preset", choices=sorted(PRESETS), help="run at this preset instead of the scene's settings")
    parser.add_argument("--repeat", type=int, default=1, help="timed runs of each measurement; the best is used")
    parser.add_argument("--json", metavar="OUT.json", help="also write every figure to this JSON file")
    args = parser.parse_args(argv)
    if args.repeat < 1:
        parser.error("--repeat must be >= 1")
    return args


def display_path(path) -> str:
    """``path`` relative to the working directory when it lies below it."""
    rel = os.path.relpath(Path(path).resolve())
    return str(path) if rel.startswith("..") else rel


def load_inputs(scene_path, points_path):
    """(scene, points, normals), lengths in metres."""
    scene = load_scene(scene_path)
    points, normals = read_points(points_path, scene.unit_scale)
    return scene, points, normals


# ---------------------------------------------------------------------------
# 1. The engine
# ---------------------------------------------------------------------------

def warm_up(scene, points, normals, options: Options) -> float:
    """One small untimed run so numba kernels are loaded and compiled; returns its seconds.

    The kernels are specialised on array types only, so cheap settings warm them up
    as well as the real ones.
    """
    t0 = time.perf_counter()
    cheap = options.replace(samples=64, bounces=min(options.bounces, 1))
    Integrator(scene, cheap).compute(points[:WARMUP_POINTS], normals[:WARMUP_POINTS])
    return time.perf_counter() - t0


def run_engine(scene, points, normals, options: Options) -> dict:
    """One timed engine run from a fresh integrator (empty cache)."""
    t0 = time.perf_counter()
    result = Integrator(scene, options).compute(points, normals)
    wall = time.perf_counter() - t0
    s = result.stats
    return {"wall_seconds": wall, "seconds": s.seconds, "rays": int(s.rays),
            "records": [int(r) for r in s.records], "new_records": [int(r) for r in s.new_records],
            "queries": [int(q) for q in s.queries], "rays_per_second": s.rays / s.seconds,
            "mean_illuminance": float(np.mean(result.illuminance))}


def bench_engine(scene, points, normals, options: Options, repeat: int, threads: int | None = None) -> dict:
    """Best (fastest) of ``repeat`` engine runs, with every run's figures.

    ``threads``: limit numba's kernels and the ray-casting pool to this many threads.
    """
    saved_env, saved_numba = os.environ.get("LBL_ILLUM_THREADS"), numba.get_num_threads()
    if threads is not None:
        os.environ["LBL_ILLUM_THREADS"] = str(threads)
        numba.set_num_threads(min(threads, numba.config.NUMBA_NUM_THREADS))
    try:
        runs = [run_engine(scene, points, normals, options) for _ in range(repeat)]
    finally:
        if saved_env is None:
            os.environ.pop("LBL_ILLUM_THREADS", None)
        else:
            os.environ["LBL_ILLUM_THREADS"] = saved_env
        numba.set_num_threads(saved_numba)
    best = max(runs, key=lambda r: r["rays_per_second"])
    return {**best, "threads": threads or thread_count(), "all_wall_seconds": [r["wall_seconds"] for r in runs],
            "all_rays_per_second": [r["rays_per_second"] for r in runs]}


# ---------------------------------------------------------------------------
# 2. Raw embree
# ---------------------------------------------------------------------------

def room_triangles(triangles, points, margin=ROOM_MARGIN) -> np.ndarray:
    """Indices of the triangles whose centroid lies in the points' box grown by ``margin``."""
    lo = points.min(axis=0) - margin
    hi = points.max(axis=0) + margin
    c = triangles.vertices.mean(axis=1)
    return np.flatnonzero(np.all((c >= lo) & (c <= hi), axis=1))


def cosine_about(normals: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """(n, 3) cosine-distributed unit directions about unit ``normals`` (Malley's method)."""
    n = len(normals)
    u1, u2 = rng.random(n), rng.random(n)
    r, phi = np.sqrt(u1), 2.0 * np.pi * u2
    local = np.stack([r * np.cos(phi), r * np.sin(phi), np.sqrt(1.0 - u1)], axis=1)
    # orthonormal basis (t, b, n) per normal (Duff et al. 2017)
    sign = np.where(normals[:, 2] >= 0.0, 1.0, -1.0)
    a = -1.0 / (sign + normals[:, 2])
    b = normals[:, 0] * normals[:, 1] * a
    t = np.stack([1.0 + sign * normals[:, 0] ** 2 * a, sign * b, -sign * normals[:, 0]], axis=1)
    bt = np.stack([b, sign + normals[:, 1] ** 2 * a, -normals[:, 1]], axis=1)
    return local[:, :1] * t + local[:, 1:2] * bt + local[:, 2:] * normals


def surface_rays(triangles, index: np.ndarray, n: int, rng: np.random.Generator):
    """``n`` rays leaving random points (uniform by area) of the triangles ``index``.

    Origins are offset ``RAW_OFFSET`` along the face normal, directions are
    cosine-distributed about it.  Returns C-contiguous float32 (n, 3) arrays.
    """
    areas = triangles.areas[index]
    pick = index[rng.choice(len(index), size=n, p=areas / areas.sum())]
    v = triangles.vertices[pick]
    s, t = np.sqrt(rng.random(n)), rng.random(n)
    p = (1.0 - s)[:, None] * v[:, 0] + (s * (1.0 - t))[:, None] * v[:, 1] + (s * t)[:, None] * v[:, 2]
    nrm = triangles.normals[pick]
    origins = p + RAW_OFFSET * nrm
    directions = cosine_about(nrm, rng)
    return (np.ascontiguousarray(origins, dtype=np.float32),
            np.ascontiguousarray(directions, dtype=np.float32))


def embree_scene(triangles):
    """An embreex scene of every triangle, its BVH built by one tiny trace."""
    scene = rtcore_scene.EmbreeScene()
    TriangleMesh(scene, np.ascontiguousarray(triangles.vertices, dtype=np.float32))
    scene.run(np.zeros((1, 3), np.float32), np.array([[0, 0, 1]], np.float32), output=1)
    return scene


def chunk_slices(n: int, size: int = CHUNK_RAYS) -> list:
    return [slice(i, min(n, i + size)) for i in range(0, n, size)]


def time_trace(scene, origins, directions, threads: int, query: str) -> float:
    """Seconds to trace all rays in chunks, on ``threads`` threads (1: no pool)."""
    if query == "OCCLUDED":
        def work(s):
            return scene.run(origins[s], directions[s], query="OCCLUDED")
    else:
        def work(s):
            return scene.run(origins[s], directions[s], output=1)
    slices = chunk_slices(len(origins))
    if threads == 1:
        t0 = time.perf_counter()
        for s in slices:
            work(s)
        return time.perf_counter() - t0
    with ThreadPoolExecutor(max_workers=threads) as pool:
        list(pool.map(lambda _: None, range(threads)))       # start the workers untimed
        t0 = time.perf_counter()
        list(pool.map(work, slices))
        return time.perf_counter() - t0


def bench_embree(triangles, points, n_rays: int, repeat: int) -> dict:
    """Raw embree rays/s for the configurations of the report (best of ``repeat``)."""
    index = room_triangles(triangles, points)
    rng = np.random.default_rng(SEED)
    origins, directions = surface_rays(triangles, index, n_rays, rng)
    scene = embree_scene(triangles)
    cpus = os.cpu_count() or 1
    configs = [("intersect", 1), ("intersect", cpus)]
    if cpus != 2:
        configs.append(("intersect", 2))
    configs.append(("occluded", 2))
    results = {}
    for query, threads in configs:
        secs = [time_trace(scene, origins, directions, threads, query.upper()) for _ in range(repeat)]
        results[f"{query}_{threads}t"] = {
            "query": query, "threads": threads, "seconds": min(secs), "all_seconds": secs,
            "rays_per_second": n_rays / min(secs), "all_rays_per_second": [n_rays / s for s in secs]}
    return {"rays": n_rays, "room_triangles": int(len(index)), "cpu_count": cpus, "runs": results}


# ---------------------------------------------------------------------------
# 4. Profile
# ---------------------------------------------------------------------------

def numba_kernels() -> set:
    """(file, line) of the Python source of every numba dispatcher in ``lbl_illum``."""
    from numba.core.dispatcher import Dispatcher

    found = set()
    for name, module in list(sys.modules.items()):
        if not (name == "lbl_illum" or name.startswith("lbl_illum.")) or module is None:
            continue
        for value in vars(module).values():
            # a RowKernel (compiled.py) holds its dispatcher
            for obj in (getattr(value, "kernel", value),):
                if isinstance(obj, Dispatcher):
                    code = obj.py_func.__code__
                    found.add((code.co_filename, code.co_firstlineno))
    return found


def profile_engine(scene, points, normals, options: Options, rows: int = PROFILE_ROWS) -> dict:
    """Top ``rows`` functions of one engine run by cumulative time (lbl_illum and embreex)."""
    profiler = cProfile.Profile()
    profiler.enable()
    t0 = time.perf_counter()
    Integrator(scene, options).compute(points, normals)
    total = time.perf_counter() - t0
    profiler.disable()
    kernels = numba_kernels()
    table = []
    for (filename, line, func), (_, ncalls, tottime, cumtime, _) in pstats.Stats(profiler).stats.items():
        if "embreex" in filename or "embreex" in func:
            kind = "embreex"
        elif "lbl_illum" in filename:
            kind = "numba" if (filename, line) in kernels else "python"
        else:
            continue
        where = Path(filename).name if kind != "embreex" else "embreex"
        table.append({"function": f"{where}:{line}({func})", "kind": kind, "calls": int(ncalls),
                      "tottime": tottime, "cumtime": cumtime, "share": cumtime / total})
    table.sort(key=lambda r: -r["cumtime"])
    return {"seconds_under_profiler": total, "top": table[:rows]}


# ---------------------------------------------------------------------------
# Report
# ---------------------------------------------------------------------------

def summarise(engine: dict, raw: dict) -> dict:
    """The ratio of the report and what it implies."""
    base = raw["runs"]["intersect_2t"]["rays_per_second"]
    ratio = engine["rays_per_second"] / base
    return {"ratio": ratio, "target": TARGET_RATIO, "meets_target": ratio >= TARGET_RATIO,
            "raw_2t_rays_per_second": base,
            "embree_seconds_for_engine_rays": engine["rays"] / base}


def fmt_rate(rays_per_second: float) -> str:
    return f"{rays_per_second / 1e6:8.3f} Mrays/s"


def print_report(report: dict) -> None:
    eng, raw, summ, prof = report["engine"], report["embree"], report["summary"], report["profile"]
    line = "-" * 78
    print(line)
    print(f"bench_engine: {report['scene']}  +  {report['points']}  ({report['n_points']} points)")
    print(f"options: {report['options']}")
    print(f"python {report['python']}, numpy {report['numpy']}, os.cpu_count() = {raw['cpu_count']}, "
          f"engine threads = {eng['threads']}, repeat = {report['repeat']}")
    print(f"warm-up (untimed, {WARMUP_POINTS} points, cheap settings): {report['warmup_seconds']:.2f} s")
    print(line)
    print("1. ENGINE  Integrator(scene, options).compute(points, normals)")
    print(f"   wall time            {eng['wall_seconds']:10.2f} s   (all: "
          + ", ".join(f"{s:.2f}" for s in eng["all_wall_seconds"]) + ")")
    print(f"   stats.seconds        {eng['seconds']:10.2f} s")
    print(f"   rays traced          {eng['rays']:>10,d}")
    print(f"   records per level    {eng['records']}   (total {sum(eng['records']):,d})")
    print(f"   queries per level    {eng['queries']}")
    print(f"   mean illuminance     {eng['mean_illuminance']:10.1f} lux")
    print(f"   engine rays/s        {fmt_rate(eng['rays_per_second'])}   (all: "
          + ", ".join(f"{r / 1e6:.3f}" for r in eng["all_rays_per_second"]) + ")")
    print(line)
    print(f"2. RAW EMBREE  {raw['rays']:,d} incoherent rays from {raw['room_triangles']} room triangles, "
          f"chunks of {CHUNK_RAYS}")
    print(f"   {'query':<10} {'threads':>7} {'seconds':>9} {'rays/s':>17}   all Mrays/s")
    for r in raw["runs"].values():
        print(f"   {r['query']:<10} {r['threads']:>7d} {r['seconds']:9.3f} {fmt_rate(r['rays_per_second']):>17}   "
              + ", ".join(f"{x / 1e6:.3f}" for x in r["all_rays_per_second"]))
    print(line)
    verdict = "meets target" if summ["meets_target"] else "BELOW target"
    print("3. RATIO  engine rays/s / raw embree rays/s (intersect, 2 threads)")
    print(f"   {eng['rays_per_second'] / 1e6:.3f} / {summ['raw_2t_rays_per_second'] / 1e6:.3f} Mrays/s = "
          f"{summ['ratio']:.3f}    target >= {summ['target']}  -> {verdict}")
    print(f"   embree alone would trace the engine's rays in {summ['embree_seconds_for_engine_rays']:.2f} s "
          f"of its {eng['seconds']:.2f} s ({100 * summ['embree_seconds_for_engine_rays'] / eng['seconds']:.1f} %)")
    print(line)
    print(f"4. PROFILE  one engine run under cProfile ({prof['seconds_under_profiler']:.2f} s), "
          f"top {len(prof['top'])} by cumulative time")
    print(f"   {'cumtime':>8} {'share':>6} {'tottime':>8} {'calls':>7}  {'kind':<7} function")
    for r in prof["top"]:
        print(f"   {r['cumtime']:8.2f} {100 * r['share']:5.1f}% {r['tottime']:8.2f} {r['calls']:7d}  "
              f"{r['kind']:<7} {r['function']}")
    print("   (cProfile sees the main thread only: embree calls made on the tracer's thread pool")
    print("    appear as the time raycast.py _run spends waiting for the pool.)")
    print(line)
    one = report["one_core"]
    print("5. CORES  the engine on one thread (numba and ray casting) against all")
    print(f"   1 thread: {one['seconds']:.2f} s, {fmt_rate(one['rays_per_second'])};  "
          f"{eng['threads']} threads: {eng['seconds']:.2f} s;  speed-up {report['speedup']:.2f}x")
    print(line)
    print(f"engine: {eng['rays']:,d} rays, {sum(eng['records']):,d} records in {eng['seconds']:.2f} s; "
          f"ratio to raw embree {summ['ratio']:.3f}; speed-up 1 -> {eng['threads']} cores {report['speedup']:.2f}x")


def main(argv=None) -> int:
    args = parse_args(argv)
    scene, points, normals = load_inputs(args.scene, args.points)
    options = scene.options.with_preset(args.preset) if args.preset else scene.options
    warmup = warm_up(scene, points, normals, options)
    engine = bench_engine(scene, points, normals, options, args.repeat)
    one_core = bench_engine(scene, points, normals, options, args.repeat, threads=1)
    raw = bench_embree(scene.triangles, points, min(engine["rays"], MAX_RAW_RAYS), args.repeat)
    report = {
        "scene": display_path(args.scene), "points": display_path(args.points), "n_points": int(len(points)),
        "options": options.as_dict(), "repeat": args.repeat, "python": sys.version.split()[0],
        "numpy": np.__version__, "warmup_seconds": warmup,
        "engine": engine, "one_core": one_core, "speedup": one_core["seconds"] / engine["seconds"],
        "embree": raw, "summary": summarise(engine, raw),
        "profile": profile_engine(scene, points, normals, options),
    }
    print_report(report)
    if args.json:
        Path(args.json).write_text(json.dumps(report, indent=2))
        print(f"wrote {args.json}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

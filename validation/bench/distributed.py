"""Runs on a Dask cluster: the speed-up from 1 to 2 workers, and what a round costs the
driver against its work (docs/distributed.md), measured in one run on one machine.

Workloads, on the office example (``examples/office``):

* ``grid``: a dense grid over the box of the office's grid (``--spacing``, 0.1 m: 1,581
  points at the grid's height), preset ``draft`` (every sensor its own record of 1,024
  rays), chunks of ``--grid-chunk`` (128) points;
* ``image``: a 240 × 180 perspective view of the room at ``draft``, chunks of 4,096 of its
  diffuse hits (the camera paths are traced by the driver, as in one process);
* ``annual``: a year (Oakland TMY3) at a grid of ``--annual-spacing`` (0.3 m: 190
  points) at ``draft``, chunks of 32.

Each runs in this process through the rounds (``--workers 0``), on a LocalCluster of 1
worker (using both cores) and on one of 2 workers (one core each), worker processes on
127.0.0.1, in turn, ``--repeat`` (3) times, the best time of each kept; timed from the
first task sent to the answers back (the cluster's start-up is timed apart, and a small
untimed run on each cluster first lets its workers build the scene and load the
compiled kernels).  The three results must be equal bit for bit (printed).
``speed-up`` = seconds on 1 worker / seconds on 2.

Per round of the 2-worker run: the records sent, the seconds to send them to every
worker (``send``), to merge the new ones (``merge``), from first task to last result
(``wall``) and the tasks' own seconds summed (``tasks``).  Then, apart from any run, the
send and merge costs against the size of the record set (10^4 … 10^6 records; 16 deltas
of 1 % each merged), from which the cost of a round on many machines can be estimated:
the driver's share of a round is send (once per worker) + merge, its work is tasks /
workers.

The machine is shared: compare figures of one run; ``uptime`` is printed before and
after.  Usage (from the repository root)::

    python validation/bench/distributed.py [--spacing 0.1] [--grid-chunk 128] [--repeat 3] [--out FILE.json]
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

# This file's name is Dask's package's: run as a script, its folder must not shadow it.
sys.path[:] = [p for p in sys.path if Path(p or ".").resolve() != Path(__file__).resolve().parent]

import numpy as np  # noqa: E402

from lbl_illum import load_scene, read_points  # noqa: E402
from lbl_illum.daylight import read_weather  # noqa: E402
from lbl_illum.distributed import (DaskCluster, Decomposition, InProcess, SceneRecipe, annual_solver, merge_round,
                                   record_set, solve_points)  # noqa: E402
from lbl_illum.engine import Integrator, IrradianceCache, annual_light, render_image  # noqa: E402
from lbl_illum.io import atomic_write_text  # noqa: E402
from lbl_illum.scene import view_from_string  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
OFFICE = ROOT / "examples" / "office" / "scene.toml"
WEATHER = ROOT / "examples" / "weather" / "USA_CA_Oakland.Intl.AP.724930_TMY3.epw"
VIEW = "-vtv -vp 2 0.5 1.5 -vd 0 1 -0.1 -vh 80 -vv 60"


def load_average() -> str:
    return " ".join(f"{x:.2f}" for x in os.getloadavg())


def dense_grid(scene, spacing):
    """Points every ``spacing`` metres over the box of the office's grid, at its height, facing up."""
    P, _ = read_points(OFFICE.parent / "grid.pts", scene.unit_scale)
    lo, hi = P.min(axis=0), P.max(axis=0)
    xs = np.arange(lo[0], hi[0] + 1e-9, spacing)
    ys = np.arange(lo[1], hi[1] + 1e-9, spacing)
    x, y = np.meshgrid(xs, ys, indexing="ij")
    points = np.column_stack([x.ravel(), y.ravel(), np.full(x.size, lo[2])])
    return points, np.tile([0.0, 0.0, 1.0], (len(points), 1))


def workloads(args):
    """name -> (function of a cluster that runs it and returns (array, costs), description)."""
    scene = load_scene(OFFICE)
    options = scene.options.with_preset("draft")
    recipe = SceneRecipe(str(OFFICE.resolve()))
    grid_points, grid_normals = dense_grid(scene, args.spacing)
    sensors, facing = dense_grid(scene, args.annual_spacing)
    weather = read_weather(WEATHER)
    view = view_from_string(VIEW, scene.unit_scale)

    def grid(cluster):
        integ = Integrator(scene, options)
        cluster.prepare(recipe, options, integ.fingerprint, scene, integ.context)
        result, costs, _ = solve_points(cluster, recipe, integ, grid_points, grid_normals,
                                        plan=Decomposition(args.grid_chunk, 16))
        return result.rgb, costs

    def image(cluster):
        integ = Integrator(scene, for_images(options))
        cluster.prepare(recipe, integ.options, integ.fingerprint, scene, integ.context)
        costs = []

        def shade(points, normals, spacing, taper):
            result, cost, _ = solve_points(cluster, recipe, integ, points, normals, spacing=spacing, taper=taper,
                                           plan=Decomposition(4096, 16))
            costs.append(cost)
            return result
        rgb = render_image(scene, view, 240, 180, integrator=integ, shade=shade).rgb
        return rgb, costs[0]

    def annual(cluster):
        costs = []
        year = annual_light(scene, sensors, facing, weather, options,
                            solve=annual_solver(cluster, recipe.path, Decomposition(32, 16), costs=costs))
        return year.illuminance, costs[0]

    def warm_up(cluster):
        integ = Integrator(scene, options)
        cluster.prepare(recipe, options, integ.fingerprint, scene, integ.context)
        solve_points(cluster, recipe, integ, grid_points[:32], grid_normals[:32], plan=Decomposition(16, 16))

    return {"warm-up": (warm_up, ""), "grid": (grid, f"{len(grid_points)} points, chunks of {args.grid_chunk}"),
            "image": (image, "240 x 180 pixels, chunks of 4096 hits"),
            "annual": (annual, f"{len(sensors)} points x 8760 hours, chunks of 32")}


def for_images(options):
    """The options an image uses (no point samples)."""
    from lbl_illum.engine import image_options

    return image_options(options)


def timed(fn, cluster):
    t = time.perf_counter()
    out, costs = fn(cluster)
    return time.perf_counter() - t, out, costs


def run_workloads(args) -> dict:
    """Each workload on 0, 1 and 2 workers, ``--repeat`` times in turn (0, 1, 2, 0, 1, 2, …:
    a load that drifts falls on all three alike); the best time of each is kept."""
    jobs = workloads(args)
    warm_up = jobs.pop("warm-up")[0]
    results = {name: {"what": what} for name, (_, what) in jobs.items()}
    arrays = {name: [] for name in jobs}
    clusters = {}
    try:
        for label, workers in (("0", 0), ("1", 1), ("2", 2)):
            t = time.perf_counter()
            clusters[label] = InProcess() if workers == 0 else DaskCluster(workers=workers)
            if workers:
                warm_up(clusters[label])            # the workers build the scene, load the kernels: not timed
            for name in jobs:
                results[name][f"start_{label}"] = time.perf_counter() - t
        for name, (fn, _) in jobs.items():
            for _ in range(args.repeat):
                for label, cluster in clusters.items():
                    seconds, out, costs = timed(fn, cluster)
                    key = f"seconds_{label}"
                    if seconds < results[name].get(key, float("inf")):
                        results[name][key] = seconds
                        if label == "2":
                            results[name]["rounds"] = costs.as_dict()
                    if len(arrays[name]) < len(clusters):
                        arrays[name].append(out)
                    print(f"  {name:7s} on {cluster.name}: {seconds:.2f} s (load {load_average()})", flush=True)
    finally:
        for cluster in reversed(list(clusters.values())):    # last first: each restores Dask's log levels
            cluster.close()
    for name in jobs:
        r = results[name]
        r["identical"] = all(np.array_equal(arrays[name][0], a) for a in arrays[name][1:])
        r["speedup"] = r["seconds_1"] / r["seconds_2"]
    return results


def record_costs(sizes) -> list[dict]:
    """Send (to a 2-worker LocalCluster) and merge seconds against the size of a record set."""
    rng = np.random.default_rng(1)
    rows = []
    cluster = DaskCluster(workers=2)
    try:
        for n in sizes:
            def level_set(count, seed):
                cache = IrradianceCache("bench", [0.1], np.zeros(3), 10.0)
                r = np.random.default_rng(seed)
                normals = r.normal(size=(count, 3))
                normals /= np.linalg.norm(normals, axis=1, keepdims=True)
                cache.levels[0].add(r.uniform(-5, 5, (count, 3)), normals, r.uniform(0.1, 0.5, count),
                                    E=r.uniform(0, 100, (count, 3)))
                return record_set(cache)
            base = level_set(n, int(rng.integers(1 << 30)))
            deltas = [level_set(max(1, n // 100), int(rng.integers(1 << 30))) for _ in range(16)]
            sent = []
            for _ in range(3):
                t = time.perf_counter()
                future = cluster.share(base)
                cluster.client.wait(future) if hasattr(cluster.client, "wait") else None
                sent.append(time.perf_counter() - t)
                del future
            merged = []
            for _ in range(3):
                t = time.perf_counter()
                merge_round(base, deltas)
                merged.append(time.perf_counter() - t)
            size = sum(a.nbytes for a in base.arrays.values())
            rows.append({"records": n, "bytes": int(size), "send": min(sent), "merge_16_deltas": min(merged)})
            print(f"  {n:>9,} records ({size / 1e6:7.1f} MB): send to 2 workers {min(sent):.3f} s, "
                  f"merge 16 deltas of 1 % {min(merged):.3f} s", flush=True)
    finally:
        cluster.close()
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--spacing", type=float, default=0.1, help="grid spacing [m] (default 0.1)")
    parser.add_argument("--grid-chunk", type=int, default=128, help="points a chunk of the grid (default 128)")
    parser.add_argument("--annual-spacing", type=float, default=0.3, help="annual grid spacing [m] (default 0.3)")
    parser.add_argument("--sizes", default="1e4,1e5,1e6", help="record-set sizes for the send/merge costs")
    parser.add_argument("--repeat", type=int, default=3, help="runs of each workload on each cluster, best kept "
                        "(default 3)")
    parser.add_argument("--out", help="write the figures as JSON")
    args = parser.parse_args()
    import logging

    logging.getLogger("distributed").setLevel(logging.ERROR)    # no INFO lines as clusters close
    print(f"load average before: {load_average()}  ({os.cpu_count()} cores)", flush=True)
    results = run_workloads(args)
    print("\nworkload  what                                     0 workers   1 worker   2 workers  speed-up  identical")
    for name, r in results.items():
        print(f"{name:8s}  {r['what']:39s}  {r['seconds_0']:8.2f}  {r['seconds_1']:9.2f}  {r['seconds_2']:9.2f}  "
              f"{r['speedup']:8.2f}  {r['identical']}")
    print("\nrounds of the 2-worker runs: records sent, send s, merge s, wall s, tasks s (driver's share)")
    for name, r in results.items():
        for i, c in enumerate(r["rounds"]["rounds"]):
            s = c["seconds"]
            share = (s["send"] + s["merge"]) / s["wall"] if s["wall"] else 0.0
            print(f"  {name:7s} round {i + 1}: {c['chunks']:2d} chunks, {c['records']:>8,} records sent, "
                  f"send {s['send']:.3f}, merge {s['merge']:.3f}, wall {s['wall']:.2f}, tasks {s['tasks']:.2f} "
                  f"({100 * share:.1f} %)")
    print("\nrecord sets apart from any run:")
    sizes = [int(float(x)) for x in args.sizes.split(",")]
    costs = record_costs(sizes)
    print(f"load average after: {load_average()}")
    if args.out:
        atomic_write_text(args.out, json.dumps({"workloads": results, "record_sets": costs}, indent=2) + "\n")


if __name__ == "__main__":
    main()

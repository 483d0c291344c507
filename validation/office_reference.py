"""Converged reference illuminance for the office grid, computed by the tool itself.

Pure Monte Carlo (``accuracy = 0``: every sensor gets its own primary evaluation of
``--samples`` stratified hemisphere rays, and every deeper bounce follows one path ray
per hit, so nothing is interpolated) with enough bounces that the bounce limit's bias
is negligible (the reference counts every bounce that matters).  It is repeated with
``--seeds`` independent seeds; the reference is their mean and its standard error per
point is the standard deviation of the runs over sqrt(seeds).

Run from the repository root::

    python validation/office_reference.py [--samples 16384] [--bounces 12] [--seeds 4]
        [-o validation/data/office_reference.json]

The result is a small JSON file (one value per sensor) that the accuracy studies and
benchmarks compare against.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from lbl_illum import Options, compute_illuminance, load_scene, read_points  # noqa: E402
from lbl_illum.io import atomic_write_text  # noqa: E402

SCENE = ROOT / "examples" / "office" / "scene.toml"
POINTS = ROOT / "examples" / "office" / "grid.pts"


def reference(samples: int, bounces: int, seeds: int) -> dict:
    scene = load_scene(SCENE)
    points, normals = read_points(POINTS, scene.unit_scale)
    runs, rays, t0 = [], 0, time.perf_counter()
    for seed in range(seeds):
        result = compute_illuminance(scene, points, normals,
                                     Options(accuracy=0.0, samples=samples, bounces=bounces, seed=1000 + seed))
        runs.append(result.illuminance)
        rays += result.stats.rays
        print(f"  seed {seed}: mean {result.illuminance.mean():.2f} lux, {result.stats.rays:,} rays, "
              f"{result.stats.seconds:.1f} s", file=sys.stderr)
    runs = np.array(runs)
    mean = runs.mean(axis=0)
    stderr = runs.std(axis=0, ddof=1) / np.sqrt(seeds)
    return {
        "scene": "examples/office/scene.toml", "points": "examples/office/grid.pts",
        "method": "pure Monte Carlo (accuracy 0), mean of independent seeds",
        "samples": samples, "bounces": bounces, "seeds": seeds,
        "rays": int(rays), "seconds": time.perf_counter() - t0,
        "illuminance": mean.round(4).tolist(),
        "standard_error": stderr.round(4).tolist(),
        "relative_standard_error": {"mean": float(np.mean(stderr / mean)), "max": float(np.max(stderr / mean))},
    }


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--samples", type=int, default=16384)
    parser.add_argument("--bounces", type=int, default=12)
    parser.add_argument("--seeds", type=int, default=4)
    parser.add_argument("-o", "--output", default=str(ROOT / "validation" / "data" / "office_reference.json"))
    args = parser.parse_args(argv)
    doc = reference(args.samples, args.bounces, args.seeds)
    atomic_write_text(args.output, json.dumps(doc, indent=1) + "\n")
    rse = doc["relative_standard_error"]
    print(f"office reference: {len(doc['illuminance'])} points, mean {np.mean(doc['illuminance']):.2f} lux, "
          f"relative standard error mean {100 * rse['mean']:.2f} % max {100 * rse['max']:.2f} %, "
          f"{doc['rays']:,} rays, {doc['seconds']:.0f} s -> {args.output}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

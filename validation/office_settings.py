"""Cost and error of a few settings on the office grid, against the committed reference.

Each row is one run: wall seconds of the calculation, rays, records per level, and the
mean and largest relative error per sensor against ``validation/data/office_reference.json``
(make it with ``office_reference.py``), with the reference's own standard error stated.
Seconds are only comparable within one run of this script (shared, noisy machines).

    python validation/office_settings.py [--json out.json]
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from lbl_illum import Options, compute_illuminance, load_scene, read_points  # noqa: E402

SETTINGS = [
    ("default (a 0.1, 1024 samples, 8 bounces)", {}),
    ("--accuracy 0.15", {"accuracy": 0.15}),
    ("--accuracy 0.2", {"accuracy": 0.2}),
    ("--bounces 5", {"bounces": 5}),
    ("--bounces 2", {"bounces": 2}),
    ("--interpolation paper", {"interpolation": "paper"}),
    ("--point-samples 4096 --accuracy 0.14 --samples 256", {"point_samples": 4096, "accuracy": 0.14,
                                                          "samples": 256}),
    ("--point-samples 4096 --accuracy 0.2 --samples 256", {"point_samples": 4096, "accuracy": 0.2,
                                                         "samples": 256}),
    ("--accuracy 0 --samples 4096 (pure Monte Carlo)", {"accuracy": 0.0, "samples": 4096}),
    ("--accuracy 0 --samples 16384 (pure Monte Carlo)", {"accuracy": 0.0, "samples": 16384}),
]


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--json", help="write the rows as JSON")
    args = parser.parse_args(argv)
    ref_doc = json.loads((ROOT / "validation" / "data" / "office_reference.json").read_text())
    ref = np.array(ref_doc["illuminance"])
    scene = load_scene(ROOT / "examples" / "office" / "scene.toml")
    points, normals = read_points(ROOT / "examples" / "office" / "grid.pts", scene.unit_scale)
    compute_illuminance(scene, points[:2], normals[:2], Options(samples=16, bounces=1))   # load kernels
    rse = ref_doc["relative_standard_error"]
    print(f"reference: {ref_doc['method']}, {ref_doc['samples']} samples x {ref_doc['seeds']} seeds, "
          f"{ref_doc['bounces']} bounces; standard error {100 * rse['mean']:.2f} % mean, {100 * rse['max']:.2f} % max")
    print(f"{'settings':48s} {'s':>6s} {'rays':>7s} {'mean err':>9s} {'max err':>8s} {'bias':>7s}  records per level")
    rows = []
    for label, changes in SETTINGS:
        result = compute_illuminance(scene, points, normals, Options(**changes))
        err = result.illuminance / ref - 1.0
        row = {"settings": label, "seconds": result.stats.seconds, "rays": result.stats.rays,
               "records": result.stats.records, "mean_error": float(np.mean(np.abs(err))),
               "max_error": float(np.max(np.abs(err))), "bias": float(np.mean(err))}
        rows.append(row)
        print(f"{label:48s} {row['seconds']:6.1f} {row['rays'] / 1e6:6.2f}M {100 * row['mean_error']:8.2f}% "
              f"{100 * row['max_error']:7.2f}% {100 * row['bias']:+6.2f}%  {row['records']}")
    if args.json:
        Path(args.json).write_text(json.dumps(rows, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())

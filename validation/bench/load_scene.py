"""How long a real Radiance model takes to load: the LBNL open-plan office
(validation/corpus/lbnl-open-office, 14 Radiance files, 13,966 polygons, desk outlines up
to 64 vertices) read from its ``.rad`` files, against the 2 s target of the Radiance
import.

Each figure is taken in a fresh process (best of ``--repeat``), with the geometry cache
switched off (``LBL_ILLUM_CACHE_DIR=off``; Radiance files are never cached anyway):

* ``load``: :func:`lbl_illum.load_scene` alone — reading and parsing the primitives,
  triangulating every polygon with its holes and checking its area, the
  materials from ``materials.mat``;
* ``import + load``: the same with the package's import, as a command pays it.

Usage: ``python validation/bench/load_scene.py [--repeat N]``.  Nothing is asserted; the
figures go to the docs by hand, with the machine they were taken on.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
SCENE = ROOT / "validation" / "corpus" / "lbnl-open-office" / "overcast.toml"
TARGET = 2.0
CHILD = """
import time, sys
t0 = time.perf_counter()
from lbl_illum import load_scene
t1 = time.perf_counter()
scene = load_scene(sys.argv[1])
t2 = time.perf_counter()
print(t2 - t1, t2 - t0, len(scene.triangles))
"""


def one_run() -> tuple[float, float, int]:
    env = {**os.environ, "LBL_ILLUM_CACHE_DIR": "off"}
    out = subprocess.run([sys.executable, "-c", CHILD, str(SCENE)], env=env, capture_output=True, text=True,
                         check=True).stdout.split()
    return float(out[0]), float(out[1]), int(out[2])


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=5, help="fresh processes per figure (default 5)")
    args = parser.parse_args(argv)
    runs = [one_run() for _ in range(args.repeat)]
    load = min(r[0] for r in runs)
    whole = min(r[1] for r in runs)
    print(f"LBNL open-plan office, {runs[0][2]:,} triangles, best of {args.repeat} fresh processes:")
    print(f"  load           {load:6.3f} s   ({load / TARGET:.2f} of the {TARGET:g} s target)")
    print(f"  import + load  {whole:6.3f} s   ({whole / TARGET:.2f} of the {TARGET:g} s target)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

"""Whole commands as a user types them: the timings the README, ``--help`` and the docs quote.

Each command runs in a fresh process from the repository root, with the installed
``lbl-illum`` script (or ``python -m lbl_illum`` when none is on PATH), and its wall time
is taken from outside, start-up included:

* ``lbl-illum --help`` (best of 5);
* the README's job (the office example at the default preset) on its **first run** —
  numba's disk cache and the geometry cache empty, in temporary folders — and then warm
  (best of ``--repeat``);
* the office example at ``draft``, warm: the whole command against the calculation's own
  seconds (``--stats``), the difference being the process overhead (start-up, imports,
  loading kernels and the scene, writing the output);
* the render of docs/rendering.md (512 × 352 pixels, default preset), warm.

Usage: ``python validation/bench/commands.py [--repeat N] [--out DIR]`` (``--out`` writes
``commands.json``).  Nothing here is asserted: the figures go to the docs by hand, with
the machine they were taken on.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
OFFICE = ["examples/office/scene.toml", "--points", "examples/office/grid.pts"]
VIEW = "--view=-vtv -vp 2 5.5 1.5 -vd 0 -1 -0.1 -vh 80 -vv 60"


def _command() -> list[str]:
    script = shutil.which("lbl-illum")
    return [script] if script else [sys.executable, "-m", "lbl_illum"]


def timed(args: list[str], env: dict | None = None) -> float:
    """Wall seconds of one command (it must succeed)."""
    t0 = time.perf_counter()
    subprocess.run(_command() + args, cwd=ROOT, env=env, check=True, stdout=subprocess.DEVNULL,
                   stderr=subprocess.DEVNULL)
    return time.perf_counter() - t0


def best(args: list[str], repeat: int, env: dict | None = None) -> tuple[float, list[float]]:
    times = [timed(args, env) for _ in range(repeat)]
    return min(times), times


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeat", type=int, default=3, help="warm runs per command, best taken (default 3)")
    parser.add_argument("--out", type=Path, help="folder for commands.json")
    args = parser.parse_args(argv)
    out_dir = Path(tempfile.mkdtemp(prefix="lbl-illum-bench-"))
    rows = {}
    try:
        rows["help"] = best(["--help"], 5)
        # first run: numba's kernels and the geometry cache not on disk yet
        cold = dict(os.environ, NUMBA_CACHE_DIR=str(out_dir / "numba"), LBL_ILLUM_CACHE_DIR=str(out_dir / "geometry"))
        readme = ["illuminance", *OFFICE, "-o", str(out_dir / "results.csv")]
        rows["readme first run"] = (timed(readme, cold), [])
        rows["readme warm"] = best(readme, args.repeat, cold)
        stats = out_dir / "draft.json"
        draft = ["illuminance", *OFFICE, "-o", str(out_dir / "draft.csv"), "--preset", "draft", "--stats", str(stats)]
        whole, _ = best(draft, args.repeat, cold)
        compute = json.loads(stats.read_text())["compute_seconds"]
        rows["draft warm"] = (whole, [])
        rows["draft compute (in the run)"] = (compute, [])
        rows["draft overhead"] = (whole - compute, [])
        rows["render warm"] = best(["render", "examples/office/scene.toml", VIEW, "-o", str(out_dir / "office.exr")],
                                   args.repeat, cold)
    finally:
        shutil.rmtree(out_dir, ignore_errors=True)
    print(f"{'command':32s} {'seconds':>8s}   all runs")
    for name, (seconds, runs) in rows.items():
        print(f"{name:32s} {seconds:8.2f}   {' '.join(f'{t:.2f}' for t in runs)}")
    if args.out:
        args.out.mkdir(parents=True, exist_ok=True)
        report = {"machine": {"cpus": os.cpu_count(), "python": platform.python_version(),
                              "processor": platform.processor() or platform.machine()},
                  "seconds": {name: seconds for name, (seconds, _) in rows.items()},
                  "runs": {name: runs for name, (_, runs) in rows.items()}}
        (args.out / "commands.json").write_text(json.dumps(report, indent=2) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())

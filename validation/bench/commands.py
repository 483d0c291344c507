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

Python's bytecode cache is on, in a temporary folder (``PYTHONPYCACHEPREFIX``), as in
an installed copy, even where ``PYTHONDONTWRITEBYTECODE`` is set (then every command
compiles the package's 70 modules again, about 0.1 s more each), and it holds what a
run imports before the first run, as pip's install compiles every module once: the
README's job is run once beforehand with numba's disk cache and the geometry cache in
folders of their own, deleted after it (:func:`warm_bytecode`), so that whatever a
first run imports has its bytecode, as after pip's install (a list of imports would
miss what only a first run imports).  ``--no-bytecode-cache`` leaves the environment
as it is.

``--install`` times a copy that pip installs into a virtual environment, run from the
repository's root, as the README's first command does; by default the ``lbl-illum`` on
PATH (an editable install times the checkout itself).

Usage: ``python validation/bench/commands.py [--repeat N] [--out DIR] [--install] [--no-bytecode-cache]``
(``--out`` writes ``commands.json``).  Nothing here is asserted: the figures go to the docs by hand, with
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

try:
    import resource
except ImportError:             # Windows: wall seconds only
    resource = None

ROOT = Path(__file__).resolve().parents[2]
OFFICE = ["examples/office/scene.toml", "--points", "examples/office/grid.pts"]
VIEW = "--view=-vtv -vp 2 5.5 1.5 -vd 0 -1 -0.1 -vh 80 -vv 60"


def warm_bytecode(env: dict, scratch: Path) -> None:
    """Fill the bytecode cache of ``env`` with every module a first run imports, numba's
    compiler included: the README's job, run once with numba's disk cache and the geometry
    cache in folders of ``scratch`` that are deleted afterwards."""
    kernels, geometry = scratch / "warm-numba", scratch / "warm-geometry"
    subprocess.run([*_command(), "illuminance", *OFFICE, "-o", str(scratch / "warm.csv"), "--preset", "draft", "-q"],
                   cwd=ROOT, check=True, env=dict(env, NUMBA_CACHE_DIR=str(kernels), LBL_ILLUM_CACHE_DIR=str(geometry)))
    for folder in (kernels, geometry):
        shutil.rmtree(folder, ignore_errors=True)


#: The command timed: set by ``--install`` to the copy it installs.
COMMAND: list[str] = []


def _command() -> list[str]:
    if COMMAND:
        return COMMAND
    script = shutil.which("lbl-illum")
    return [script] if script else [sys.executable, "-m", "lbl_illum"]


def install_copy(folder: Path) -> list[str]:
    """Install the repository as the README does (``pip install .``, without its
    dependencies) into a virtual environment in ``folder`` that sees this Python's
    packages; return its ``lbl-illum``.  Run from the repository's root, as the README's
    command is, this is the case where the working folder holds a second copy of the
    package (the checkout) beside the installed one."""
    venv = folder / "venv"
    subprocess.run([sys.executable, "-m", "venv", "--system-site-packages", str(venv)], check=True)
    bin_dir = venv / ("Scripts" if os.name == "nt" else "bin")
    subprocess.run([str(bin_dir / "python"), "-m", "pip", "install", "--quiet", "--no-deps", str(ROOT)], check=True,
                   stdout=subprocess.DEVNULL)
    return [str(bin_dir / "lbl-illum")]


#: CPU seconds (user + system, the command's processes) of each timed run, by wall seconds.
CPU: dict[float, float] = {}


def timed(args: list[str], env: dict | None = None) -> float:
    """Wall seconds of one command (it must succeed); its CPU seconds go to :data:`CPU`."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN) if resource else None
    t0 = time.perf_counter()
    subprocess.run(_command() + args, cwd=ROOT, env=env, check=True, stdout=subprocess.DEVNULL,
                   stderr=subprocess.DEVNULL)
    wall = time.perf_counter() - t0
    if resource:
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        CPU[wall] = after.ru_utime + after.ru_stime - before.ru_utime - before.ru_stime
    return wall


def best(args: list[str], repeat: int, env: dict | None = None) -> tuple[float, list[float]]:
    times = [timed(args, env) for _ in range(repeat)]
    return min(times), times


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeat", type=int, default=3, help="warm runs per command, best taken (default 3)")
    parser.add_argument("--out", type=Path, help="folder for commands.json")
    parser.add_argument("--install", action="store_true",
                        help="time a copy installed by pip into a virtual environment (default: the lbl-illum on PATH)")
    parser.add_argument("--no-bytecode-cache", action="store_true",
                        help="keep the environment's PYTHONDONTWRITEBYTECODE (default: a bytecode cache in a temporary folder)")
    args = parser.parse_args(argv)
    out_dir = Path(tempfile.mkdtemp(prefix="lbl-illum-bench-"))
    base = dict(os.environ)
    if not args.no_bytecode_cache:
        base.pop("PYTHONDONTWRITEBYTECODE", None)
        base["PYTHONPYCACHEPREFIX"] = str(out_dir / "pycache")
    rows = {}
    try:
        if args.install:
            COMMAND[:] = install_copy(out_dir)
        rows["help"] = best(["--help"], 5, base)
        if not args.no_bytecode_cache:      # the bytecode an installed copy has of what a run imports
            warm_bytecode(base, out_dir)
        # first run: numba's kernels and the geometry cache not on disk yet
        cold = dict(base, NUMBA_CACHE_DIR=str(out_dir / "numba"), LBL_ILLUM_CACHE_DIR=str(out_dir / "geometry"))
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
    print(f"{'command':32s} {'seconds':>8s} {'cpu':>6s}   all runs")
    for name, (seconds, runs) in rows.items():
        cpu = f"{CPU[seconds]:6.2f}" if seconds in CPU else " " * 6
        print(f"{name:32s} {seconds:8.2f} {cpu}   {' '.join(f'{t:.2f}' for t in runs)}")
    if args.out:
        args.out.mkdir(parents=True, exist_ok=True)
        report = {"machine": {"cpus": os.cpu_count(), "python": platform.python_version(),
                              "processor": platform.processor() or platform.machine(),
                              "load": os.getloadavg() if hasattr(os, "getloadavg") else None},
                  "bytecode_cache": not args.no_bytecode_cache and "PYTHONDONTWRITEBYTECODE" not in base,
                  "installed_copy": bool(args.install),
                  "seconds": {name: seconds for name, (seconds, _) in rows.items()},
                  "cpu_seconds": {name: CPU[seconds] for name, (seconds, _) in rows.items() if seconds in CPU},
                  "runs": {name: runs for name, (_, runs) in rows.items()}}
        (args.out / "commands.json").write_text(json.dumps(report, indent=2) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())

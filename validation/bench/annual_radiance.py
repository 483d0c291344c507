"""A year of daylight: ``lbl-illum annual`` against Radiance's two-phase matrix route at
equal error, whole commands on the same machine.

The office example (77 sensors) and the Oakland typical year.  The reference is Radiance's
two-phase year at the settings that converge (``validation/studies/annual_radiance.py``,
``CONVERGED``: ``-ab 11 -ad 131072 -lw 5e-7``), with the direct sun traced to each hour's
own position as ``lbl-illum annual`` does (``illuminance_exact_sun``), and that sun at
lbl_illum's solar positions (``sun="lbl_illum"``, here and in every Radiance run below):
``gendaymtx``'s own positions lie about 0.45° from the solar position algorithm's, which
moves sunlit patches' edges across sensors, a difference of convention, not of accuracy.
Then:

* ``lbl-illum annual`` at each preset, as a user types it (``--no-plots -q``; a fresh
  process, start-up included, kernels compiled by a run before);
* Radiance's two-phase at a ladder of cheaper settings, Honeybee's default
  (``-ab 2 -ad 5000 -lw 2e-5``) among them, the whole pipeline timed (export, ``oconv``,
  ``gendaymtx``, ``rcontrib``, ``dctimestep``, the direct sun).

The error of a run: the mean over the points of |its year's illuminance sum at the point /
the reference's − 1| (the occupied and unoccupied hours alike), and the largest such
difference; beside it the mean DA300 difference in percentage points.  The ratio printed
for each preset is its time over the time of the cheapest Radiance run whose error is at
most the preset's (none when no Radiance run of the ladder reaches it).

Usage: ``python validation/bench/annual_radiance.py [--out DIR]`` (``--out`` writes
``annual_radiance.json``).  Needs Radiance's programs (the pyradiance wheel).  Nothing is
asserted; the figures go to docs/annual.md by hand, with the machine they were taken on.
"""

from __future__ import annotations

import argparse
import json
import platform
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from lbl_illum import load_scene, read_points
from lbl_illum.workplane import lm83_occupancy
from lbl_illum_studies import annual_radiance

ROOT = Path(__file__).resolve().parents[2]

EPW = ROOT / "examples" / "weather" / "USA_CA_Oakland.Intl.AP.724930_TMY3.epw"
SCENE = ROOT / "examples" / "office" / "scene.toml"
POINTS = ROOT / "examples" / "office" / "grid.pts"
PRESETS = ("draft", "low", "medium")
#: (label, ab, ad, lw): Honeybee's default first, then cheaper and dearer ones.
LADDER = (("Honeybee default", 2, 5000, 2e-5), ("ab 6, ad 1024", 6, 1024, 1e-4), ("ab 11, ad 4096", 11, 4096, 2e-5),
          ("ab 11, ad 16384", 11, 16384, 4e-6), ("ab 11, ad 65536", 11, 65536, 1e-6))


def _errors(year: np.ndarray, reference: np.ndarray) -> dict:
    per_point = year.sum(axis=1) / reference.sum(axis=1) - 1.0
    occupied = lm83_occupancy() > 0
    da = (year[:, occupied] >= 300.0).mean(axis=1) * 100.0
    da_ref = (reference[:, occupied] >= 300.0).mean(axis=1) * 100.0
    return {"mean_abs": float(np.abs(per_point).mean()), "max_abs": float(np.abs(per_point).max()),
            "bias": float(year.sum() / reference.sum() - 1.0), "da_mean_abs": float(np.abs(da - da_ref).mean())}


def _ours(preset: str, tmp: Path) -> tuple[float, np.ndarray]:
    script = shutil.which("lbl-illum")
    argv = ([script] if script else [sys.executable, "-m", "lbl_illum"]) + [
        "annual", str(SCENE), "--points", str(POINTS), "--weather", str(EPW), "-o", str(tmp / preset), "--preset",
        preset, "--no-plots", "-q"]
    t0 = time.perf_counter()
    subprocess.run(argv, cwd=ROOT, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    return time.perf_counter() - t0, np.load(tmp / preset / "illuminance.npy")


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", metavar="DIR", help="write annual_radiance.json there")
    args = parser.parse_args(argv)
    if annual_radiance.unavailable():
        print(f"annual_radiance: {annual_radiance.unavailable()}", file=sys.stderr)
        return 1
    scene = load_scene(SCENE)
    points, normals = read_points(POINTS, scene.unit_scale)
    rows = []
    with tempfile.TemporaryDirectory() as folder:
        tmp = Path(folder)
        reference = annual_radiance.two_phase(SCENE, points, normals, EPW, tmp / "reference", sun="lbl_illum")
        ref = reference["illuminance_exact_sun"]
        print(f"reference: Radiance two-phase {reference['settings']}, {reference['seconds']:.1f} s")
        _ours(PRESETS[0], tmp)                         # the kernels compiled before the timed runs
        for preset in PRESETS:
            seconds, year = _ours(preset, tmp)
            rows.append({"program": "lbl-illum annual", "settings": preset, "seconds": seconds,
                         **_errors(year, ref)})
        for label, ab, ad, lw in LADDER:
            out = annual_radiance.two_phase(SCENE, points, normals, EPW, tmp / label.replace(" ", "_"), ab=ab, ad=ad,
                                            lw=lw, sun="lbl_illum")
            rows.append({"program": "Radiance two-phase", "settings": label, "seconds": out["seconds"],
                         **_errors(out["illuminance_exact_sun"], ref)})
    print(f"{'program':20s} {'settings':18s} {'seconds':>8s} {'mean |e|':>9s} {'max |e|':>8s} {'bias':>8s} "
          f"{'DA |e|':>7s}  ratio at equal error")
    radiance = [r for r in rows if r["program"].startswith("Radiance")]
    for r in rows:
        ratio = ""
        if r["program"] == "lbl-illum annual":
            able = [x["seconds"] for x in radiance if x["mean_abs"] <= r["mean_abs"]]
            r["ratio"] = r["seconds"] / min(able) if able else None
            ratio = f"{r['ratio']:.2f}" if able else "Radiance did not reach it"
        print(f"{r['program']:20s} {r['settings']:18s} {r['seconds']:8.1f} {100 * r['mean_abs']:8.2f}% "
              f"{100 * r['max_abs']:7.2f}% {100 * r['bias']:+7.2f}% {r['da_mean_abs']:7.2f}  {ratio}")
    if args.out:
        Path(args.out).mkdir(parents=True, exist_ok=True)
        doc = {"reference": {"settings": reference["settings"], "seconds": reference["seconds"]}, "rows": rows,
               "machine": {"cpus": __import__("os").cpu_count(), "python": platform.python_version()}}
        (Path(args.out) / "annual_radiance.json").write_text(json.dumps(doc, indent=2) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())

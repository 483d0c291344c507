"""Our sky matrix against Radiance's ``gendaymtx`` on a weather file: the helpers of the test
in ``test_skymatrix.py`` and, run as a script, the whole-year table of ``docs/annual-sky.md``::

    python3 tests/daylight/gendaymtx_check.py [weather.epw|.wea]

``gendaymtx`` is run with ``-h -of`` (binary float, full precision: its ASCII output has 3
digits) and ``-c 1 1 1`` (a grey sky: its default colour has brightness 0.99975); its RGB
radiance [W sr⁻¹ m⁻²] is turned into luminance by Radiance's 179 lm/W and RGB weights
(0.265, 0.670, 0.065).  Its ``-O0`` (the default) is visible radiance; ``-O1`` would be
total solar radiance.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np

from lbl_illum.daylight.skymatrix import SkyMatrix, sky_matrix, sky_patches

DATA = Path(__file__).resolve().parents[2] / "examples" / "weather"
EPW = DATA / "USA_CA_Oakland.Intl.AP.724930_TMY3.epw"
WEA = DATA / "oakland_tmy3.wea"
#: Radiance's luminous efficacy [lm/W] and RGB → luminance weights.
EFFICACY, RGB = 179.0, np.array([0.265, 0.670, 0.065])
#: Sun altitude bands [°] of the hourly table.
BANDS = ((0, 5), (5, 10), (10, 20), (20, 90))


def run_gendaymtx(tool: str, weather: Path, mf: int = 1, *options: str) -> np.ndarray:
    """(patches, hours) luminance [cd/m²] of ``gendaymtx -m mf options weather``."""
    out = subprocess.run([tool, "-h", "-of", "-c", "1", "1", "1", "-m", str(mf), *options, str(weather)],
                         capture_output=True, check=True).stdout
    rgb = np.frombuffer(out, dtype="<f4").reshape(len(sky_patches(mf)), -1, 3)
    return EFFICACY * (rgb.astype(np.float64) @ RGB)


def compare(ours: SkyMatrix, theirs: np.ndarray, samples: int = 20, seed: int = 0) -> dict:
    """Agreement of two matrices of one weather file, over the hours that are daylight in
    both: the relative difference of each hour's horizontal illuminance Σ L cos Z Ω (sky
    patches) by sun altitude band; per patch, on ``samples`` hours drawn at random, the
    largest |ΔL| / L and |ΔL| / (the column's largest L), and the median over those hours of
    each hour's largest |ΔL| / (its largest L); and the columns only
    ``gendaymtx`` lights (twilight) with their share of its yearly horizontal illuminance."""
    p = ours.patches
    weight = p.directions[p.sky, 2] * p.solid_angles[p.sky]
    e_ours, e_theirs = weight @ ours.luminance[p.sky], weight @ theirs[p.sky]
    lit = theirs.sum(axis=0) > 0
    both = ours.daylight & lit
    twilight = lit & ~ours.daylight
    rel = (e_ours[both] - e_theirs[both]) / e_theirs[both]
    alt = ours.sun_altitude[both]
    bands = {}
    for lo, hi in BANDS:
        r = np.abs(rel[(alt > lo) & (alt <= hi)])
        bands[(lo, hi)] = {"hours": len(r), "max": float(r.max()), "p95": float(np.percentile(r, 95)),
                           "mean": float(rel[(alt > lo) & (alt <= hi)].mean())}
    hours = np.random.default_rng(seed).choice(np.flatnonzero(both), samples, replace=False)
    a, b = ours.luminance[:, hours], theirs[:, hours]
    diff = np.abs(a - b)
    return {
        "hours": int(both.sum()), "only_ours": int((ours.daylight & ~lit).sum()), "twilight": int(twilight.sum()),
        "twilight_share": float(e_theirs[twilight].sum() / e_theirs.sum()),
        "max": float(np.abs(rel).max()), "p95": float(np.percentile(np.abs(rel), 95)), "mean": float(rel.mean()),
        "year": float(e_ours[both].sum() / e_theirs[both].sum() - 1.0), "bands": bands,
        "patch_max": float((diff / np.where(b > 0, b, np.inf)).max()),
        "patch_max_of_column": float((diff / b.max(axis=0)).max()),
        "patch_median_of_column": float(np.median((diff / b.max(axis=0)).max(axis=0))),
    }


def main(argv: list[str]) -> None:
    import shutil

    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
    from conftest import radiance_tool

    tool = radiance_tool("gendaymtx") or shutil.which("gendaymtx")
    if tool is None:
        sys.exit("gendaymtx not found (pip install pyradiance)")
    weather = Path(argv[0]) if argv else EPW
    print(f"{weather.name}; gendaymtx {tool}")
    print("| MF | sun | solar position | hours | hourly E_h: max | p95 | mean | year | "
          "per patch (20 h): max ΔL/L | max ΔL/L_max | median ΔL/L_max | twilight columns (share) |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    for mf in (1, 2, 4):
        for sun, options in (("patches", ()), ("separate", ("-s",))):
            theirs = run_gendaymtx(tool, weather, mf, *options)
            for position in ("gendaymtx", "auto"):
                ours = sky_matrix(weather, mf=mf, sun=sun, solar_position=position)
                c = compare(ours, theirs)
                print(f"| {mf} | {sun} | {ours.solar_position_method} | {c['hours']} | {c['max']:.2e} | "
                      f"{c['p95']:.2e} | {c['mean']:+.1e} | {c['year']:+.1e} | {c['patch_max']:.1e} | "
                      f"{c['patch_max_of_column']:.1e} | {c['patch_median_of_column']:.1e} | "
                      f"{c['twilight']} ({c['twilight_share']:.1e}) |")
                if mf == 1 and position == "auto":
                    for (lo, hi), s in c["bands"].items():
                        print(f"|   |   | sun {lo}–{hi}° | {s['hours']} | {s['max']:.2e} | {s['p95']:.2e} | "
                              f"{s['mean']:+.1e} | | | | | |")


if __name__ == "__main__":
    main(sys.argv[1:])

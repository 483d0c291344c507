"""lbl_illum side by side with Radiance's ``rtrace``: seconds against error on the same scenes.

Both programs compute illuminance at the same sensor points of the same scene, over a
ladder of quality settings each, on the same number of processes or threads (2 by
default); every run is scored against a converged reference and timed.  The question is
the one a user asks: *to get within x % of the right answer, which program is faster,
and by how much?*

**Scenes** (``--scenes``)

* ``office``: ``examples/office`` (4 × 6 × 3 m, one window, CIE overcast sky, 77
  workplane sensors).  Reference: ``validation/data/office_reference.json``, our pure
  Monte Carlo (accuracy 0: nothing interpolated), 16 seeds × 16,384 samples, 12
  bounces; standard error 0.28 % mean over the sensors.
* ``sphere-plane``: the paper's §4 scene (``examples/sphere_on_plane``: unit sphere on a
  plane, ρ = 0.7, sun at the zenith, E0 = 1000 lux, direct light plus one reflection),
  at ``SPHERE_POINTS`` points spread evenly by area over the sphere above γ = −50°.
  Reference: the closed form (upper half) and contour integral (lower half) of
  ``validation/studies/sphere_plane_reference.py``; the 10 km plane lacks < 0.03 % of E.
* ``furnished``: the office with desks, chairs, bookcases and a coffered ceiling at
  ``--triangles`` triangles (``examples/furnished_office/make_furnished_office.py``),
  generated into ``--build``.  Reference: our pure Monte Carlo, ``REFERENCE_SEEDS``
  seeds, samples per seed chosen to fit ``--reference-minutes``, 12 bounces; mean and
  standard error over the seeds, cached in
  ``validation/data/furnished_office_reference_<triangles>.json`` (``--remake-reference``
  recomputes it) together with a cross-check against a converged Radiance run
  (``RADIANCE_CHECK``: ``-aa 0``, pure Monte Carlo).

* the accuracy corpus (``validation/studies/corpus_scenes.py``: eight scenes, the deep room twice,
  each under an overcast sky and a sunny hour): ``corpus`` takes every case,
  ``corpus:NAME`` both skies of one scene, ``corpus:NAME-SKY`` one case (e.g.
  ``corpus:lbnl-open-office-overcast,corpus:cabin-sunny``).  Reference: the case's
  ``validation/data/corpus/NAME-SKY.json`` (pure Monte Carlo over independent seeds,
  ``validation/corpus_reference.py``); a case without one is skipped and listed.  Here
  both sides are what a user waits for: ours is the whole command
  ``python -m lbl_illum illuminance SCENE --points PTS -o OUT.csv FLAGS --stats S.json -q``
  from start to exit (``CORPUS_ENGINE_LADDER``: the four presets, three explicit
  ``--accuracy --samples --point-samples`` settings and pure Monte Carlo at the sample
  counts of Radiance's ``-aa 0`` runs; one untimed
  run per case first), Radiance's is ``oconv`` plus ``rtrace -ab 11 …``
  (``RADIANCE_LADDERS["corpus"]``: five (-aa, -ad) pairs, ``-aa 0`` at three -ad with the default ``-as`` and with ``-as 0``).
  Compared at ``CORPUS_ERROR_LEVELS`` (5 %, 2 %, 1 %, 0.5 %); a run on corpus cases
  only writes ``OUT/radiance-comparison-corpus/`` (``CORPUS_NAME``), so it leaves the
  classic scenes' report alone.

**Ladders** (``ENGINE_LADDERS``, ``RADIANCE_LADDERS``, ``RAD_PRESETS``; shorter on the
furnished office, where a run costs about ten office runs).  lbl_illum: the presets
(draft … high), a grid over ``accuracy`` and ``samples``, ``point_samples``, the paper's
interpolation (Eq. 5 without gradients), and pure Monte Carlo (accuracy 0) at rising
samples.  Radiance: ``rtrace -I -h -n 2`` over
``-aa`` × ``-ad`` (``-as`` = ``-ad``/2), then ``-as 0``, ``-ab`` and ``-ar`` one at a
time, pure Monte Carlo (``-aa 0``) at rising ``-ad``, and the options the ``rad``
program picks for QUALITY = LOW, MEDIUM and HIGH (a ``.rif`` with the room as an
interior ZONE, DETAIL = medium, VARIABILITY = high, INDIRECT as in ``RAD_PRESETS``; the
``rpict`` options ``rad -n -e`` prints, minus the view and picture ones).  Radiance's
``-ab`` counts the sky seen from a sensor as a bounce (the sky is a ``glow``, found by
the indirect calculation only), so ``-ab n`` follows n − 1 reflections, like our
``bounces = n − 1``.  ``-ar`` is set as ``rad`` sets it, relative to the room:
``ar = f · cube / zone`` with cube the octree's size and zone the room's mean side, so
that the smallest record radius, ``aa · cube / ar`` (Radiance's ambient.c), is
``aa · zone / f`` whatever the size of the ground around the room.  The scene goes to
Radiance through ``lbl_illum.io.radiance.export_radiance`` with ``glass = "brtdfunc"``,
our angle-independent glass exactly, so the two programs solve the same problem.

**Measured per run.**  Each run is a child process whose resources are read with
``os.wait4`` (``ru_maxrss``: the peak resident memory of the child, or of its largest
waited-for descendant — for ``rtrace -n 2``, of one of its processes, which share the
octree), started from a small launcher process (see :data:`LAUNCHER`: at least about
7 MiB is the launcher's), which also stops a run past ``--run-timeout`` seconds or
``--memory-limit`` GiB resident.  lbl_illum runs in a small worker (this file with
``--worker``) that loads the scene, warms up once on 4 points at cheap settings (numba
kernels, Embree's BVH; one untimed run of the first setting before each scene's ladder
fills numba's on-disk cache, so no timed run compiles) and then times
``Integrator(scene, options).compute(points, normals)``; its seconds are that compute
time, and the whole process's wall time (Python start-up, imports, loading, warm-up) is
reported beside it.  Radiance's seconds are the wall time of
``rtrace`` (which reads the octree itself); ``oconv`` is timed once per scene.  Errors
are relative to the reference per point: mean and max of |E/E_ref − 1| and the mean
signed error (bias).  Records: ours in all diffuse levels; Radiance's the lines of
``lookamb -d`` of the run's ``-af`` file (0 for ``-aa 0``, which keeps none).

**Equal error.**  Each program's Pareto front is the runs no faster run beats in mean
error.  The time a program needs for mean error e is interpolated on its front,
linearly in log seconds against log error between the two runs that bracket e; when
even its fastest run is within e the time is at most that run's ("≤"), and when no
run reaches e it is "not reached".  The ratio of our time to Radiance's is given at
``ERROR_LEVELS``; the target is a ratio ≤ ``TARGET_RATIO`` at every level Radiance
reaches.  Seconds on a shared machine drift by tens of percent from run to run;
ratios taken in one run on one machine are what compare.

Usage (from the repository root)::

    python validation/bench/compare_radiance.py [--out docs/performance]
        [--scenes office,sphere-plane,furnished] [--quick] [--list]
        [--triangles 1000000] [--remake-reference] [--memory-limit 6]
    python validation/bench/compare_radiance.py --scenes corpus [--run-timeout 1200]
    python validation/bench/compare_radiance.py --scenes corpus:NAME-SKY,... --merge

writes ``OUT/radiance-comparison/`` (report.md, report.html, one plot per scene,
results.json; ``radiance-comparison-corpus/`` for corpus cases only), whole or not at
all.  ``--quick``: two or three settings per program on the office only, or two per
program on the corpus cases named (under a minute on an idle machine; the full run
about two hours, the whole corpus several more).  ``--merge``: keep the cases of the
existing corpus report that this run does not measure (the corpus measured in parts).  ``--list``: print the ladders and exit.  Without
``pyradiance`` (or ``oconv`` and ``rtrace`` on the PATH) only our side runs, and the
report says so.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import shlex
import shutil
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Sequence

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
OFFICE_SCENE = ROOT / "examples" / "office" / "scene.toml"
OFFICE_POINTS = ROOT / "examples" / "office" / "grid.pts"
OFFICE_REFERENCE = ROOT / "validation" / "data" / "office_reference.json"
SPHERE_SCENE = ROOT / "examples" / "sphere_on_plane" / "scene.toml"
FURNISHED_SCRIPT = ROOT / "examples" / "furnished_office" / "make_furnished_office.py"
DATA = ROOT / "validation" / "data"
DEFAULT_BUILD = ROOT / "build" / "compare-radiance"
NAME = "radiance-comparison"
TITLE = "lbl_illum and Radiance's rtrace: seconds against error at equal accuracy"

SCENES = ("office", "sphere-plane", "furnished")
#: Mean relative errors at which the two programs' times are compared.
ERROR_LEVELS = (0.05, 0.02, 0.01)
#: Target: our time / Radiance's time at equal mean error.
TARGET_RATIO = 0.5
#: Processes (Radiance ``-n``) and threads (ours) of every run.
PROCESSES = 2
#: Points of the untimed warm-up run of our worker.
WARMUP_POINTS = 4
#: Sensor points on the sphere of the sphere-plane scene, and the lowest elevation [deg].
SPHERE_POINTS = 400
SPHERE_GAMMA_MIN = -50.0
#: Radiance's sensors on the sphere sit this far [m] off the surface along the normal, so
#: that its rays do not start exactly on it (effect on E about 1e-4 relative).
SPHERE_RADIANCE_OFFSET = 1e-4
#: The sphere-plane scene's "zone" for -ar: the sphere's bounding box [m].
SPHERE_ZONE = (-1.0, 1.0, -1.0, 1.0, 0.0, 2.0)
#: ``-lw`` of the ladder runs: Radiance's default 1e-4 cuts the deep bounces of runs with
#: many divisions (a first-level ambient ray already weighs about 0.5 / -ad).
LIMIT_WEIGHT = "1e-5"
#: The room is the box of the surfaces within this distance [m] of the sensor points' box
#: (it leaves out the ground around the building).
ZONE_MARGIN = 3.0
#: Furnished office: triangles, reference seeds, bounces and time budget [min].
FURNISHED_TRIANGLES = 1_000_000
REFERENCE_SEEDS = 16
REFERENCE_BOUNCES = 12
REFERENCE_MINUTES = 15.0
REFERENCE_SAMPLES = (1024, 16384)          # bounds on the samples per seed
#: Converged Radiance run the furnished reference is checked against.
RADIANCE_CHECK = ["-ab", str(REFERENCE_BOUNCES + 1), "-aa", "0", "-ad", "16384", "-as", "0", "-lw", LIMIT_WEIGHT]
#: Longest a single run may take [s], and most resident memory [GiB] it may hold (with
#: its child processes), before it is stopped and reported as failed.
RUN_TIMEOUT = 2700.0
MEMORY_LIMIT_GIB = 6.0
#: The accuracy corpus (``validation/studies/corpus_scenes.py``): ``--scenes corpus`` takes
#: every case, ``corpus:NAME`` both skies of one scene, ``corpus:NAME-SKY`` one case.
CORPUS = "corpus"
CORPUS_PREFIX = CORPUS + ":"
#: Mean relative errors at which the corpus cases are compared.
CORPUS_ERROR_LEVELS = (0.05, 0.02, 0.01, 0.005)
#: Report folder of a run on corpus cases only (the classic scenes' stays NAME).
CORPUS_NAME = NAME + "-corpus"


# ---------------------------------------------------------------------------
# Settings and ladders
# ---------------------------------------------------------------------------

@dataclass
class Setting:
    """One run of one program.

    program : ``"lbl_illum"`` or ``"radiance"``;  family : group in tables and plots
    label : what the table shows;  options : lbl_illum: ``Options`` fields;
    args : Radiance: the rtrace options (ambient and others) before the octree;
    lbl_illum on corpus cases: the quality flags of ``lbl-illum illuminance``
    """

    program: str
    family: str
    label: str
    options: dict = field(default_factory=dict)
    args: list = field(default_factory=list)

    @property
    def key(self) -> str:
        """What makes two settings the same run."""
        if self.program == "lbl_illum":
            return "lbl_illum " + json.dumps(self.options, sort_keys=True) + "".join(" " + a for a in self.args)
        return "radiance " + " ".join(self.args)


def engine_options(preset: str | None = None, **fields) -> dict:
    """Every ``Options`` field (defaults, then ``preset``, then ``fields``) as a dict."""
    from lbl_illum import Options

    options = Options()
    if preset is not None:
        options = options.with_preset(preset)
    return options.replace(**fields).as_dict() if fields else options.as_dict()


def engine_label(options: dict) -> str:
    """Short description of our quality options."""
    if options["accuracy"] == 0:
        text = f"accuracy 0 (Monte Carlo), {options['samples']} samples"
    else:
        text = f"a {options['accuracy']:g}, {options['samples']} samples"
        if options.get("point_samples"):
            text += f", point samples {options['point_samples']}"
        if options.get("interpolation", "gradients") != "gradients":
            text += f", {options['interpolation']} interpolation"
    return text + f", {options['bounces']} bounces"


#: Our ladders per kind of scene: presets; (accuracy, samples) with the cache from the
#: points (gradients, the paper's method); (accuracy, samples, point samples) with
#: gradients; the same with the Hessian's record domains; (accuracy, samples) with the
#: paper's interpolation; pure Monte Carlo samples.  The furnished office's is shorter:
#: each run there costs about ten office runs.
ENGINE_LADDERS = {
    "office": {"presets": ("draft", "low", "medium", "high"),
               "grid": [(0.1, 256), (0.15, 256), (0.2, 256), (0.1, 1024), (0.3, 64)],
               "point_samples": [(0.14, 256, 1024), (0.15, 128, 1024)],
               "hessian": [(0.15, 64, 512), (0.12, 128, 1024), (0.08, 128, 2048), (0.05, 256, 4096)],
               "paper": [(0.1, 256)],
               "pure": (1024, 4096, 16384)},
    # (1 M triangles: a = 0.1 with the cache from the points needs more than the 6 GiB a run may take)
    "furnished": {"presets": ("draft", "low", "medium"),
                  "grid": [(0.3, 64), (0.2, 256)],
                  "point_samples": [(0.3, 64, 1024)], "hessian": [(0.15, 64, 512)], "paper": [],
                  "pure": (1024, 4096)},
    "sphere-plane": {"presets": ("draft", "low", "medium", "high"),
                     "grid": [(a, s) for a in (0.05, 0.1, 0.2, 0.3) for s in (256, 1024)],
                     "point_samples": [], "hessian": [(0.1, 256, 0)], "paper": [(0.1, 1024), (0.2, 1024)],
                     "pure": (256, 1024, 4096)},
}
QUICK_ENGINE_LADDER = {"presets": ("draft", "medium"), "grid": [(0.3, 64)], "point_samples": [], "hessian": [],
                       "paper": [], "pure": ()}


def engine_ladder(kind: str, quick: bool = False) -> list[Setting]:
    """Our settings for a scene of ``kind`` (a key of :data:`ENGINE_LADDERS`).

    ``sphere-plane`` fixes ``bounces = 1`` (its reference is direct light plus the first
    reflection), presets included.
    """
    ladder = QUICK_ENGINE_LADDER if quick else ENGINE_LADDERS[kind]
    bounces = {"bounces": 1} if kind == "sphere-plane" else {}
    out: list[Setting] = []

    def add(family, label, options):
        out.append(Setting("lbl_illum", family, label, options=options))

    for name in ladder["presets"]:
        options = engine_options(name, **bounces)
        add("preset", f"preset {name}" + (" (bounces 1)" if bounces else ""), options)
    for a, s in ladder["grid"]:
        options = engine_options(accuracy=a, samples=s, point_samples=0, **bounces)
        add("a × samples", engine_label(options), options)
    for a, s, ps in ladder["point_samples"]:
        options = engine_options(accuracy=a, samples=s, point_samples=ps, **bounces)
        add("point samples", engine_label(options), options)
    for a, s, ps in ladder["hessian"]:
        options = engine_options(accuracy=a, samples=s, point_samples=ps, interpolation="hessian", **bounces)
        add("Hessian", engine_label(options), options)
    for a, s in ladder["paper"]:
        options = engine_options(accuracy=a, samples=s, point_samples=0, interpolation="paper", **bounces)
        add("paper interpolation", engine_label(options), options)
    for s in ladder["pure"]:
        options = engine_options(accuracy=0.0, samples=s, point_samples=0, **bounces)
        add("Monte Carlo", engine_label(options), options)
    return dedupe(out)


def rtrace_args(aa: float, ad: int, as_: int | None, ab: int, ar: int | None = None) -> list[str]:
    """rtrace ambient options ``-ab -aa -ad [-as] [-ar] -lw`` (``as_`` None: rtrace's default -as)."""
    args = ["-ab", str(ab), "-aa", f"{aa:g}", "-ad", str(ad)]
    if as_ is not None:
        args += ["-as", str(as_)]
    if ar is not None:
        args += ["-ar", str(ar)]
    return args + ["-lw", LIMIT_WEIGHT]


def ambient_resolution(f: float, cube: float, zone_size: float) -> int:
    """``-ar`` that makes the smallest record radius aa · zone_size / f, as ``rad`` does
    (``ar = f · cube / zone``; ambient.c: minarad = aa · cube / ar) [-]."""
    return max(1, int(f * cube / zone_size))


#: Diffuse bounces on corpus cases: those of every preset (lbl_illum.options.PRESETS; a test
#: keeps them equal), given to the explicit settings and, plus one, to Radiance's -ab.
CORPUS_BOUNCES = 10
#: Radiance's ladders per kind of scene: -ab of every run; (-aa, -ad) pairs at -as = -ad/2;
#: then at (-aa 0.1, -ad 1024) one change at a time: -as 0 (at these -ad), -ab, -ar (as the
#: factor f of :func:`ambient_resolution`; 8 otherwise); -aa 0 at these -ad ("pure", rtrace's
#: default -as, which adds super-samples where the first level's divisions differ most) and,
#: on corpus cases, -aa 0 -as 0 at these -ad ("pure_as0": plain Monte Carlo; on the office
#: overcast at -ad 1024 it read 3.41 % mean error in 0.72 s against 4.44 % in 1.07 s with
#: the default -as, whose super-samples bias -aa 0 low: -4.14 % against -0.34 %).
RADIANCE_LADDERS = {
    "office": {"ab": 8, "pairs": [(0.3, 256), (0.3, 512)] + [(0.2, ad) for ad in (512, 1024, 2048, 4096)]
               + [(0.1, ad) for ad in (512, 1024, 2048, 4096)] + [(0.05, ad) for ad in (512, 1024, 2048)],
               "as0": (1024, 2048), "ab_ladder": (5, 6, 7, 9), "ar_ladder": (4, 32),
               "pure": (1024, 4096, 16384, 65536), "pure_as0": ()},
    # (kept short: every run on 1 M triangles takes minutes)
    "furnished": {"ab": 8, "pairs": [(0.3, 256), (0.2, 512), (0.1, 1024)],
                  "as0": (), "ab_ladder": (), "ar_ladder": (), "pure": (1024, 4096), "pure_as0": ()},
    "sphere-plane": {"ab": 1, "pairs": [(aa, ad) for aa in (0.2, 0.1, 0.05) for ad in (256, 1024, 4096)],
                     "as0": (1024,), "ab_ladder": (), "ar_ladder": (2, 32), "pure": (256, 1024, 4096, 16384),
                     "pure_as0": ()},
    # corpus cases: -ab 11 = our presets' 10 bounces (the sky is Radiance's first); 11 runs a case
    CORPUS: {"ab": CORPUS_BOUNCES + 1, "pairs": [(0.2, 512), (0.1, 1024), (0.1, 2048), (0.05, 2048), (0.05, 4096)],
             "as0": (), "ab_ladder": (), "ar_ladder": (), "pure": (1024, 4096, 16384),
             "pure_as0": (1024, 4096, 16384)},
}
QUICK_RADIANCE_PAIRS = {"sphere-plane": [(0.2, 256), (0.1, 1024)], CORPUS: [(0.2, 512), (0.1, 1024)]}
QUICK_RADIANCE_DEFAULT = [(0.3, 256), (0.1, 1024)]
#: ``rad`` presets per kind of scene: (QUALITY, INDIRECT); LOW takes no INDIRECT.
RAD_PRESETS = {
    "office": [("LOW", 2), ("MEDIUM", 2), ("MEDIUM", 5), ("HIGH", 2), ("HIGH", 5)],
    "furnished": [("LOW", 2), ("MEDIUM", 2), ("MEDIUM", 5)],
    "sphere-plane": [],
    CORPUS: [],
}
QUICK_RAD_PRESETS = [("MEDIUM", 2)]
#: The -ar factor f of every run not on the -ar ladder.
AR_FACTOR = 8


def radiance_ladder(kind: str, cube: float, zone_size: float, quick: bool = False) -> list[Setting]:
    """Radiance's rtrace settings for a scene of ``kind`` (a key of
    :data:`RADIANCE_LADDERS`), given the octree's cube size and the zone's mean side [m]."""
    ladder = RADIANCE_LADDERS[kind]
    out: list[Setting] = []
    ab, probe = ladder["ab"], (0.1, 1024)

    def ar(f):
        return ambient_resolution(f, cube, zone_size)

    def add(family, args):
        out.append(Setting("radiance", family, " ".join(a for a in args if a not in ("-lw", LIMIT_WEIGHT)),
                           args=args))

    pairs = QUICK_RADIANCE_PAIRS.get(kind, QUICK_RADIANCE_DEFAULT) if quick else ladder["pairs"]
    for aa, ad in pairs:
        add("-aa × -ad", rtrace_args(aa, ad, ad // 2, ab, ar(AR_FACTOR)))
    if quick:
        return out
    for ad in ladder["as0"]:
        add("-as 0", rtrace_args(probe[0], ad, 0, ab, ar(AR_FACTOR)))
    for n in ladder["ab_ladder"]:
        add("-ab", rtrace_args(probe[0], probe[1], probe[1] // 2, n, ar(AR_FACTOR)))
    for f in ladder["ar_ladder"]:
        add("-ar", rtrace_args(probe[0], probe[1], probe[1] // 2, ab, ar(f)))
    for ad in ladder["pure"]:
        add("-aa 0 (Monte Carlo)", rtrace_args(0.0, ad, None, ab))
    for ad in ladder["pure_as0"]:
        add("-aa 0 -as 0 (Monte Carlo)", rtrace_args(0.0, ad, 0, ab))
    return dedupe(out)


#: Our ladder on corpus cases, as ``lbl-illum illuminance`` flags: the presets, explicit
#: (accuracy, samples, point samples) below and above them (the command's defaults
#: otherwise: gradients interpolation; CORPUS_BOUNCES bounces), pure Monte Carlo samples.
CORPUS_ENGINE_LADDER = {"presets": ("draft", "low", "medium", "high"),
                        "explicit": [(0.3, 64, 512), (0.2, 64, 512), (0.08, 256, 4096)],
                        "pure": RADIANCE_LADDERS[CORPUS]["pure"]}      # Monte Carlo at the samples Radiance's -ad takes
QUICK_CORPUS_ENGINE_LADDER = {"presets": ("draft", "medium"), "explicit": [], "pure": ()}
#: Cheap settings of the other kinds run untimed before the first corpus case, so that no
#: timed run compiles a kernel (numba's on-disk cache) whatever the first setting is.
CORPUS_PRIMERS = (["--accuracy", "0.3", "--samples", "16", "--point-samples", "16"],
                  ["--accuracy", "0", "--samples", "16", "--point-samples", "0"])


def explicit_flags(accuracy: float, samples: int, point_samples: int) -> list[str]:
    """``lbl-illum illuminance`` quality flags of an explicit setting."""
    return ["--accuracy", f"{accuracy:g}", "--samples", str(samples), "--point-samples", str(point_samples),
            "--bounces", str(CORPUS_BOUNCES)]


def corpus_engine_ladder(quick: bool = False) -> list[Setting]:
    """Our settings on a corpus case: each the quality flags of one whole command
    (:func:`engine_command`)."""
    ladder = QUICK_CORPUS_ENGINE_LADDER if quick else CORPUS_ENGINE_LADDER
    out = [Setting("lbl_illum", "preset", f"preset {p}", args=["--preset", p]) for p in ladder["presets"]]
    for a, s, ps in ladder["explicit"]:
        flags = explicit_flags(a, s, ps)
        out.append(Setting("lbl_illum", "options", " ".join(flags), args=flags))
    for s in ladder["pure"]:
        flags = explicit_flags(0.0, s, 0)
        out.append(Setting("lbl_illum", "Monte Carlo", " ".join(flags) + " (Monte Carlo)", args=flags))
    return dedupe(out)


def engine_command(scene: Path, points: Path, output: Path, stats: Path, flags: Sequence[str]) -> list[str]:
    """The whole command a user types: ``python -m lbl_illum illuminance SCENE --points
    PTS -o OUT.csv FLAGS --stats STATS.json -q``."""
    return [sys.executable, "-m", "lbl_illum", "illuminance", str(scene), "--points", str(points), "-o",
            str(output), *flags, "--stats", str(stats), "-q"]


def read_illuminance_csv(path: Path) -> np.ndarray:
    """Column ``illuminance`` [lux] of the command's CSV output
    (``x,y,z,nx,ny,nz,illuminance,direct,indirect[,area]``)."""
    import csv

    with open(path, newline="", encoding="utf-8") as f:
        rows = list(csv.reader(f))
    if not rows or "illuminance" not in rows[0]:
        raise ValueError(f"{Path(path).name}: no 'illuminance' column in the header")
    k = rows[0].index("illuminance")
    return np.array([float(r[k]) for r in rows[1:] if r], float)


def dedupe(settings: Sequence[Setting]) -> list[Setting]:
    """``settings`` without repeats (the first of each kept)."""
    seen, out = set(), []
    for s in settings:
        if s.key not in seen:
            seen.add(s.key)
            out.append(s)
    return out


# ---------------------------------------------------------------------------
# rad: the options of its quality presets
# ---------------------------------------------------------------------------

#: rpict options and their argument counts.  Kept: what rtrace understands the same way.
RPICT_KEEP = {"-dp": 1, "-ds": 1, "-dt": 1, "-dc": 1, "-dr": 1, "-dj": 1, "-ss": 1, "-st": 1, "-ms": 1,
              "-ab": 1, "-aa": 1, "-ad": 1, "-as": 1, "-ar": 1, "-av": 3, "-aw": 1, "-lr": 1, "-lw": 1}
#: Dropped: the view, the picture, reporting and our own ambient file.
RPICT_DROP = {"-vp": 3, "-vd": 3, "-vu": 3, "-vh": 1, "-vv": 1, "-vo": 1, "-va": 1, "-vs": 1, "-vl": 1,
              "-vf": 1, "-x": 1, "-y": 1, "-ps": 1, "-pt": 1, "-pj": 1, "-pa": 1, "-pm": 1, "-pd": 1,
              "-t": 1, "-e": 1, "-S": 1, "-PP": 1, "-af": 1, "-o": 1, "-z": 1, "-r": 1, "-ro": 1}


def rad_rtrace_options(rad_output: str) -> list[str]:
    """The rtrace options of the ``rpict`` command in ``rad -n -e`` output: the rendering
    options (``-d* -s* -a* -l* -ms``) in their order, without the view (``-vt* -vp …``),
    the picture (``-x -y -p*``), reports and the ambient file.  Raises ValueError when
    there is no rpict command or an option is unknown."""
    for line in rad_output.splitlines():
        words = shlex.split(line.strip())
        if words and os.path.basename(words[0]) == "rpict":
            break
    else:
        raise ValueError("no rpict command in the rad output")
    if ">" in words:
        words = words[:words.index(">")]
    words = words[1:-1]                      # the last word is the octree
    out, i = [], 0
    while i < len(words):
        w = words[i]
        if w in RPICT_KEEP:
            n = RPICT_KEEP[w]
            out += words[i:i + 1 + n]
        elif w in RPICT_DROP:
            n = RPICT_DROP[w]
        elif w.startswith("-vt") or w in ("-i", "-i+", "-i-", "-u", "-u+", "-u-", "-w", "-w+", "-w-"):
            n = 0
        else:
            raise ValueError(f"unknown rpict option {w!r} in the rad output")
        if i + 1 + n > len(words):
            raise ValueError(f"rpict option {w!r} lacks its {n} argument(s)")
        i += 1 + n
    return out


def rif_text(zone: Sequence[float], scene_files: Sequence[str], octree: str, quality: str,
             indirect: int) -> str:
    """A ``rad`` input file for an interior zone (x0 x1 y0 y1 z0 z1 [m]) at QUALITY
    ``quality``, DETAIL medium, VARIABILITY high (daylight: bright sky, dim corners),
    INDIRECT ``indirect``, no penumbras (no light sources with area but the sun)."""
    return (f"ZONE= I {' '.join(f'{v:.6g}' for v in zone)}\n"
            f"scene= {' '.join(scene_files)}\n"
            f"OCTREE= {octree}\n"
            f"QUALITY= {quality}\nDETAIL= medium\nVARIABILITY= high\nINDIRECT= {indirect}\nPENUMBRAS= F\n")


def rad_settings(programs: dict, export, zone, presets: Sequence[tuple[str, int]]) -> list[Setting]:
    """Settings with the options ``rad`` picks for each (QUALITY, INDIRECT) of ``presets``
    (LOW ignores INDIRECT)."""
    rad = Path(programs["bin"]["rtrace"]).parent / "rad"
    if not rad.is_file():
        found = shutil.which("rad")
        if not found:
            return []
        rad = Path(found)
    env = dict(programs["env"])
    env["PATH"] = os.pathsep.join([str(rad.parent), env.get("PATH", "")])
    out = []
    for quality, indirect in presets:
        rif = export.directory / f"bench_{quality.lower()}_{indirect}.rif"
        rif.write_text(rif_text(zone, export.scene_files, export.octree, quality, indirect))
        run = subprocess.run([str(rad), "-n", "-e", rif.name], cwd=export.directory, env=env,
                             capture_output=True, text=True)
        if run.returncode != 0:
            raise RuntimeError(f"rad {rif.name}: {run.stderr.strip()[-200:]}")
        args = rad_rtrace_options(run.stdout)
        name = f"rad QUALITY={quality}" + ("" if quality == "LOW" else f", INDIRECT={indirect}")
        out.append(Setting("radiance", "rad presets", name, args=args))
    return out


# ---------------------------------------------------------------------------
# Running a child process and reading its resources
# ---------------------------------------------------------------------------

@dataclass
class Measured:
    """A finished child process: exit code, wall seconds, peak resident memory [KiB]
    (``ru_maxrss``), its standard output and error, and why it was stopped, if it was."""

    returncode: int
    seconds: float
    maxrss_kib: int
    stdout: bytes
    stderr: str
    stopped: str | None = None      # "timeout" or "memory" when the launcher killed it


#: The launcher of every measured child: a bare Python (``-S``: no site packages) that
#: forks, executes the command and waits for it with ``os.wait4``.  Linux counts into a
#: process's ``ru_maxrss`` the resident memory of the process image an ``exec`` replaces,
#: so a child forked straight from this (large) process would report at least this
#: process's own memory; forked from the launcher it reports at least the launcher's,
#: about 7 MiB.  ``rtrace -n 2`` runs its work in child processes that ``ru_maxrss`` of
#: the command does not always include, so the launcher also samples the resident memory
#: of the command and its children every 0.05 s and reports the larger figure.
LAUNCHER = r"""
import json, os, signal, sys, threading, time
spec = json.loads(sys.stdin.read())
def opened(path, flags):
    return os.open(path or os.devnull, flags, 0o666)
t0 = time.perf_counter()
pid = os.fork()
if pid == 0:
    try:
        if spec["cwd"]:
            os.chdir(spec["cwd"])
        fds = (opened(spec["stdin"], os.O_RDONLY), opened(spec["stdout"], os.O_WRONLY | os.O_CREAT | os.O_TRUNC),
               opened(spec["stderr"], os.O_WRONLY | os.O_CREAT | os.O_TRUNC))
        for target, fd in enumerate(fds):
            os.dup2(fd, target)
        os.execvpe(spec["cmd"][0], spec["cmd"], spec["env"] if spec["env"] is not None else os.environ)
    except BaseException as exc:
        os.write(2, ("cannot run %s: %s\n" % (spec["cmd"][0], exc)).encode())
    os._exit(127)
why = []
def stop(reason):
    why.append(reason)
    try:
        os.kill(pid, signal.SIGKILL)
    except ProcessLookupError:
        pass
def rss_kib(p):
    try:
        with open("/proc/%d/status" % p) as f:
            for line in f:
                if line.startswith("VmRSS:"):
                    return int(line.split()[1])
    except (OSError, ValueError):
        pass
    return 0
def children(p):
    try:
        with open("/proc/%d/task/%d/children" % (p, p)) as f:
            return [int(c) for c in f.read().split()]
    except (OSError, ValueError):
        return []
peak = [0]
def watch():
    limit, timeout = spec["memory_kib"], spec["timeout"]
    while not done.wait(0.05):
        if timeout and time.perf_counter() - t0 > timeout:
            return stop("timeout")
        total = rss_kib(pid) + sum(rss_kib(c) for c in children(pid))
        peak[0] = max(peak[0], total)
        if limit and total > limit:
            return stop("memory")
done = threading.Event()
threading.Thread(target=watch, daemon=True).start()
_, status, usage = os.wait4(pid, 0)
seconds = time.perf_counter() - t0
done.set()
print(json.dumps({"returncode": os.waitstatus_to_exitcode(status), "seconds": seconds,
                  "maxrss_kib": max(usage.ru_maxrss, peak[0]), "stopped": why[0] if why else None}))
"""


def run_measured(cmd: Sequence[str], cwd=None, env=None, stdin=None, stdout_path=None,
                 timeout: float | None = RUN_TIMEOUT, memory_gib: float | None = MEMORY_LIMIT_GIB) -> Measured:
    """Run ``cmd`` through :data:`LAUNCHER`: its wall time from start to exit and its
    resource usage from ``os.wait4`` (on Linux ``ru_maxrss`` is in KiB).  ``stdin`` is a
    file to read, ``stdout_path`` a file to write (else standard output is returned).
    The launcher kills the command when it runs longer than ``timeout`` seconds or when
    its resident memory with its children's exceeds ``memory_gib`` GiB (sampled every
    0.1 s); :attr:`Measured.stopped` then says which."""
    with tempfile.TemporaryDirectory(prefix="compare-radiance-") as tmp:
        out = Path(stdout_path) if stdout_path is not None else Path(tmp) / "stdout"
        err = Path(tmp) / "stderr"
        spec = {"cmd": [str(c) for c in cmd], "cwd": str(cwd) if cwd is not None else None,
                "env": dict(env) if env is not None else None, "stdin": str(stdin) if stdin is not None else None,
                "stdout": str(out), "stderr": str(err), "timeout": timeout,
                "memory_kib": int(memory_gib * 1024 * 1024) if memory_gib else None}
        launched = subprocess.run([sys.executable, "-S", "-c", LAUNCHER], input=json.dumps(spec),
                                  capture_output=True, text=True)
        if launched.returncode != 0:
            raise RuntimeError(f"launcher failed: {launched.stderr.strip()[-300:]}")
        doc = json.loads(launched.stdout)
        stdout = out.read_bytes() if stdout_path is None else b""
        stderr = err.read_text("utf-8", "replace") if err.exists() else ""
    return Measured(int(doc["returncode"]), float(doc["seconds"]), int(doc["maxrss_kib"]), stdout, stderr,
                    doc.get("stopped"))


def failure(m: Measured) -> str:
    """Why a measured run failed, in one line."""
    if m.stopped == "memory":
        return "stopped: over the memory limit"
    if m.stopped == "timeout":
        return "stopped: over the time limit"
    return f"exit code {m.returncode}: {m.stderr.strip()[-300:]}"


def count_ambient_records(lookamb_text: str) -> int:
    """Records in ``lookamb -h -d`` output: one non-empty line each."""
    return sum(1 for line in lookamb_text.splitlines() if line.strip())


def parse_worker_output(text: str) -> dict:
    """The JSON summary our worker prints as its last non-empty line."""
    lines = [line for line in text.splitlines() if line.strip()]
    if not lines:
        raise ValueError("the worker printed nothing")
    doc = json.loads(lines[-1])
    missing = {"seconds", "rays", "records"} - set(doc)
    if missing:
        raise ValueError(f"the worker's summary lacks {', '.join(sorted(missing))}")
    return doc


def warmup_options(options: dict) -> dict:
    """Cheap settings of the same kind as ``options`` for the untimed warm-up: the same
    interpolation and accuracy 0 or not, at most 64 samples and 2 bounces."""
    warm = dict(options)
    warm["samples"] = min(options["samples"], 64)
    warm["bounces"] = min(options["bounces"], 2)
    if options.get("point_samples"):
        warm["point_samples"] = min(options["point_samples"], 64)
    if options["accuracy"] > 0:
        warm["accuracy"] = max(options["accuracy"], 0.3)
    return warm


def worker(spec_path: str) -> int:
    """Child process of one lbl_illum run: load the scene and points, warm up on
    ``WARMUP_POINTS`` points at :func:`warmup_options`, then time
    ``Integrator(scene, options).compute(points, normals)``.  Saves the illuminance
    [lux] to ``spec["output"]`` (.npy) and prints a JSON summary line."""
    spec = json.loads(Path(spec_path).read_text())
    t_start = time.perf_counter()
    from lbl_illum import Integrator, Options, load_scene, read_points

    scene = load_scene(spec["scene"])
    points, normals = read_points(spec["points"], scene.unit_scale)
    t_loaded = time.perf_counter()
    options = Options(**spec["options"])
    Integrator(scene, Options(**warmup_options(spec["options"]))).compute(points[:WARMUP_POINTS],
                                                                       normals[:WARMUP_POINTS])
    t0 = time.perf_counter()
    result = Integrator(scene, options).compute(points, normals)
    seconds = time.perf_counter() - t0
    np.save(spec["output"], result.illuminance)
    stats = result.stats
    print(json.dumps({"seconds": seconds, "load_seconds": t_loaded - t_start, "warmup_seconds": t0 - t_loaded,
                      "rays": int(stats.rays), "records": [int(r) for r in stats.records],
                      "primary_evaluations": int(stats.primary_evaluations)}))
    return 0


# ---------------------------------------------------------------------------
# Pareto fronts and time at equal error
# ---------------------------------------------------------------------------

def pareto_front(seconds: Sequence[float], errors: Sequence[float]) -> list[int]:
    """Indices of the runs on the front of seconds against error, fastest first: each
    has a lower error than every faster run (ties in seconds: the lower error first).
    Runs with a missing or non-finite value are left out."""
    ok = [i for i in range(len(seconds))
          if seconds[i] is not None and errors[i] is not None
          and math.isfinite(seconds[i]) and math.isfinite(errors[i]) and seconds[i] > 0 and errors[i] > 0]
    front, best = [], math.inf
    for i in sorted(ok, key=lambda i: (seconds[i], errors[i])):
        if errors[i] < best:
            front.append(i)
            best = errors[i]
    return front


def time_at_error(front: Sequence[tuple[float, float]], level: float) -> tuple[float | None, str]:
    """Seconds a program needs for mean error ``level``, from its Pareto front given as
    (seconds, error) pairs, fastest (largest error) first.

    Returns ``(seconds, "interpolated")`` between the two runs that bracket ``level``
    (linear in log seconds against log error), ``(seconds of the fastest run, "at most")``
    when the fastest run is already within ``level``, ``(None, "not reached")`` when no
    run is, and ``(None, "no runs")`` for an empty front.
    """
    if not front:
        return None, "no runs"
    if level > front[0][1]:
        return front[0][0], "at most"
    if level < front[-1][1]:
        return None, "not reached"
    for (s0, e0), (s1, e1) in zip(front[:-1], front[1:]):
        if e1 <= level <= e0:
            if level == e0:
                return s0, "interpolated"
            if level == e1:
                return s1, "interpolated"
            t = math.log(level / e0) / math.log(e1 / e0)
            return math.exp(math.log(s0) + t * (math.log(s1) - math.log(s0))), "interpolated"
    return front[0][0], "interpolated"        # one-run front with level == its error


def compare_at(ours: Sequence[tuple[float, float]], theirs: Sequence[tuple[float, float]], level: float,
               target: float = TARGET_RATIO) -> dict:
    """Our time over Radiance's at mean error ``level``, each from its front.

    ``relation`` is "=" when both times are interpolated, "≤" when ours is an upper
    bound, "≥" when Radiance's is, None when undetermined.  ``verdict``: "met" (ratio
    ≤ target), "missed", "undetermined" (the bounds do not decide it) or "n/a" (Radiance
    does not reach ``level``)."""
    o_s, o_k = time_at_error(ours, level)
    r_s, r_k = time_at_error(theirs, level)
    out = {"level": level, "ours_seconds": o_s, "ours_kind": o_k, "radiance_seconds": r_s,
           "radiance_kind": r_k, "ratio": None, "relation": None}
    if r_s is None:
        out["verdict"] = "n/a"
        return out
    if o_s is None:
        out["verdict"] = "missed"
        return out
    ratio = o_s / r_s
    out["ratio"] = ratio
    if o_k == "interpolated" and r_k == "interpolated":
        out["relation"], out["verdict"] = "=", ("met" if ratio <= target else "missed")
    elif o_k == "at most" and r_k == "interpolated":
        out["relation"], out["verdict"] = "≤", ("met" if ratio <= target else "undetermined")
    elif o_k == "interpolated" and r_k == "at most":
        out["relation"], out["verdict"] = "≥", ("missed" if ratio > target else "undetermined")
    else:
        out["verdict"] = "undetermined"
    return out


def ratio_text(c: dict) -> str:
    """A :func:`compare_at` result as the report prints its ratio."""
    if c["ratio"] is None:
        if c["verdict"] == "n/a":
            return "Radiance not reached"
        return "lbl_illum not reached"
    value = f"{c['ratio']:.2f}"
    if c["relation"] in ("≤", "≥"):
        return f"{c['relation']} {value}"
    if c["relation"] is None:
        return f"({value}: both ladders start below)"
    return value


def short_ratio(c: dict) -> str:
    """A :func:`compare_at` result in a few characters, for the summary line."""
    if c["ratio"] is None:
        return "Radiance-n.r." if c["verdict"] == "n/a" else "ours-n.r."
    if c["relation"] is None:
        return "?"
    return ("" if c["relation"] == "=" else c["relation"]) + f"{c['ratio']:.2f}"


def seconds_text(seconds: float | None, kind: str) -> str:
    if seconds is None:
        return kind
    return ("≤ " if kind == "at most" else "") + f"{seconds:.3g}"


def run_table(runs: Sequence[dict]) -> tuple[list[str], list[list]]:
    """Header and rows of a scene's table of runs: program, family, setting, seconds
    (ours: compute), whole-process seconds, peak memory, errors, records, rays, and
    whether the run is on its program's Pareto front (★)."""
    header = ["program", "family", "setting", "seconds", "process s", "peak MiB", "mean error", "max error",
              "bias", "records", "rays", "front"]
    rows = []
    for r in runs:
        if r.get("failed"):
            rows.append([r["program"], r["family"], r["label"], "failed", "—", "—", "—", "—", "—", "—", "—", ""])
            continue
        rows.append([r["program"], r["family"], r["label"], f"{r['seconds']:.3g}", f"{r['process_seconds']:.3g}",
                     f"{r['maxrss_kib'] / 1024:.0f}", pct(r["mean_error"]), pct(r["max_error"]), pct(r["bias"]),
                     "—" if r.get("records") is None else f"{r['records']:,}",
                     "—" if r.get("rays") is None else f"{r['rays']:,}", "★" if r.get("front") else ""])
    return header, rows


def pct(value, digits: int = 2) -> str:
    if value is None or not math.isfinite(value):
        return "—"
    return f"{100.0 * value:.{digits}f} %"


def front_pairs(runs: Sequence[dict], program: str, key: str = "seconds") -> list[tuple[float, float]]:
    """(seconds, mean error) of ``program``'s Pareto front in ``runs`` (marking its runs
    ``front`` when ``key`` is "seconds")."""
    mine = [r for r in runs if r["program"] == program and not r.get("failed")]
    idx = pareto_front([r[key] for r in mine], [r["mean_error"] for r in mine])
    if key == "seconds":
        for k, r in enumerate(mine):
            r["front"] = k in idx
    return [(mine[i][key], mine[i]["mean_error"]) for i in idx]


# ---------------------------------------------------------------------------
# Scenes and references
# ---------------------------------------------------------------------------

@dataclass
class Bench:
    """One scene of the comparison: files, points, reference [lux] and how it was made."""

    name: str
    title: str
    kind: str                     # a key of ENGINE_LADDERS and RADIANCE_LADDERS
    scene_path: Path
    points_path: Path
    points: np.ndarray
    normals: np.ndarray
    reference: np.ndarray
    reference_info: dict
    zone: tuple | None = None
    radiance_offset: float = 0.0
    notes: list = field(default_factory=list)


def room_zone(triangles, points, margin: float = ZONE_MARGIN) -> tuple:
    """(x0, x1, y0, y1, z0, z1) [m]: the box of the triangles that lie wholly within
    ``margin`` of the sensor points' box (the room, without the ground around it)."""
    lo, hi = points.min(axis=0) - margin, points.max(axis=0) + margin
    v = triangles.vertices
    inside = np.all((v >= lo) & (v <= hi), axis=(1, 2))
    if not np.any(inside):
        box_lo, box_hi = points.min(axis=0), points.max(axis=0)
    else:
        box_lo, box_hi = v[inside].reshape(-1, 3).min(axis=0), v[inside].reshape(-1, 3).max(axis=0)
    return tuple(float(x) for pair in zip(box_lo, box_hi) for x in pair)


def prepare_office() -> Bench:
    from lbl_illum import load_scene, read_points

    scene = load_scene(OFFICE_SCENE)
    points, normals = read_points(OFFICE_POINTS, scene.unit_scale)
    doc = json.loads(OFFICE_REFERENCE.read_text())
    reference = np.asarray(doc["illuminance"], float)
    if len(reference) != len(points):
        raise SystemExit(f"{OFFICE_REFERENCE.name}: {len(reference)} values for {len(points)} points")
    rse = np.asarray(doc["standard_error"], float) / reference
    info = {"method": f"{doc['method']}: {doc['seeds']} seeds × {doc['samples']:,} samples, {doc['bounces']} bounces",
            "file": "validation/data/office_reference.json", "standard_error_mean": float(rse.mean()),
            "standard_error_max": float(rse.max())}
    return Bench("office", "Side-lit office (examples/office), CIE overcast sky, 77 sensors", "office",
                 OFFICE_SCENE, OFFICE_POINTS, points, normals, reference, info,
                 zone=room_zone(scene.triangles, points))


def prepare_sphere_plane(build: Path, n: int = SPHERE_POINTS) -> Bench:
    """The §4 scene with ``n`` points over γ ≥ ``SPHERE_GAMMA_MIN`` (a Fibonacci spiral,
    uniform by area) and the closed-form / contour-integral reference."""
    from lbl_illum_studies import sphere_plane, sphere_plane_reference as ref

    points, normals = sphere_plane.sphere_points(n, SPHERE_GAMMA_MIN)
    gamma = np.radians(sphere_plane.elevation(normals))
    reference = ref.illuminance(gamma)
    folder = build / "sphere-plane"
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / "points.pts"
    body = "".join("%.12g %.12g %.12g %.12g %.12g %.12g\n" % tuple(r) for r in np.hstack([points, normals]).tolist())
    path.write_text(f"# {n} points on the unit sphere centred (0, 0, 1), elevation >= {SPHERE_GAMMA_MIN:g} deg\n"
                    + body)
    deficit = ref.truncation_deficit(gamma, sphere_plane.HALF_WIDTH) / reference
    quad = ref.quadrature_error(gamma)
    info = {"method": "closed form (upper half) and contour integral (lower half), direct light plus the first "
                      "reflection (validation/studies/sphere_plane_reference.py)",
            "standard_error_mean": 0.0, "standard_error_max": 0.0,
            "plane_truncation_max": float(deficit.max()), "quadrature_error_max": float(quad.max())}
    return Bench("sphere-plane", f"Sphere on a plane (the paper's §4), sun at the zenith, {n} points on the sphere",
                 "sphere-plane", SPHERE_SCENE, path, points, normals, reference, info, zone=SPHERE_ZONE,
                 radiance_offset=SPHERE_RADIANCE_OFFSET)


def furnished_reference_path(triangles: int) -> Path:
    return DATA / f"furnished_office_reference_{triangles}.json"


def prepare_furnished(build: Path, triangles: int, remake: bool, minutes: float, programs, say) -> Bench:
    """Generate the furnished office (unless already in ``build``) and load or make its
    reference (:func:`make_furnished_reference`)."""
    from lbl_illum import load_scene, read_points

    folder = build / f"furnished-{triangles}"
    if not (folder / "scene.toml").is_file() or not (folder / "grid.pts").is_file():
        say(f"generating the furnished office ({triangles:,} triangles)")
        run = subprocess.run([sys.executable, str(FURNISHED_SCRIPT), "--triangles", str(triangles), "--out",
                              str(folder)], capture_output=True, text=True)
        if run.returncode != 0:
            raise SystemExit(f"{FURNISHED_SCRIPT.name}: {(run.stderr.strip().splitlines() or ['failed'])[-1]}")
    scene = load_scene(folder / "scene.toml")
    points, normals = read_points(folder / "grid.pts", scene.unit_scale)
    path = furnished_reference_path(triangles)
    doc = None
    if path.is_file() and not remake:
        doc = json.loads(path.read_text())
        if len(doc["illuminance"]) != len(points) or doc.get("triangles") != len(scene.triangles):
            say(f"{path.name} does not match the generated scene: remaking it")
            doc = None
    from lbl_illum.io import atomic_write_text

    if doc is None:
        doc = make_furnished_reference(scene, points, normals, folder, minutes, programs, say)
        atomic_write_text(path, json.dumps(doc, indent=1) + "\n")
    elif programs is not None and not doc.get("radiance_check"):
        say("furnished reference: converged Radiance cross-check")
        doc["radiance_check"] = radiance_difference(scene, points, normals, folder, programs,
                                                    np.asarray(doc["illuminance"], float))
        atomic_write_text(path, json.dumps(doc, indent=1) + "\n")
    reference = np.asarray(doc["illuminance"], float)
    rse = np.asarray(doc["standard_error"], float) / reference
    info = {"method": f"{doc['method']}: {doc['seeds']} seeds × {doc['samples']:,} samples, {doc['bounces']} bounces, "
                      f"{doc['seconds'] / 60:.1f} min",
            "file": f"validation/data/{path.name}", "standard_error_mean": float(rse.mean()),
            "standard_error_max": float(rse.max()), "radiance_check": doc.get("radiance_check")}
    return Bench("furnished", f"Furnished office, {len(scene.triangles):,} triangles, 77 sensors", "furnished",
                 folder / "scene.toml", folder / "grid.pts", points, normals, reference, info,
                 zone=room_zone(scene.triangles, points))


def corpus_module():
    """``lbl_illum_studies.corpus_scenes`` (the corpus's scenes, skies and references)."""
    from lbl_illum_studies import corpus_scenes

    return corpus_scenes


def corpus_case_names() -> list[str]:
    """Every corpus case, ``NAME-SKY``, in the corpus's order."""
    return [f"{scene.name}-{sky}" for scene, sky in corpus_module().cases()]


def corpus_case(case: str):
    """(CorpusScene, sky) of case ``NAME-SKY``; ValueError naming an unknown one."""
    corpus = corpus_module()
    for scene, sky in corpus.cases():
        if case == f"{scene.name}-{sky}":
            return scene, sky
    raise ValueError(f"--scenes: unknown corpus case {case!r} (cases are NAME-SKY: "
                     f"{', '.join(corpus_case_names())})")


def corpus_bench(name: str, title: str, scene_path: Path, points_path: Path, reference_file: Path,
                 info: dict | None = None) -> Bench:
    """A corpus case as a :class:`Bench`: the scene and points files as the command
    reads them and the reference of ``reference_file`` (``illuminance`` per point [lux],
    ``standard_error``, ``relative_standard_error``, ``seeds``, ``method``, ``estimator``).
    ValueError when the reference is unreadable or does not match the points."""
    from lbl_illum import load_scene, read_points

    scene = load_scene(scene_path)
    points, normals = read_points(points_path, scene.unit_scale)
    try:
        doc = json.loads(Path(reference_file).read_text())
        reference = np.asarray(doc["illuminance"], float)
    except (OSError, ValueError, KeyError) as exc:
        raise ValueError(f"{Path(reference_file).name}: unreadable reference ({exc})") from exc
    if reference.shape != (len(points),) or not np.all(np.isfinite(reference)) or np.any(reference <= 0):
        raise ValueError(f"{Path(reference_file).name}: {reference.size} reference values for {len(points)} points "
                         "(or not all positive)")
    rse = doc.get("relative_standard_error") or {}
    if "standard_error" in doc and not rse:
        se = np.asarray(doc["standard_error"], float) / reference
        rse = {"mean": float(se.mean()), "max": float(se.max())}
    est = doc.get("estimator") or {}
    method = doc.get("method", "reference")
    if est:
        method += " (" + ", ".join(f"{k.replace('_', ' ')} {v:,}" if isinstance(v, int) else f"{k} {v}"
                                   for k, v in est.items()) + ")"
    if doc.get("seeds"):
        method += f"; {doc['seeds']} seeds"
    try:
        shown = str(Path(reference_file).resolve().relative_to(ROOT))
    except ValueError:
        shown = str(reference_file)
    full = {"method": method, "file": shown, "standard_error_mean": float(rse.get("mean", 0.0)),
            "standard_error_max": float(rse.get("max", 0.0)), "seeds": doc.get("seeds"), "estimator": est,
            "seconds": doc.get("seconds"), **(info or {})}
    return Bench(name, title, CORPUS, Path(scene_path), Path(points_path), points, normals, reference, full,
                 zone=room_zone(scene.triangles, points))


def shown_path(path: Path) -> str:
    """``path`` as a report shows it: relative to the repository when inside it (a
    report names no machine's folders)."""
    path = Path(path).resolve()
    return path.relative_to(ROOT).as_posix() if path.is_relative_to(ROOT) else path.name


def prepare_corpus(case: str) -> Bench | str:
    """The corpus case ``NAME-SKY`` as a :class:`Bench`, or why it is skipped (no
    reference yet, or one that does not match the scene)."""
    corpus = corpus_module()
    scene, sky = corpus_case(case)
    ref = corpus.reference_path(scene, sky)
    if not ref.is_file():
        return f"no reference yet ({ref.relative_to(ROOT) if ref.is_relative_to(ROOT) else ref} is missing)"
    try:
        files, points = corpus.prepare(scene)
        info = {"role": scene.role, "source": scene.source, "description": scene.description, "sky": sky,
                "scene_file": shown_path(files[sky])}
        return corpus_bench(case, f"{case}: {scene.description}, {sky} sky", files[sky], points, ref, info)
    except (ValueError, OSError, subprocess.CalledProcessError) as exc:
        return f"cannot be prepared: {exc}"


def make_furnished_reference(scene, points, normals, folder: Path, minutes: float, programs, say) -> dict:
    """Our pure Monte Carlo (accuracy 0) at ``REFERENCE_BOUNCES`` bounces over
    ``REFERENCE_SEEDS`` seeds: the mean per point, and its standard error (the runs'
    standard deviation / √seeds).  The samples per seed are the largest power of 2 in
    ``REFERENCE_SAMPLES`` that fits ``minutes`` after a timing run at 256 samples.
    Then the converged Radiance run ``RADIANCE_CHECK`` and its difference from the mean."""
    from lbl_illum import Options, compute_illuminance

    t_start = time.perf_counter()
    probe = compute_illuminance(scene, points, normals,
                                Options(accuracy=0.0, samples=256, bounces=REFERENCE_BOUNCES, seed=999))
    per_sample = probe.stats.seconds / 256
    budget = 60.0 * minutes * 0.75 / REFERENCE_SEEDS         # leave a quarter for the Radiance check
    samples = REFERENCE_SAMPLES[0]
    while samples * 2 <= REFERENCE_SAMPLES[1] and samples * 2 * per_sample <= budget:
        samples *= 2
    runs, rays = [], int(probe.stats.rays)
    for k in range(REFERENCE_SEEDS):
        say(f"furnished reference: seed {k + 1}/{REFERENCE_SEEDS}, {samples:,} samples")
        result = compute_illuminance(scene, points, normals, Options(accuracy=0.0, samples=samples,
                                                                     bounces=REFERENCE_BOUNCES, seed=1000 + k))
        runs.append(result.illuminance)
        rays += int(result.stats.rays)
    runs = np.array(runs)
    mean = runs.mean(axis=0)
    stderr = runs.std(axis=0, ddof=1) / math.sqrt(REFERENCE_SEEDS)
    doc = {"scene": "examples/furnished_office (make_furnished_office.py)", "triangles": int(len(scene.triangles)),
           "points": "grid.pts (the office's 77 sensors)",
           "method": "pure Monte Carlo (accuracy 0), mean of independent seeds",
           "samples": samples, "bounces": REFERENCE_BOUNCES, "seeds": REFERENCE_SEEDS, "rays": rays,
           "seconds": time.perf_counter() - t_start,
           "illuminance": mean.round(4).tolist(), "standard_error": stderr.round(4).tolist(),
           "relative_standard_error": {"mean": float(np.mean(stderr / mean)), "max": float(np.max(stderr / mean))}}
    if programs is not None:
        say("furnished reference: converged Radiance cross-check")
        doc["radiance_check"] = radiance_difference(scene, points, normals, folder, programs, mean)
    return doc


def radiance_difference(scene, points, normals, folder: Path, programs, reference) -> dict:
    """The converged Radiance run (:func:`radiance_check`) against ``reference`` [lux]:
    mean and max |E/E_ref − 1|, the mean signed difference, Radiance's seconds."""
    check = radiance_check(scene, points, normals, folder / "radiance-check", programs)
    err = check["illuminance"] / reference - 1.0
    return {"options": " ".join(RADIANCE_CHECK), "seconds": check["seconds"],
            "mean_difference": float(np.mean(np.abs(err))), "max_difference": float(np.max(np.abs(err))),
            "bias": float(np.mean(err))}


def radiance_check(scene, points, normals, folder: Path, programs) -> dict:
    """One Radiance run at ``RADIANCE_CHECK`` on a fresh export: illuminance [lux], seconds."""
    from lbl_illum.io import export_radiance, illuminance_from_rtrace

    ex = export_radiance(scene, folder, points, normals, glass="brtdfunc")
    oconv = _program(ex.oconv_command(), programs)
    m = run_measured(oconv, cwd=ex.directory, env=_env(programs, ex), stdout_path=ex.directory / ex.octree)
    if m.returncode != 0:
        raise RuntimeError(f"oconv: {m.stderr.strip()[-200:]}")
    m = run_measured(_program(ex.rtrace_command(RADIANCE_CHECK, PROCESSES), programs), cwd=ex.directory,
                     env=_env(programs, ex), stdin=ex.directory / ex.points)
    if m.returncode != 0:
        raise RuntimeError(f"rtrace: {m.stderr.strip()[-200:]}")
    return {"illuminance": illuminance_from_rtrace(m.stdout.decode()), "seconds": m.seconds}


def _program(cmd: list[str], programs: dict) -> list[str]:
    """``cmd`` with its program name replaced by the Radiance binary's path."""
    name = cmd[0]
    return [str(programs["bin"].get(name, name)), *cmd[1:]]


def _env(programs: dict, export) -> dict:
    """Radiance's environment with the export folder first on RAYPATH."""
    from lbl_illum.io import radiance_programs

    found = radiance_programs(export.directory)
    return found["env"] if found is not None else programs["env"]


# ---------------------------------------------------------------------------
# Running the ladders
# ---------------------------------------------------------------------------

class Runner:
    """Runs the settings of one scene and scores them against its reference."""

    def __init__(self, bench: Bench, build: Path, programs, processes: int = PROCESSES,
                 timeout: float | None = RUN_TIMEOUT, memory_gib: float | None = MEMORY_LIMIT_GIB):
        self.bench, self.build, self.programs, self.processes = bench, build, programs, processes
        self.limits = {"timeout": timeout, "memory_gib": memory_gib}
        self.folder = build / bench.name
        self.folder.mkdir(parents=True, exist_ok=True)
        self.export = None
        self.radiance = {}

    # -- Radiance ---------------------------------------------------------------------
    def prepare_radiance(self) -> dict:
        """Export the scene (glass as BRTDfunc), compile the octree; the cube size,
        export and oconv seconds."""
        from lbl_illum import load_scene
        from lbl_illum.io import export_radiance

        b = self.bench
        scene = load_scene(b.scene_path)
        pts = b.points + b.radiance_offset * b.normals
        t0 = time.perf_counter()
        self.export = ex = export_radiance(scene, self.folder / "radiance", pts, b.normals, glass="brtdfunc")
        export_seconds = time.perf_counter() - t0
        self.env = _env(self.programs, ex)
        m = run_measured(_program(ex.oconv_command(), self.programs), cwd=ex.directory, env=self.env,
                         stdout_path=ex.directory / ex.octree)
        if m.returncode != 0:
            raise RuntimeError(f"oconv: {m.stderr.strip()[-300:]}")
        cube = None
        if "getinfo" in self.programs["bin"]:
            info = subprocess.run([str(self.programs["bin"]["getinfo"]), "-d", ex.octree], cwd=ex.directory,
                                  env=self.env, capture_output=True, text=True)
            if info.returncode == 0 and info.stdout.split():
                cube = float(info.stdout.split()[-1])
        if cube is None:
            v = scene.triangles.vertices.reshape(-1, 3)
            cube = float(np.max(v.max(axis=0) - v.min(axis=0)))
        version = subprocess.run([str(self.programs["bin"]["rtrace"]), "-version"], env=self.env,
                                 capture_output=True, text=True).stdout.strip()
        self.radiance = {"export_seconds": export_seconds, "oconv_seconds": m.seconds,
                         "oconv_maxrss_kib": m.maxrss_kib, "cube": cube, "version": version,
                         "mesh": bool(ex.mesh), "triangles": ex.triangles, "spheres": ex.spheres}
        return self.radiance

    def run_radiance(self, s: Setting) -> dict:
        ex = self.export
        amb = ex.directory / "bench.amb"
        amb.unlink(missing_ok=True)
        aa = _arg(s.args, "-aa")
        use_af = aa is None or float(aa) > 0      # rtrace's default -aa is 0.1
        args = list(s.args) + (["-af", amb.name] if use_af else [])
        cmd = _program(ex.rtrace_command(args, self.processes), self.programs)
        m = run_measured(cmd, cwd=ex.directory, env=self.env, stdin=ex.directory / ex.points, **self.limits)
        row = self._row(s)
        if m.returncode != 0:
            row.update(failed=True, error=failure(m), elapsed=m.seconds)
            return row
        from lbl_illum.io import illuminance_from_rtrace

        values = illuminance_from_rtrace(m.stdout.decode())
        records = 0
        if use_af and amb.exists() and "lookamb" in self.programs["bin"]:
            look = subprocess.run([str(self.programs["bin"]["lookamb"]), "-h", "-d", amb.name], cwd=ex.directory,
                                  env=self.env, capture_output=True, text=True)
            records = count_ambient_records(look.stdout) if look.returncode == 0 else None
        elif use_af:
            records = None
        amb.unlink(missing_ok=True)
        row.update(seconds=m.seconds, process_seconds=m.seconds, maxrss_kib=m.maxrss_kib, records=records, rays=None)
        if self.bench.kind == CORPUS:
            # a user with a new scene runs oconv, then rtrace: both count
            oconv = self.radiance["oconv_seconds"]
            row.update(rtrace_seconds=m.seconds, oconv_seconds=oconv, seconds=oconv + m.seconds,
                       process_seconds=oconv + m.seconds,
                       maxrss_kib=max(m.maxrss_kib, self.radiance.get("oconv_maxrss_kib", 0)))
        return self._score(row, values)

    # -- lbl_illum -----------------------------------------------------------------------
    def run_engine(self, s: Setting) -> dict:
        spec = {"scene": str(self.bench.scene_path), "points": str(self.bench.points_path), "options": s.options,
                "output": str(self.folder / "engine_values.npy")}
        spec_path = self.folder / "engine_spec.json"
        spec_path.write_text(json.dumps(spec))
        env = dict(os.environ)
        env["LBL_ILLUM_THREADS"] = str(self.processes)
        env["NUMBA_NUM_THREADS"] = str(self.processes)
        m = run_measured([sys.executable, str(Path(__file__).resolve()), "--worker", str(spec_path)], cwd=ROOT, env=env,
                         **self.limits)
        row = self._row(s)
        if m.returncode != 0:
            row.update(failed=True, error=failure(m))
            return row
        doc = parse_worker_output(m.stdout.decode())
        values = np.load(spec["output"])
        row.update(seconds=doc["seconds"], process_seconds=m.seconds, maxrss_kib=m.maxrss_kib,
                   records=int(sum(doc["records"])), records_per_level=doc["records"], rays=doc["rays"],
                   load_seconds=doc.get("load_seconds"), warmup_seconds=doc.get("warmup_seconds"))
        return self._score(row, values)

    def run_command(self, s: Setting) -> dict:
        """One whole ``lbl-illum illuminance`` command (:func:`engine_command`) with the
        quality flags ``s.args``, in a child process: seconds = its wall time from start
        to exit; the illuminance from its CSV, records and rays from its ``--stats``."""
        work = self.folder / "lbl_illum"
        work.mkdir(parents=True, exist_ok=True)
        out, stats = work / "out.csv", work / "stats.json"
        for path in (out, stats, work / "out.summary.json"):
            path.unlink(missing_ok=True)
        cmd = engine_command(self.bench.scene_path, self.bench.points_path, out, stats, s.args)
        env = dict(os.environ)
        env["LBL_ILLUM_THREADS"] = str(self.processes)
        env["NUMBA_NUM_THREADS"] = str(self.processes)
        m = run_measured(cmd, cwd=ROOT, env=env, **self.limits)
        row = self._row(s)
        row["command"] = " ".join(["lbl-illum", "illuminance", self.bench.scene_path.name, "--points",
                                   self.bench.points_path.name, "-o", "out.csv", *s.args, "--stats", "stats.json",
                                   "-q"])
        if m.returncode != 0:
            row.update(failed=True, error=failure(m), elapsed=m.seconds)
            return row
        try:
            values = read_illuminance_csv(out)
            doc = json.loads(stats.read_text())
        except (OSError, ValueError) as exc:
            row.update(failed=True, error=f"unreadable output: {exc}", elapsed=m.seconds)
            return row
        row.update(seconds=m.seconds, process_seconds=m.seconds, maxrss_kib=m.maxrss_kib,
                   compute_seconds=doc.get("compute_seconds"), stats_seconds=doc.get("seconds"),
                   records=int(sum(doc["records"])), records_per_level=doc["records"], rays=int(doc["rays"]),
                   primary_evaluations=doc.get("primary_evaluations"), settings=doc.get("settings"))
        return self._score(row, values)

    # -- shared ------------------------------------------------------------------------------
    @staticmethod
    def _row(s: Setting) -> dict:
        row = {"program": s.program, "family": s.family, "label": s.label}
        if s.program == "lbl_illum":
            if s.options:
                row["options"] = s.options
            if s.args:
                row["flags"] = s.args
        else:
            row["args"] = s.args
        return row

    def _score(self, row: dict, values: np.ndarray) -> dict:
        ref = self.bench.reference
        if values.shape != ref.shape or not np.all(np.isfinite(values)):
            row.update(failed=True, error=f"{values.size} values for {ref.size} points, or not finite")
            return row
        err = values / ref - 1.0
        row.update(mean_error=float(np.mean(np.abs(err))), max_error=float(np.max(np.abs(err))),
                   bias=float(np.mean(err)), rms_error=float(np.sqrt(np.mean(err * err))))
        if self.bench.kind == CORPUS:
            row["illuminance"] = [round(float(v), 4) for v in values]
        return row


def _arg(args: Sequence[str], name: str) -> str | None:
    """The value after the last ``name`` in ``args``, or None."""
    value = None
    for i, a in enumerate(args[:-1]):
        if a == name:
            value = args[i + 1]
    return value


# ---------------------------------------------------------------------------
# The report
# ---------------------------------------------------------------------------

def scene_section(report, bench: Bench, res: dict) -> None:
    """Heading, reference, table, plot and equal-error ratios of one scene."""
    info = bench.reference_info
    report.heading(bench.title)
    ref_text = f"Reference: {info['method']}" + (f" (`{info['file']}`)" if info.get("file") else "")
    if info["standard_error_max"] > 0:
        ref_text += (f"; its standard error is {pct(info['standard_error_mean'])} mean and "
                     f"{pct(info['standard_error_max'])} max over the points.")
    else:
        ref_text += "; it has no sampling error."
    if bench.name == "sphere-plane":
        ref_text += (f"  The 10 km plane lacks at most {pct(info['plane_truncation_max'], 3)} of E at these points "
                     f"and the quadrature is exact to {info['quadrature_error_max']:.1e}; our runs and Radiance's "
                     f"follow one reflection (`bounces = 1`, `-ab 1`: the sun is a light source, not a glow).")
    check = info.get("radiance_check")
    if check:
        ref_text += (f"  Cross-check: Radiance `rtrace {check['options']}` ({check['seconds']:.0f} s) differs from it "
                     f"by {pct(check['mean_difference'])} mean, {pct(check['max_difference'])} max, bias "
                     f"{pct(check['bias'])}.")
    report.text(ref_text)
    rad = res.get("radiance_setup")
    if rad:
        report.text(f"Radiance ({rad['version']}): export {rad['export_seconds']:.2f} s"
                    + (" (triangles compiled by obj2mesh)" if rad["mesh"] else "")
                    + f", `oconv` {rad['oconv_seconds']:.3g} s once per scene (not in the run times), octree cube "
                      f"{rad['cube']:.4g} m; zone {' '.join(f'{v:g}' for v in bench.zone)} m.")
    rad_runs = [r for r in res["runs"] if r["family"] == "rad presets"]
    if rad_runs:
        report.text("The rtrace options of the rad presets (from `rad -n -e`):")
        report.bullets([f"{r['label']}: `{' '.join(r['args'])}`" for r in rad_runs])
    header, rows = run_table(res["runs"])
    report.table(header, rows, caption=(f"{bench.name}: every run. seconds = our compute time "
                                        "(Integrator.compute after warm-up) or rtrace's wall time; process s = the "
                                        "whole child process; ★ = on its program's Pareto front."))
    report.figure(f"{bench.name}-front", front_figure(bench, res), f"{bench.name}: seconds against mean relative "
                  "error, all runs (faint) and each program's Pareto front (lines); dotted: the error levels compared.")
    comp = res.get("comparison")
    if comp:
        rows = []
        for c, cw in zip(comp["compute"], comp["process"]):
            rows.append([pct(c["level"], 0), seconds_text(c["ours_seconds"], c["ours_kind"]),
                         seconds_text(c["radiance_seconds"], c["radiance_kind"]), ratio_text(c), c["verdict"],
                         ratio_text(cw)])
        report.table(["mean error", "lbl_illum s", "Radiance s", "ratio", f"target ≤ {TARGET_RATIO:g}",
                      "ratio (whole process)"], rows,
                     caption=f"{bench.name}: time at equal mean error, interpolated on each Pareto front; ratio = "
                             "ours / Radiance's (whole process: our process wall time instead of compute time).")


def front_figure(bench: Bench, res: dict, levels: Sequence[float] = ERROR_LEVELS,
                 ylabel: str = "seconds (2 processes / threads)"):
    from lbl_illum_studies.report import new_figure

    fig, ax = new_figure(6.4, 4.4)
    styles = {"lbl_illum": ("tab:blue", "o"), "radiance": ("tab:red", "s")}
    for program, (color, marker) in styles.items():
        runs = [r for r in res["runs"] if r["program"] == program and not r.get("failed")]
        if not runs:
            continue
        ax.scatter([100 * r["mean_error"] for r in runs], [r["seconds"] for r in runs], color=color, marker=marker,
                   alpha=0.3, s=18)
        front = sorted((r for r in runs if r.get("front")), key=lambda r: r["seconds"])
        ax.plot([100 * r["mean_error"] for r in front], [r["seconds"] for r in front], color=color, marker=marker,
                label=f"{program} (front)")
        for r in runs:
            if r["family"] in ("preset", "rad presets"):
                short = r["label"].replace("preset ", "").replace(" (bounces 1)", "")
                ax.annotate(short.replace("rad QUALITY=", "rad ").replace(", INDIRECT=", "/"),
                            (100 * r["mean_error"], r["seconds"]), fontsize=6, color=color,
                            xytext=(3, 3), textcoords="offset points")
    for level in levels:
        ax.axvline(100 * level, color="0.6", linestyle=":", linewidth=1)
    se = bench.reference_info.get("standard_error_mean")
    errors = [100 * r["mean_error"] for r in res["runs"] if not r.get("failed")] + [100 * x for x in levels]
    lo, hi = min(errors + ([100 * se] if se else [])) / 1.5, max(errors) * 1.5
    if se:
        ax.axvspan(lo, 100 * se, color="0.9", zorder=0, label="below the reference's standard error")
    ax.set_xlim(lo, hi)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("mean relative error [%]")
    ax.set_ylabel(ylabel)
    ax.set_title(bench.name)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    return fig


def case_verdict(comparisons: Sequence[dict]) -> str:
    """Whether a case meets the target over its levels (:func:`compare_at` results):
    "met" when every level Radiance reaches is met, "missed" when one is missed,
    "undetermined" when the bounds leave one open, "n/a" when Radiance reaches none."""
    verdicts = [c["verdict"] for c in comparisons if c["verdict"] != "n/a"]
    if not verdicts:
        return "n/a"
    if "missed" in verdicts:
        return "missed"
    if "undetermined" in verdicts:
        return "undetermined"
    return "met"


def corpus_run_table(runs: Sequence[dict]) -> tuple[list[str], list[list]]:
    """Header and rows of a corpus case's table of runs: seconds are each program's whole
    time (ours: the command from start to exit; Radiance: oconv + rtrace), with the parts
    beside them (ours: the compute time our ``--stats`` reports)."""
    header = ["program", "family", "setting", "seconds", "of which", "peak MiB", "mean error", "max error", "bias",
              "records", "rays", "front"]
    rows = []
    for r in runs:
        if r.get("failed"):
            why = "stopped (time)" if "time limit" in r.get("error", "") else (
                "stopped (memory)" if "memory limit" in r.get("error", "") else "failed")
            after = f"after {r['elapsed']:.3g} s" if r.get("elapsed") is not None else "—"
            rows.append([r["program"], r["family"], r["label"], why, after, "—", "—", "—", "—", "—", "—", ""])
            continue
        if r["program"] == "radiance":
            parts = f"oconv {r['oconv_seconds']:.3g} + rtrace {r['rtrace_seconds']:.3g}"
        else:
            parts = "—" if r.get("compute_seconds") is None else f"compute {r['compute_seconds']:.3g}"
        rows.append([r["program"], r["family"], r["label"], f"{r['seconds']:.3g}", parts,
                     f"{r['maxrss_kib'] / 1024:.0f}", pct(r["mean_error"]), pct(r["max_error"]), pct(r["bias"]),
                     "—" if r.get("records") is None else f"{r['records']:,}",
                     "—" if r.get("rays") is None else f"{r['rays']:,}", "★" if r.get("front") else ""])
    return header, rows


def corpus_section(report, bench: Bench, res: dict, processes: int) -> None:
    """Heading, reference, table of runs, plot and equal-error ratios of one corpus case."""
    info = bench.reference_info
    report.heading(bench.title)
    text = (f"Scene `{info.get('scene_file', bench.scene_path.name)}` ({info.get('source', '')}; role "
            f"{info.get('role', '?')}).  Reference: {info['method']} (`{info['file']}`); its standard error is "
            f"{pct(info['standard_error_mean'])} mean and {pct(info['standard_error_max'])} max over the "
            f"{len(bench.reference)} points, so a mean error much below about "
            f"{pct(0.8 * info['standard_error_mean'])} cannot be told from the reference's own noise.")
    report.text(text)
    rad = res.get("radiance_setup")
    if rad:
        report.text(f"Radiance ({rad['version']}): export {rad['export_seconds']:.2f} s (not counted)"
                    + (" (triangles compiled by obj2mesh)" if rad["mesh"] else "")
                    + f"; `oconv` {rad['oconv_seconds']:.3g} s, counted in every Radiance run; octree cube "
                      f"{rad['cube']:.4g} m; zone {' '.join(f'{v:.3g}' for v in bench.zone)} m; `-ar` "
                      f"{rad.get('ar', '?')}.")
    elif res.get("radiance_error"):
        report.text(f"**Radiance did not run on this case**: {res['radiance_error']}")
    header, rows = corpus_run_table(res["runs"])
    report.table(header, rows, caption=(f"{bench.name}: every run.  seconds = lbl_illum: the whole command "
                                        "`lbl-illum illuminance …` from start to exit; Radiance: oconv + "
                                        f"`rtrace -I -h -n {processes}`; ★ = on its program's Pareto front."))
    report.figure(f"{bench.name}-front", front_figure(bench, res, CORPUS_ERROR_LEVELS,
                                                      "seconds (whole command; Radiance oconv + rtrace)"),
                  f"{bench.name}: seconds against mean relative error, all runs (faint) and each program's Pareto "
                  "front (lines); dotted: the error levels compared; grey: below the reference's standard error.")
    comp = res.get("comparison")
    if comp:
        rows = [[pct(c["level"], 1), seconds_text(c["ours_seconds"], c["ours_kind"]),
                 seconds_text(c["radiance_seconds"], c["radiance_kind"]), ratio_text(c), c["verdict"]]
                for c in comp["command"]]
        report.table(["mean error", "lbl_illum s", "Radiance s", "ratio", f"target ≤ {TARGET_RATIO:g}"], rows,
                     caption=f"{bench.name}: time at equal mean error, interpolated on each Pareto front; ratio = "
                             f"ours / Radiance's.  Over the levels Radiance reaches: **{res['verdict']}**.")


def corpus_summary(report, benches: Sequence[Bench], results: dict, skipped: dict, radiance: bool) -> None:
    """The corpus summary: case × error level → ratio, and whether the target is met."""
    rows = []
    for b in benches:
        res = results[b.name]
        comp = res.get("comparison")
        se = pct(b.reference_info["standard_error_mean"])
        if comp:
            cells = [ratio_text(c) + ("" if c["verdict"] in ("met", "n/a") else f" ({c['verdict']})")
                     for c in comp["command"]]
            rows.append([b.name, b.reference_info.get("role", ""), se] + cells + [res["verdict"],
                                                                                  res.get("measured", "—")])
        else:
            why = "Radiance did not run" if not radiance else (res.get("radiance_error") or "no comparison")
            rows.append([b.name, b.reference_info.get("role", ""), se] + ["—"] * len(CORPUS_ERROR_LEVELS)
                        + [why[:60], res.get("measured", "—")])
    for case, why in skipped.items():
        rows.append([case, "", "—"] + ["—"] * len(CORPUS_ERROR_LEVELS) + [f"skipped: {why}", "—"])
    if rows:
        report.table(["case", "role", "ref. SE"] + [f"ratio at {pct(level, 1)}" for level in CORPUS_ERROR_LEVELS]
                     + ["target", "measured"], rows,
                     caption=f"Corpus: our time / Radiance's at equal mean relative error, each the whole time a "
                             f"user waits (our command; oconv + rtrace).  Target: ≤ {TARGET_RATIO:g} at every level "
                             "Radiance reaches; “Radiance not reached”: none of its runs gets there (the level does "
                             "not count), “lbl_illum not reached”: ours does not (a miss).  ref. SE: the "
                             "reference's mean relative standard error; measured: the date of the run that "
                             "measured the case (all of a case's runs, ours and Radiance's, come from that one run).")
    verdicts = [results[b.name].get("verdict") for b in benches if results[b.name].get("comparison")]
    if verdicts:
        counts = {v: verdicts.count(v) for v in ("met", "missed", "undetermined", "n/a") if verdicts.count(v)}
        report.text(f"Corpus target over {len(verdicts)} compared case(s): "
                    + ", ".join(f"{n} {v}" for v, n in counts.items()) + "."
                    + (f"  Skipped: {', '.join(skipped)} (see the table)." if skipped else ""))
    elif skipped:
        report.text(f"Skipped corpus cases: {'; '.join(f'{c}: {w}' for c, w in skipped.items())}.")


def write_report(out: Path, benches: list, results: dict, args, programs, seconds: float,
                 skipped: dict | None = None) -> Path:
    from lbl_illum_studies.report import Report, environment

    skipped = skipped or {}
    classic = [b for b in benches if b.kind != CORPUS]
    corpus = [b for b in benches if b.kind == CORPUS]
    name = CORPUS_NAME if (corpus or skipped) and not classic else NAME
    command = "python validation/bench/compare_radiance.py --out " + str(args.out_display)
    if args.scenes_given and getattr(args, "merge", False):        # the one run that measures them all
        command += " --scenes " + ",".join(CORPUS_PREFIX + b.name for b in corpus)
    elif args.scenes_given:
        command += " --scenes " + (args.scenes if corpus or skipped else ",".join(b.name for b in benches))
    if args.quick:
        command += " --quick"
    if getattr(args, "run_timeout", RUN_TIMEOUT) != RUN_TIMEOUT:
        command += f" --run-timeout {args.run_timeout:g}"
    report = Report(name, TITLE, command)
    report.heading("Summary")
    if programs is None:
        report.text("**Radiance did not run** (`--no-radiance`, or no `pyradiance` and no `oconv`/`rtrace` on the "
                    "PATH): only lbl_illum ran, so there are no ratios.  Install the `radiance` extra to compare.")
    rows = []
    for b in classic:
        comp = results[b.name].get("comparison")
        if comp:
            rows.append([b.name] + [ratio_text(c) + f" ({c['verdict']})" for c in comp["compute"]])
    if rows:
        report.table(["scene"] + [f"ratio at {pct(level, 0)}" for level in ERROR_LEVELS], rows,
                     caption=f"Our time / Radiance's at equal mean relative error (target ≤ {TARGET_RATIO:g} at every "
                             "level Radiance reaches).")
    if classic:
        report.text(
            f"Target: at every mean error level Radiance reaches among {', '.join(pct(x, 0) for x in ERROR_LEVELS)}, "
            f"lbl_illum needs at most {TARGET_RATIO:g} × Radiance's time (a ratio ≤ {TARGET_RATIO:g}).  Both run on "
            f"{args.processes} processes or threads; " + ("this is the quick version (a few settings, office only)."
                                                          if args.quick else "the full ladders."))
    if corpus or skipped:
        corpus_summary(report, corpus, results, skipped, programs is not None)
        dates = sorted({results[b.name].get("measured", "—") for b in corpus})
        if len(dates) > 1:
            report.text(f"The cases were measured in separate runs ({', '.join(dates)}; `--merge` keeps the cases "
                        "a run does not measure): each case's ratios come from one run, in which ours and "
                        "Radiance's alternate, but ratios of different cases may come from different runs.")
        report.text(
            f"Corpus target: at every mean error level Radiance reaches among "
            f"{', '.join(pct(x, 1) for x in CORPUS_ERROR_LEVELS)}, the whole `lbl-illum illuminance` command takes "
            f"at most {TARGET_RATIO:g} × Radiance's oconv + rtrace.  Both run on {args.processes} processes or "
            "threads; " + ("this is the quick version (two settings per program)." if args.quick
                           else "the full corpus ladders."))
    report.heading("How it is measured")
    bullets = []
    if classic:
        bullets += [
            "lbl_illum (office, sphere-plane, furnished): a child process per run loads the scene, warms up on 4 "
            "points at cheap settings (after one untimed run per scene that fills numba's compilation cache), then "
            "times `Integrator(scene, options).compute(points, normals)` (the **seconds** column); **process s** is "
            "the child's whole wall time (Python start-up, imports, scene loading, warm-up).",
            f"Radiance (office, sphere-plane, furnished): `rtrace -I -h -n {args.processes}` reading the points on "
            "standard input; seconds = its wall time; `oconv` is timed once per scene and not counted.  Ladder "
            f"runs use `-lw {LIMIT_WEIGHT}`; rtrace's defaults otherwise.",
            "Radiance's `-ab` counts the sky (a glow found by the indirect calculation) as a bounce: `-ab n` ≈ our "
            "`bounces = n − 1`.  The interior ladders use `-ab 8`, ours `bounces = 8`; the references follow 12.",
            "rad presets: the `rpict` options `rad -n -e` prints for a .rif with the room as an interior ZONE, "
            "DETAIL=medium, VARIABILITY=high and INDIRECT 2 or 5 (the diffuse reflections that matter, counting "
            "the sky's light as the first), minus the view and picture "
            "options; they include rad's own `-av` (a constant ambient at the bounce limit) and `-lr`/`-lw`.  "
            "QUALITY=LOW sets no `-ab` (0: the ambient is `-av` alone).",
        ]
    if corpus or skipped:
        ladder = corpus_engine_ladder(args.quick)
        bullets += [
            "lbl_illum on corpus cases: every run is the whole command a user types, `python -m lbl_illum "
            "illuminance SCENE --points PTS -o OUT.csv FLAGS --stats STATS.json -q`, timed from start to exit "
            "(Python start-up, imports, loading the scene, compiled kernels from numba's disk cache, the "
            "calculation, writing); one untimed run of the first setting per case (and cheap ones of the other "
            "kinds before the first case) fills the kernel cache.  Illuminance: column `illuminance` of the CSV; "
            "records: the sum over levels of `records` in the stats, rays: `rays`; “compute” is the stats' "
            f"`compute_seconds`.  FLAGS: {'; '.join(f'`{s.label}`' for s in ladder)} (the presets are "
            "`lbl_illum.options.PRESETS`; explicit flags leave the rest at the command's defaults).",
            f"Radiance on corpus cases: the scene exported once by `lbl_illum.io.radiance.export_radiance` (glass as a "
            f"constant-coefficient BRTDfunc; export time not counted), then `oconv` (timed once per case) and "
            f"`rtrace -I -h -n {args.processes}` with `-ab {CORPUS_BOUNCES + 1}` (= our {CORPUS_BOUNCES} bounces: Radiance "
            "counts the sky as one), "
            f"`-lw {LIMIT_WEIGHT}`, (-aa, -ad) pairs with `-as` = -ad/2 and pure Monte Carlo `-aa 0` at rising "
            "-ad, with rtrace's default `-as` and with `-as 0`; a run's seconds are oconv's plus rtrace's (a user with a new scene runs both).",
            f"Every run is stopped after `--run-timeout` ({args.run_timeout:g} s) or past `--memory-limit` "
            f"({args.memory_limit:g} GiB) and shown as stopped; failed runs are shown as failed.  Cases whose "
            "reference (`validation/data/corpus/NAME-SKY.json`) is missing are skipped and listed.",
        ]
    bullets += [
        "`-ar` relative to the room, as `rad` sets it: ar = f · cube / zone (f = 8 unless stated), smallest record "
        "radius aa · zone / f.",
        "Peak memory: the larger of `ru_maxrss` of the child from `os.wait4` and the resident memory of the child "
        "and its own children sampled every 0.05 s (for `rtrace -n 2`, the sum over its processes, whose "
        "`ru_maxrss` the parent does not always include); children start from a small launcher process "
        "(about 7 MiB of any figure is the launcher's image).",
        "Errors: per point |E/E_ref − 1|, mean and max over the points, and the mean signed error (bias).",
        "Equal error: time interpolated on each program's Pareto front, linear in log seconds against log error; "
        "“≤” where the program's fastest run is already within the level (its time is an upper bound), "
        "“not reached” where no run gets there.",
        "Seconds on a shared machine drift by tens of percent between runs; ratios from one run are what compare.",
    ]
    report.bullets(bullets)
    for b in classic:
        scene_section(report, b, results[b.name])
    for b in corpus:
        corpus_section(report, b, results[b.name], args.processes)
    report.results = {"scenes": {b.name: {"title": b.title, "reference": b.reference_info, "zone": b.zone,
                                          **results[b.name]} for b in classic},
                      "error_levels": list(ERROR_LEVELS), "target_ratio": TARGET_RATIO,
                      "processes": args.processes, "radiance": programs is not None}
    if corpus or skipped:
        report.results.update(
            corpus={b.name: {"title": b.title, "reference": b.reference_info, "zone": b.zone,
                             "scene_file": shown_path(b.scene_path), "points_file": shown_path(b.points_path),
                             "reference_illuminance": b.reference.tolist(), **results[b.name]} for b in corpus},
            corpus_skipped=dict(skipped), corpus_error_levels=list(CORPUS_ERROR_LEVELS),
            corpus_verdicts={b.name: results[b.name].get("verdict") for b in corpus},
            run_timeout=args.run_timeout, memory_limit_gib=args.memory_limit)
    meta = {"quick": args.quick, "seconds": seconds, "environment": environment()}
    return report.write(out / name, meta)


# ---------------------------------------------------------------------------
# Command line
# ---------------------------------------------------------------------------

def parse_scenes(text: str) -> list[str]:
    """Scene names from a comma-separated list; ValueError naming an unknown one.

    Besides :data:`SCENES`: ``corpus`` (every corpus case), ``corpus:NAME`` (both skies
    of corpus scene NAME) and ``corpus:NAME-SKY`` (one case), each returned as
    ``corpus:NAME-SKY`` in the corpus's order within the item."""
    names = []
    for n in (s.strip() for s in text.split(",")):
        if not n:
            continue
        if n == CORPUS:
            names += [CORPUS_PREFIX + c for c in corpus_case_names()]
        elif n.startswith(CORPUS_PREFIX):
            case = n[len(CORPUS_PREFIX):].strip()
            scenes = {scene.name for scene, _ in corpus_module().cases()}
            if case in scenes:
                names += [CORPUS_PREFIX + f"{scene.name}-{sky}" for scene, sky in corpus_module().cases([case])]
            else:
                corpus_case(case)                      # ValueError when unknown
                names.append(CORPUS_PREFIX + case)
        elif n in SCENES:
            names.append(n)
        else:
            raise ValueError(f"--scenes: unknown scene {n!r} (choose from {', '.join(SCENES)}, {CORPUS}, "
                             f"{CORPUS_PREFIX}NAME or {CORPUS_PREFIX}NAME-SKY)")
    if not names:
        raise ValueError("--scenes: no scene given")
    return list(dict.fromkeys(names))


def is_corpus(name: str) -> bool:
    """Whether a name of :func:`parse_scenes` is a corpus case."""
    return name.startswith(CORPUS_PREFIX)


def parse_args(argv=None) -> argparse.Namespace:
    parser = argparse.ArgumentParser(
        description="lbl_illum side by side with Radiance's rtrace: seconds against error on the office, the "
                    "sphere on a plane and the furnished office, and on the accuracy corpus (--scenes corpus); "
                    "time ratio at equal error.",
        epilog="Writes OUT/radiance-comparison/ (report.md, report.html, plots, results.json).  The full run takes "
               "about two hours on 2 cores; --quick under a minute.")
    parser.add_argument("--out", default="docs/performance", metavar="DIR",
                        help="folder of the report folder radiance-comparison/ (default: docs/performance)")
    parser.add_argument("--scenes", default=None,
                        help=f"comma-separated scenes of {', '.join(SCENES)} (default: all; office with --quick), "
                             f"or corpus cases: {CORPUS} (all, hours), {CORPUS_PREFIX}NAME (both skies), "
                             f"{CORPUS_PREFIX}NAME-SKY (e.g. {CORPUS_PREFIX}deep-room-overcast)")
    parser.add_argument("--quick", action="store_true",
                        help="two or three settings per program (two on corpus cases), on the office unless "
                             "--scenes says otherwise")
    parser.add_argument("--list", action="store_true", help="print the ladders and exit")
    parser.add_argument("--processes", type=int, default=PROCESSES,
                        help=f"Radiance -n and our threads (default {PROCESSES})")
    parser.add_argument("--triangles", type=int, default=FURNISHED_TRIANGLES,
                        help=f"triangles of the furnished office (default {FURNISHED_TRIANGLES:,})")
    parser.add_argument("--remake-reference", action="store_true",
                        help="recompute the furnished office's reference even if cached")
    parser.add_argument("--reference-minutes", type=float, default=REFERENCE_MINUTES,
                        help=f"time budget of the furnished reference (default {REFERENCE_MINUTES:g})")
    parser.add_argument("--build", default=str(DEFAULT_BUILD), metavar="DIR",
                        help="working folder for exports and generated scenes (default: build/compare-radiance)")
    parser.add_argument("--no-radiance", action="store_true", help="run our side only")
    parser.add_argument("--run-timeout", type=float, default=RUN_TIMEOUT, metavar="S",
                        help=f"stop a run after S seconds and report it failed (default {RUN_TIMEOUT:g})")
    parser.add_argument("--memory-limit", type=float, default=MEMORY_LIMIT_GIB, metavar="GIB",
                        help=f"stop a run holding more than GIB GiB resident (default {MEMORY_LIMIT_GIB:g})")
    parser.add_argument("--merge", action="store_true",
                        help="corpus runs only: keep the cases of the existing corpus report that this run does "
                             "not measure (each case's ratios still come from one run; the report gives the date "
                             "each case was measured)")
    parser.add_argument("--worker", metavar="SPEC", help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    args.scenes_given = args.scenes is not None
    try:
        args.scene_list = parse_scenes(args.scenes) if args.scenes else (["office"] if args.quick else list(SCENES))
    except ValueError as exc:
        parser.exit(2, f"compare_radiance: {exc}\n")
    if args.processes < 1:
        parser.exit(2, "compare_radiance: --processes must be >= 1\n")
    if args.merge and not all(is_corpus(n) for n in args.scene_list):
        parser.exit(2, "compare_radiance: --merge: only corpus cases can be merged (--scenes corpus:NAME-SKY,...)\n")
    if args.triangles < 1000:
        parser.exit(2, "compare_radiance: --triangles must be >= 1000\n")
    args.out_display = display_path(args.out)
    return args


def display_path(path: Path) -> Path:
    """``path`` as the report's command shows it: an absolute path inside a repository
    (a folder with ``pyproject.toml`` above it) relative to that repository's root, so
    that no machine's folders are written into a committed report; others as given."""
    path = Path(path)
    if not path.is_absolute():
        return path
    for root in path.parents:
        if (root / "pyproject.toml").is_file():
            return path.relative_to(root)
    return path


def list_ladders(args) -> None:
    corpus = [n for n in args.scene_list if is_corpus(n)]
    if corpus:
        ours = corpus_engine_ladder(args.quick)
        theirs = radiance_ladder(CORPUS, cube=1.0, zone_size=1.0, quick=args.quick)
        print(f"corpus ({len(corpus)} case(s): {', '.join(n[len(CORPUS_PREFIX):] for n in corpus)}): lbl_illum "
              f"{len(ours)} runs, Radiance {len(theirs)} runs each (-ar shown for cube = zone)")
        for s in ours + theirs:
            print(f"  {s.program:9s} {s.family:20s} {s.label}")
    for name in (n for n in args.scene_list if not is_corpus(n)):
        ours = engine_ladder(name, args.quick)
        theirs = radiance_ladder(name, cube=1.0, zone_size=1.0, quick=args.quick)
        rad = QUICK_RAD_PRESETS if args.quick and RAD_PRESETS[name] else RAD_PRESETS[name]
        print(f"{name}: lbl_illum {len(ours)} runs, Radiance {len(theirs) + len(rad)} runs (-ar shown for cube = zone)")
        for s in ours + theirs:
            print(f"  {s.program:9s} {s.family:20s} {s.label}")
        for quality, indirect in rad:
            print(f"  {'radiance':9s} {'rad presets':20s} QUALITY={quality}" + ("" if quality == "LOW" else
                                                                                f", INDIRECT={indirect}"))


def run_order(settings: Sequence[Setting]) -> list[int]:
    """Indices of ``settings`` with the two programs' runs alternating (each in ladder
    order), so that a drift in the machine's speed falls on both alike."""
    ours = [k for k, s in enumerate(settings) if s.program == "lbl_illum"]
    theirs = [k for k, s in enumerate(settings) if s.program != "lbl_illum"]
    out = []
    for i in range(max(len(ours), len(theirs))):
        out += ours[i:i + 1] + theirs[i:i + 1]
    return out


def main(argv=None) -> int:
    if argv is None and len(sys.argv) > 2 and sys.argv[1] == "--worker":
        return worker(sys.argv[2])
    args = parse_args(argv)
    try:
        return compare(args)
    except (RuntimeError, OSError) as exc:
        print(f"compare_radiance: {exc}", file=sys.stderr)
        return 2


def compare(args) -> int:
    """Run the benchmark as ``args`` (from :func:`parse_args`) say and write the report."""
    if args.worker:
        return worker(args.worker)
    if args.list:
        list_ladders(args)
        return 0
    from tqdm import tqdm

    from lbl_illum.io import radiance_programs

    t_start = time.perf_counter()
    build = Path(args.build)
    build.mkdir(parents=True, exist_ok=True)
    programs = None if args.no_radiance else radiance_programs()
    bar = tqdm(total=0, unit="run", file=sys.stderr, dynamic_ncols=True)

    def say(text):
        bar.set_description_str(text[:60])
        bar.refresh()

    if programs is None:
        print("compare_radiance: Radiance not run (--no-radiance, or not found): lbl_illum only", file=sys.stderr)
    if not OFFICE_REFERENCE.is_file() and "office" in args.scene_list:
        print(f"compare_radiance: {OFFICE_REFERENCE.name}: no such file", file=sys.stderr)
        return 2
    benches, results, failures, skipped = [], {}, 0, {}
    primed = False
    for name in args.scene_list:
        if is_corpus(name):
            case = name[len(CORPUS_PREFIX):]
            say(f"{case}: preparing")
            bench = prepare_corpus(case)
            if isinstance(bench, str):
                skipped[case] = bench
                tqdm.write(f"compare_radiance: {case}: skipped: {bench}", file=sys.stderr)
                continue
            runner, settings, res = corpus_setup(bench, build / CORPUS, programs, args, say, tqdm.write)
            bar.total += len(settings)
            bar.refresh()
            say(f"{case}: priming")
            if not primed:                         # cheap runs of the other kinds: every kernel in the cache
                for flags in CORPUS_PRIMERS:
                    runner.run_command(Setting("lbl_illum", "primer", " ".join(flags), args=list(flags)))
                primed = True
            first = runner.run_command(settings[0])     # untimed: caches warm, kernels compiled
            res["priming"] = {"label": settings[0].label, "seconds": first.get("seconds", first.get("elapsed")),
                              "failed": bool(first.get("failed"))}
        else:
            say(f"{name}: preparing")
            if name == "office":
                bench = prepare_office()
            elif name == "sphere-plane":
                bench = prepare_sphere_plane(build)
            else:
                bench = prepare_furnished(build, args.triangles, args.remake_reference, args.reference_minutes,
                                          programs, say)
            kind = bench.kind
            runner = Runner(bench, build, programs, args.processes, args.run_timeout, args.memory_limit)
            settings = engine_ladder(kind, args.quick)
            res = {"runs": []}
            if programs is not None:
                setup = runner.prepare_radiance()
                res["radiance_setup"] = setup
                settings += radiance_ladder(kind, setup["cube"], zone_mean_side(bench.zone), args.quick)
                presets = QUICK_RAD_PRESETS if args.quick and RAD_PRESETS[kind] else RAD_PRESETS[kind]
                settings += rad_settings(programs, runner.export, bench.zone, presets)
            bar.total += len(settings)
            bar.refresh()
            engine_settings = [s for s in settings if s.program == "lbl_illum"]
            if engine_settings:
                say(f"{name}: priming")
                runner.run_engine(engine_settings[0])      # untimed: numba compiles into its cache here
        rows: dict = {}
        for k in run_order(settings):
            s = settings[k]
            say(f"{bench.name}: {s.program} {s.label}")
            if s.program != "lbl_illum":
                row = runner.run_radiance(s)
            else:
                row = runner.run_command(s) if bench.kind == CORPUS else runner.run_engine(s)
            if row.get("failed"):
                failures += 1
                tqdm.write(f"compare_radiance: {bench.name}: {s.program} {s.label}: failed: {row.get('error', '')}",
                           file=sys.stderr)
            rows[k] = row
            bar.update(1)
        res["runs"] = [rows[k] for k in range(len(settings))]
        ours = front_pairs(res["runs"], "lbl_illum")
        theirs = front_pairs(res["runs"], "radiance")
        if bench.kind == CORPUS:
            if "radiance_setup" in res:
                res["comparison"] = {"command": [compare_at(ours, theirs, e) for e in CORPUS_ERROR_LEVELS]}
                res["verdict"] = case_verdict(res["comparison"]["command"])
        elif programs is not None:
            ours_process = front_pairs(res["runs"], "lbl_illum", key="process_seconds")
            res["comparison"] = {"compute": [compare_at(ours, theirs, e) for e in ERROR_LEVELS],
                                 "process": [compare_at(ours_process, theirs, e) for e in ERROR_LEVELS]}
        res["fronts"] = {"lbl_illum": ours, "radiance": theirs}
        res["measured"] = time.strftime("%Y-%m-%d")
        benches.append(bench)
        results[bench.name] = res
    bar.close()
    out = Path(args.out)
    if args.merge:
        kept = merge_corpus_cases(out / CORPUS_NAME / "results.json", args, results, skipped)
        order = {case: k for k, case in enumerate(n[len(CORPUS_PREFIX):] for n in parse_scenes(CORPUS))}
        benches = sorted(benches + [bench for bench, _ in kept], key=lambda b: order.get(b.name, len(order)))
        results.update({bench.name: res for bench, res in kept})
    folder = write_report(out, benches, results, args, programs, time.perf_counter() - t_start, skipped)
    parts = []
    for b in benches:
        comp = results[b.name].get("comparison")
        if comp and b.kind == CORPUS:
            parts.append(f"{b.name} " + " / ".join(short_ratio(c) for c in comp["command"])
                         + f" ({results[b.name]['verdict']})")
        elif comp:
            parts.append(f"{b.name} " + " / ".join(short_ratio(c) for c in comp["compute"]))
        else:
            parts.append(f"{b.name} (ours only)")
    parts += [f"{case} skipped" for case in skipped]
    runs = sum(len(r["runs"]) for r in results.values())
    levels = "/".join(pct(e, 0).replace(' ', '') for e in ERROR_LEVELS)
    if any(b.kind == CORPUS for b in benches):
        levels += " (corpus " + "/".join(pct(e, 1).replace(' ', '') for e in CORPUS_ERROR_LEVELS) + ")"
    print(f"radiance-comparison: {len(benches)} scene(s), {runs} runs ({failures} failed or stopped); ratio "
          f"ours/Radiance at {levels}: {'; '.join(parts)}; {time.perf_counter() - t_start:.0f} s -> {folder}")
    return 0


#: Keys of a corpus case in results.json that the report adds to the run's own results.
CASE_DESCRIPTION_KEYS = ("title", "reference", "zone", "scene_file", "points_file", "reference_illuminance")


def merge_corpus_cases(path: Path, args, results: dict, skipped: dict) -> list:
    """(bench, results) of the corpus cases of the report ``path`` that this run did not
    measure, to be written again beside the new ones (``--merge``).  Refused when the
    earlier report ran on other processes or another run timeout; a case whose reference
    has changed since it was measured, or which cannot be prepared now, is dropped with a
    line saying so (it has to be measured again)."""
    if not path.is_file():
        return []
    doc = json.loads(path.read_text(encoding="utf-8"))
    old = doc.get("results", {})
    if old.get("processes") != args.processes or old.get("run_timeout") != args.run_timeout:
        raise RuntimeError(f"--merge: {path} was measured with --processes {old.get('processes')} and "
                           f"--run-timeout {old.get('run_timeout')}; this run uses {args.processes} and "
                           f"{args.run_timeout:g}: measure all cases again without --merge")
    kept = []
    for case, stored in old.get("corpus", {}).items():
        if case in results or case in skipped:
            continue
        bench = prepare_corpus(case)
        if isinstance(bench, str):
            print(f"compare_radiance: --merge: {case} dropped: {bench}", file=sys.stderr)
            continue
        if not np.array_equal(np.asarray(stored.get("reference_illuminance"), np.float64), bench.reference):
            print(f"compare_radiance: --merge: {case} dropped: its reference changed since it was measured",
                  file=sys.stderr)
            continue
        res = {k: v for k, v in stored.items() if k not in CASE_DESCRIPTION_KEYS}
        res.setdefault("measured", doc.get("environment", {}).get("date", "before --merge")[:10])
        kept.append((bench, res))
    return kept


def zone_mean_side(zone: Sequence[float]) -> float:
    """Mean side [m] of a zone (x0, x1, y0, y1, z0, z1): ``rad``'s zone size for ``-ar``."""
    z = zone
    return ((z[1] - z[0]) + (z[3] - z[2]) + (z[5] - z[4])) / 3.0


def corpus_setup(bench: Bench, build: Path, programs, args, say, warn) -> tuple:
    """The runner, the settings (ours, then Radiance's when it runs) and the result dict
    of one corpus case.  Radiance's export and ``oconv`` are done here; when they fail
    the case runs on our side only and ``res["radiance_error"]`` says why."""
    runner = Runner(bench, build, programs, args.processes, args.run_timeout, args.memory_limit)
    settings = corpus_engine_ladder(args.quick)
    res: dict = {"runs": []}
    if programs is not None:
        say(f"{bench.name}: Radiance export and oconv")
        try:
            setup = runner.prepare_radiance()
        except Exception as exc:        # noqa: BLE001 - one case's export must not stop the corpus
            res["radiance_error"] = f"{type(exc).__name__}: {str(exc)[-300:]}"
            warn(f"compare_radiance: {bench.name}: Radiance not run: {res['radiance_error']}", file=sys.stderr)
        else:
            zone_size = zone_mean_side(bench.zone)
            setup["ar"] = ambient_resolution(AR_FACTOR, setup["cube"], zone_size)
            setup["zone_size"] = zone_size
            res["radiance_setup"] = setup
            settings += radiance_ladder(CORPUS, setup["cube"], zone_size, args.quick)
    return runner, settings, res


if __name__ == "__main__":
    sys.exit(main())

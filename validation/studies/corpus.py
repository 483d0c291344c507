"""Study: every preset on a corpus of daylit interiors, most of them modelled by others.

The corpus (:mod:`corpus_scenes`, ``validation/corpus/README.md``) holds our office,
furnished office and deep room (glazed, and with an unglazed opening nobody drew a portal
over) and four third-party interiors read from their own Radiance files: LBNL's open-plan
office with cubicles, Radiance's office with a light shelf, its cabin and its building-90
office with a venetian blind — each under a CIE overcast sky and a clear winter hour of a
real weather file.  The presets were chosen on the ``choose`` scenes (office, deep room,
LBNL office); the others are held out and only reported.

Every run is the whole command a user types, ``lbl-illum illuminance SCENE --points PTS
-o OUT --preset P``, timed from start to exit (Python start-up, loading, compiled kernels
from their disk cache, the calculation, writing), after one untimed run that fills the
kernel cache.  Its result is compared, sensor by sensor, with the case's converged
reference (``validation/corpus_reference.py``: pure Monte Carlo over independent seeds,
its standard error stated), which was cross-checked against Radiance where the file says so.

Targets (the project's accuracy targets for the corpus): every preset's bias within ±1 % on every case;
the default preset's mean error at most 1.5 × the reference's own standard error + 0.5 %.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from lbl_illum.options import DEFAULT_PRESET, PRESETS

from .corpus_scenes import SCENES, cases, corpus_root, prepare, reference_path
from .report import Report, StudyContext, error_summary, fmt, new_figure, pct

TITLE = "Every preset on a corpus of daylit interiors"

#: Bias every preset must stay within, and the default preset's error allowance.
BIAS_TARGET = 0.01
NOISE_FACTOR, ERROR_ALLOWANCE = 1.5, 0.005
#: Agreement of Radiance's pure Monte Carlo with a reference beyond which the report points to why.
RADIANCE_AGREEMENT = 0.02
#: Seeds per preset (the others run once, at seed 0).  A run's bias — its mean signed error
#: over the sensors — scatters from seed to seed, because every sensor reads the same few
#: records: at draft on the cabin its standard deviation is about 1 % (five seeds, +1.80,
#: -0.38, +0.89, -0.19, +0.62 %).  The bias a preset has is the mean over its seeds; the
#: spread, what one run of it may be off by besides, is reported beside it.
PRESET_SEEDS = {"draft": 5}
#: The quick version: one small case, two presets.
QUICK_CASES = [("deep-room", "overcast")]
QUICK_PRESETS = ("draft", "low")


def unavailable() -> str | None:
    """Why the study cannot run here (it needs the repository's corpus and references)."""
    root = corpus_root()
    if root is None:
        return "needs the repository's validation/corpus (run it from a source checkout)"
    return None


def _missing_references(todo) -> list[str]:
    return [f"{s.name}-{sky}" for s, sky in todo if not reference_path(s, sky).is_file()]



def _command(scene_file: Path, points: Path, preset: str, out: Path, stats: Path, seed: int = 0) -> list[str]:
    return [sys.executable, "-m", "lbl_illum", "illuminance", str(scene_file), "--points", str(points),
            "-o", str(out), "--preset", preset, "--stats", str(stats), "-q"] + (["--seed", str(seed)] if seed else [])


def _run(scene_file: Path, points: Path, preset: str, work: Path, seed: int = 0) -> dict:
    """One whole command: wall seconds, illuminance per sensor, records and rays."""
    out, stats = work / "out.csv", work / "stats.json"
    env = dict(os.environ)
    t0 = time.perf_counter()
    proc = subprocess.run(_command(scene_file, points, preset, out, stats, seed), capture_output=True, text=True,
                          env=env)
    seconds = time.perf_counter() - t0
    if proc.returncode != 0:
        raise RuntimeError(f"{scene_file.name} --preset {preset}: exit {proc.returncode}: {proc.stderr.strip()[-300:]}")
    values = np.loadtxt(out, delimiter=",", skiprows=1, usecols=6, ndmin=1)
    doc = json.loads(stats.read_text())
    return {"seconds": seconds, "illuminance": values, "records": int(sum(doc["records"])), "rays": int(doc["rays"]),
            "compute_seconds": float(doc.get("compute_seconds", np.nan))}


def run(ctx: StudyContext) -> Report:
    chosen = QUICK_CASES if ctx.quick else [(s.name, sky) for s, sky in cases()]
    presets = QUICK_PRESETS if ctx.quick else tuple(PRESETS)
    by_name = {s.name: s for s in SCENES}
    todo = [(by_name[n], sky) for n, sky in chosen]
    missing = _missing_references(todo)
    if missing and (ctx.quick or len(missing) == len(todo)):
        from lbl_illum.errors import InputError

        raise InputError(f"corpus: no converged reference for {', '.join(missing)} "
                         "(make them with python validation/corpus_reference.py)")
    todo = [(s, sky) for s, sky in todo if f"{s.name}-{sky}" not in missing]
    ctx.plan(len(todo) * (sum(_seeds(p, ctx.quick) for p in presets) + 1))
    rows, refs = [], {}
    with tempfile.TemporaryDirectory(prefix="lbl-corpus-") as tmp:
        work = Path(tmp)
        for scene, sky in todo:
            files, points = prepare(scene)
            ref = json.loads(reference_path(scene, sky).read_text())
            refs[f"{scene.name}-{sky}"] = ref
            E_ref = np.asarray(ref["illuminance"])
            _run(files[sky], points, presets[0], work)            # fills the kernel cache, loads the scene once
            ctx.step(f"{scene.name} {sky}: warm-up")
            for preset in presets:
                runs = []
                for seed in range(_seeds(preset, ctx.quick)):
                    r = _run(files[sky], points, preset, work, seed)
                    runs.append(r | error_summary(r["illuminance"], E_ref))
                    ctx.rays += r["rays"]
                    ctx.records += r["records"]
                    ctx.step(f"{scene.name} {sky}: {preset}" + (f" seed {seed}" if seed else ""))
                rows.append({"scene": scene.name, "sky": sky, "role": scene.role, "preset": preset,
                             "points": len(E_ref), "reference_rse": ref["relative_standard_error"]["mean"]}
                            | seed_summary(runs))
    return _report(rows, refs, presets, ctx.quick, missing)


def _seeds(preset: str, quick: bool) -> int:
    return 2 if quick and preset in PRESET_SEEDS else PRESET_SEEDS.get(preset, 1)


def seed_summary(runs: list[dict]) -> dict:
    """One preset on one case over its seeds (``runs``: each with seconds, records, rays,
    bias, mean and max error): the means over the seeds — bias, mean error, seconds,
    records, rays — the largest max error, and the bias's spread from seed to seed
    (standard deviation, 0 for one seed) and the standard error of its mean."""
    bias = np.array([r["bias"] for r in runs])
    n = len(runs)
    spread = float(np.std(bias, ddof=1)) if n > 1 else 0.0
    return {"seeds": n, "seconds": float(np.mean([r["seconds"] for r in runs])),
            "compute_seconds": float(np.mean([r["compute_seconds"] for r in runs])),
            "records": int(round(np.mean([r["records"] for r in runs]))),
            "rays": int(round(np.mean([r["rays"] for r in runs]))),
            "bias": float(bias.mean()), "bias_spread": spread, "bias_standard_error": spread / np.sqrt(n),
            "seed_bias": bias.tolist(), "mean_error": float(np.mean([r["mean"] for r in runs])),
            "max_error": float(max(r["max"] for r in runs))}


def _report(rows, refs, presets, quick, missing=()) -> Report:
    rep = Report("corpus", TITLE, "")
    res = rep.results
    res["runs"] = rows
    res["references"] = {k: {key: v[key] for key in ("method", "estimator", "seeds", "rays", "seconds",
                                                     "relative_standard_error") if key in v}
                         | ({"radiance_check": {k2: v2 for k2, v2 in v["radiance_check"].items()
                                                if k2 != "illuminance"}} if "radiance_check" in v else {})
                         for k, v in refs.items()}
    rep.text(f"""
Every number below is a whole command, `lbl-illum illuminance SCENE --points PTS -o OUT --preset P`, timed
from start to exit on {os.cpu_count()} cores, against the converged reference of its case.  The error of a
run is |E/E_ref − 1| per sensor; *mean* and *max* are over the sensors, *bias* is the mean signed error.
The presets were chosen on the scenes marked *chosen on* and are reported unchanged on the others.
{'(Quick version: one case, two presets; the full version is in docs/validation/corpus.)' if quick else ''}""")
    if missing:
        rep.text(f"**Not measured** (no converged reference yet): {', '.join(missing)}.  The targets below "
                 "are claimed for the measured cases only.")
    rep.heading("The corpus")
    rep.table(["scene", "source", "what it is", "role"],
              [[s.name, s.source, s.description, "chosen on" if s.role == "choose" else "held out"]
               for s in SCENES if any(r["scene"] == s.name for r in rows)])
    rep.heading("References")
    ref_rows = []
    for key, ref in refs.items():
        rc = ref.get("radiance_check")
        ref_rows.append([key, fmt(ref["seeds"]), f"{ref['seconds']:.0f}", pct(ref["relative_standard_error"]["mean"]),
                         pct(ref["relative_standard_error"]["max"]),
                         pct(rc["mean_lux_ratio"] - 1) if rc else "—", " ".join(rc["args"]) if rc else ""])
    rep.table(["case", "seeds", "s", "std. error mean", "max", "Radiance − ours (mean lux)", "Radiance options"],
              ref_rows)
    apart = [k for k, ref in refs.items() if "radiance_check" in ref
             and abs(ref["radiance_check"]["mean_lux_ratio"] - 1) > RADIANCE_AGREEMENT]
    if apart:
        rep.text(f"Radiance's pure Monte Carlo differs from the reference by more than {pct(RADIANCE_AGREEMENT, 0)} "
                 f"on {', '.join(apart)}: validation/corpus/README.md says what one program counts and the other "
                 "does not.")
    rep.heading("Every preset on every case")
    header = ["case", "preset", "s", "records", "rays", "seeds", "bias", "spread of a run's bias", "mean err",
              "max err", "target"]
    table = []
    for r in rows:
        ok = abs(r["bias"]) <= BIAS_TARGET
        if r["preset"] == DEFAULT_PRESET:
            ok &= r["mean_error"] <= NOISE_FACTOR * r["reference_rse"] + ERROR_ALLOWANCE
        table.append([f"{r['scene']} {r['sky']}" + ("" if r["role"] == "choose" else " (held out)"), r["preset"],
                      f"{r['seconds']:.1f}", fmt(r["records"]), fmt(r["rays"]), str(r.get("seeds", 1)),
                      pct(r["bias"]) + (f" ± {pct(r['bias_standard_error'])}" if r.get("seeds", 1) > 1 else ""),
                      pct(r["bias_spread"]) if r.get("seeds", 1) > 1 else "—", pct(r["mean_error"]),
                      pct(r["max_error"]), "met" if ok else "**missed**"])
    rep.table(header, table, caption="seconds, records, rays, bias and mean error: means over the seeds; "
              "bias ± its standard error over the seeds; spread: the standard deviation of one run's bias from "
              "seed to seed (what a single run may read off besides the bias); max err: the largest over the seeds.")
    res["targets"] = _targets(rows)
    res["targets"]["unmeasured"] = list(missing)
    if len(rows) > 2:
        rep.heading("Seconds against error")
        fig, ax = new_figure(7.5, 4.6)
        for i, preset in enumerate(presets):
            sel = [r for r in rows if r["preset"] == preset]
            ax.scatter([r["seconds"] for r in sel], [100 * r["mean_error"] for r in sel], label=preset, s=24,
                       c=f"C{i}", marker="o")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("whole command [s]")
        ax.set_ylabel("mean relative error [%]")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8)
        rep.figure("seconds_vs_error", fig, "Each preset on each case: whole-command seconds against mean error.")
    rep.heading("Findings")
    t = res["targets"]
    spread = {p: [r["bias_spread"] for r in rows if r["preset"] == p and r.get("seeds", 1) > 1] for p in presets}
    rep.bullets([f"One {p} run's bias scatters from seed to seed by {pct(float(np.median(v)))} (median over the "
                 f"cases, largest {pct(max(v))}): the bias of the preset is the mean over its "
                 f"{PRESET_SEEDS.get(p, 2)} seeds." for p, v in spread.items() if v] + [
        f"Bias within ±{pct(BIAS_TARGET, 0)}: {t['bias_met']} of {t['runs']} runs "
        f"({', '.join(t['bias_missed']) or 'none missed'}).",
        f"Default preset ({DEFAULT_PRESET}) within {NOISE_FACTOR:g} × the reference's standard error + "
        f"{pct(ERROR_ALLOWANCE, 1)}: {t['default_met']} of {t['default_runs']} cases "
        f"({', '.join(t['default_missed']) or 'none missed'}).",
        f"Cases without a reference, not measured: {', '.join(missing) or 'none'}.",
        f"Largest |bias| on the held-out scenes: {pct(t['held_out_worst_bias'])}; on the scenes the presets were "
        f"chosen on: {pct(t['chosen_worst_bias'])}.",
    ])
    return rep


def _targets(rows) -> dict:
    bias_missed = [f"{r['scene']} {r['sky']} {r['preset']}" for r in rows if abs(r["bias"]) > BIAS_TARGET]
    default = [r for r in rows if r["preset"] == DEFAULT_PRESET]
    default_missed = [f"{r['scene']} {r['sky']}" for r in default
                      if r["mean_error"] > NOISE_FACTOR * r["reference_rse"] + ERROR_ALLOWANCE]
    worst = {role: max([abs(r["bias"]) for r in rows if r["role"] == role] or [float("nan")])
             for role in ("choose", "report")}
    return {"runs": len(rows), "bias_met": len(rows) - len(bias_missed), "bias_missed": bias_missed,
            "default_runs": len(default), "default_met": len(default) - len(default_missed),
            "default_missed": default_missed, "chosen_worst_bias": worst["choose"],
            "held_out_worst_bias": worst["report"]}

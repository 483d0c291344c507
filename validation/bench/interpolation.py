"""The three interpolation rules at equal time: seconds against error on the office grid.

``interpolation = "paper"`` (Eq. 5 as published), ``"gradients"`` (Eq. 5 over values
extrapolated by each record's rotational and translational gradients, Ward & Heckbert
1992) and ``"hessian"`` (that, with elliptical record domains sized by the irradiance
Hessian and leak sectors, Schwarzhaupt, Jensen & Jarosz 2012) each run a ladder of
accuracies in two regimes — every level interpolated (``samples`` 256) and the sensors
evaluated alone (``point_samples`` 1024, ``samples`` 128, the fast route under 1 %).
Each run is a child process (:meth:`compare_radiance.Runner.run_engine`: warm-up, then
the timed ``Integrator.compute``), scored against the converged reference of
``validation/data/office_reference.json``.  For each rule the Pareto front of seconds
against mean error gives the time at 2 %, 1 % and 0.7 % (interpolated in log–log),
and the report divides it by the fastest rule's.

Run from the repository root (about 15 minutes on two cores)::

    python validation/bench/interpolation.py [--out docs/performance] [--quick]

Writes ``interpolation/report.md`` (and .html, .png, results.json) under ``--out``.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

import compare_radiance as cr  # noqa: E402

NAME = "interpolation"
TITLE = "Interpolation rules at equal time: paper, gradients and Hessian on the office grid"
RULES = ("paper", "gradients", "hessian")
LEVELS = (0.02, 0.01, 0.007)
#: accuracies per rule and regime; the Hessian's domains grow as a^(-1/2), so its
#: ladder reaches lower a for the same number of records
LADDERS = {
    "interpolated": {"paper": (0.07, 0.1, 0.15, 0.2), "gradients": (0.07, 0.1, 0.12, 0.15, 0.2),
                     "hessian": (0.05, 0.07, 0.1, 0.15, 0.2)},
    "point samples": {"paper": (0.1, 0.15, 0.2, 0.3), "gradients": (0.1, 0.15, 0.2, 0.3),
                      "hessian": (0.07, 0.1, 0.15, 0.2, 0.3)},
}
REGIMES = {"interpolated": {"samples": 256, "point_samples": 0},
           "point samples": {"samples": 128, "point_samples": 1024}}
QUICK = {"interpolated": {"gradients": (0.15,), "hessian": (0.15,), "paper": (0.15,)}}


def ladder(quick: bool = False) -> list[cr.Setting]:
    out = []
    for regime, per_rule in (QUICK if quick else LADDERS).items():
        for rule, accuracies in per_rule.items():
            for a in accuracies:
                options = cr.engine_options(accuracy=a, interpolation=rule, **REGIMES[regime])
                out.append(cr.Setting("lbl_illum", f"{rule}, {regime}", cr.engine_label(options), options=options))
    return out


def fronts(runs: list[dict]) -> dict:
    """(seconds, mean error) Pareto front per rule, over both regimes."""
    out = {}
    for rule in RULES:
        mine = [r for r in runs if not r.get("failed") and r["options"]["interpolation"] == rule]
        idx = cr.pareto_front([r["seconds"] for r in mine], [r["mean_error"] for r in mine])
        for k, r in enumerate(mine):
            r["front"] = k in idx
        out[rule] = [(mine[i]["seconds"], mine[i]["mean_error"]) for i in idx]
    return out


def equal_time(front: dict) -> list[dict]:
    """Per error level: each rule's seconds (or why none) and its ratio to the fastest."""
    rows = []
    for level in LEVELS:
        times = {rule: cr.time_at_error(front[rule], level) for rule in RULES}
        known = [s for s, kind in times.values() if s is not None and kind == "interpolated"]
        best = min(known) if known else None
        rows.append({"level": level, "seconds": {r: t[0] for r, t in times.items()},
                     "kind": {r: t[1] for r, t in times.items()},
                     "ratio": {r: (t[0] / best if best and t[0] is not None and t[1] == "interpolated" else None)
                               for r, t in times.items()}})
    return rows


def figure(runs: list[dict], front: dict):
    from lbl_illum_studies.report import new_figure

    fig, ax = new_figure(6.4, 4.2)
    colours = {"paper": "tab:gray", "gradients": "tab:blue", "hessian": "tab:red"}
    markers = {"interpolated": "o", "point samples": "s"}
    for r in runs:
        if r.get("failed"):
            continue
        rule = r["options"]["interpolation"]
        regime = "point samples" if r["options"].get("point_samples") else "interpolated"
        ax.scatter(100 * r["mean_error"], r["seconds"], color=colours[rule], marker=markers[regime], s=22,
                   alpha=0.9 if r.get("front") else 0.35)
    for rule in RULES:
        if front[rule]:
            s, e = zip(*front[rule])
            ax.plot([100 * x for x in e], s, color=colours[rule], label=rule)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("mean relative error [%]")
    ax.set_ylabel("compute seconds (2 threads)")
    ax.invert_xaxis()
    ax.legend(title="interpolation (○ all levels, □ point samples)")
    ax.grid(True, which="both", alpha=0.3)
    return fig


def write_report(out: Path, bench, runs: list[dict], args, seconds: float) -> Path:
    from lbl_illum_studies.report import Report, environment

    front = fronts(runs)
    rows = equal_time(front)
    command = "python validation/bench/interpolation.py" + (" --quick" if args.quick else "")
    report = Report(NAME, TITLE, command)
    report.heading("Summary")

    def cell(row, rule):
        s, kind, ratio = row["seconds"][rule], row["kind"][rule], row["ratio"][rule]
        if s is None:
            return kind
        text = ("≤ " if kind == "at most" else "") + f"{s:.2f} s"
        return text + (f" (× {ratio:.2f})" if ratio is not None else "")

    report.table(["mean error"] + list(RULES), [[cr.pct(r["level"], 1)] + [cell(r, rule) for rule in RULES]
                                                for r in rows],
                 caption="Compute seconds at equal mean error, interpolated on each rule's Pareto front "
                         "(× : over the fastest rule at that level).")
    report.figure("fronts", figure(runs, front), "Seconds against mean error; lines join each rule's Pareto front.")
    report.heading("How it is measured")
    report.bullets([
        f"Scene: {bench.title}; reference: {bench.reference_info['method']} (standard error "
        f"{cr.pct(bench.reference_info['standard_error_mean'])} mean).",
        "Each run is a child process on 2 threads: load, warm up on 4 points at cheap settings, then the timed "
        "`Integrator(scene, options).compute(points, normals)`.",
        "Two regimes per rule: every level interpolated (samples 256) and the sensors evaluated alone "
        "(point samples 1024, samples 128); the front of each rule takes the best of both.",
        "The Hessian rule's domains scale as a^(-1/2) (its error bound is of second order), so its ladder "
        "reaches lower accuracies for the same number of records.",
        "Seconds on a shared machine drift between runs; the ratios within one run are what compare.",
    ])
    report.heading("Runs")
    header, table = cr.run_table(runs)
    report.table(header, table)
    report.results = {"runs": runs, "fronts": front, "equal_time": rows, "levels": list(LEVELS)}
    return report.write(out / NAME, {"quick": args.quick, "seconds": seconds, "environment": environment()})


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--out", type=Path, default=cr.ROOT / "docs" / "performance",
                        help="folder for the report (default docs/performance)")
    parser.add_argument("--build", type=Path, default=cr.ROOT / "build" / "interpolation",
                        help="scratch folder for the runs")
    parser.add_argument("--quick", action="store_true", help="one setting per rule (a smoke test)")
    parser.add_argument("--worker", help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.worker:
        return cr.worker(args.worker)
    from tqdm import tqdm

    t0 = time.perf_counter()
    bench = cr.prepare_office()
    runner = cr.Runner(bench, args.build, programs=None)
    settings = ladder(args.quick)
    # one untimed run fills numba's compilation cache for every rule
    for rule in RULES:
        runner.run_engine(cr.Setting("lbl_illum", "warm", "warm", options=cr.engine_options(
            accuracy=0.3, samples=64, bounces=2, interpolation=rule)))
    runs = []
    for s in tqdm(settings, desc="interpolation ladder", unit="run"):
        runs.append(runner.run_engine(s))
    path = write_report(args.out, bench, runs, args, time.perf_counter() - t0)
    rows = equal_time(fronts(runs))
    summary = "; ".join(f"{cr.pct(r['level'], 1)}: " + ", ".join(
        f"{rule} {r['seconds'][rule]:.2f} s" if r["seconds"][rule] is not None else f"{rule} {r['kind'][rule]}"
        for rule in RULES) for r in rows)
    print(f"interpolation: {len(runs)} runs in {time.perf_counter() - t0:.0f} s; {summary}; report {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

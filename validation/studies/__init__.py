"""Validation studies: each compares the tool with an analytic or independently
computed answer, or measures what a setting costs and buys, and writes a report.

Run one with ``lbl-illum validate NAME [--report DIR] [--quick]``.  These modules live
in the repository's ``validation/studies/`` folder and are installed as the package
``lbl_illum_studies`` (see ``pyproject.toml``), so the command works from a source
checkout and from an installed copy alike.

A study module has ``TITLE`` and ``run(ctx: StudyContext) -> Report``; ``ctx.quick``
selects the reduced version the test suite runs.  A study that needs something not every
installation has (Radiance's programs, the ``examples/`` folder of a source checkout) also
has ``unavailable() -> str | None``, saying why it cannot run here; :func:`unavailable`
asks it, and ``lbl-illum validate all`` skips such a study with that line instead of
stopping.
"""

from __future__ import annotations

import importlib
import time
from pathlib import Path

from .report import Report, StudyContext, environment

__all__ = ["STUDIES", "run_study", "unavailable", "Report", "StudyContext", "repository_root"]

#: study name -> module
STUDIES = {
    "sphere-plane": "sphere_plane",
    "integrating-sphere": "integrating_sphere",
    "office-tradeoff": "office_tradeoff",
    "extremes": "extremes",
    "scene-requires": "scene_requires",
    "figure5": "figure5",
    "deep-room": "deep_room",
    "sky-component": "sky_component",
    "office-daylight": "office_daylight",
    "corpus": "corpus",
    "electric": "electric",
    "glare": "glare",
    "annual": "annual",
}


def command(name: str, quick: bool, report_dir: str = "docs/validation") -> str:
    """The command that regenerates a report where it is (``--force``: it is there)."""
    return f"lbl-illum validate {name} --report {report_dir} --force" + (" --quick" if quick else "")


def repository_root() -> Path | None:
    """The source checkout holding ``examples/`` (for studies of the bundled examples):
    the folder above ``validation/`` when run from a checkout, else the working folder
    if it holds ``examples/``; None when neither does."""
    here = Path(__file__).resolve()
    for candidate in (here.parents[2], Path.cwd()):
        if (candidate / "examples" / "office" / "scene.toml").is_file():
            return candidate
    return None


def unavailable(name: str) -> str | None:
    """Why study ``name`` cannot run here (its module's ``unavailable()``), or None when it
    can or has no such hook."""
    module = importlib.import_module(f".{STUDIES[name]}", __name__)
    hook = getattr(module, "unavailable", None)
    return hook() if callable(hook) else None


def run_study(name: str, ctx: StudyContext, report_dir: str | Path, command_dir: str | None = None) -> Path:
    """Run study ``name`` and write its report to ``report_dir/name/``."""
    module = importlib.import_module(f".{STUDIES[name]}", __name__)
    t0 = time.perf_counter()
    report: Report = module.run(ctx)
    report.command = command(name, ctx.quick, command_dir or "docs/validation")
    meta = {"quick": ctx.quick, "seconds": time.perf_counter() - t0, "rays": ctx.rays,
            "records": ctx.records, "runs": ctx.runs, "environment": environment()}
    return report.write(Path(report_dir) / name, meta)

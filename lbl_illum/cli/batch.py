"""``lbl-illum batch STUDIES.toml``: many studies — scenes, variants, grids, views, weather
files — on one cluster, with one progress display and one summary table
(docs/distributed.md).

A batch file lists studies, each one run of ``illuminance``, ``daylight-factor``,
``render`` or ``annual`` with that command's own options::

    [defaults]                       # options every study gets unless it gives its own
    preset = "draft"

    [[study]]
    name = "office grid"
    command = "illuminance"
    scene = "office/scene.toml"      # paths relative to the batch file
    points = "office/grid.pts"
    output = "out/office.csv"
    options = { bounces = 4, cache = "out/office.cache" }

    [[study]]                        # one study per variant: a glob of scene files
    command = "daylight-factor"
    scene = "variants/*.toml"
    points = "office/grid.pts"
    output = "out/{stem}-df.csv"     # {stem}: the scene file's name without .toml

An option's key is its long name without the dashes (``min_spacing`` or ``min-spacing``;
``x`` and ``y`` of ``render``); ``true`` gives a flag, a list several values.  Every study is
parsed and checked before any runs (unknown options, missing files, bad or shared
output paths: one line naming the study, exit 2, nothing written).  The studies then run
one after the other, each on the batch's cluster (``--workers``, ``--scheduler``; the
chunks and rounds of ``--chunk-size`` and ``--round-chunks``), their progress going to
the batch's one display (the study, its stage, percent and time left of the batch) and
their summary lines gathered, not shown: at the end the batch prints one table (study, command, seconds, the study's summary
line).  The display's share of the work done is each study's own (its rounds, its
levels' blocks) as its share of the batch.  A study that fails while running is marked in
the table and the others go on (exit status 1).
"""

from __future__ import annotations

import contextlib
import glob
import io
import sys
import time
from dataclasses import dataclass
from pathlib import Path

from ..errors import InputError
from .shared import add_cluster_arguments, check_cluster_arguments, open_study_cluster

__all__ = ["add_batch_arguments", "batch_command", "read_batch", "COMMANDS"]

#: The commands a study may run, and their required positional and path options.
COMMANDS = ("illuminance", "daylight-factor", "render", "annual")
#: Keys of a study table besides ``options``.
STUDY_KEYS = {"name", "command", "scene", "points", "weather", "output", "options"}
#: Options whose values are paths (relative to the batch file; ``{stem}`` the scene's), and
#: of those the files a study writes (two studies may share a cache file, not an output).
PATH_OPTIONS = {"cache", "stats", "summary", "plot", "preview", "falsecolor", "glare-json", "view-file", "schedule",
                "view3d"}
OUTPUT_OPTIONS = {"stats", "summary", "plot", "preview", "falsecolor", "glare-json", "view3d"}
#: Options a study may not set: the batch's own.
BATCH_ONLY = {"workers", "scheduler", "chunk-size", "round-chunks", "quiet", "q"}


def add_batch_arguments(parser) -> None:
    """Arguments of ``lbl-illum batch``."""
    parser.add_argument("batch", metavar="STUDIES.toml", help="the batch file: [defaults] and [[study]] tables")
    add_cluster_arguments(parser)
    parser.add_argument("--table", metavar="FILE", help="write the summary table as JSON too (default: none)")
    parser.add_argument("-q", "--quiet", action="store_true", help="no progress display and no table")


@dataclass
class Study:
    """One study of a batch: its name, command and the command line it runs."""

    name: str
    command: str
    argv: list
    outputs: list


def _option_argv(key: str, value, where: str) -> list[str]:
    """The command-line words of one option of a study."""
    name = key.replace("_", "-")
    if name in BATCH_ONLY:
        raise InputError(f"{where}: option '{key}' is the batch's own (give it on the batch's command line)")
    flag = f"-{name}" if len(name) == 1 else f"--{name}"
    if value is True:
        return [flag]
    if value is False:
        return []
    if isinstance(value, list):
        return [flag, *(str(v) for v in value)]
    if isinstance(value, dict):
        raise InputError(f"{where}: option '{key}' must be a value, not a table")
    return [f"{flag}={value}"] if str(value).startswith("-") else [flag, str(value)]


def read_batch(path) -> list[Study]:
    """The studies of the batch file ``path``, each as the command line it runs (paths made
    relative to the batch file's folder, scene globs expanded); bad input is one
    :class:`InputError` line naming the study."""
    try:
        import tomllib
    except ImportError:  # Python 3.10
        import tomli as tomllib

    path = Path(path)
    here = path.parent
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise InputError(f"{path}: no such batch file") from None
    except IsADirectoryError:
        raise InputError(f"{path}: is a folder; give a batch file (.toml)") from None
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise InputError(f"{path.name}: not a TOML file ({str(exc).splitlines()[0]})") from None
    unknown = sorted(set(data) - {"defaults", "study"})
    if unknown:
        raise InputError(f"{path.name}: unknown table '{unknown[0]}' (a batch has [defaults] and [[study]])")
    defaults = data.get("defaults", {})
    tables = data.get("study", [])
    if not isinstance(defaults, dict) or not isinstance(tables, list) or not tables:
        raise InputError(f"{path.name}: no [[study]] table")
    studies = []
    for i, table in enumerate(tables, 1):
        where = f"{path.name}: study {i}" + (f" ({table['name']})" if isinstance(table.get("name"), str) else "")
        extra = sorted(set(table) - STUDY_KEYS)
        if extra:
            raise InputError(f"{where}: unknown key '{extra[0]}' (options go under options = {{...}})")
        command = table.get("command")
        if command not in COMMANDS:
            raise InputError(f"{where}: command must be one of {', '.join(COMMANDS)}, got {command!r}")
        for key in ("scene", "output"):
            if not isinstance(table.get(key), str):
                raise InputError(f"{where}: '{key}' (a path) is required")
        pattern = str(here / table["scene"])
        scenes = sorted(glob.glob(pattern)) if glob.has_magic(table["scene"]) else [pattern]
        if not scenes:
            raise InputError(f"{where}: no scene file matches {table['scene']}")
        options = {**defaults, **table.get("options", {})}
        for scene in scenes:
            stem = Path(scene).stem
            name = f"{table['name']} [{stem}]" if "name" in table and len(scenes) > 1 else \
                str(table.get("name", f"{command} {stem}"))
            output = str(here / table["output"].replace("{stem}", stem))
            argv = [command, scene, "-o", output]
            for key in ("points", "weather"):
                if key in table:
                    argv += [f"--{key}", str(here / table[key])]
            outputs = [output]
            for key, value in options.items():
                option = key.replace("_", "-")
                if option in PATH_OPTIONS:
                    value = str(here / str(value).replace("{stem}", stem))
                    if option in OUTPUT_OPTIONS:
                        outputs.append(value)
                argv += _option_argv(key, value, where)
            studies.append(Study(name, command, argv, outputs))
    seen = {}
    for study in studies:
        for out in study.outputs:
            key = str(Path(out).resolve())
            if key in seen:
                raise InputError(f"{path.name}: studies '{seen[key]}' and '{study.name}' both write {out}")
            seen[key] = study.name
    return studies


def _parse(study: Study, parser):
    """The namespace of a study's command line, checked as its command checks it before any
    work; its errors named after the study."""
    try:
        args = parser.parse_args(study.argv)
        if study.command in ("illuminance", "daylight-factor"):
            from .main import _check_run_files

            _check_run_files(args)
        elif study.command == "render":
            from .render import _check_outputs

            _check_outputs(args)
        else:
            from .annual import _check

            _check(args)
        for key in ("scene", "points", "weather"):
            value = getattr(args, key, None)
            if value and not Path(value).exists():
                raise InputError(f"{value}: no such file")
    except InputError as exc:
        message = str(exc)
        if message.startswith("lbl-illum"):            # the parser's "lbl-illum[ COMMAND]: ..."
            message = message.split(": ", 1)[1]
        raise InputError(f"study '{study.name}': {message}") from None
    return args


class _StudyProgress:
    """A study's progress calls (``update``, ``describe``, ``fraction``) forwarded to the
    batch's one display, the study's share of the work being its share of the batch."""

    enabled = False          # no compile listener of its own (cli.progress.compile_notice)

    def __init__(self, bar, index: int, count: int, name: str):
        self.bar, self.index, self.count, self.name = bar, index, count, name

    def update(self, rays: int) -> None:
        self.bar.update(rays)

    def describe(self, text: str) -> None:
        head = f"study {self.index + 1} of {self.count} ({self.name})"
        self.bar.describe(f"{head}: {text}" if text and text != "done" else head)

    def fraction(self, done: float) -> None:
        self.bar.fraction((self.index + min(max(float(done), 0.0), 1.0)) / self.count)


class _Borrowed:
    """The batch's cluster lent to one study: the study's ``close`` leaves it open."""

    def __init__(self, cluster):
        self._cluster = cluster

    def __getattr__(self, name):
        return getattr(self._cluster, name)

    def close(self) -> None:
        pass


def batch_command(args, parser) -> int:
    """``lbl-illum batch``: check every study, run them on one cluster, print one table;
    0, or 1 if a study failed while running (``parser``: the program's, which parses each
    study's command line)."""
    from .shared import check_output_file

    t0 = time.perf_counter()
    check_output_file(args.table, ".json", "--table")
    check_cluster_arguments(args)
    studies = read_batch(args.batch)
    parsed = [_parse(study, parser) for study in studies]
    cluster = open_study_cluster(args)
    rows = []
    from .progress import ProgressBar

    bar = ProgressBar(enabled=not args.quiet, label="lbl-illum batch")
    try:
        for i, (study, sargs) in enumerate(zip(studies, parsed)):
            sargs.progress = _StudyProgress(bar, i, len(studies), study.name)
            sargs.progress.describe("")
            sargs.progress.fraction(0.0)
            for key in ("workers", "scheduler", "chunk_size", "round_chunks"):
                setattr(sargs, key, getattr(args, key))
            sargs.cluster = _Borrowed(cluster) if cluster is not None else None
            rows.append(_run_study(study, sargs))
        bar.fraction(1.0)
    finally:
        bar.close()
        if cluster is not None:
            cluster.close()
    failed = sum(row["status"] != "ok" for row in rows)
    if args.table:
        import json

        from ..io.files import atomic_write_text

        atomic_write_text(args.table, json.dumps({"batch": str(args.batch), "studies": rows}, indent=2) + "\n")
    if not args.quiet:
        print(_table(rows), file=sys.stderr)
        where = f" on {cluster.name}" if cluster is not None else ""
        print(f"lbl-illum: batch of {len(rows)} stud{'ies' if len(rows) != 1 else 'y'} in "
              f"{time.perf_counter() - t0:.1f} s{where}: {len(rows) - failed} done, {failed} failed", file=sys.stderr)
    return 1 if failed else 0


def _run_study(study: Study, args) -> dict:
    """Run one study with its progress and summary line gathered; its row of the table."""
    t = time.perf_counter()
    lines = io.StringIO()
    with contextlib.redirect_stderr(lines):
        try:
            status = _dispatch(study.command, args)
            note = ""
        except InputError as exc:
            status, note = 2, " ".join(str(exc).split())
        except Exception as exc:  # noqa: BLE001 — one study's failure is its row, the batch goes on
            status, note = 1, f"{type(exc).__name__}: {' '.join(str(exc).split())}"
    said = [line for line in lines.getvalue().splitlines() if line.startswith("lbl-illum: ") and
            not line.startswith(("lbl-illum: note", "lbl-illum: warning"))]
    summary = said[-1][len("lbl-illum: "):] if said and status == 0 else note
    return {"study": study.name, "command": study.command, "seconds": round(time.perf_counter() - t, 2),
            "status": "ok" if status == 0 else "failed", "summary": summary, "command_line": study.argv}


def _dispatch(command: str, args) -> int:
    if command == "illuminance":
        from .main import _run_illuminance

        return _run_illuminance(args)
    if command == "daylight-factor":
        from .main import _run_daylight_factor

        return _run_daylight_factor(args)
    if command == "render":
        from .render import render_command

        return render_command(args, progress=args.progress)
    from .annual import annual_command

    return annual_command(args)


def _table(rows) -> str:
    """The summary table: study, command, seconds, and its summary line (or its error)."""
    head = ("study", "command", "s", "result")
    cells = [(r["study"], r["command"], f"{r['seconds']:.1f}",
              r["summary"] if r["status"] == "ok" else f"FAILED: {r['summary']}") for r in rows]
    width = [max(len(head[k]), *(len(c[k]) for c in cells)) for k in range(3)]
    lines = ["  ".join(h.ljust(w) for h, w in zip(head[:3], width)) + "  " + head[3]]
    lines += ["  ".join(c[k].ljust(width[k]) for k in range(3)) + "  " + c[3] for c in cells]
    return "\n".join(lines)

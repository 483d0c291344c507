"""A validation report: headings, prose, tables, equations and figures, written as
``report.md``, ``report.html``, PNG plots and ``results.json`` (every number the
report states), all at once or not at all.

Studies build a :class:`Report` block by block; :meth:`Report.write` renders both
documents from the same blocks, so the Markdown and the HTML say the same thing.
Inline markup in prose is the small Markdown subset both renderings share:
```code```, ``**bold**``, ``*emphasis*`` and ``[text](url)``.
"""

from __future__ import annotations

import datetime as _dt
import html
import io
import json
import math
import os
import platform
import re
import shutil
import tempfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable

import numpy as np

__all__ = ["Report", "StudyContext", "error_summary", "fmt", "pct", "new_figure"]


def fmt(value: Any, digits: int = 3) -> str:
    """A number as a report prints it: ``digits`` significant digits, thousands
    separators for integers, ``—`` for None or NaN."""
    if value is None:
        return "—"
    if isinstance(value, (bool, np.bool_)):
        return "yes" if value else "no"
    if isinstance(value, (int, np.integer)):
        return f"{int(value):,}"
    if isinstance(value, (float, np.floating)):
        if not math.isfinite(value):
            return "—" if math.isnan(value) else ("∞" if value > 0 else "−∞")
        if value == 0:
            return "0"
        if abs(value) >= 10 ** (digits + 3) or abs(value) < 10 ** -(digits + 1):
            return f"{value:.{digits - 1}e}"
        if abs(value) >= 10 ** digits:
            return f"{value:,.0f}"
        return f"{value:.{digits}g}"
    return str(value)


def pct(value: float | None, digits: int = 2) -> str:
    """A fraction as a percentage with ``digits`` decimals."""
    if value is None or not math.isfinite(value):
        return "—"
    return f"{100.0 * value:.{digits}f} %"


def error_summary(values, reference) -> dict:
    """Relative error of ``values`` against ``reference`` (same shape): mean of |err|,
    max of |err|, mean signed error (bias) and RMS, as fractions."""
    values = np.asarray(values, np.float64)
    reference = np.asarray(reference, np.float64)
    err = values / reference - 1.0
    return {"mean": float(np.mean(np.abs(err))), "max": float(np.max(np.abs(err))),
            "bias": float(np.mean(err)), "rms": float(np.sqrt(np.mean(err * err)))}


def new_figure(width: float = 6.4, height: float = 4.0, **subplots):
    """``(figure, axes)``: a matplotlib figure made without pyplot (no display, no
    global state), for :meth:`Report.figure`."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=(width, height), layout="constrained")
    return fig, fig.subplots(**subplots)


# -- inline markup -------------------------------------------------------------------
_INLINE = [
    (re.compile(r"`([^`]+)`"), r"<code>\1</code>"),
    (re.compile(r"\*\*([^*]+)\*\*"), r"<strong>\1</strong>"),
    (re.compile(r"(?<![*\w])\*([^*\s][^*]*)\*(?![*\w])"), r"<em>\1</em>"),
    (re.compile(r"\[([^\]]+)\]\(([^)\s]+)\)"), r'<a href="\2">\1</a>'),
]


def _inline_html(text: str) -> str:
    out = html.escape(text, quote=False)
    # code spans first, and keep their contents away from the other rules
    codes: list[str] = []

    def stash(match):
        codes.append(f"<code>{match.group(1)}</code>")
        return f"\x00{len(codes) - 1}\x00"

    out = _INLINE[0][0].sub(stash, out)
    for pattern, repl in _INLINE[1:]:
        out = pattern.sub(repl, out)
    return re.sub(r"\x00(\d+)\x00", lambda m: codes[int(m.group(1))], out)


@dataclass
class _Figure:
    name: str
    figure: Any           # a matplotlib Figure
    caption: str


@dataclass
class Report:
    """One study's report.  ``command`` is the one command that regenerates it."""

    name: str
    title: str
    command: str
    blocks: list = field(default_factory=list)
    results: dict = field(default_factory=dict)

    # -- building ------------------------------------------------------------------
    def heading(self, text: str, level: int = 2) -> None:
        self.blocks.append(("heading", level, text))

    def text(self, text: str) -> None:
        """One or more paragraphs (separated by blank lines) of inline-marked prose."""
        for para in re.split(r"\n\s*\n", text.strip()):
            self.blocks.append(("para", " ".join(line.strip() for line in para.splitlines())))

    def intro(self, docstring: str) -> None:
        """The opening of a study from its module docstring: the paragraph after the title
        line as text, then its ``* `` items (up to the "Criteria" paragraph) as bullets."""
        doc = docstring.split("\n\n", 1)[1].split("Criteria")[0]
        paragraphs = doc.strip().split("\n\n")
        self.text(paragraphs[0])
        items = []
        for line in "\n".join(paragraphs[1:]).splitlines():
            if line.startswith("* "):
                items.append(line[2:].strip())
            elif items:
                items[-1] += " " + line.strip()
        self.bullets(items)

    def bullets(self, items) -> None:
        self.blocks.append(("bullets", [str(i) for i in items]))

    def equation(self, text: str) -> None:
        """A preformatted block (derivations in plain text and Unicode)."""
        self.blocks.append(("pre", text.strip("\n")))

    def table(self, header, rows, caption: str | None = None) -> None:
        """``rows`` of cells; numbers are formatted by :func:`fmt`, strings kept."""
        cells = [[c if isinstance(c, str) else fmt(c) for c in row] for row in rows]
        self.blocks.append(("table", [str(h) for h in header], cells, caption))

    def figure(self, name: str, figure, caption: str) -> None:
        """A matplotlib figure, saved as ``name.png`` next to the report."""
        self.blocks.append(("figure", _Figure(name, figure, caption)))

    # -- rendering -----------------------------------------------------------------
    def markdown(self) -> str:
        lines = [f"# {self.title}", "", f"Regenerate this report with `{self.command}`.", ""]
        for block in self.blocks:
            kind = block[0]
            if kind == "heading":
                lines += ["#" * block[1] + " " + block[2], ""]
            elif kind == "para":
                lines += [block[1], ""]
            elif kind == "bullets":
                lines += [f"- {item}" for item in block[1]] + [""]
            elif kind == "pre":
                lines += ["```", block[1], "```", ""]
            elif kind == "table":
                _, header, rows, caption = block
                if caption:
                    lines += [caption, ""]
                lines.append("| " + " | ".join(header) + " |")
                lines.append("|" + "|".join("---" for _ in header) + "|")
                lines += ["| " + " | ".join(c.replace("|", "\\|") for c in row) + " |" for row in rows]
                lines.append("")
            elif kind == "figure":
                fig = block[1]
                lines += [f"![{fig.caption}]({fig.name}.png)", "", f"*{fig.caption}*", ""]
        return "\n".join(lines).rstrip() + "\n"

    def html(self) -> str:
        parts = [
            "<!DOCTYPE html>", '<html lang="en">', "<head>", '<meta charset="utf-8">',
            f"<title>{html.escape(self.title)}</title>",
            "<style>body{font-family:system-ui,sans-serif;max-width:60rem;margin:2rem auto;padding:0 1rem;"
            "line-height:1.45}table{border-collapse:collapse;margin:1rem 0}td,th{border:1px solid #bbb;"
            "padding:.2rem .5rem;text-align:right}th{background:#eee}td:first-child,th:first-child"
            "{text-align:left}pre{background:#f6f6f6;padding:.7rem;overflow-x:auto}img{max-width:100%}"
            "figcaption{font-style:italic}</style>", "</head>", "<body>",
            f"<h1>{html.escape(self.title)}</h1>",
            f"<p>Regenerate this report with <code>{html.escape(self.command)}</code>.</p>"]
        for block in self.blocks:
            kind = block[0]
            if kind == "heading":
                parts.append(f"<h{block[1]}>{_inline_html(block[2])}</h{block[1]}>")
            elif kind == "para":
                parts.append(f"<p>{_inline_html(block[1])}</p>")
            elif kind == "bullets":
                parts.append("<ul>" + "".join(f"<li>{_inline_html(i)}</li>" for i in block[1]) + "</ul>")
            elif kind == "pre":
                parts.append(f"<pre>{html.escape(block[1])}</pre>")
            elif kind == "table":
                _, header, rows, caption = block
                cap = f"<caption>{_inline_html(caption)}</caption>" if caption else ""
                head = "".join(f"<th>{_inline_html(h)}</th>" for h in header)
                body = "".join("<tr>" + "".join(f"<td>{_inline_html(c)}</td>" for c in row) + "</tr>"
                               for row in rows)
                parts.append(f"<table>{cap}<thead><tr>{head}</tr></thead><tbody>{body}</tbody></table>")
            elif kind == "figure":
                fig = block[1]
                parts.append(f'<figure><img src="{fig.name}.png" alt="{html.escape(fig.caption)}">'
                             f"<figcaption>{_inline_html(fig.caption)}</figcaption></figure>")
        parts += ["</body>", "</html>"]
        return "\n".join(parts) + "\n"

    def write(self, folder: str | os.PathLike, meta: dict | None = None) -> Path:
        """Write ``folder/`` (replacing an older one) with report.md, report.html,
        results.json and the figures.  Everything is written to a temporary folder
        beside it first and swapped in by renames, so a failed or interrupted write
        leaves the old report whole."""
        folder = Path(folder)
        folder.parent.mkdir(parents=True, exist_ok=True)
        tmp = Path(tempfile.mkdtemp(prefix=f".{folder.name}.", dir=folder.parent))
        try:
            for block in self.blocks:
                if block[0] == "figure":
                    fig = block[1]
                    buf = io.BytesIO()
                    fig.figure.savefig(buf, format="png", dpi=110, bbox_inches="tight")
                    (tmp / f"{fig.name}.png").write_bytes(buf.getvalue())
            (tmp / "report.md").write_text(self.markdown(), encoding="utf-8")
            (tmp / "report.html").write_text(self.html(), encoding="utf-8")
            doc = {"study": self.name, "title": self.title, "command": self.command, **(meta or {}),
                   "results": self.results}
            (tmp / "results.json").write_text(json.dumps(_plain(doc), indent=1) + "\n", encoding="utf-8")
            mode = 0o777 & ~_umask()
            os.chmod(tmp, mode)
            old = None
            if folder.exists():
                old = folder.with_name(f".{folder.name}.old-{os.getpid()}")
                os.replace(folder, old)
            os.replace(tmp, folder)
            if old is not None:
                shutil.rmtree(old, ignore_errors=True)
        except BaseException:
            shutil.rmtree(tmp, ignore_errors=True)
            raise
        return folder


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def _plain(obj):
    """JSON-ready copy: numpy scalars and arrays to Python, non-finite floats to None."""
    if isinstance(obj, dict):
        return {str(k): _plain(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_plain(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return _plain(obj.tolist())
    if isinstance(obj, (np.integer,)):
        return int(obj)
    if isinstance(obj, (float, np.floating)):
        return float(obj) if math.isfinite(obj) else None
    if isinstance(obj, (np.bool_,)):
        return bool(obj)
    return obj


@dataclass
class StudyContext:
    """What a study gets from the command line: the reduced (``quick``) or full
    version, a progress callback, and counters for the summary line."""

    quick: bool = False
    progress: Callable[[str], None] | None = None
    rays: int = 0
    records: int = 0
    runs: int = 0
    planned: int = 0
    on_plan: Callable[[int], None] | None = None

    def plan(self, runs: int) -> None:
        """Announce how many runs (steps) follow, for the progress bar."""
        self.planned += runs
        if self.on_plan is not None:
            self.on_plan(self.planned)

    def step(self, label: str, stats=None) -> None:
        """One run done; ``stats`` (a :class:`lbl_illum.engine.integrator.RunStats`) adds its
        rays and records to the totals."""
        self.runs += 1
        if stats is not None:
            self.rays += int(stats.rays)
            self.records += int(sum(stats.new_records))
        if self.progress is not None:
            self.progress(label)


def environment() -> dict:
    """Where and when a report was made (for results.json)."""
    from lbl_illum import __version__

    return {"lbl_illum": __version__, "python": platform.python_version(),
            "machine": platform.machine(), "cpus": os.cpu_count(),
            "date": _dt.date.today().isoformat()}

"""The report writer of the validation studies: both renderings say the same thing,
results.json holds plain JSON, and a report is replaced whole or not at all."""

import json

import numpy as np
import pytest

from lbl_illum_studies.report import Report, error_summary, fmt, new_figure, pct


def sample_report():
    rep = Report("demo", "Demo study", "lbl-illum validate demo")
    rep.heading("Derivation")
    rep.text("The **plane** at `z = 0` is lit at *E0*; see [the paper](https://example.org).\n\nSecond one.")
    rep.equation("E = E0 sin γ")
    rep.bullets(["first", "second <b>"])
    rep.table(["a", "mean", "n"], [[0.1, pct(0.0123), 12345], [0.025, float("nan"), 3]], caption="Errors")
    fig, ax = new_figure(3, 2)
    ax.plot([0, 1], [0, 1])
    rep.figure("line", fig, "A line")
    rep.results.update({"a": np.float32(0.5), "n": np.int64(3), "list": np.arange(3), "bad": float("inf")})
    return rep


def test_markdown_and_html_carry_the_same_content(tmp_path):
    folder = sample_report().write(tmp_path / "demo", {"quick": True})
    md = (folder / "report.md").read_text()
    page = (folder / "report.html").read_text()
    assert md.startswith("# Demo study\n\nRegenerate this report with `lbl-illum validate demo`.")
    assert "| 0.1 | 1.23 % | 12,345 |" in md and "| 0.025 | — | 3 |" in md
    assert "![A line](line.png)" in md and (folder / "line.png").read_bytes()[:4] == b"\x89PNG"
    assert "<strong>plane</strong>" in page and "<code>z = 0</code>" in page and "<em>E0</em>" in page
    assert '<a href="https://example.org">the paper</a>' in page
    assert "second &lt;b&gt;" in page and "<td>12,345</td>" in page and '<img src="line.png"' in page
    doc = json.loads((folder / "results.json").read_text())
    assert doc["quick"] is True and doc["study"] == "demo"
    assert doc["results"] == {"a": 0.5, "n": 3, "list": [0, 1, 2], "bad": None}


def test_a_failed_write_keeps_the_old_report(tmp_path):
    sample_report().write(tmp_path / "demo")
    before = (tmp_path / "demo" / "report.md").read_text()
    broken = sample_report()
    broken.results["oops"] = object()            # not JSON: the write fails half way
    with pytest.raises(TypeError):
        broken.write(tmp_path / "demo")
    assert (tmp_path / "demo" / "report.md").read_text() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["demo"]     # no temporary folder left


def test_number_formats():
    assert fmt(1234567) == "1,234,567"
    assert fmt(0.012345) == "0.0123"
    assert fmt(12345.6) == "12,346"
    assert fmt(3.2e-9) == "3.20e-09"
    assert fmt(None) == "—" and fmt(float("nan")) == "—"
    assert pct(0.01234) == "1.23 %" and pct(None) == "—"


def test_error_summary():
    err = error_summary([1.1, 0.9, 1.0], [1.0, 1.0, 1.0])
    assert err["mean"] == pytest.approx(0.2 / 3)
    assert err["max"] == pytest.approx(0.1)
    assert err["bias"] == pytest.approx(0.0, abs=1e-15)
    assert err["rms"] == pytest.approx(np.sqrt(0.02 / 3))

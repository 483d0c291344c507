"""The command line's progress (lbl_illum/cli/progress.py): plain lines every few
seconds when standard error is not a terminal, nothing when quiet, and a note before
the work when numba has the engine's kernels still to compile."""

import io

from lbl_illum.cli.progress import LINE_SECONDS, ProgressBar, compile_notice


class Clock:
    def __init__(self):
        self.now = 100.0

    def __call__(self):
        return self.now


def test_plain_lines_off_a_terminal_every_few_seconds():
    out, clock = io.StringIO(), Clock()
    bar = ProgressBar(True, stream=out, clock=clock)
    assert bar.bar is None and bar.plain
    bar.describe("placing level 1 (500 queries)")
    bar.update(1000)
    clock.now += LINE_SECONDS - 0.1
    bar.update(1000)
    assert out.getvalue() == ""                      # not yet
    clock.now += 0.2
    bar.update(500)
    clock.now += 1.0
    bar.describe("evaluating level 1")               # too soon after the last line
    clock.now += LINE_SECONDS
    bar.describe("evaluating level 2")
    bar.close()
    assert out.getvalue().splitlines() == [
        "lbl-illum: placing level 1 (500 queries), 2,500 rays, 5 s",
        "lbl-illum: evaluating level 2, 2,500 rays, 11 s"]


def test_quiet_prints_nothing():
    out, clock = io.StringIO(), Clock()
    bar = ProgressBar(False, stream=out, clock=clock)
    clock.now += 60
    bar.update(10)
    bar.describe("x")
    assert out.getvalue() == "" and bar.bar is None


def test_compile_notice_only_when_kernels_are_missing(monkeypatch):
    from lbl_illum.engine import compiled

    out = io.StringIO()
    monkeypatch.setattr(compiled, "kernels_on_disk", lambda: False)
    compile_notice(True, stream=out)
    compile_notice(False, stream=out)
    assert out.getvalue().startswith("lbl-illum: note: compiling the calculation's kernels (first run")
    assert len(out.getvalue().splitlines()) == 1
    monkeypatch.setattr(compiled, "kernels_on_disk", lambda: True)
    out = io.StringIO()
    compile_notice(True, stream=out)
    assert out.getvalue() == ""


def test_kernels_on_disk_reads_numba_index_files(monkeypatch, tmp_path):
    """A kernel whose index file is missing means a first run; with it present, the
    answer is what the other kernels' index files say."""
    import os

    from lbl_illum.engine import compiled, hemisphere, octree

    index = octree._lookup_kernel._cache._cache_file
    monkeypatch.setattr(index, "_index_path", str(tmp_path / "missing.nbi"))
    assert compiled.kernels_on_disk() is False
    (tmp_path / "missing.nbi").write_bytes(b"")
    others = (octree._covered_kernel, octree.freeze, hemisphere._stratified_kernels[0])
    assert compiled.kernels_on_disk() is all(os.path.exists(k._cache._cache_file._index_path) for k in others)

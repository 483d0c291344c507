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
    """A first run says so, unless quiet; a later one says nothing."""
    from lbl_illum.engine import compiled

    out = io.StringIO()
    monkeypatch.setattr(compiled, "kernels_on_disk", lambda: False)
    compile_notice(True, stream=out)
    compile_notice(False, stream=out)
    assert out.getvalue().startswith("lbl-illum: note: compiling the calculation's kernels, first run")
    assert len(out.getvalue().splitlines()) == 1
    monkeypatch.setattr(compiled, "kernels_on_disk", lambda: True)
    out = io.StringIO()
    compile_notice(True, stream=out)
    assert out.getvalue() == ""


def test_a_first_run_names_each_compilation_in_the_progress_display(monkeypatch):
    """While the work runs on a first run, every kernel numba compiles is named in the
    progress display (a plain line here, the clock past LINE_SECONDS), and only then."""
    import numba

    from lbl_illum.engine import compiled

    monkeypatch.setattr(compiled, "kernels_on_disk", lambda: False)
    out, clock = io.StringIO(), Clock()
    bar = ProgressBar(True, stream=out, clock=clock)
    clock.now += 2 * LINE_SECONDS

    def fresh_kernel(x):
        return x + 1

    with compile_notice(True, stream=io.StringIO(), bar=bar):
        numba.njit(fresh_kernel)(1)
    assert out.getvalue().startswith("lbl-illum: compiling kernels, first run only (1)")
    clock.now += 2 * LINE_SECONDS
    numba.njit(lambda x: x + 2)(1)                    # after the work: nothing said
    assert bar.stage == "compiling kernels, first run only (1)"


def test_kernels_on_disk_reads_numba_index_files(monkeypatch, tmp_path):
    """A kernel whose index file is missing means a first run; with it present, the
    answer is what the other kernels' index files say."""
    import os

    from lbl_illum.engine import compiled, hemisphere, octree

    index = octree._lookup_kernel._cache._cache_file
    monkeypatch.setattr(index, "_index_path", str(tmp_path / "missing.nbi"))
    assert compiled.kernels_on_disk() is False
    (tmp_path / "missing.nbi").write_bytes(b"")
    others = (octree._covered_kernel, octree._layout, hemisphere._stratified_kernel.kernel)
    assert compiled.kernels_on_disk() is all(os.path.exists(k._cache._cache_file._index_path) for k in others)


def test_plain_lines_give_the_share_done_and_the_time_left():
    out, clock = io.StringIO(), Clock()
    bar = ProgressBar(True, stream=out, clock=clock)
    bar.fraction(0.25)
    bar.describe("placing level 2")
    clock.now += 10.0
    bar.update(100)
    bar.fraction(0.1)                                 # never goes back
    clock.now += 10.0
    bar.fraction(0.5)
    bar.describe("evaluating level 1")
    assert out.getvalue().splitlines() == [
        "lbl-illum: placing level 2, 25%, about 30 s left, 100 rays, 10 s",
        "lbl-illum: evaluating level 1, 50%, about 20 s left, 100 rays, 20 s"]


def test_the_engine_reports_the_share_of_its_blocks_done(monkeypatch):
    """With query blocks of 64, a run over a grid solves several blocks per level: the
    shares it reports lie in 0…1, rise, and end at exactly 1."""
    import numpy as np

    from lbl_illum import Options, compute_illuminance
    from lbl_illum.engine import integrator

    from conftest import make_scene

    monkeypatch.setattr(integrator, "QUERY_BLOCK", 64)
    scene = make_scene([{"shape": "box", "center": [0, 0, 1.5], "size": [4, 4, 3], "material": "wall"}],
                       {"wall": {"type": "diffuse", "reflectance": 0.5}}, {"type": "uniform"})
    g = np.linspace(-1.5, 1.5, 12)
    P = np.column_stack([np.repeat(g, 12), np.tile(g, 12), np.full(144, 0.8)])

    class Recorder:
        def __init__(self):
            self.shares = []

        def update(self, rays):
            pass

        def describe(self, text):
            pass

        def fraction(self, done):
            self.shares.append(done)

    rec = Recorder()
    compute_illuminance(scene, P, np.tile([0, 0, 1.0], (144, 1)), Options(bounces=2, samples=32, accuracy=0.2),
                        progress=rec)
    s = np.array(rec.shares)
    assert s[-1] == 1.0 and np.all((s >= 0) & (s <= 1))
    inner = s[(s > 0) & (s < 1)]
    assert len(np.unique(np.round(inner, 6))) >= 3          # it moves through the blocks
    assert np.all(np.diff(s) >= -1e-12)                      # never back


def test_terminal_bar_shows_percent_and_rays_after_one_second():
    class Terminal(io.StringIO):
        def isatty(self):
            return True

    out, clock = Terminal(), Clock()
    bar = ProgressBar(True, stream=out, clock=clock)
    assert bar.bar is not None and not bar.plain
    bar.describe("placing level 1")
    bar.update(500)
    bar.fraction(0.2)
    assert out.getvalue() == ""                      # nothing for a run under a second
    clock.now += 1.5
    bar.update(500)
    shown = out.getvalue().split("\r")[-1]
    assert "placing level 1" in shown and "20%" in shown and "1,000 rays" in shown
    bar.close()

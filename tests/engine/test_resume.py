"""Interrupted runs: the records of the levels already evaluated are saved, and a second run
with the same cache file finishes with the result of a run that was never interrupted.

Records are placed top-down and evaluated bottom-up (lbl_illum.engine.integrator), so an
interruption during evaluation of level k leaves levels k+1.. complete and level 0..k
records without values.  The tests stop runs at each stage — in-process through the
progress callback, and by signalling a subprocess — and compare the resumed result with
an uninterrupted one bit for bit.
"""

import os
import signal
import subprocess
import sys
import textwrap
import time

import numpy as np
import pytest

from lbl_illum import IrradianceCache, Options, load_scene, read_points
from lbl_illum.engine import integrator
from lbl_illum.engine.integrator import Integrator
from lbl_illum.io.cachefile import attach_cache_file

from conftest import EXAMPLES, ROOT

OPTS = Options(accuracy=0.2, bounces=2, samples=128)
#: elliptical domains, point samples (level 0 has accuracy 0) and three bounces
OPTS_HESSIAN = Options(accuracy=0.2, bounces=3, samples=64, interpolation="hessian", point_samples=256)


@pytest.fixture(scope="module")
def office():
    scene = load_scene(EXAMPLES / "office" / "scene.toml")
    points, normals = read_points(EXAMPLES / "office" / "grid.pts", scene.unit_scale)
    return scene, points[::3], normals[::3]


class StopAt:
    """A progress callback that raises ``error`` when the integrator reaches a stage."""

    def __init__(self, stage, error=KeyboardInterrupt):
        self.stage, self.error = stage, error

    def describe(self, text):
        if text.startswith(self.stage):
            raise self.error()

    def update(self, rays):
        pass


@pytest.fixture(scope="module")
def reference(office):
    """Uninterrupted results (no cache file) for each option set."""
    scene, points, normals = office
    return {name: Integrator(scene, opts).compute(points, normals)
            for name, opts in (("round", OPTS), ("hessian", OPTS_HESSIAN))}


@pytest.mark.parametrize("name, opts, stage, kept", [
    ("round", OPTS, "evaluating level 1", [0, 0, True]),         # level 2 evaluated
    ("round", OPTS, "evaluating level 0", [0, True, True]),
    ("round", OPTS, "direct light at the points", [True, True, True]),
    ("round", OPTS, "placing level 2", [0, 0, 0]),                # nothing evaluated yet
    ("hessian", OPTS_HESSIAN, "evaluating level 2", [0, 0, 0, True]),
    ("hessian", OPTS_HESSIAN, "evaluating level 0", [0, True, True, True]),   # level 0: accuracy 0, never kept
])
def test_interrupted_run_resumes_to_the_uninterrupted_result(office, reference, tmp_path, name, opts, stage, kept):
    scene, points, normals = office
    ref = reference[name]
    path = tmp_path / "office.lblcache"
    first = Integrator(scene, opts, progress=StopAt(stage))
    attach_cache_file(first, path)
    with pytest.raises(KeyboardInterrupt) as info:
        first.compute(points, normals)
    expected = [ref.stats.records[k] if keep is True else 0 for k, keep in enumerate(kept)]
    if any(expected):
        assert info.value.saved_cache == str(path)
        assert IrradianceCache.load(path).record_counts == expected
    else:
        assert not path.exists()              # nothing complete, nothing written
    # the interrupted integrator's own cache went back to complete records only
    assert [lv.count for lv in first.cache.levels][1:] == expected[1:]

    second = Integrator(scene, opts)
    attach_cache_file(second, path)
    result = second.compute(points, normals)
    assert np.array_equal(result.rgb, ref.rgb)
    assert result.stats.records == ref.stats.records
    for k, keep in enumerate(kept):
        if keep is True and k > 0:
            assert result.stats.new_records[k] == 0
    # and the file now holds what an uninterrupted run with a cache file writes
    third = Integrator(scene, opts)
    attach_cache_file(third, tmp_path / "fresh.lblcache")
    third.compute(points, normals)
    assert IrradianceCache.load(path).record_counts == IrradianceCache.load(tmp_path / "fresh.lblcache").record_counts


def test_interrupted_in_memory_cache_can_go_on(office, reference):
    """Without a file: the integrator's cache drops the records without values, so the
    same integrator can run again and still gives the uninterrupted result."""
    scene, points, normals = office
    integ = Integrator(scene, OPTS, progress=StopAt("evaluating level 0", RuntimeError))
    with pytest.raises(RuntimeError):
        integ.compute(points, normals)
    assert integ.cache.record_counts == [0] + reference["round"].stats.records[1:]
    integ.progress = None
    assert np.array_equal(integ.compute(points, normals).rgb, reference["round"].rgb)


CHILD = textwrap.dedent("""
    import signal, sys, time
    import numpy as np
    # Ctrl-C as at a terminal, even when this test runs in a background job (which starts
    # its children with SIGINT ignored, and Python then installs no handler of its own)
    signal.signal(signal.SIGINT, signal.default_int_handler)
    from lbl_illum import Options, load_scene, read_points
    from lbl_illum.engine import integrator
    from lbl_illum.engine.integrator import Integrator
    from lbl_illum.io.cachefile import attach_cache_file

    if len(sys.argv) > 5:
        integrator.QUERY_BLOCK = int(sys.argv[5])
    scene = load_scene(sys.argv[1])
    points, normals = read_points(sys.argv[2], scene.unit_scale)
    points, normals = points[::3], normals[::3]

    class WaitThere:
        # stops at the given stage until a signal comes (a run that is slow there)
        def describe(self, text):
            if sys.argv[4] in text:
                print("READY", flush=True)
                time.sleep(60)
        def update(self, rays):
            pass

    integ = Integrator(scene, Options(accuracy=0.2, bounces=2, samples=128), progress=WaitThere())
    attach_cache_file(integ, sys.argv[3])
    try:
        integ.compute(points, normals)
    except KeyboardInterrupt as exc:
        print("SAVED", getattr(exc, "saved_records", None), flush=True)
        sys.exit(130)
""")


def signal_child(tmp_path, cache, stage, signum, *extra):
    """Run CHILD on the office with ``cache``; when it reaches ``stage`` send ``signum``.
    Returns (return code, standard output, standard error)."""
    script = tmp_path / "child.py"
    script.write_text(CHILD)
    env = dict(os.environ, PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    child = subprocess.Popen([sys.executable, str(script), str(EXAMPLES / "office" / "scene.toml"),
                              str(EXAMPLES / "office" / "grid.pts"), str(cache), stage, *map(str, extra)],
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
    try:
        line = child.stdout.readline()
        assert line.strip() == "READY", child.stderr.read()
        child.send_signal(signum)
        out, err = child.communicate(timeout=60)
    finally:
        if child.poll() is None:
            child.kill()
    return child.returncode, out, err


@pytest.mark.parametrize("signum", [signal.SIGTERM, signal.SIGINT], ids=["SIGTERM", "SIGINT"])
@pytest.mark.skipif(sys.platform == "win32", reason="POSIX signals")
def test_signalled_subprocess_saves_and_resumes(office, reference, tmp_path, signum):
    """Kill a run in a subprocess during evaluation of level 1; the next run resumes."""
    scene, points, normals = office
    path = tmp_path / "office.lblcache"
    code, out, err = signal_child(tmp_path, path, "evaluating level 1", signum)
    assert code == 130, err
    assert "SAVED" in out
    saved = IrradianceCache.load(path).record_counts
    assert saved == [0, 0, reference["round"].stats.records[2]]
    second = Integrator(scene, OPTS)
    attach_cache_file(second, path)
    result = second.compute(points, normals)
    assert result.stats.new_records[2] == 0
    assert np.array_equal(result.rgb, reference["round"].rgb)


@pytest.mark.skipif(sys.platform == "win32", reason="POSIX signals")
def test_subprocess_terminated_while_placing_resumes(office, blocked_reference, tmp_path):
    """SIGTERM while level 0's second block is being placed: the first block's records
    (all levels) are saved, and the next run finishes with the uninterrupted result."""
    scene, points, normals = office
    stage = f"placing level 0 ({len(points) - SMALL_BLOCK} queries, block 2 of 2)"
    path = tmp_path / "office.lblcache"
    code, out, err = signal_child(tmp_path, path, stage, signal.SIGTERM, SMALL_BLOCK)
    assert code == 130, err
    saved = IrradianceCache.load(path).record_counts
    assert saved[0] > 0 and all(saved)
    second = Integrator(scene, OPTS)
    attach_cache_file(second, path)
    result = second.compute(points, normals)
    assert np.array_equal(result.rgb, blocked_reference.rgb)


@pytest.mark.skipif(sys.platform == "win32", reason="POSIX signals")
def test_killed_subprocess_leaves_the_old_file_intact(office, tmp_path):
    """SIGKILL cannot be caught: nothing new is saved, and the file written before is untouched."""
    scene, points, normals = office
    path = tmp_path / "office.lblcache"
    first = Integrator(scene, OPTS)
    attach_cache_file(first, path)
    first.compute(points[:4], normals[:4])
    before = path.read_bytes()
    signal_child(tmp_path, path, "writing the cache file", signal.SIGKILL)
    time.sleep(0.05)
    assert path.read_bytes() == before
    assert IrradianceCache.load(path).record_counts == first.cache.record_counts


# -- levels taken in blocks of queries ------------------------------------------------------

#: a block size that splits every level of the test run (27 sensors, 128 samples)
SMALL_BLOCK = 16


@pytest.fixture
def small_blocks(monkeypatch):
    monkeypatch.setattr(integrator, "QUERY_BLOCK", SMALL_BLOCK)


@pytest.fixture
def blocked_reference(office, small_blocks):
    scene, points, normals = office
    return Integrator(scene, OPTS).compute(points, normals)


class StopAfter:
    """Raises ``error`` the ``count``-th time the integrator reaches a stage."""

    def __init__(self, stage, count, error=KeyboardInterrupt):
        self.stage, self.count, self.error = stage, count, error
        self.seen = 0

    def describe(self, text):
        if text.startswith(self.stage):
            self.seen += 1
            if self.seen == self.count:
                raise self.error()

    def update(self, rays):
        pass


@pytest.mark.parametrize("stage, count", [
    ("placing level 0", 2),        # level 0's second block: the first one's whole tree is kept
    ("placing level 1", 40),       # in the middle of level 1's blocks under level 0's first block
    ("placing level 2", 100),
    ("evaluating level 1", 30),
])
def test_interruption_during_placement_keeps_the_finished_blocks(office, blocked_reference, tmp_path, stage, count):
    """With the levels split into blocks, a run stopped while it is placing records keeps
    every block finished before, and the resumed run gives the uninterrupted result."""
    scene, points, normals = office
    ref = blocked_reference
    assert len(points) > SMALL_BLOCK                      # level 0 itself has two blocks
    path = tmp_path / "office.lblcache"
    first = Integrator(scene, OPTS, progress=StopAfter(stage, count))
    attach_cache_file(first, path)
    with pytest.raises(KeyboardInterrupt) as info:
        first.compute(points, normals)
    saved = IrradianceCache.load(path).record_counts
    assert info.value.saved_records == saved
    assert 0 < sum(saved) < sum(ref.stats.records)
    assert all(0 < s <= r for s, r in zip(saved[1:], ref.stats.records[1:]))
    if stage == "placing level 0":
        assert saved[0] > 0                                # level 0's first block, evaluated
    second = Integrator(scene, OPTS)
    attach_cache_file(second, path)
    result = second.compute(points, normals)
    assert np.array_equal(result.rgb, ref.rgb)
    assert result.stats.records == ref.stats.records
    assert sum(result.stats.new_records) == sum(ref.stats.records) - sum(saved)


def test_blocks_change_the_records_not_the_accuracy(office, reference, blocked_reference):
    """Blocks change which records are made (later blocks reuse earlier ones) but not what
    they estimate: the two runs agree within their noise."""
    whole, blocked = reference["round"], blocked_reference
    assert blocked.stats.records != whole.stats.records
    rel = blocked.illuminance / whole.illuminance - 1.0
    assert abs(rel.mean()) < 0.03 and np.abs(rel).max() < 0.10

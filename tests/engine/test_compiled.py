import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from numba import prange

from lbl_illum.engine import compiled
from lbl_illum.engine.compiled import PARALLEL_MIN, PIECES_PER_THREAD, RowKernel


def _scaled_rows(x, shift, out, seen):
    for i in prange(x.shape[0]):
        for j in range(x.shape[1]):
            out[i, j] = 2.0 * x[i, j] + shift[j]
        seen[i] = x.shape[0]                      # the rows this call was given


@pytest.mark.parametrize("threads", [1, 2, 3])
def test_a_row_kernel_gives_the_same_rows_whole_or_cut_over_threads(monkeypatch, threads):
    """Rows are cut only from ``work`` = PARALLEL_MIN and with more than one thread, into
    PIECES_PER_THREAD ranges per thread; cut or not, every row is the same."""
    monkeypatch.setattr(compiled.numba.config, "NUMBA_NUM_THREADS", threads)
    kernel = RowKernel(_scaled_rows, rows=(0, 2, 3))
    x = np.random.default_rng(0).random((5000, 3))
    shift = np.array([0.0, 10.0, 20.0])
    whole, cut = np.empty_like(x), np.empty_like(x)
    seen_whole, seen_cut = np.zeros(5000, np.int64), np.zeros(5000, np.int64)
    kernel(x, shift, whole, seen_whole)
    kernel(x, shift, cut, seen_cut, work=PARALLEL_MIN)
    np.testing.assert_array_equal(whole, 2.0 * x + shift)
    np.testing.assert_array_equal(cut, whole)
    assert (seen_whole == 5000).all()
    pieces = 1 if threads == 1 else PIECES_PER_THREAD * threads
    assert np.unique(seen_cut).tolist() in ([5000 // pieces, 5000 // pieces + 1], [5000 // pieces])
    assert len(kernel.kernel.signatures) == 1     # slices of C arrays: no second specialisation


def test_a_row_kernel_is_compiled_once_without_the_gil():
    kernel = RowKernel(_scaled_rows, rows=(0, 2, 3))
    assert kernel.kernel.targetoptions.get("nogil") and not kernel.kernel.targetoptions.get("parallel")


def test_the_first_run_kernels_are_declared_with_the_types_a_run_calls_them_with(office_cache):
    """compiled.FIRST_RUN names each kernel the README job compiles and the argument types
    the engine passes: a kernel compiled ahead with other types would be compiled again."""
    for part in compiled.FIRST_RUN:
        for name, signature in part:
            kernel = compiled._dispatcher(name)
            called = [tuple(s) for s in kernel.signatures]
            assert called in ([], [compiled._argument_types(signature)]), name
    assert compiled._dispatcher("octree:_lookup_kernel").signatures      # the run did call them


def test_the_kernels_compiled_ahead_are_keyed_in_the_disk_cache_as_calls_key_them(monkeypatch):
    """compile_part hands numba the argument types, not the signature's text: numba keys
    its disk cache entry by what ``compile`` is given, and a call looks it up by types."""
    from numba.core import types

    given = []

    class Kernel:
        def compile(self, signature):
            given.append(signature)

    monkeypatch.setattr(compiled, "_dispatcher", lambda name: Kernel())
    compiled.compile_part(1)
    assert len(given) == len(compiled.FIRST_RUN[1])
    assert all(isinstance(s, tuple) and all(isinstance(t, types.Type) for t in s) for s in given)


def test_a_first_run_compiles_half_the_kernels_in_a_second_process(monkeypatch):
    calls = []

    class Helper:
        def __init__(self, command, env, **kwargs):
            calls.append(("start", command, env["PYTHONPATH"], kwargs.get("cwd")))

        def wait(self, timeout=None):
            calls.append(("wait", timeout))

        def poll(self):
            return 0

    monkeypatch.setattr("subprocess.Popen", Helper)
    monkeypatch.setattr(os, "cpu_count", lambda: 2)
    monkeypatch.setattr(compiled, "compile_part", lambda part: calls.append(("compile", part)))
    monkeypatch.setattr(compiled, "_STARTED", [])
    monkeypatch.setattr(compiled, "_HELPER", [])
    monkeypatch.setattr(compiled, "_on_disk", lambda kernel: True)
    compiled.start_first_run()                        # every kernel on disk: nothing to do
    compiled.finish_first_run()
    assert calls == []
    monkeypatch.setattr(compiled, "_STARTED", [])
    monkeypatch.setattr(compiled, "_on_disk", lambda kernel: False)
    compiled.start_first_run()
    compiled.start_first_run()                        # once a process
    assert len(calls) == 1 and "compile_part(1)" in calls[0][1][-1]
    assert calls[0][2].split(os.pathsep)[0] == str(Path(compiled.__file__).parents[2])
    # started beside this package: from a checkout's root with the package installed, a
    # helper started there imported the checkout and compiled kernels the run never found
    assert calls[0][3] == str(Path(compiled.__file__).parents[2])
    compiled.finish_first_run()
    assert calls[1:] == [("compile", 0), ("wait", compiled.HELPER_TIMEOUT)] and not compiled._HELPER


def test_kernel_threads_follow_numba_without_launching_its_threading_layer():
    """Without set_num_threads, the kernels' thread count is NUMBA_NUM_THREADS and numba's
    own threading layer stays unlaunched; after it, numba's count for the thread."""
    code = ("import numba; from numba.np.ufunc import parallel; from lbl_illum.engine.compiled import kernel_threads; "
            "a = kernel_threads(); launched = parallel._is_initialized; numba.set_num_threads(1); "
            "print(a, launched, kernel_threads())")
    env = dict(os.environ, NUMBA_NUM_THREADS="2")
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True).stdout
    assert out.split() == ["2", "False", "1"]


def test_the_second_process_imports_the_package_of_the_run_whatever_the_working_folder(tmp_path):
    """The helper's command, run where start_first_run starts it, finds this package even
    when the working folder of the run holds another one (a source checkout)."""
    decoy = tmp_path / "lbl_illum"
    decoy.mkdir()
    (decoy / "__init__.py").write_text("raise ImportError('the decoy')\n")
    root = Path(compiled.__file__).parents[2]
    code = "import lbl_illum.engine.compiled as c; print(c.__file__)"
    env = dict(os.environ, PYTHONPATH=str(root))
    wrong = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, env=env, capture_output=True, text=True)
    assert wrong.returncode != 0 and "the decoy" in wrong.stderr       # what happened before
    right = subprocess.run([sys.executable, "-c", code], cwd=root, env=env, capture_output=True, text=True,
                           check=True)
    assert Path(right.stdout.strip()) == Path(compiled.__file__)


def test_a_cached_kernel_loads_without_numba_s_compiler_registries_and_computes_alike(tmp_path):
    """A new process loads this package's kernels from numba's disk cache without importing
    numba's typing and lowering registries (0.1 s of every run) or the module of the
    ``np.empty`` the kernel calls (for globals its code never reads), and the loaded kernel
    gives what the process that compiled it and wrote it to an empty cache got."""
    code = ("import sys, json, numpy as np; from lbl_illum.engine import placement; "
            f"rng = np.random.default_rng(3); key = rng.integers(0, 40, 500).astype(np.int64); off = rng.random(500); "
            "out = [a.tolist() for a in placement._nearest_per_key(key, off)]; "
            "print(json.dumps([out, 'numba.typed.typeddict' in sys.modules, 'numba.np.npyimpl' in sys.modules, "
            "'numba.np.arraymath' in sys.modules, 'numba.np.arrayobj' in sys.modules]))")
    import json

    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "cache"),
               PYTHONPATH=os.pathsep.join(p for p in (str(Path(compiled.__file__).parents[2]),
                                                      os.environ.get("PYTHONPATH")) if p))
    runs = [json.loads(subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True,
                                      check=True).stdout) for _ in range(2)]
    (here, *compiling), (there, typed_loaded, ufuncs_loaded, numpy_functions_loaded, empty_loaded) = runs
    assert compiling[2] and list((tmp_path / "cache").rglob("*.nbi"))     # the first compiled and wrote it
    assert there == here
    assert not typed_loaded and not ufuncs_loaded and not numpy_functions_loaded and not empty_loaded


def test_a_kernel_loaded_lightly_links_into_a_kernel_compiled_after_it():
    """The bitcode a light load leaves unparsed is parsed when a kernel compiled later in the
    same process calls the loaded one (numba links the callee's bitcode into the caller),
    and the caller computes what the kernel computes called directly."""
    compiled._dispatcher("placement:_nearest_per_key").compile(compiled._argument_types("(int64[::1], float64[::1])"))
    code = ("import json, numpy as np; from numba import njit; from lbl_illum.engine import placement; "
            "rng = np.random.default_rng(5); key = rng.integers(0, 30, 400).astype(np.int64); off = rng.random(400); "
            "direct = [a.tolist() for a in placement._nearest_per_key(key, off)]; "
            "library = placement._nearest_per_key.overloads[placement._nearest_per_key.signatures[0]].library; "
            "unparsed = '_shared_bitcode' in library.__dict__; "
            "caller = njit(lambda k, o: placement._nearest_per_key(k, o)); "
            "linked = [a.tolist() for a in caller(key, off)]; "
            "print(json.dumps([direct == linked, len(direct[0]), unparsed, '_shared_bitcode' in library.__dict__]))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    import json

    same, found, unparsed_after_loading, unparsed_after_linking = json.loads(out)
    assert same and found > 0
    assert unparsed_after_loading and not unparsed_after_linking


def test_kernels_of_other_packages_load_as_numba_loads_them(tmp_path):
    """The light load is for this package's kernels only: another module's cached kernel,
    in a process that imported this package, loads through numba's own path, which
    registers the compiler's modules first."""
    (tmp_path / "their_kernels.py").write_text(
        "from numba import njit\n\n@njit(cache=True)\ndef twice(x):\n    return 2.0 * x\n")
    code = ("import sys; import lbl_illum.engine.compiled; import their_kernels; "
            "print(their_kernels.twice(1.5), 'numba.typed.typeddict' in sys.modules)")
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(tmp_path), str(Path(compiled.__file__).parents[2])]),
               NUMBA_CACHE_DIR=str(tmp_path / "cache"))
    first = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True).stdout
    second = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True).stdout
    assert first.split() == second.split() == ["3.0", "True"]
    assert list((tmp_path / "cache").rglob("*.nbi"))          # the second process loaded it from there

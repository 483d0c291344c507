"""Compiling array kernels with numba, each once, run on every core for large inputs.

numba's ``parallel=True`` kernels run on a thread pool that costs milliseconds to wake
on a busy machine: more than a loop over a few thousand items takes on one core; and a
parallel kernel compiles twice as slowly as a serial one, and had to be compiled a second
time, serial, for the engine's many small calls (a placement pass over a few hundred
queries, a level of a few records).  So every kernel is compiled once, without the GIL,
and a large call runs it over ranges of its items on Python threads:
:func:`nogil_kernel` with :func:`in_threads` where the kernel takes its range itself,
:class:`RowKernel` where its iterations are the rows of some of its arrays (written with
``prange``, which a serial kernel runs as ``range``).  The parallel twins of the cache
lookups and gradients took 8.4 of the 22.6 s of the office example's first run, those of
the hemisphere directions and hit points another 1.0 s (each kernel's compile time measured
one by one, ``numba:compile`` events).
"""

from __future__ import annotations

import sys
from concurrent.futures import ThreadPoolExecutor

import numba
from numba import njit

__all__ = ["PARALLEL_MIN", "RowKernel", "nogil_kernel", "in_threads"]


def _without_blas_probe(run_import) -> None:
    """Run ``run_import``, which imports numba's numpy functions (:mod:`numba.np.arraymath`),
    without importing SciPy.

    That module asks at import whether BLAS is there by importing
    ``scipy.linalg.cython_blas``: 0.2 s of every run (SciPy's array-API layer clones
    numpy, which imports ``numpy.f2py`` and ``numpy.testing``), for functions such as
    ``np.dot`` that no kernel here calls.  Here it is answered by whether SciPy is
    installed; a kernel that does call linear algebra still imports SciPy when it is
    compiled (:func:`numba.np.linalg.ensure_blas`).  With another layout of numba than
    the one expected, the import is run as it is."""
    import importlib.util

    try:
        from numba.np import linalg
        ensure_blas = linalg.ensure_blas
    except (ImportError, AttributeError):
        run_import()
        return

    def scipy_installed():
        if importlib.util.find_spec("scipy") is None:
            raise ImportError("scipy is required for linear algebra")

    linalg.ensure_blas = scipy_installed
    try:
        run_import()
    finally:
        linalg.ensure_blas = ensure_blas
    arraymath = sys.modules.get("numba.np.arraymath")
    if getattr(arraymath, "ensure_blas", None) is scipy_installed:
        arraymath.ensure_blas = ensure_blas


class _ArraymathImport:
    """An import hook, used once: whatever first imports :mod:`numba.np.arraymath`
    (compiling any kernel; loading one whose code calls numba's own array functions; numba
    loading another package's kernel) runs it under :func:`_without_blas_probe`.  A run
    whose kernels are all on disk then does not import it at all (0.03 s), and none pays
    for SciPy's import.  The module's own loader does the work; this one wraps it."""

    name = "numba.np.arraymath"

    @classmethod
    def find_spec(cls, name, path=None, target=None):
        from importlib.machinery import PathFinder

        if name != cls.name:
            return None
        if cls in sys.meta_path:
            sys.meta_path.remove(cls)
        spec = PathFinder.find_spec(name, path, target)
        if spec is not None and spec.loader is not None:
            spec.loader = cls(spec.loader)
        return spec

    def __init__(self, loader):
        self.loader = loader

    def __getattr__(self, attr):                   # get_source, get_filename …: the module's own
        return getattr(self.loader, attr)

    def create_module(self, spec):
        return self.loader.create_module(spec)

    def exec_module(self, module):
        _without_blas_probe(lambda: self.loader.exec_module(module))


def _load_kernels_lightly() -> None:
    """Load this package's kernels from numba's disk cache without first loading numba's
    whole compiler.

    Before it loads a cached kernel, numba imports and registers every typing and lowering
    module it has (``BaseContext.refresh``: array methods, linear algebra, typed
    containers, random numbers …), which only compiling needs: 0.1 s of every run, a
    sixth of a small run's whole command.  Loading machine code needs only the symbols it
    links against: numba's C helpers and Python's exceptions (registered when numba's CPU
    context is made) and the reference-counting runtime, which is started here.  The
    kernels here call nothing else (no hashing of strings, no parallel loops, whose
    symbols those modules or numba's threading layer register).  A kernel not in the
    cache is compiled as before, and compiling refreshes the context itself.  Kernels of
    other packages load as numba does.  With another layout of numba than the one
    expected, nothing is changed.

    Two more things numba does on loading a kernel serve only compiling, and wait here
    until it asks for them (:func:`_light_loading`): the LLVM bitcode kept beside the
    machine code, for inlining into other kernels, is parsed when a compilation links it,
    not on loading (with the scan of its symbols, 1.6 ms a kernel); and the modules of
    numba's own functions a kernel calls (``np.empty``'s, in ``numba.np.arrayobj``) are not
    imported to give their compiled code the module's globals, which code compiled without
    Python objects never reads (0.015 s).  Together 0.04 s of the 17 kernels a small cached
    run loads."""
    try:
        from numba.core import caching
        from numba.core.runtime import rtsys

        numba_load = caching.Cache.load_overload
        caching.Cache._load_overload, caching.Cache._guard_against_spurious_io_errors  # noqa: B018
        if getattr(numba_load, "_lbl_illum", False):
            return
    except (ImportError, AttributeError):
        return
    try:
        light = _light_loading()
    except (ImportError, AttributeError):
        import contextlib

        light = contextlib.nullcontext
    ours = __name__.split(".")[0] + "."

    def load_overload(self, sig, target_context):
        if not getattr(getattr(self, "_py_func", None), "__module__", "").startswith(ours):
            return numba_load(self, sig, target_context)
        rtsys.initialize(target_context)
        with self._guard_against_spurious_io_errors(), light():
            return self._load_overload(sig, target_context)

    load_overload._lbl_illum = True
    caching.Cache.load_overload = load_overload


def _light_loading():
    """A context manager under which numba loads a cached kernel of this package without
    parsing its bitcode for linking or importing numba modules for globals
    (:func:`_load_kernels_lightly`).  numba loads kernels holding its compiler lock, so
    the flag it sets is seen by that load alone; a library numba serialised otherwise
    than expected loads numba's way.  Raises AttributeError or ImportError when numba's
    layout is not the one expected (the kernels then load numba's way, still without
    its compiler registries)."""
    import contextlib

    import llvmlite.binding as ll
    from numba.core import codegen, environment

    base = codegen.JITCodeLibrary
    numba_unserialize = base._unserialize
    numba_rebuild_env = environment._rebuild_env
    environment.Environment._memo, base.enable_object_caching, base._set_compiled_object  # noqa: B018
    base._finalize_final_module, codegen.JitEngine._load_defined_symbols  # noqa: B018
    loading = []

    class LazyLinkingLibrary(base):
        """A kernel's code library whose bitcode for linking is parsed when first asked for."""

        @property
        def _shared_module(self):
            bitcode = self.__dict__.pop("_shared_bitcode", None)
            if bitcode is not None:
                module = ll.parse_bitcode(bitcode)
                self.__dict__["_parsed_shared_module"] = module
                self._codegen._engine._load_defined_symbols(module)
            return self.__dict__.get("_parsed_shared_module")

        @_shared_module.setter
        def _shared_module(self, module):
            self.__dict__["_parsed_shared_module"] = module

        def get_pointer_to_function(self, name):
            # numba first asks whether the session's scanned symbols hold ``name``; the
            # engine's own lookup gives 0 for a name it does not hold, as numba does
            self._ensure_finalized()
            return self._codegen._engine.get_function_address(name)

    def unserialize(cls, codegen_, state):
        try:
            name, kind, (object_code, shared_bitcode) = state
        except (TypeError, ValueError):
            kind = None
        if not loading or kind != "object" or codegen_._library_class is not base:
            return numba_unserialize(codegen_, state)
        library = LazyLinkingLibrary(codegen_, name)
        library.enable_object_caching()
        library._set_compiled_object(object_code)
        library._shared_bitcode = shared_bitcode
        library._finalize_final_module()
        return library

    def rebuild_env(modname, consts, env_name):
        env = environment.Environment._memo.get(env_name)
        if env is not None or not loading or not modname.startswith("numba.") or modname in sys.modules:
            return env if env is not None else numba_rebuild_env(modname, consts, env_name)
        env = environment.Environment({"__name__": modname})
        env.consts[:] = consts
        env.env_name = env_name
        environment.Environment._memo[env_name] = env
        return env

    base._unserialize = classmethod(unserialize)

    @contextlib.contextmanager
    def light():
        # numba pickles an environment as a call of ``environment._rebuild_env``, named
        # when it saves a kernel: the name must then be numba's own function (a
        # function of this module's would be pickled by value, with a flag of its own),
        # so it is replaced only while a kernel of this package loads
        environment._rebuild_env = rebuild_env
        loading.append(True)
        try:
            yield
        finally:
            loading.pop()
            if not loading:
                environment._rebuild_env = numba_rebuild_env

    return light


_load_kernels_lightly()
if _ArraymathImport.name not in sys.modules and _ArraymathImport not in sys.meta_path:
    sys.meta_path.insert(0, _ArraymathImport)

#: Items (rays, queries) from which a kernel runs on every core.
PARALLEL_MIN = 100_000
#: Ranges per thread a :class:`RowKernel` call is cut into (rows of unequal cost balance out).
PIECES_PER_THREAD = 4
_POOL: list[ThreadPoolExecutor] = []


def nogil_kernel(func):
    """``func`` compiled once, cached on disk, releasing the GIL (for :func:`in_threads`)."""
    return njit(cache=True, nogil=True)(func)


def kernel_threads() -> int:
    """Threads the kernels run on: ``numba.get_num_threads()`` (what ``numba.set_num_threads``
    set, for the calling thread) once numba's threading layer runs, else
    ``NUMBA_NUM_THREADS``.  Asking numba first launches that layer, which no kernel here
    uses (they run on :func:`in_threads`'s pool): it imports multiprocessing's
    synchronisation and loads a threading library, 0.03 s of every run."""
    from numba.np.ufunc import parallel

    if getattr(parallel, "_is_initialized", True):
        return numba.get_num_threads()
    return numba.config.NUMBA_NUM_THREADS


def in_threads(n: int, pieces: int, call) -> None:
    """``call(lo, hi)`` for ``pieces`` consecutive ranges that cover items 0…n − 1
    (piece p is [p n / pieces, (p + 1) n / pieces), as a ``prange`` over blocks splits
    them), on numba's number of threads (``NUMBA_NUM_THREADS``); ``call`` runs a
    :func:`nogil_kernel` on its range.  Returns when every piece is done; an exception
    in one is raised here."""
    if not _POOL:
        _POOL.append(ThreadPoolExecutor(max_workers=numba.config.NUMBA_NUM_THREADS,
                                         thread_name_prefix="lbl-illum-kernel"))
    bounds = [p * n // pieces for p in range(pieces + 1)]
    for _ in _POOL[0].map(lambda p: call(bounds[p], bounds[p + 1]), range(pieces)):
        pass


class RowKernel:
    """A kernel whose iterations are independent rows of some of its arrays, compiled once
    (:func:`nogil_kernel`).

    ``rows`` are the positions of the arguments cut by rows (their first axis is the
    kernel's ``prange``); the others are passed whole.  A call with ``work`` of at least
    PARALLEL_MIN (default: the number of rows) runs the kernel on consecutive row ranges
    on every thread, a smaller one on the calling thread; each row is computed alike
    either way, so results do not depend on the split.
    """

    def __init__(self, func, rows: tuple[int, ...]):
        self.kernel = nogil_kernel(func)
        self.rows = tuple(rows)

    def __call__(self, *args, work: int | None = None) -> None:
        n = args[self.rows[0]].shape[0]
        threads = numba.config.NUMBA_NUM_THREADS
        if (n if work is None else work) < PARALLEL_MIN or threads < 2 or n < 2:
            self.kernel(*args)
            return

        def rows(lo: int, hi: int) -> None:
            cut = list(args)
            for k in self.rows:
                cut[k] = args[k][lo:hi]
            self.kernel(*cut)

        in_threads(n, min(n, PIECES_PER_THREAD * threads), rows)


def kernels_on_disk() -> bool:
    """Whether numba's on-disk cache already holds the kernels every cached run uses (the
    cache lookups and record layout, the hemisphere directions): False on the first run
    after installing, when compiling them takes most of half a minute.  Read from the
    index files numba keeps beside each kernel; when numba's layout is not the one
    expected, True (say nothing rather than something wrong)."""
    import os

    from . import hemisphere, octree

    try:
        kernels = (octree._lookup_kernel, octree._covered_kernel, octree._layout, hemisphere._stratified_kernel.kernel)
        return all(os.path.exists(k._cache._cache_file._index_path) for k in kernels)
    except AttributeError:
        return True


# -- the first run: kernels compiled on two cores ----------------------------------------------

#: The kernels of every illuminance run (``module:name`` in this package) with the argument
#: types the engine calls them with, in two parts: the first compiled by the run's own
#: process, the second meanwhile by a second one (:func:`start_first_run`), which first
#: starts Python and numba (≈ 0.9 s) while the run reads the scene (a first run parses
#: the office's OBJ: 1.3 s).  Compile times one by one on the 2-core machine of
#: docs/performance (s): lookup 2.3, layout 0.9, directions 0.3, plane hits 0.3, nearest
#: per key 0.2, hit light 0.15 | portal irradiance 1.0, coverage 0.7, gradients 0.65,
#: radix sort 0.4, record keys 0.3, query keys 0.3, insertion 0.3, compaction 0.25, the
#: rest 0.1–0.2 each.  From the command's start, the run's half is done after 5.6 CPU
#: seconds (1.3 of them parsing the office's OBJ) and the second process's after 5.1
#: more from its start at 0.4 s.
#: A kernel missing here, or called with other types, is compiled when first called, as
#: any other (tests/engine/test_compiled.py checks the README job's calls against this).
FIRST_RUN = (
    (("hemisphere:_stratified_kernel", "(float64[:, ::1], float64[:, ::1], float64[:, ::1], int64, int64, "
      "float64[:, :, ::1])"),
     ("raycast:_plane_hits", "(float64[:, ::1], float64[:, ::1], float64[::1], int32[::1], int64[::1], "
      "float64[:, ::1], float64[:, ::1], float64[:, ::1], float64[:, ::1])"),
     ("octree:_layout", "(int64[::1], int64, float64[:, ::1], float32[:, ::1], float32[::1], uint8[::1], float64)"),
     ("placement:_nearest_per_key", "(int64[::1], float64[::1])"),
     ("integrator:_add_hit_light", "(int32[::1], float32[:, ::1], float64[:, ::1], float64[:, ::1], int32[::1], "
      "float32[::1], float64[:, ::1])"),
     ("octree:_lookup_kernel", "(float64[:, ::1], float64[:, ::1], uint8[::1], int64[::1], int64, float64, bool, "
      "bool, bool, float32[:, :, ::1], uint32[::1], int32[::1], float64[:, ::1], float32[:, ::1], "
      "float32[:, :, ::1], int64[::1], float64, float64[:, ::1], float64[::1], int32[::1], int32[:, ::1], "
      "float64[:, ::1])")),
    (("octree:_covered_kernel", "(float64[:, ::1], float64[:, ::1], uint8[::1], float64, bool, float32[:, :, ::1], "
      "uint32[::1], int32[::1], float64[:, ::1], float32[:, ::1], float32[:, :, ::1], int64[::1], bool[::1])"),
     ("octree:insert_records", "(int64, int64, float64[:, ::1], float32[::1], float64, int32[::1], "
      "float64[:, ::1], float64[::1], int32[:, ::1], int64)"),
     ("octree:_record_keys", "(int64, int64, int32[::1], int32[:, ::1], float64[:, ::1], float64[::1], "
      "float64[:, ::1])"),
     ("octree:_radix_order", "(uint64[::1],)"),
     ("octree:_query_keys", "(float64[:, ::1], float64[::1], float64)"),
     ("placement:_distance_bands_kernel", "(float64[:, ::1], float64[::1], float64[::1], float64, int64[::1])"),
     ("placement:_cell_keys_kernel", "(float64[:, ::1], float64[:, ::1], int64[::1], float64, int64[::1], "
      "float64[::1])"),
     ("integrator:_compact", "(bool[::1], int64[::1], float64[:, ::1], float64[:, ::1], int64[::1])"),
     ("lambert:_portal_kernel", "(float64[:, ::1], float64[:, ::1], float64[:, ::1], float64[:, ::1], "
      "float64[:, :, ::1], float64[::1], float64[:, ::1], float64[:, ::1])"),
     ("gradients:_gradients_kernel", "(float64[:, ::1], float64[:, :, :, ::1], float64[:, :, :, ::1], "
      "float64[:, :, ::1], float64[:, :, ::1], float64[:, :, ::1])")),
)
#: Longest wait [s] for the second process; past it the run compiles what it still lacks.
HELPER_TIMEOUT = 300.0
_HELPER: list = []
_STARTED: list = []


def _dispatcher(name: str):
    """The numba dispatcher of ``module:name`` (a :class:`RowKernel`'s kernel)."""
    import importlib

    module, attr = name.split(":")
    kernel = getattr(importlib.import_module(f"{__package__}.{module}"), attr)
    return kernel.kernel if isinstance(kernel, RowKernel) else kernel


def _on_disk(dispatcher) -> bool:
    """Whether numba's disk cache has an index for ``dispatcher`` (True when numba's
    layout is not the one expected: then nothing is compiled ahead)."""
    import os

    try:
        return os.path.exists(dispatcher._cache._cache_file._index_path)
    except AttributeError:
        return True


def _argument_types(signature: str) -> tuple:
    """The numba types of a signature's arguments.  A dispatcher compiled with them keys
    its disk cache entry as a call does (given the text, it would key it by the text,
    which no call finds)."""
    from numba.core import sigutils

    return tuple(sigutils.normalize_signature(signature)[0])


def compile_part(part: int) -> None:
    """Compile the kernels of ``FIRST_RUN[part]`` (each found in numba's disk cache, or
    compiled and written there), without Python's garbage collector meanwhile: numba's
    compiler makes objects by the hundred thousand, and the collections that go through
    them took 0.3 s of each half (0.8 s of the run's, on a loaded machine)."""
    import gc

    collecting = gc.isenabled()
    gc.disable()
    try:
        for name, signature in FIRST_RUN[part]:
            _dispatcher(name).compile(_argument_types(signature))
    finally:
        if collecting:
            gc.enable()


def start_first_run() -> None:
    """On a first run (the second part of :data:`FIRST_RUN` not in numba's disk cache),
    start compiling that part in a second Python process; :func:`finish_first_run`
    compiles the first part here and waits for it.  Compiling holds the GIL, so one
    process compiles on one core: this halves the 9 s of compiling of the README job's
    first run on 2 cores.  Nothing on one core, when numba's JIT is disabled, in a
    worker process (a pool's or a cluster's: the workers of one run would each start
    one), or when the kernels are on disk (every later run)."""
    import multiprocessing
    import os
    import subprocess
    import sys

    if (_STARTED or numba.config.DISABLE_JIT or (os.cpu_count() or 1) < 2 or not sys.executable
            or multiprocessing.parent_process() is not None):
        return
    _STARTED.append(True)
    if all(_on_disk(_dispatcher(name)) for name, _ in FIRST_RUN[1]):
        return
    env = dict(os.environ)
    if numba.config.CACHE_DIR:
        env["NUMBA_CACHE_DIR"] = numba.config.CACHE_DIR
    root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    env["PYTHONPATH"] = os.pathsep.join(p for p in (root, env.get("PYTHONPATH")) if p)
    try:
        # started in the folder that holds this package: ``-c`` puts the working folder first
        # on sys.path, and from a source checkout with the package installed (the README's
        # first command) the helper would import the checkout and compile its kernels, not
        # the installed ones the run looks up
        helper = subprocess.Popen([sys.executable, "-c", f"from {__name__} import compile_part; compile_part(1)"],
                                  env=env, cwd=root, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                                  stderr=subprocess.DEVNULL)
    except OSError:
        return
    _HELPER.append(helper)
    import atexit

    atexit.register(_stop_helper)


def _stop_helper() -> None:
    """End the second process if it still runs (the calculation never started)."""
    while _HELPER:
        helper = _HELPER.pop()
        if helper.poll() is None:
            helper.kill()
            helper.wait()


def finish_first_run() -> None:
    """When :func:`start_first_run` started a second process: compile the first part of
    :data:`FIRST_RUN` here, then wait for the second part (after :data:`HELPER_TIMEOUT`
    the process is stopped and what it has not compiled is compiled when first called).
    Does nothing otherwise."""
    import subprocess

    if not _HELPER:
        return
    try:
        compile_part(0)
        _HELPER[0].wait(timeout=HELPER_TIMEOUT)
    except subprocess.TimeoutExpired:
        pass
    finally:
        _stop_helper()

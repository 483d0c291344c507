"""Where the tasks run: this process (:class:`InProcess`, ``--workers 0``) or a Dask
cluster (:class:`DaskCluster`: ``--scheduler tcp://HOST:PORT`` connects to a running one,
``--workers N`` starts a ``LocalCluster`` of N worker processes on this machine).

Both offer the same three calls — :meth:`share` (send a value to every worker once, for
a round's record set), :meth:`run` (tasks, their results in the order given, whatever
order they finish in) and :meth:`prepare` (build a scene on every worker) — so the
rounds of :mod:`.rounds` are one code path.

Before any work a cluster is checked, each failure one :class:`InputError` line within
seconds (:data:`CONNECT_SECONDS`, :data:`WORKER_SECONDS`): a scheduler that does not
answer, one without workers, workers running another version of the project (its version
and a digest of its source, :func:`project_identity`), and a scene a worker cannot read
or reads otherwise than the driver (:meth:`prepare`).
"""

from __future__ import annotations

import hashlib
import itertools
import logging
import os
from pathlib import Path

from ..errors import InputError
from ..optional import check as check_optional

__all__ = ["InProcess", "DaskCluster", "open_cluster", "project_identity", "CONNECT_SECONDS", "WORKER_SECONDS"]

#: Seconds to wait for a scheduler to answer.
CONNECT_SECONDS = 5.0
#: Seconds to wait for a scheduler's first worker, and for the workers' checks.
WORKER_SECONDS = 10.0
#: Seconds a LocalCluster may take to start its workers (each imports numpy, numba, Embree).
START_SECONDS = 60.0


def project_identity() -> str:
    """``"VERSION+DIGEST"``: the project's version and the first 12 hex digits of the
    SHA-256 of its Python source (every ``.py`` file of the package, by relative path),
    so that two installs of one version with different code are told apart.  Read afresh
    at each call (a few milliseconds): the driver and the workers read it at the same time."""
    from .._version import __version__

    root = Path(__file__).resolve().parents[1]
    h = hashlib.sha256()
    for path in sorted(root.rglob("*.py")):
        h.update(str(path.relative_to(root)).encode())
        h.update(path.read_bytes())
    return f"{__version__}+{h.hexdigest()[:12]}"


def worker_identity() -> str:
    """:func:`project_identity` as a worker computes it (run there by the driver's check)."""
    return project_identity()


class InProcess:
    """The tasks run here, one after the other, in the order given."""

    workers = 0
    name = "one process (--workers 0)"

    def share(self, value):
        return value

    def run(self, fn, calls, done=None):
        """``[fn(*args) for args in calls]``, calling ``done(i, result)`` after each."""
        return self.collect(self.submit(fn, calls), done)

    def submit(self, fn, calls, priority: int = 0):
        """Tasks to run later (here: when collected)."""
        return fn, list(calls)

    def collect(self, tasks, done=None):
        """The results of :meth:`submit`'s tasks, in their order."""
        fn, calls = tasks
        out = []
        for i, args in enumerate(calls):
            out.append(fn(*args))
            if done is not None:
                done(i, out[-1])
        return out

    def prepare(self, recipe, options, fingerprint, scene=None, context=None) -> None:
        from .worker import remember

        if scene is not None:
            remember(recipe, scene, context)

    def release(self, recipe) -> None:
        """Drop the scene of ``recipe`` from this process."""
        from .worker import forget

        forget(recipe)

    def close(self) -> None:
        pass


class DaskCluster:
    """A Dask client, checked (module text).  ``address``: a scheduler to connect to;
    ``workers``: the size of a LocalCluster to start here instead (loopback only; each
    worker process runs one task at a time with the machine's cores / ``workers`` threads,
    ``LBL_ILLUM_THREADS`` and ``NUMBA_NUM_THREADS``)."""

    def __init__(self, address: str | None = None, workers: int | None = None):
        check_optional("distributed", "--workers/--scheduler")
        from distributed import Client, LocalCluster

        self.cluster = None
        if address is None:
            # the machine's cores shared among the workers: each runs its tasks one at a time
            # (Dask thread) with cores/N threads for its ray casting and lookups
            cores = str(max(1, (os.cpu_count() or 1) // int(workers)))
            self.cluster = LocalCluster(n_workers=int(workers), threads_per_worker=1, processes=True,
                                        host="127.0.0.1", dashboard_address=":0", silence_logs=logging.ERROR,
                                        death_timeout=START_SECONDS,
                                        env={"LBL_ILLUM_THREADS": cores, "NUMBA_NUM_THREADS": cores})
            self.client = Client(self.cluster, timeout=START_SECONDS)
            self.name = f"a local cluster of {workers} worker{'s' if workers != 1 else ''}"
        else:
            self.client = _connect(Client, address)
            self.name = address
        self._keys = itertools.count()
        try:
            self._check_workers(address)
        except BaseException:
            self.close()
            raise

    @property
    def workers(self) -> int:
        return len(self.client.scheduler_info(n_workers=-1)["workers"]) if hasattr(self, "client") else 0

    def _check_workers(self, address) -> None:
        try:
            self.client.wait_for_workers(1, timeout=WORKER_SECONDS)
        except Exception:   # TimeoutError; older versions raise others
            raise InputError(f"scheduler {address}: no workers joined within {WORKER_SECONDS:g} s") from None
        self._check_versions(address)

    def _check_versions(self, address=None) -> None:
        """Refuse workers that run another version of the project (or none)."""
        mine = project_identity()
        try:
            theirs = self.client.run(worker_identity, wait=True)
        except Exception as exc:  # a worker without lbl_illum: ModuleNotFoundError in the unpickling
            reason = str(exc).strip().splitlines()[0][:100] if str(exc).strip() else ""
            raise InputError(f"scheduler {address or self.name}: a worker cannot run lbl_illum "
                             f"({type(exc).__name__}{': ' + reason if reason else ''}); install it on every "
                             "worker") from None
        other = {w: v for w, v in theirs.items() if v != mine}
        if other:
            worker, version = sorted(other.items())[0]
            raise InputError(f"worker {worker} runs lbl_illum {version}, this process {mine}: install the same "
                             f"version on every worker ({len(other)} of {len(theirs)} differ)")

    def share(self, value):
        """A future of ``value`` held by every worker (sent once per worker).  A worker lost
        just before (the scheduler has not yet struck it off) makes the send fail; it is
        tried again, for up to :data:`WORKER_SECONDS`, as the scheduler notices."""
        import time

        deadline = time.monotonic() + WORKER_SECONDS
        while True:
            try:
                return self.client.scatter(value, broadcast=True, hash=False)
            except OSError:          # CommClosedError, a refused connection to the lost worker
                if time.monotonic() > deadline:
                    raise
                time.sleep(0.25)

    def run(self, fn, calls, done=None):
        """Run ``fn(*args)`` for every ``args`` of ``calls`` on the cluster; the results in
        the order of ``calls``; ``done(i, result)`` as each finishes.  A task whose worker
        is lost runs again on another (the scheduler's doing); its result is the same."""
        return self.collect(self.submit(fn, calls), done)

    def submit(self, fn, calls, priority: int = 0):
        """Send the tasks ``fn(*args)`` now, to be collected later (:meth:`collect`); among
        tasks waiting for a worker, those of higher ``priority`` start first (work that
        fills the workers a round leaves idle: a lower one)."""
        batch = next(self._keys)
        return [self.client.submit(fn, *args, key=f"lbl_illum-{fn.__name__}-{batch}-{i}", pure=False,
                                   priority=priority) for i, args in enumerate(calls)]

    def collect(self, futures, done=None):
        """The results of :meth:`submit`'s tasks in their order, ``done(i, result)`` as each
        finishes."""
        from distributed import as_completed

        index = {f.key: i for i, f in enumerate(futures)}
        out = [None] * len(futures)
        try:
            for future in as_completed(futures):
                i = index[future.key]
                out[i] = future.result()
                if done is not None:
                    done(i, out[i])
        except BaseException:
            self.client.cancel(futures)
            raise
        return out

    def prepare(self, recipe, options, fingerprint, scene=None, context=None) -> None:
        """Have every worker build the scene of ``recipe`` (a worker plugin: workers that
        join later build it too) and check that each sees the scene and settings whose
        fingerprint is ``fingerprint``; refuse otherwise, naming the worker."""
        from .plugin import ScenePlugin
        from .worker import scene_check

        self._check_versions()           # workers that joined since the cluster was checked
        self.client.register_plugin(ScenePlugin(recipe), name=_plugin_name(recipe))
        seen = self.client.run(scene_check, recipe, options, wait=True)
        for worker, answer in sorted(seen.items()):
            if answer.startswith("error: "):
                raise InputError(f"worker {worker}: {answer[len('error: '):]}")
            if answer != fingerprint:
                raise InputError(f"worker {worker} reads another scene at {recipe.path} (its fingerprint differs "
                                 "from this process's): the workers must see the same files")

    def release(self, recipe) -> None:
        """Let the workers drop the scene of ``recipe``."""
        try:
            self.client.unregister_worker_plugin(_plugin_name(recipe))
        except Exception:   # a worker gone meanwhile; nothing to free there
            pass

    def close(self) -> None:
        client = getattr(self, "client", None)
        if client is not None:
            client.close()
        if self.cluster is not None:
            self.cluster.close()


def _plugin_name(recipe) -> str:
    return f"lbl_illum-scene-{recipe.key}"


def _connect(Client, address: str):
    """A client of the scheduler at ``address``, or one InputError line within
    :data:`CONNECT_SECONDS`."""
    if "://" not in address and ":" not in address:
        raise InputError(f"--scheduler {address}: give the scheduler's address as tcp://HOST:PORT")
    try:
        return Client(address, timeout=CONNECT_SECONDS)
    except (OSError, TimeoutError) as exc:
        reason = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        raise InputError(f"--scheduler {address}: no scheduler answered within {CONNECT_SECONDS:g} s "
                         f"({reason[:100]})") from None
    except ValueError as exc:
        raise InputError(f"--scheduler {address}: {exc}") from None


def open_cluster(workers: int | None = None, scheduler: str | None = None):
    """The place to run a study's tasks: ``scheduler`` (an address) connects to a running
    cluster, ``workers`` > 0 starts a local one, ``workers == 0`` runs them in this
    process; both None: None (an ordinary run)."""
    if scheduler is not None and workers is not None:
        raise InputError("give either --workers or --scheduler, not both")
    if scheduler is not None:
        return DaskCluster(address=scheduler)
    if workers is None:
        return None
    if workers == 0:
        return InProcess()
    return DaskCluster(workers=workers)

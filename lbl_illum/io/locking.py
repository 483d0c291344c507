"""An exclusive lock on a file shared by several processes (cache files written by
concurrent runs).

The lock is held on a separate lock file, ``FILE.lock`` beside ``FILE``, because the
file itself is replaced by a rename on every write (:mod:`lbl_illum.io.files`) and a lock
on the old file would not cover the new one.  This is Radiance's discipline for shared
ambient files (``rtrace -af``: lock, re-read what others added, write, unlock; Ward,
"The RADIANCE Lighting Simulation and Rendering System", SIGGRAPH 1994, §2.3) with a
lock file instead of a lock on the data file.

POSIX: ``fcntl.lockf`` (POSIX record locks, which also work on NFS with a lock
daemon).  The lock file is removed on release; a process that had opened the file
before it was removed finds, once it holds the lock, that the path now names another
file (or none) and tries again, so two processes never both believe they hold it.
Windows: ``msvcrt.locking`` on the lock file's first byte; the lock file is left in
place.  The operating system drops a dead process's lock, so a crash never leaves a
stale lock behind.
"""

from __future__ import annotations

import os
import time
from contextlib import contextmanager
from pathlib import Path

__all__ = ["LockTimeout", "file_lock", "lock_path"]

#: Seconds to wait for another process to release the lock before giving up.  Writers
#: hold it only while they re-read, merge and write a cache file.
LOCK_TIMEOUT = 600.0
#: Seconds between attempts while another process holds the lock.
POLL_INTERVAL = 0.02


class LockTimeout(OSError):
    """The lock stayed held by another process for longer than the timeout."""


def lock_path(path: str | os.PathLike) -> Path:
    """The lock file of ``path``: the same name with ``.lock`` appended."""
    path = Path(path)
    return path.with_name(path.name + ".lock")


if os.name == "nt":  # pragma: no cover - exercised on Windows only
    import msvcrt

    def _try_lock(fd) -> bool:
        os.lseek(fd, 0, os.SEEK_SET)
        try:
            msvcrt.locking(fd, msvcrt.LK_NBLCK, 1)
        except OSError:
            return False
        return True

    def _unlock(fd, name) -> None:
        os.lseek(fd, 0, os.SEEK_SET)
        msvcrt.locking(fd, msvcrt.LK_UNLCK, 1)

    def _still_ours(fd, name) -> bool:
        return True
else:
    import fcntl

    def _try_lock(fd) -> bool:
        try:
            fcntl.lockf(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            return False
        return True

    def _unlock(fd, name) -> None:
        try:
            os.unlink(name)          # still holding the lock: nobody else can be using it
        except FileNotFoundError:
            pass
        fcntl.lockf(fd, fcntl.LOCK_UN)

    def _still_ours(fd, name) -> bool:
        """Whether the locked file is still the one ``name`` names (the previous holder may
        have removed it between our open and our lock)."""
        try:
            now = os.stat(name)
        except FileNotFoundError:
            return False
        mine = os.fstat(fd)
        return (now.st_dev, now.st_ino) == (mine.st_dev, mine.st_ino)


@contextmanager
def file_lock(path: str | os.PathLike, timeout: float = LOCK_TIMEOUT):
    """Hold the exclusive lock of ``path`` (its lock file ``path.lock``) for the ``with`` block.

    Waits for other holders, up to ``timeout`` seconds, then raises :class:`LockTimeout`.
    The lock is not re-entrant: do not take it twice in one process.
    """
    name = str(lock_path(path))
    deadline = time.monotonic() + timeout
    while True:
        fd = os.open(name, os.O_RDWR | os.O_CREAT, 0o666)
        try:
            if _try_lock(fd):
                if _still_ours(fd, name):
                    break
                _unlock_quietly(fd)
        except BaseException:
            os.close(fd)
            raise
        os.close(fd)
        if time.monotonic() > deadline:
            raise LockTimeout(f"{name}: still locked by another process after {timeout:g} s")
        time.sleep(POLL_INTERVAL)
    try:
        yield
    finally:
        try:
            _unlock(fd, name)
        finally:
            os.close(fd)


def _unlock_quietly(fd) -> None:
    """Release a lock on a lock file that is no longer the current one (POSIX only)."""
    try:
        import fcntl

        fcntl.lockf(fd, fcntl.LOCK_UN)
    except (ImportError, OSError):
        pass

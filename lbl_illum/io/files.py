"""Output files are written whole or not at all: a temporary file in the same folder,
then a rename, so an interrupted or failed run never leaves a partial file.  Input text
files are read whole as UTF-8, every failure an :class:`InputError` naming the file."""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

from ..errors import InputError

__all__ = ["atomic_write_bytes", "atomic_write_text", "atomic_write_npy", "read_text_file"]


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def atomic_write_npy(path: str | os.PathLike, array, dtype="float32") -> None:
    """``array`` as a NumPy ``.npy`` file of ``dtype``, written whole (:func:`atomic_write_bytes`)."""
    import io

    import numpy as np

    buffer = io.BytesIO()
    np.save(buffer, np.ascontiguousarray(array, dtype))
    atomic_write_bytes(path, buffer.getvalue())


def atomic_write_bytes(path: str | os.PathLike, data: bytes) -> None:
    """Write ``data`` to ``path`` through a temporary file and a rename.

    The file gets the permissions a plainly created file would (0666 less the umask).
    """
    path = Path(path)
    folder = path.parent if str(path.parent) else Path(".")
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=folder)
    try:
        with os.fdopen(fd, "wb") as fh:
            fh.write(data)
        os.chmod(tmp, 0o666 & ~_umask())
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise


def atomic_write_text(path: str | os.PathLike, text: str) -> None:
    """Write ``text`` (UTF-8) to ``path`` atomically."""
    atomic_write_bytes(path, text.encode("utf-8"))


def read_text_file(path: str | os.PathLike, what: str = "", latin1: bool = False) -> str:
    """The UTF-8 text of a file, without the byte-order mark spreadsheets and some editors
    put first; a missing, unreadable or non-UTF-8 file is an
    :class:`InputError` naming it (and the line of the first bad byte).  ``latin1``:
    text that is not UTF-8 is read as ISO 8859-1 instead (photometric files from older
    tools carry a degree sign or a manufacturer's name in it)."""
    path = Path(path)
    name = path.name or str(path)
    try:
        data = path.read_bytes()
    except FileNotFoundError:
        raise InputError(f"{name}: no such file") from None
    except IsADirectoryError:
        raise InputError(f"{name}: is a folder, not a{what} file") from None
    except OSError as exc:
        raise InputError(f"{name}: cannot read ({exc.strerror or exc.__class__.__name__})") from None
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        if latin1:
            return data.decode("latin-1")
        line = data.count(b"\n", 0, exc.start) + 1
        raise InputError(f"{name}: line {line}: not UTF-8 text (byte {exc.start})") from None

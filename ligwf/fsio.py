"""Atomic file writes: a result file is either complete or absent, never half-written.

A folder that cannot be written (full disk, read-only mount, no permission) raises
:class:`FolderNotWritable`, a :class:`ligwf.errors.LigwfError` naming the folder, so the
command line ends with one line instead of an ``OSError`` traceback.
"""

from __future__ import annotations

import errno
import json
import os
import tempfile
from pathlib import Path
from typing import Any

from ligwf.errors import LigwfError

#: errno values that mean "this folder cannot take the file" (not a bug in ligwf)
NOT_WRITABLE = frozenset({errno.ENOSPC, errno.EDQUOT, errno.EROFS, errno.EACCES, errno.EPERM})
#: free bytes below which a folder counts as full (an engine crash there is the disk's fault)
LOW_SPACE_BYTES = 1 << 20


class FolderNotWritable(LigwfError):
    """A folder ligwf must write to is full, read-only or not ours."""


def not_writable(exc: OSError, folder: Path) -> FolderNotWritable:
    """The one-line error for an ``OSError`` writing in ``folder`` (or the folder of the
    file the error names)."""
    where = Path(exc.filename).parent if exc.filename else Path(folder)
    return FolderNotWritable(f"cannot write in {where}: {exc.strerror or exc}")


def atomic_write_bytes(path: Path, data: bytes) -> None:
    """Write ``data`` to ``path`` via a temporary file in the same folder and a rename
    (a per-process unique temporary name: concurrent writers never collide)."""
    path = Path(path)
    tmp = None
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
        with os.fdopen(fd, "wb") as fh:
            fh.write(data)
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, path)
    except BaseException as exc:
        if tmp is not None and os.path.exists(tmp):
            os.unlink(tmp)
        if isinstance(exc, OSError) and exc.errno in NOT_WRITABLE:
            raise not_writable(exc, path.parent) from exc
        raise


def atomic_write_text(path: Path, text: str) -> None:
    """Write ``text`` (UTF-8) to ``path`` atomically."""
    atomic_write_bytes(path, text.encode("utf-8"))


def atomic_write_json(path: Path, obj: Any) -> None:
    """Write ``obj`` as indented, key-sorted JSON to ``path`` atomically."""
    atomic_write_text(path, json.dumps(obj, indent=2, sort_keys=True) + "\n")


def overwrite_in_place(path: Path, text: str) -> None:
    """Truncate and rewrite ``path`` (NOT atomic): only for a full disk, where the atomic
    write has no room for its temporary copy."""
    try:
        with open(path, "w", encoding="utf-8") as fh:
            fh.write(text)
    except OSError as exc:
        if exc.errno in NOT_WRITABLE:
            raise not_writable(exc, Path(path).parent) from exc
        raise


def space_left(folder: Path) -> int:
    """Bytes an unprivileged writer can still put in ``folder``'s file system."""
    try:
        st = os.statvfs(folder)
    except OSError:
        return LOW_SPACE_BYTES
    return st.f_bavail * st.f_frsize

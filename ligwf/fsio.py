"""Atomic file writes: a result file is either complete or absent, never half-written.

Files get the user's permissions (``0666`` less the umask, as ``open()`` would give them:
``0644`` under umask 022), not the ``0600`` of the temporary file, so a colleague, a web
server or a Slurm job under another account can read a study. Only a regular file (or
nothing) is ever replaced: a directory, a symbolic link, a FIFO or a device node at the
target is refused (:class:`NotReplaceable`), never turned into a regular file.

A folder that cannot be written (full disk, read-only mount, no permission) raises
:class:`FolderNotWritable`, a :class:`ligwf.errors.LigwfError` naming the folder, so the
command line ends with one line instead of an ``OSError`` traceback.
"""

from __future__ import annotations

import errno
import fcntl
import hashlib
import json
import math
import os
import stat
import tempfile
from contextlib import contextmanager
from pathlib import Path
from typing import Any, Iterator

from ligwf.errors import LigwfError

#: errno values that mean "this folder cannot take the file" (not a bug in ligwf)
NOT_WRITABLE = frozenset({errno.ENOSPC, errno.EDQUOT, errno.EROFS, errno.EACCES, errno.EPERM})
#: free bytes below which a folder counts as full (an engine crash there is the disk's fault)
LOW_SPACE_BYTES = 1 << 20


class FolderNotWritable(LigwfError):
    """A folder ligwf must write to is full, read-only or not ours."""


class NotReplaceable(LigwfError):
    """The target of a write exists and is not a regular file (a folder, a symbolic
    link, a FIFO, a device node): ligwf does not replace it."""


def umask() -> int:
    """The process's umask, read without changing it (``/proc/self/status``; else set and
    restored at once, which other threads could see for an instant)."""
    try:
        for line in Path("/proc/self/status").read_text().splitlines():
            if line.startswith("Umask:"):
                return int(line.split()[1], 8)
    except (OSError, ValueError, IndexError):
        pass
    old = os.umask(0o022)
    os.umask(old)
    return old


def file_mode() -> int:
    """Permissions of a new file: what ``open()`` would give it (0666 less the umask)."""
    return 0o666 & ~umask()


def replaceable(path: Path) -> str | None:
    """Why ``path`` must not be replaced by a file (None: absent or a regular file)."""
    try:
        st = os.lstat(path)
    except (FileNotFoundError, NotADirectoryError):
        return None
    if stat.S_ISREG(st.st_mode):
        return None
    if stat.S_ISLNK(st.st_mode):
        return f"a symbolic link (to {os.readlink(path)})"
    if stat.S_ISDIR(st.st_mode):
        return "a folder"
    if stat.S_ISFIFO(st.st_mode):
        return "a FIFO"
    if stat.S_ISCHR(st.st_mode) or stat.S_ISBLK(st.st_mode):
        return "a device node"
    if stat.S_ISSOCK(st.st_mode):
        return "a socket"
    return "not a regular file"


def check_replaceable(path: Path) -> None:
    """NotReplaceable, naming ``path`` and what it is, unless it is absent or a regular file."""
    why = replaceable(path)
    if why is not None:
        raise NotReplaceable(f"{path} is {why}: ligwf writes only regular files and does not "
                             "replace it; name another file")


def not_writable(exc: OSError, folder: Path) -> FolderNotWritable:
    """The one-line error for an ``OSError`` writing in ``folder`` (or the folder of the
    file the error names)."""
    where = Path(exc.filename).parent if exc.filename else Path(folder)
    return FolderNotWritable(f"cannot write in {where}: {exc.strerror or exc}")


@contextmanager
def writing_in(folder: Path) -> Iterator[None]:
    """Inside the block, an ``OSError`` saying a folder cannot take a file (full, read-only,
    no permission) becomes :class:`FolderNotWritable` naming the file's folder, else
    ``folder``: an error of ``write()`` carries no file name, and the current folder is not
    where a stage writes (a full disk during analysis named it)."""
    try:
        yield
    except OSError as exc:
        if exc.errno in NOT_WRITABLE:
            raise not_writable(exc, folder) from exc
        raise


def atomic_write_bytes(path: Path, data: bytes) -> None:
    """Write ``data`` to ``path`` via a temporary file in the same folder and a rename
    (a per-process unique temporary name: concurrent writers never collide), with the
    user's permissions (:func:`file_mode`). NotReplaceable when ``path`` is not a regular
    file; an error names ``path``, never the temporary file."""
    path = Path(path)
    check_replaceable(path)
    tmp = None
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
        os.fchmod(fd, file_mode())
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
        if isinstance(exc, OSError) and exc.errno is not None and exc.filename != str(path):
            # the same error, naming the file asked for instead of the temporary one
            raise type(exc)(exc.errno, exc.strerror, str(path)) from exc
        raise


def atomic_write_text(path: Path, text: str) -> None:
    """Write ``text`` (UTF-8) to ``path`` atomically."""
    atomic_write_bytes(path, text.encode("utf-8"))


def atomic_write_json(path: Path, obj: Any) -> None:
    """Write ``obj`` as indented, key-sorted JSON to ``path`` atomically."""
    atomic_write_text(path, json.dumps(obj, indent=2, sort_keys=True) + "\n")


def file_sha256(path: Path) -> str:
    """SHA-256 of a file (hex), read in 1 MiB blocks: the one digest of a file's bytes
    (case records, dump records, restart ids, the report's file record)."""
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        while block := fh.read(1 << 20):
            h.update(block)
    return h.hexdigest()


def json_safe(obj: Any) -> Any:
    """``obj`` with every non-finite float replaced by None, through dicts, lists and
    tuples (tuples become lists): what a JSON record stores, never NaN or Infinity."""
    if isinstance(obj, float):
        return obj if math.isfinite(obj) else None
    if isinstance(obj, dict):
        return {k: json_safe(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [json_safe(v) for v in obj]
    return obj


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


@contextmanager
def try_lock(path: Path) -> Iterator[bool]:
    """Try to take the exclusive lock file ``path`` without waiting: yields whether it was
    taken (released when the block ends or the process dies: flock). A folder that cannot
    hold the lock file is FolderNotWritable (one line), as for every file ligwf writes."""
    path = Path(path)
    try:
        fd = os.open(path, os.O_RDWR | os.O_CREAT | os.O_CLOEXEC, 0o666)
    except OSError as exc:
        if exc.errno in NOT_WRITABLE:
            raise not_writable(exc, path.parent) from exc
        raise
    try:
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            yield False
            return
        yield True
    finally:
        os.close(fd)

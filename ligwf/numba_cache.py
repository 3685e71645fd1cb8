"""Where numba keeps ligwf's compiled kernels, and the decorator every cached kernel uses.

numba's ``cache=True`` writes the machine code beside the source (``__pycache__``) or,
when that folder is read-only (an installed wheel, a shared site-packages), into the
user's cache folder (``~/.cache/numba``). When neither can be written (a read-only
install run by a user without a writable home, some CI containers) numba refuses at
import time ("no locator available"). :func:`cached_jit` makes sure one of them works
first, else points ``NUMBA_CACHE_DIR`` at a private folder under the temporary directory,
so the kernels still compile once per machine rather than once per process. A
``NUMBA_CACHE_DIR`` set by the user is always kept.

This module sits below every package of ligwf (it knows only numba and the file system).
"""

from __future__ import annotations

import hashlib
import inspect
import os
import tempfile
import types
from pathlib import Path

import numba
from numba import njit
from numba.misc.appdirs import AppDirs

#: the folder used when neither the source tree nor the user's cache folder is writable
FALLBACK_CACHE_DIR = Path(tempfile.gettempdir()) / f"ligwf-numba-cache-{os.getuid()}"

_CHECKED: set[Path] = set()


def _writable(folder: Path) -> bool:
    """True when ``folder`` exists or can be made, and a file can be written in it (numba's
    own test of a cache location)."""
    try:
        folder.mkdir(parents=True, exist_ok=True)
        tempfile.TemporaryFile(dir=folder).close()
    except OSError:
        return False
    return True


def ensure_cache_dir(source_folder: Path | None = None) -> str | None:
    """Make sure numba has a writable cache location for the kernels defined in
    ``source_folder`` (default: this package's folder); returns the ``NUMBA_CACHE_DIR`` it
    set (None: the user's setting or numba's default is used). Checked once per folder."""
    folder = Path(source_folder or Path(__file__).resolve().parent)
    if numba.config.CACHE_DIR or folder in _CHECKED:
        return None
    _CHECKED.add(folder)
    user_wide = Path(AppDirs(appname="numba", appauthor=False).user_cache_dir)
    if _writable(folder / "__pycache__") or _writable(user_wide):
        return None
    if not _writable(FALLBACK_CACHE_DIR):
        return None                   # nothing writable: numba itself says so on first use
    numba.config.CACHE_DIR = str(FALLBACK_CACHE_DIR)
    os.environ["NUMBA_CACHE_DIR"] = str(FALLBACK_CACHE_DIR)      # and for child processes
    return str(FALLBACK_CACHE_DIR)


def cached_jit(**options):
    """``numba.njit(cache=True, **options)`` with a writable cache location for the
    decorated function's folder ensured first."""

    def decorate(fn):
        ensure_cache_dir(Path(inspect.getfile(fn)).resolve().parent)
        return njit(cache=True, **options)(fn)

    return decorate


def law_digest(*functions) -> str:
    """A short digest of the numba functions ``functions`` *and the whole source files they
    are defined in*: part of a specialised kernel's cache name, so a kernel compiled with an
    older version of a law (or of a constant beside it) is never loaded again. numba
    itself only checks the file of the kernel it caches, not of the functions it inlines."""
    h = hashlib.sha256()
    for fn in functions:
        py_func = getattr(fn, "py_func", fn)
        h.update(f"{py_func.__module__}.{py_func.__qualname__}\0".encode())
        h.update(Path(inspect.getfile(py_func)).read_bytes())
    return h.hexdigest()[:16]


def specialised(py_func, tag: str, options: dict, **bound):
    """``py_func`` compiled and cached with the global names in ``bound`` fixed (e.g. a
    liquid law's numba functions), as its own cached kernel named ``<name>__<tag>``.

    Why: a numba kernel that takes functions as *arguments* cannot be cached across
    processes (numba keys the compiled code by the function objects, new in every process),
    so it would recompile in every process and MPI rank. A kernel that finds them among its
    globals can: it is a plain function of arrays and numbers, and the law is inlined into
    its loop exactly as before (the same machine code). ``tag`` must name the bound
    functions' version (see :func:`law_digest`): numba's cache index is keyed by the
    kernel's name, its bytecode and its own source file only."""
    globals_ = dict(py_func.__globals__)
    globals_.update(bound)
    clone = types.FunctionType(py_func.__code__, globals_, py_func.__name__,
                               py_func.__defaults__, py_func.__closure__)
    clone.__qualname__ = f"{py_func.__qualname__}__{tag}"
    clone.__doc__ = py_func.__doc__
    clone.__module__ = py_func.__module__
    return cached_jit(**options)(clone)

"""Hash a running case's dumps while the engine runs, so the done record costs ~nothing.

The dump record (:meth:`ligwf.study.case.CaseFolder.write_manifest`, ``dumps.json``)
holds the size and SHA-256 of every file in ``post/`` when a case ends ``done``. Hashing
them all at that moment took seconds to minutes on big studies, on the case's clock.
:class:`DumpHasher` hashes them in a background thread instead, each once it is complete:
LIGGGHTS writes one dump series after the other, so a dump is complete once a later
step of its series exists (or the file is older than the engine's whole run), and it ends
with ``</VTKFile>``. At the end only what was not hashed yet (the last frame) is hashed.

Crash safety: the digests live in this process only. A digest is kept only when the
file's identity (inode, size, modification time) is the same after hashing as before, and
the record uses it only when the file still has that identity; anything else is hashed
again. A runner that dies writes no record at all (a record is written only with a done
manifest), so a killed run never leaves a record claiming a dump it did not hash, and a
resumed run (a new runner) hashes the dumps it finds afresh.
"""

from __future__ import annotations

import os
import re
import threading
from pathlib import Path

from ligwf.fsio import file_sha256
from ligwf.study.case import KnownDigests, file_identity

#: ``<series>_<step>.vtu`` / ``.vtr``: the dump file names LIGGGHTS writes into post/
_DUMP = re.compile(r"^(?P<series>.+)_(?P<step>\d+)\.vt[ur]$")
#: how every complete XML VTK file LIGGGHTS writes ends
_VTK_END = b"</VTKFile>"


def complete_dumps(post: Path) -> list[Path]:
    """The dumps of ``post`` that are complete: a later step of their series exists and
    the file ends with ``</VTKFile>`` (oldest step first, then by name)."""
    series: dict[str, list[tuple[int, Path]]] = {}
    try:
        entries = list(os.scandir(post))
    except OSError:
        return []
    for e in entries:
        m = _DUMP.match(e.name)
        if m and e.is_file():
            series.setdefault(m.group("series"), []).append((int(m.group("step")), Path(e.path)))
    out = []
    for files in series.values():
        files.sort()
        out += [p for _, p in files[:-1] if dump_problem(p) is None]
    return sorted(out, key=lambda p: (int(_DUMP.match(p.name).group("step")), p.name))


def dump_problem(path: Path) -> str | None:
    """Why a dump file is not whole (empty, or cut before its closing tag), None if it is
    (also what the runner's record check calls a hole: :func:`ligwf.engine.attempt.record_hole`)."""
    try:
        size = path.stat().st_size
        if size == 0:
            return f"empty dump {path.name}"
        with open(path, "rb") as fh:
            fh.seek(max(0, size - 64))
            if _VTK_END not in fh.read():
                return f"truncated dump {path.name}"
    except OSError as exc:
        return f"unreadable dump {path.name} ({exc.strerror})"
    return None


def hash_if_unchanged(path: Path) -> tuple[tuple[int, int, int], str] | None:
    """(identity, SHA-256) of ``path`` when it did not change while it was hashed."""
    before = file_identity(path)
    if before is None:
        return None
    try:
        digest = file_sha256(path)
    except OSError:
        return None
    return (before, digest) if file_identity(path) == before else None


class DumpHasher:
    """Background hashing of a case's complete dumps (see the module doc).

    ``with DumpHasher(post) as hasher: ...run the engine...``; then ``hasher.digests``
    (:class:`~ligwf.study.case.KnownDigests`) for the done record. ``poll_seconds``: how
    often ``post/`` is looked at."""

    def __init__(self, post: Path, poll_seconds: float = 1.0) -> None:
        self.post = Path(post)
        self.poll_seconds = poll_seconds
        self._known: dict[str, tuple[tuple[int, int, int], str]] = {}
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._loop, name="ligwf-dump-hasher",
                                        daemon=True)

    def __enter__(self) -> "DumpHasher":
        self._thread.start()
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def close(self) -> None:
        """Stop the thread (a file being hashed is finished first)."""
        self._stop.set()
        if self._thread.is_alive():
            self._thread.join()

    def hash_pending(self) -> int:
        """Hash every complete dump not hashed yet (or changed since); returns how many."""
        done = 0
        for path in complete_dumps(self.post):
            if self._stop.is_set():
                break
            known = self._known.get(path.name)
            if known is not None and known[0] == file_identity(path):
                continue
            got = hash_if_unchanged(path)
            if got is not None:
                self._known[path.name] = got
                done += 1
        return done

    def _loop(self) -> None:
        while not self._stop.is_set():
            try:
                self.hash_pending()
            except Exception:    # noqa: BLE001 - a hashing hiccup only costs the end-of-case hash
                pass
            self._stop.wait(self.poll_seconds)

    @property
    def digests(self) -> KnownDigests:
        """What was hashed: file name -> (identity, SHA-256)."""
        return KnownDigests(dict(self._known))

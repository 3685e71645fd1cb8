"""Restart identity: which case, replica and attempt wrote a restart file.

LIGGGHTS names its restarts by step only (``restart_forced_liggghts_<step>.data``, the
periodic pair ``restart/restart_a|b.liggghts``), and a restart file holds no case, seed or
replica. A restart dropped into the wrong folder (another replica's, a copy of another
study's) would therefore be resumed from without a word, and two replicas would become one
trajectory. So every restart ligwf's engines write gets a sidecar next to it,
``<restart>.id.json``, written atomically by ligwf while it owns the engine:

    {"case_id", "scene_hash", "replica", "seeds", "step", "attempt", "size", "sha256"}

It is written by the runner's live poll (a file the engine has left alone for a moment),
again after every attempt (:func:`ligwf.engine.attempt.finish_attempt`), and by the
watchdog when it stops the engine of a dead runner (:mod:`ligwf.engine.guard`), each time
only for files changed since the attempt began. Resume (:mod:`ligwf.engine.resume`) takes a
restart only when its sidecar names this case (id, scene hash, replica, seeds), the file's
size and SHA-256 are the ones recorded (a truncated, garbled or replaced file is not), and
its step is not past the progress the manifest records. A restart without a sidecar was not
written by this case under ligwf: it is never used.
"""

from __future__ import annotations

import json
import os
import time
from dataclasses import dataclass
from pathlib import Path

from ligwf.engine.liggghts import restart_step
from ligwf.fsio import FolderNotWritable, atomic_write_json, file_sha256
from ligwf.study.layout import FORCED_RESTART_RE, PERIODIC_RESTARTS, RESTART_SIDECAR_SUFFIX

#: a file the engine changed less than this many seconds ago may still be being written:
#: the live poll stamps it on a later look
SETTLE_SECONDS = 0.3


@dataclass(frozen=True)
class CaseIdentity:
    """What makes a case's trajectory its own."""

    case_id: str
    scene_hash: str
    replica: int
    seeds: tuple[int, ...]

    @classmethod
    def of(cls, case) -> "CaseIdentity":
        """The identity of a :class:`ligwf.study.case.CaseFolder`."""
        return cls(case.case_id, case.scene_hash, int(case.replica),
                   tuple(int(s) for s in case.scaled.fill.seeds))

    def to_dict(self) -> dict:
        return {"case_id": self.case_id, "scene_hash": self.scene_hash,
                "replica": self.replica, "seeds": list(self.seeds)}


def sidecar(path: Path) -> Path:
    return path.with_name(path.name + RESTART_SIDECAR_SUFFIX)


def restart_paths(case_dir: Path) -> list[Path]:
    """Every restart file of a case folder that exists now (forced and periodic)."""
    case_dir = Path(case_dir)
    found = [p for p in case_dir.iterdir() if FORCED_RESTART_RE.match(p.name)]
    found += [case_dir / rel for rel in PERIODIC_RESTARTS if (case_dir / rel).is_file()]
    return found


def _read(path: Path) -> dict | None:
    try:
        data = json.loads(sidecar(path).read_text())
        return data if isinstance(data, dict) else None
    except (OSError, ValueError):
        return None


def stamp(case_dir: Path, identity: CaseIdentity, attempt: int, since: float,
          settle: float = 0.0) -> list[str]:
    """Write the sidecar of every restart in ``case_dir`` changed at or after ``since``
    (epoch s) whose sidecar does not describe its current content; ``settle``: leave
    files changed in the last ``settle`` seconds for later (the engine may be writing
    them). Returns the paths stamped (relative to the case folder). A full disk leaves
    the file unstamped (so it is never resumed from): nothing is raised."""
    case_dir = Path(case_dir)
    now = time.time()
    done: list[str] = []
    for path in restart_paths(case_dir):
        try:
            st = path.stat()
        except OSError:
            continue
        if st.st_mtime < since or now - st.st_mtime < settle:
            continue
        old = _read(path)
        if (old is not None and old.get("size") == st.st_size
                and old.get("mtime_ns") == st.st_mtime_ns):
            continue                                # already describes this content
        step = restart_step(path)
        if step is None:
            continue
        record = {**identity.to_dict(), "step": step, "attempt": int(attempt),
                  "size": st.st_size, "mtime_ns": st.st_mtime_ns, "sha256": file_sha256(path)}
        try:
            atomic_write_json(sidecar(path), record)
        except (FolderNotWritable, OSError):
            continue
        done.append(str(path.relative_to(case_dir)))
    return done


def why_not_own(path: Path, identity: CaseIdentity, max_step: int | None) -> str | None:
    """Why the restart ``path`` must not be resumed by the case ``identity`` (None: it may):
    no sidecar, another case / replica / seed, content changed since it was stamped, or a
    step past ``max_step`` (the progress the manifest records)."""
    rec = _read(path)
    if rec is None:
        return "no identity record (not written by this case under ligwf)"
    mine = identity.to_dict()
    for key in ("case_id", "scene_hash", "replica", "seeds"):
        if rec.get(key) != mine[key]:
            return f"written by another case ({key} {rec.get(key)!r}, this case {mine[key]!r})"
    try:
        size = path.stat().st_size
    except OSError:
        return "gone"
    if size != rec.get("size"):
        return f"{size} bytes, {rec.get('size')} when written (truncated or replaced)"
    if file_sha256(path) != rec.get("sha256"):
        return "content differs from what the engine wrote (SHA-256 mismatch)"
    step = restart_step(path)
    if step is None or step != rec.get("step"):
        return f"header step {step} is not the recorded {rec.get('step')}"
    if max_step is not None and step > max_step:
        return f"step {step} is past the case's recorded progress (step {max_step})"
    return None


def remove_sidecar(path: Path) -> None:
    try:
        os.unlink(sidecar(path))
    except OSError:
        pass

"""Case manifests: what ran, how, how long, and whether its outputs may be used.

The manifest sits next to the input in every case folder (file name:
:data:`ligwf.study.layout.MANIFEST_FILE`) and is always written atomically (temp file +
rename, :mod:`ligwf.fsio`), so a reader sees the previous or the new manifest, never half
of one. Later stages use only cases whose status is ``done`` and whose scene hash matches
the case's rendered scene (:meth:`ligwf.study.case.CaseFolder.why_not_usable`).

Timing for the error-vs-run-time study: ``phases`` holds engine wall seconds and
core-seconds (wall x MPI ranks) per phase (fill, settle, production), summed over all
attempts of the case (a resumed case adds its continuation's time).
"""

from __future__ import annotations

import json
import os
import socket
from dataclasses import asdict, dataclass, field
from datetime import datetime, timezone
from pathlib import Path
from typing import Any

from ligwf.errors import ConfigError
from ligwf.fsio import atomic_write_json
from ligwf.engine.health import KILLED, RUNNING, STATUSES
from ligwf.study.layout import MANIFEST_FILE, SCREEN_FILE


def now_iso() -> str:
    """Current UTC time, ISO 8601 with seconds."""
    return datetime.now(timezone.utc).isoformat(timespec="seconds")


@dataclass
class Attempt:
    """One launch of the engine for a case (a fresh run or a resume)."""

    number: int
    started: str
    ended: str | None = None
    wall_seconds: float = 0.0
    nprocs: int = 1
    command: list[str] = field(default_factory=list)
    input: str = "in.liggghts"
    from_restart: str | None = None
    from_step: int = 0
    exit_code: int | None = None
    screen: str = SCREEN_FILE
    status: str = RUNNING
    reason: str = ""


@dataclass
class Manifest:
    """Everything recorded about one case (JSON-serialisable)."""

    case_id: str
    index: int
    scene_hash: str
    ligwf_version: str
    liggghts_version: str
    status: str = RUNNING
    reason: str = ""
    reason_step: int | None = None
    issues: list[dict] = field(default_factory=list)
    launcher: str = "mpirun"            # "mpirun" or "ensemble"
    nprocs: int = 1
    command: list[str] = field(default_factory=list)
    host: str = field(default_factory=socket.gethostname)
    pid: int = field(default_factory=os.getpid)
    started: str = field(default_factory=now_iso)
    ended: str | None = None
    wall_seconds: float = 0.0           # launcher wall time over all attempts, s
    core_seconds: float = 0.0           # wall x ranks over all attempts, core-s
    steps_done: int = 0
    total_steps: int = 0
    atoms_start: int | None = None
    atoms_after_settle: int | None = None
    atoms_end: int | None = None
    simulated_time: float = 0.0         # s
    phases: dict[str, dict[str, float]] = field(default_factory=dict)
    attempts: list[Attempt] = field(default_factory=list)

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> "Manifest":
        data = dict(data)
        # a hand-written or foreign manifest may carry only status and scene hash
        for key, default in (("index", -1), ("ligwf_version", ""), ("liggghts_version", "")):
            data.setdefault(key, default)
        data["attempts"] = [Attempt(**a) for a in data.get("attempts", [])]
        known = {f for f in cls.__dataclass_fields__}
        return cls(**{k: v for k, v in data.items() if k in known})


def write_manifest(case_dir: Path, manifest: Manifest) -> None:
    """Write the case's manifest atomically (a bad status is refused first)."""
    if manifest.status not in STATUSES:
        raise ConfigError(f"manifest status {manifest.status!r} (allowed: {', '.join(STATUSES)})")
    atomic_write_json(Path(case_dir) / MANIFEST_FILE, manifest.to_dict())


def read_manifest(case_dir: Path) -> Manifest | None:
    """The case's manifest, or None when there is none (or it is unreadable)."""
    path = Path(case_dir) / MANIFEST_FILE
    try:
        return Manifest.from_dict(json.loads(path.read_text()))
    except FileNotFoundError:
        return None
    except (json.JSONDecodeError, TypeError, KeyError):
        return None


def pid_alive(pid: int) -> bool:
    """Whether a process with this id exists on this host."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def effective_status(m: Manifest) -> str:
    """The manifest's status, with a ``running`` case whose runner died read as ``killed``.

    (SIGKILL, a node crash or a scheduler timeout leave ``running`` behind.)
    """
    if m.status == RUNNING:
        if m.host != socket.gethostname() or not pid_alive(m.pid) or m.pid == os.getpid():
            return KILLED
    return m.status

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
import time
from dataclasses import asdict, dataclass, field
from datetime import datetime, timezone
from enum import StrEnum
from pathlib import Path
from typing import Any

from ligwf.errors import ConfigError
from ligwf.fsio import atomic_write_json, overwrite_in_place, try_lock
from ligwf.study.layout import INPUT_NAME, MANIFEST_FILE, RUNNER_LOCK, SCREEN_FILE
from ligwf.study.processes import EngineProcess, start_time

#: Case states a manifest can hold.
DONE, FAILED, UNSTABLE, KILLED, RUNNING = "done", "failed", "unstable", "killed", "running"
STATUSES = (DONE, FAILED, UNSTABLE, KILLED, RUNNING)
#: Shown for a case without a (readable) manifest: not run yet. Never written to one.
MISSING = "missing"

#: how the reason of an attempt ended by a full disk begins (the runner then stops)
DISK_FULL_REASON = "disk full"


class Stop(StrEnum):
    """Why a case's last attempt stopped short of done in a way the runners act on (the
    manifest's ``stop``; ``reason`` says it in words for people): the runners branch on this,
    never on the reason's words."""

    NONE = ""                               # ran to its verdict (done, failed, unstable, ...)
    DISK_FULL = "disk_full"                 # the folder filled up: the runner stops
    INCOMPLETE_RECORD = "incomplete_record"  # a hole in its rows or dumps: resume before it
    RESTART_SET_ASIDE = "restart_set_aside"  # the engine could not read its restart
    INTERRUPTED = "interrupted"             # stopped on request (Ctrl-C, SIGTERM, scancel)
    JOB_ENDED = "job_ended"                 # an ensemble job ended under it (another member)
    NO_PROGRESS = "no_progress"             # ensemble launches that moved no member on

    @classmethod
    def from_reason(cls, reason: str) -> "Stop":
        """The stop of a manifest written before ``stop`` was recorded, from its words."""
        for words, stop in ((DISK_FULL_REASON, cls.DISK_FULL),
                            ("incomplete record", cls.INCOMPLETE_RECORD),
                            ("interrupted by the user", cls.INTERRUPTED),
                            ("stopped when the ensemble job ended", cls.JOB_ENDED),
                            ("ensemble job ended", cls.NO_PROGRESS)):
            if reason.startswith(words):
                return stop
        if reason.startswith("restart ") and reason.endswith("set aside"):
            return cls.RESTART_SET_ASIDE
        return cls.NONE


def now_iso() -> str:
    """Current UTC time, ISO 8601 with seconds."""
    return datetime.now(timezone.utc).isoformat(timespec="seconds")


@dataclass
class Attempt:
    """One launch of the engine for a case (a fresh run or a resume)."""

    number: int
    started: str
    started_at: float = field(default_factory=time.time)   # epoch s (wall of a lost runner)
    ended: str | None = None
    wall_seconds: float = 0.0
    steps: int = 0                      # steps this attempt ran (re-run steps count again)
    phases: dict[str, dict[str, float]] = field(default_factory=dict)
    nprocs: int = 1
    command: list[str] = field(default_factory=list)
    input: str = INPUT_NAME
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
    liggghts_executable: str = ""       # the engine that ran: executable (the --np path) ...
    liggghts_library: str = ""          # ... and the library it links to (the ensemble path)
    status: str = RUNNING
    reason: str = ""
    reason_step: int | None = None
    stop: Stop = Stop.NONE
    issues: list[dict] = field(default_factory=list)
    launcher: str = "mpirun"            # "mpirun" or "ensemble"
    nprocs: int = 1
    command: list[str] = field(default_factory=list)
    host: str = field(default_factory=socket.gethostname)
    pid: int = field(default_factory=os.getpid)
    pid_start: int | None = None        # runner start time (/proc): a recycled pid is no runner
    engine: list[dict] = field(default_factory=list)   # engine processes (pid, start, name)
    started: str = field(default_factory=now_iso)
    ended: str | None = None
    wall_seconds: float = 0.0           # launcher wall time, sum over attempts, s
    core_seconds: float = 0.0           # wall x ranks, sum over attempts, core-s
    steps_done: int = 0
    #: last step up to which thermo rows and dumps are whole (None: no hole found); a
    #: resume takes no restart past it, so a hole left by a full disk is run again
    complete_upto: int | None = None
    total_steps: int = 0
    atoms_start: int | None = None
    atoms_after_settle: int | None = None
    atoms_end: int | None = None
    simulated_time: float = 0.0         # s
    phases: dict[str, dict[str, float]] = field(default_factory=dict)
    attempts: list[Attempt] = field(default_factory=list)

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)

    def engine_processes(self) -> list[EngineProcess]:
        """The engine processes the runner recorded for the current attempt."""
        return [EngineProcess.from_dict(d) for d in self.engine]

    def add_up_attempts(self) -> None:
        """Wall, core-seconds and per-phase totals as the sums over the attempts."""
        self.wall_seconds = sum(a.wall_seconds for a in self.attempts)
        self.core_seconds = sum(a.wall_seconds * a.nprocs for a in self.attempts)
        self.phases = {}
        for a in self.attempts:
            for phase, rec in a.phases.items():
                tot = self.phases.setdefault(phase, {"wall_seconds": 0.0, "core_seconds": 0.0,
                                                     "steps": 0})
                tot["wall_seconds"] += rec.get("wall_seconds", 0.0)
                tot["core_seconds"] += rec.get("wall_seconds", 0.0) * a.nprocs
                tot["steps"] += int(rec.get("steps", 0))

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> "Manifest":
        data = dict(data)
        # a hand-written or foreign manifest may carry only status and scene hash
        for key, default in (("index", -1), ("ligwf_version", ""), ("liggghts_version", "")):
            data.setdefault(key, default)
        fields = Attempt.__dataclass_fields__
        data["attempts"] = [Attempt(**{k: v for k, v in a.items() if k in fields})
                            for a in data.get("attempts", [])]
        try:
            data["stop"] = Stop(data["stop"]) if "stop" in data else Stop.from_reason(
                str(data.get("reason", "")))
        except ValueError:              # a stop word of a newer ligwf: read its words
            data["stop"] = Stop.from_reason(str(data.get("reason", "")))
        known = {f for f in cls.__dataclass_fields__}
        return cls(**{k: v for k, v in data.items() if k in known})


def write_manifest(case_dir: Path, manifest: Manifest) -> None:
    """Write the case's manifest atomically (a bad status is refused first)."""
    if manifest.status not in STATUSES:
        raise ConfigError(f"manifest status {manifest.status!r} (allowed: {', '.join(STATUSES)})")
    atomic_write_json(Path(case_dir) / MANIFEST_FILE, manifest.to_dict())


def overwrite_manifest(case_dir: Path, manifest: Manifest) -> None:
    """Overwrite the manifest in place: the last resort on a full disk, where the atomic
    write finds no room for its temporary copy (truncating frees the old blocks first)."""
    overwrite_in_place(Path(case_dir) / MANIFEST_FILE,
                       json.dumps(manifest.to_dict(), indent=2, sort_keys=True) + "\n")


def read_manifest(case_dir: Path) -> Manifest | None:
    """The case's manifest, or None when there is none (or it is unreadable)."""
    path = Path(case_dir) / MANIFEST_FILE
    try:
        return Manifest.from_dict(json.loads(path.read_text()))
    except FileNotFoundError:
        return None
    except (json.JSONDecodeError, TypeError, KeyError):
        return None


def pid_alive(pid: int, start: int | None = None) -> bool:
    """Whether a process with this id (and, when given, this start time) exists here."""
    now = start_time(pid)
    return now is not None and (start is None or now == start)


def runner_alive(m: Manifest) -> bool:
    """Whether the process that wrote ``running`` into ``m`` is still running (this host,
    same pid and start time, not this process)."""
    return (m.host == socket.gethostname() and m.pid != os.getpid()
            and pid_alive(m.pid, m.pid_start))


def effective_status(m: Manifest) -> str:
    """The manifest's status, with a ``running`` case whose runner died read as ``killed``.

    (SIGKILL, a node crash or a scheduler timeout leave ``running`` behind.)
    """
    if m.status == RUNNING and not runner_alive(m):
        return KILLED
    return m.status


def case_lock(case_dir: Path):
    """Try to become the one runner of a case: a context that yields whether the lock was
    taken (no waiting). Two ``ligwf run`` on one study split its cases this way."""
    return try_lock(Path(case_dir) / RUNNER_LOCK)


def case_busy(case_dir: Path) -> bool:
    """Whether another runner holds the case's lock right now."""
    with case_lock(case_dir) as mine:
        return not mine

"""Processes as a study folder records them: pid plus kernel start time.

A manifest lists the engine processes of a case's attempt and the runner that holds it
(:mod:`ligwf.study.manifest`); a later runner must tell them apart from a process that got
a recycled pid, so a process is recorded with its start time from ``/proc/<pid>/stat``.
Finding and stopping engines is :mod:`ligwf.engine.guard`; this module only names them.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path


@dataclass(frozen=True)
class EngineProcess:
    """A process by pid and kernel start time (clock ticks since boot), so a pid the kernel
    has since given to another process is not mistaken for the engine."""

    pid: int
    start: int
    name: str = ""

    def alive(self) -> bool:
        return start_time(self.pid) == self.start

    def to_dict(self) -> dict:
        return {"pid": self.pid, "start": self.start, "name": self.name}

    @classmethod
    def from_dict(cls, d: dict) -> "EngineProcess":
        return cls(int(d["pid"]), int(d["start"]), str(d.get("name", "")))


def start_time(pid: int) -> int | None:
    """Start time of ``pid`` (field 22 of /proc/<pid>/stat), None when it does not exist
    or has ended (a zombie, state Z or X, waiting for its parent to reap it, is no
    process that runs: never a live runner or engine)."""
    try:
        with open(f"/proc/{pid}/stat", "rb") as fh:
            stat = fh.read().decode(errors="replace")
    except OSError:
        return None
    # the command name (field 2) may hold spaces and parentheses: split after the last ')'
    fields = stat[stat.rfind(")") + 2:].split()
    if fields and fields[0] in ("Z", "X"):
        return None
    try:
        return int(fields[19])
    except (IndexError, ValueError):
        return None


def process(pid: int) -> EngineProcess | None:
    """``pid`` with its start time and name, None when it is gone."""
    start = start_time(pid)
    if start is None:
        return None
    try:
        name = Path(f"/proc/{pid}/comm").read_text().strip()
    except OSError:
        name = ""
    return EngineProcess(pid, start, name)

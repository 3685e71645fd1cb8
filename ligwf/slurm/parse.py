"""Pure parsers of Slurm's text: ``sbatch --parsable``, ``squeue``, ``scontrol -o``, jobcomp.

Tested against text captured from a real Slurm 22.05 (tests/data/slurm/). Parsing is kept
apart from running the commands so that a site's odd output can be reproduced in a test
from a pasted snippet.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

from ligwf.errors import SubmitError

# keys of scontrol/jobcomp records: JobId, AllocNode:Sid, CPUs/Task, NtasksPerN:B:S:C, ...
_PAIR = re.compile(r"(?:^|\s)([A-Za-z][A-Za-z0-9_:/]*)=(.*?)(?=\s+[A-Za-z][A-Za-z0-9_:/]*=|\s*$)")

#: Slurm states after which a task will not run again by itself.
FINISHED_STATES = frozenset({"COMPLETED", "FAILED", "CANCELLED", "TIMEOUT", "NODE_FAIL",
                             "OUT_OF_MEMORY", "PREEMPTED", "BOOT_FAIL", "DEADLINE"})


def parse_sbatch_parsable(text: str) -> str:
    """Job id from ``sbatch --parsable`` output (``123`` or ``123;cluster``)."""
    lines = [ln.strip() for ln in text.splitlines() if ln.strip()]
    if not lines:
        raise SubmitError("sbatch --parsable printed nothing (expected a job id)")
    job_id = lines[-1].split(";", 1)[0]
    if not job_id.isdigit():
        raise SubmitError(f"sbatch --parsable printed {lines[-1]!r}, not a job id")
    return job_id


@dataclass(frozen=True)
class QueueEntry:
    """One line of ``squeue -r -o '%i|%F|%K|%T|%r'``: an array task or a plain job."""

    job_id: str
    array_job_id: str
    array_task_id: int | None
    state: str
    reason: str


def parse_squeue(text: str) -> list[QueueEntry]:
    """Parse squeue lines in ligwf's format; pending ranges (``2-3%2``) are expanded."""
    entries: list[QueueEntry] = []
    for raw in text.splitlines():
        line = raw.strip()
        if not line:
            continue
        parts = line.split("|")
        if len(parts) != 5:
            raise SubmitError(f"unexpected squeue line {line!r} (want 5 '|'-separated fields)")
        job_id, array_id, task, state, reason = (p.strip() for p in parts)
        if task in ("", "N/A"):
            entries.append(QueueEntry(job_id, array_id, None, state, reason))
            continue
        for index in expand_task_ids(task):
            entries.append(QueueEntry(f"{array_id}_{index}", array_id, index, state, reason))
    return entries


def expand_task_ids(text: str) -> list[int]:
    """``0-3%2`` / ``[1,4-5]`` / ``7`` -> list of task indices."""
    body = text.strip().strip("[]").split("%", 1)[0]
    out: list[int] = []
    for part in body.split(","):
        part = part.strip()
        if not part:
            continue
        step = 1
        if ":" in part:
            part, step_text = part.split(":", 1)
            step = int(step_text)
        if "-" in part:
            lo, hi = part.split("-", 1)
            out.extend(range(int(lo), int(hi) + 1, step))
        else:
            out.append(int(part))
    return out


def parse_records(text: str) -> list[dict[str, str]]:
    """``Key=Value Key=Value`` records, one per line (``scontrol -o show job``, jobcomp).

    Values may contain spaces (``Command=/my path/x.sh``) but not `` Key=``.
    """
    records = []
    for line in text.splitlines():
        line = line.strip()
        if not line or "=" not in line:
            continue
        records.append({k: v.strip() for k, v in _PAIR.findall(line)})
    return records


@dataclass(frozen=True)
class TaskRecord:
    """A task's state as the controller (scontrol) or the jobcomp file reports it."""

    job_id: str
    array_job_id: str | None
    array_task_id: int | None
    state: str
    exit_code: str

    @property
    def finished(self) -> bool:
        return self.state.split()[0] in FINISHED_STATES


def task_records(text: str) -> list[TaskRecord]:
    """Task records from ``scontrol -o show job`` or jobcomp text.

    The pending remainder of an array (``ArrayTaskId=2-3%2``) is expanded into one record
    per index; records without ``JobState`` are skipped.
    """
    out: list[TaskRecord] = []
    for rec in parse_records(text):
        if "JobState" not in rec or "JobId" not in rec:
            continue
        array_id = rec.get("ArrayJobId") or None
        task = rec.get("ArrayTaskId") or ""
        state, exit_code = rec["JobState"], rec.get("ExitCode", "")
        if array_id and task and task != "N/A":
            for index in expand_task_ids(task):
                out.append(TaskRecord(rec["JobId"], array_id, index, state, exit_code))
        else:
            out.append(TaskRecord(rec["JobId"], None, None, state, exit_code))
    return out


def is_unknown_job(text: str) -> bool:
    """True for scontrol/squeue's answer about a job the controller has forgotten."""
    return "Invalid job id specified" in text

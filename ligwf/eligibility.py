"""What a study still needs, read from its folder: the one answer every executor and loop
asks (signac-flow's eligible operations: a task is eligible when its postcondition does
not hold and nobody is doing it).

The tasks and their postconditions:

* **run a case**: its manifest says ``done`` for its scene, at its end step, the
  production extension (:mod:`ligwf.study.extension`) included. A case that needs running
  needs it :data:`FRESH` (not run, scene changed, failed, or unstable with
  ``retry_unstable``), as a :data:`RESUME` (killed, or ``running`` with a dead runner:
  continued from its newest own restart, else again from step 0) or as an :data:`EXTEND`
  (done, production extended since: continued from its restart). The rule is
  :func:`ligwf.engine.resume.standing`; the restart a case continues from is
  :func:`ligwf.engine.resume.plan_case`'s, asked only where it is priced or run.
  Not eligible: :data:`DONE`, :data:`UNSTABLE` (the same input blows up the same way) and
  :data:`HELD` (a live runner on this host has it, or the executor still has its task
  queued or running: it will write its manifest itself);
* **analyse**: the analysis record exists, is readable and still holds for the study
  (:meth:`~ligwf.analysis.records.analysis_record.AnalysisRecord.stale`: same cases,
  scenes, dumps and settings) and its tables are those it wrote (:func:`analysis_due`);
* **report**: the report's record of its files is newer than the analysis record and the
  rounds record (:func:`report_due`: after the last look of a sequential study, only the
  final report remains);
* **take a look** (a sequential study): every case of the round done (:attr:`Eligible.settled`).

:func:`eligible` answers for a study's cases: ``ligwf run`` / ``study`` schedule the
cases it names (:mod:`ligwf.local`), ``ligwf slurm resubmit`` submits them again
(:mod:`ligwf.pipeline.submit`), the rounds on a scheduler read where a round stands from
it (:mod:`ligwf.pipeline.submit_rounds`) and ``ligwf status`` (``--executor slurm`` too)
shows each case's need beside its manifest. So an extended done case, whose manifest still reads ``done``,
is run by all of them alike.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import StrEnum
from pathlib import Path
from typing import Iterable, Mapping

from ligwf.engine.resume import Why, standing
from ligwf.study.case import CaseFolder
from ligwf.study.layout import ANALYSIS_RECORD, REPORT_FILES_RECORD, ROUNDS_FILE
from ligwf.study.study import Study


class Need(StrEnum):
    """What a case needs before its postcondition holds (the value is the word shown)."""

    DONE = "done"               # nothing: it holds
    FRESH = "fresh"             # a run from step 0
    RESUME = "resume"           # stopped before its end: continue it
    EXTEND = "extend"           # done, production extended since: continue it
    UNSTABLE = "unstable"       # left alone unless retry_unstable
    HELD = "held"               # a live runner or a queued task has it


DONE, FRESH, RESUME, EXTEND, UNSTABLE, HELD = (Need.DONE, Need.FRESH, Need.RESUME,
                                               Need.EXTEND, Need.UNSTABLE, Need.HELD)
#: the needs that make a case eligible to run
RUNNABLE = frozenset({FRESH, RESUME, EXTEND})

_NEED_OF = {Why.NOT_RUN: FRESH, Why.SCENE_CHANGED: FRESH, Why.RERUN: FRESH,
            Why.KILLED: RESUME, Why.EXTENDED: EXTEND, Why.DONE: DONE,
            Why.UNSTABLE: UNSTABLE, Why.HELD: HELD}


@dataclass(frozen=True)
class CaseTask:
    """One case and what it needs, with the reason in words (``queued``: the executor's
    task that holds it)."""

    case: CaseFolder
    need: Need
    reason: str
    queued: str | None = None

    @property
    def runnable(self) -> bool:
        return self.need in RUNNABLE


@dataclass(frozen=True)
class Eligible:
    """What each case of a study (or of a share of its cases) needs, in case order."""

    tasks: tuple[CaseTask, ...]

    @property
    def to_run(self) -> tuple[CaseFolder, ...]:
        """The cases a runner starts, resumes or extends now."""
        return tuple(t.case for t in self.tasks if t.runnable)

    @property
    def indices(self) -> tuple[int, ...]:
        """The case indices of :attr:`to_run`."""
        return tuple(c.index for c in self.to_run)

    @property
    def not_done(self) -> tuple[CaseTask, ...]:
        """The cases whose postcondition does not hold (eligible, held or unstable)."""
        return tuple(t for t in self.tasks if t.need != DONE)

    @property
    def settled(self) -> bool:
        """Every case done: the analysis of these runs (and a round's look) may follow."""
        return not self.not_done

    def of(self, index: int) -> CaseTask:
        """The task of the case with index ``index``."""
        return next(t for t in self.tasks if t.case.index == index)


def case_task(case: CaseFolder, retry_unstable: bool = False,
              queued: str | None = None) -> CaseTask:
    """What ``case`` needs (``queued``: the executor's task still holding it, if any)."""
    if queued is not None:
        return CaseTask(case, HELD, f"queued or running as {queued}", queued)
    now = standing(case, retry_unstable)
    return CaseTask(case, _NEED_OF[now.why], now.reason)


def eligible(cases: Iterable[CaseFolder], retry_unstable: bool = False,
             queued: Mapping[int, str] | None = None) -> Eligible:
    """What each of ``cases`` needs (module docstring); ``queued``: case index -> the
    executor's task that still holds it (a scheduler's queued or running array task)."""
    queued = queued or {}
    return Eligible(tuple(case_task(c, retry_unstable, queued.get(c.index)) for c in cases))


def analysis_due(study: Study) -> str | None:
    """Why the analysis of ``study`` must run, in words; None when its record holds for the study and its tables are those it wrote."""
    # the analysis package is loaded on use (runs and resubmits never need it)
    from ligwf.analysis.records.analysis_record import AnalysisRecord, UnreadableRecord

    try:
        record = AnalysisRecord.load(study.analysis_dir)
    except FileNotFoundError:
        return "not analysed yet"
    except UnreadableRecord as exc:
        return f"its record is unreadable ({exc})"
    why = record.stale(study, study.analysis)
    if why is None and (damaged := record.damaged()):
        why = f"its tables changed since ({damaged[0]})"
    return why


def report_due(study: Study) -> bool:
    """Whether the report of ``study`` must be written: its record of files is missing, or
    older than the analysis record or the rounds record (a look taken, or the study
    stopped, since it was written)."""
    try:
        written = (Path(study.report_dir) / REPORT_FILES_RECORD).stat().st_mtime_ns
    except FileNotFoundError:
        return True
    inputs = (Path(study.analysis_dir) / ANALYSIS_RECORD, Path(study.path) / ROUNDS_FILE)
    return any(p.is_file() and p.stat().st_mtime_ns >= written for p in inputs)

"""The executor interface: what ligwf asks of whatever runs a study's cases -- this machine
(:class:`ligwf.local.LocalExecutor`) or a batch scheduler (Slurm, or PBS, LSF, ...).

Every :class:`Executor` runs cases (:meth:`Executor.run_cases`: on this machine now; on a
scheduler as a job array it waits for), says where each case stands
(:meth:`Executor.status`: its manifest beside the executor's own view of it, a live runner
or a queued task), stops them (:meth:`Executor.cancel`) and analyses what they wrote
(:meth:`Executor.analyse`: shares side by side, merged). The pipeline runs cases and the
analysis only through this interface (:func:`ligwf.pipeline.run.run_study`,
:func:`ligwf.pipeline.post.postprocess`).

A batch scheduler (:class:`Scheduler`) is an executor that can also hand a whole study to
the queue and return at once: job arrays and a follow-up job, as below.

A scheduler runs a written study as job arrays: one task per case (each runs ``ligwf
run-case STUDY --index I``, the local runner with its manifests, health checks and
resume), one array per rank count of the rank plan (the phases of
:func:`ligwf.engine.plan.allocation_schedule`), and a follow-up job after all of them
that runs the pipeline's post-processing commands. Four things differ between
schedulers, and a :class:`Scheduler` implements them:

* **script building** (:meth:`Scheduler.plan_jobs`, pure): the batch scripts and what
  each one covers; :meth:`Scheduler.dry_run_text` shows them without submitting;
* **submit** (:meth:`Scheduler.submit`): write the scripts, submit them in order (the
  follow-up job depends on the arrays), record every submission in the study folder;
* **status** (:meth:`Scheduler.status`): each case's manifest beside the scheduler's view
  of its latest task (:class:`StudyStatus`);
* **cancel** (:meth:`Scheduler.cancel`): stop the study's queued and running jobs (array
  tasks get the scheduler's signal, so the runner writes forced restarts and marks the
  case ``killed``; a resubmit resumes it).

Which cases a resubmit runs again is not the scheduler's to say: it is what
:func:`ligwf.eligibility.eligible` says of the case folders, with the cases whose task the
scheduler still has queued or running held.

Where an executor waits (a scheduler for the arrays it submitted, this machine for the
analysis shares it started) it waits in :func:`wait_for`. The case's outcome is always its
manifest: the scheduler only says whether a task is still queued or running. The Slurm implementation is :class:`ligwf.slurm.scheduler.SlurmScheduler`;
the pipeline (:mod:`ligwf.pipeline.submit`) chains preparation, rank plan and scheduler.
"""

from __future__ import annotations

import threading
import time
from dataclasses import dataclass
from pathlib import Path
from types import MappingProxyType
from typing import Callable, Iterable, Mapping, Protocol, Sequence, runtime_checkable


class CaseView(Protocol):
    """What the pipeline reads of one case's status (the Slurm one: its ``CaseStatus``)."""

    index: int
    case_id: str
    manifest: str           # the manifest status, or MISSING
    job: str | None         # the scheduler's id of its latest task

    @property
    def queued(self) -> bool:
        """Still pending or running (it will write its manifest itself)."""


class StudyStatus(Protocol):
    """Every case's status, the recorded jobs (with their ``state``; a job after the
    arrays also with ``active``: still queued or running) and, in tolerant mode, why the
    scheduler's view is missing."""

    cases: list
    jobs: list[dict]
    scheduler_error: str | None


def active_tasks(cases: Iterable[CaseView]) -> list[CaseView]:
    """Cases whose latest task is still pending or running."""
    return [c for c in cases if c.queued]


def queued_tasks(status: StudyStatus) -> dict[int, str]:
    """Case index -> the task still holding it (pending or running), for
    :func:`ligwf.eligibility.eligible`."""
    return {c.index: c.job or "?" for c in status.cases if c.queued}


def wait_for(pending: Callable[[], bool], stop: threading.Event, poll_seconds: float,
             on_stop: Callable[[], object] | None = None) -> bool:
    """The one wait loop of the executors: ask ``pending()`` every ``poll_seconds`` until
    it says nothing is pending. The first time ``stop`` is set, ``on_stop`` runs once
    (cancel what runs: the wait then goes on until it has ended) or, without one, the wait
    returns at once. Whether ``stop`` ended or interrupted it."""
    stopped = False
    while pending():
        if stop.is_set() and not stopped:
            stopped = True
            if on_stop is None:
                return True
            on_stop()
        if stopped:             # stop stays set: pace the looks until what runs has ended
            time.sleep(poll_seconds)
        else:
            stop.wait(poll_seconds)
    return stopped


@runtime_checkable
class Executor(Protocol):
    """What runs a study's cases (see the module docstring)."""

    #: the name shown to users and recorded with submissions (``local``, ``slurm``)
    name: str

    def require(self) -> None:
        """A one-line error unless the executor can run anything (the engine, the
        scheduler's commands): checked before anything is written."""

    def run_cases(self, study, cases: Sequence, monitor=None, stop=None) -> bool:
        """Run ``cases`` (:class:`ligwf.study.case.CaseFolder`) of ``study`` to their end
        and return whether all of them are done; ``stop`` (a threading.Event) set: stop
        them resumably (forced restarts, ``killed``) and return; ``monitor``: live
        progress where the executor can see it."""

    def analyse(self, study, tasks: int = 1, stop=None) -> dict | None:
        """Analyse ``study``'s runs with its stored analysis settings into its analysis
        folder, split into ``tasks`` shares run side by side (1: one; the outputs are the
        same bytes however it is split) and merged; the analysis record (None when
        ``stop`` ended it first)."""

    def status(self, study_dir: Path, tolerant: bool = False) -> StudyStatus:
        """Every case's manifest beside the executor's view of it (``tolerant``: an
        executor that cannot be asked leaves its view empty and says why)."""

    def cancel(self, study_dir: Path) -> list[str]:
        """Stop the study's cases that are still queued or running; what was stopped."""


@dataclass(frozen=True)
class JobRound:
    """What one submission round asks of a scheduler (:meth:`Scheduler.plan_jobs`).

    ``indices``: the cases to run (none: the follow-up job alone); ``ranks``: case index
    -> MPI ranks from the rank plan (None: the site's fixed task count), planned on
    ``plan_cores`` cores (recorded, so a resubmit plans again on as many);
    ``post_steps``: the ``ligwf <step> STUDY`` commands of the follow-up job, in order;
    ``analysis_tasks`` > 1: its ``analyse`` step as an array of that many tasks staged
    under ``token``, then a merge job running the other steps; ``round_no``: the
    submission round the scripts are numbered by; ``study_round``: the round of a
    sequential study the jobs run (recorded with them)."""

    indices: tuple[int, ...] = ()
    round_no: int = 1
    ranks: Mapping[int, int] | None = None
    post_steps: tuple[str, ...] = ()
    plan_cores: int | None = None
    analysis_tasks: int = 1
    token: str | None = None
    study_round: int | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "indices", tuple(sorted({int(i) for i in self.indices})))
        object.__setattr__(self, "post_steps", tuple(self.post_steps))
        if self.ranks is not None:
            object.__setattr__(self, "ranks", MappingProxyType(
                {int(k): int(v) for k, v in self.ranks.items()}))


class BatchJob(Protocol):
    """A planned script: its kind (``array`` or the follow-up ``analysis``), where it is
    written, its text and the case indices it covers."""

    kind: str
    script_path: Path
    script_text: str
    indices: tuple[int, ...]


@runtime_checkable
class Scheduler(Executor, Protocol):
    """A batch scheduler ligwf submits studies to (see the module docstring)."""

    def plan_jobs(self, study_dir: Path, study_name: str, request: JobRound
                  ) -> Sequence[BatchJob]:
        """The scripts of one submission round (pure): one array per rank count of
        ``request.ranks`` and, with ``request.post_steps``, the follow-up job (see
        :class:`JobRound`)."""

    def plan_analysis(self, study_dir: Path, study_name: str, tasks: int, token: str
                      ) -> Sequence[BatchJob]:
        """The scripts of a split analysis of a written study (pure): an array of ``tasks``
        analysis tasks, each one share of the study's (case, frame) tasks staged under
        ``token``, and the job that merges them into the analysis folder."""

    def dry_run_text(self, jobs: Sequence[BatchJob]) -> str:
        """Every script and the command that would submit it."""

    def submit(self, study_dir: Path, jobs: Sequence[BatchJob]) -> list[dict]:
        """Write and submit ``jobs`` in order, recording each; the new record entries."""

    def next_round(self, study_dir: Path) -> int:
        """1 + the submission rounds recorded in the study folder so far."""

    def recorded(self, study_dir: Path) -> bool:
        """Whether the study folder records a submission of this scheduler."""

"""The executor interface: what ligwf asks of whatever runs a study's cases -- this machine
(:class:`ligwf.local.LocalExecutor`) or a batch scheduler (Slurm, or PBS, LSF, ...).

Every :class:`Executor` runs cases (:meth:`Executor.run_cases`: on this machine now; on a
scheduler as job arrays it waits for), analyses what they wrote (:meth:`Executor.analyse`:
shares side by side, merged), says where each case stands (:meth:`Executor.status`: its
manifest beside the executor's own view of it, a live runner or a queued task) and stops
them (:meth:`Executor.cancel`); :meth:`Executor.require` refuses, before anything is
written, an executor that cannot run anything. The pipeline runs cases and the analysis
only through these five (:func:`ligwf.pipeline.run.run_study`,
:func:`ligwf.pipeline.post.postprocess`).

A batch scheduler (:class:`Scheduler`) implements job verbs instead, as snakemake's
executor plugins do (run a job, check the active ones, cancel): :meth:`Scheduler.plan_jobs`
builds the scripts of a submission (pure: one task per case, each running ``ligwf
run-case STUDY --index I``, the local runner with its manifests, health checks and
resume; one array per rank count of the rank plan, the phases of
:func:`ligwf.engine.plan.allocation_schedule`; and a follow-up job after them running the
pipeline's post-processing, its analysis split into shares and a merge when asked),
:meth:`Scheduler.submit` writes and submits them in order and records each in the study
folder, :meth:`Scheduler.status` polls (each case's manifest beside its latest task, each
recorded job's state) and :meth:`Scheduler.cancel` stops the study's jobs (array tasks get
the scheduler's signal, so the runner writes forced restarts and marks the case
``killed``; a resubmit resumes it); :meth:`Scheduler.require` checks its commands.
:class:`SubmitAndWait`, written once, makes any scheduler an executor: its
``run_cases`` and ``analyse`` submit and then wait in :func:`wait_for`, the one wait loop
(this machine's analysis shares wait in it too). What a scheduler shows in a dry run is
its own command line's business (:mod:`ligwf.cli.slurm`), not the pipeline's.

Which cases a resubmit runs again is not the scheduler's to say: it is what
:func:`ligwf.eligibility.eligible` says of the case folders, with the cases whose task the
scheduler still has queued or running held. The case's outcome is always its manifest:
the scheduler only says whether a task is still queued or running. The Slurm
implementation is :class:`ligwf.slurm.scheduler.SlurmScheduler`; the pipeline
(:mod:`ligwf.pipeline.submit`) chains preparation, rank plan and scheduler.
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
    """Every case's status, the recorded jobs (with their ``state``, the scheduler's word;
    a job after the arrays also with ``active``: still queued or running, and
    ``completed``: ended well) and, in tolerant mode, why the scheduler's view is
    missing."""

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
    ``analysis_tasks`` > 1 (or a ``token``): its ``analyse`` step as an array of that many
    tasks staged under ``token``, then a merge job running the other steps (no
    ``indices`` and ``post_steps`` ``("analyse",)``: a written study's split analysis);
    ``round_no``: the submission round the scripts are numbered by (None: the one after
    the submissions the study folder records); ``study_round``: the round of a sequential
    study the jobs run (recorded with them)."""

    indices: tuple[int, ...] = ()
    round_no: int | None = None
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
class Scheduler(Protocol):
    """A batch scheduler ligwf submits studies to (see the module docstring): the job
    verbs a new one implements (snakemake's executor plugins: run a job, check the active
    ones, cancel). :class:`SubmitAndWait` makes one an :class:`Executor`."""

    #: the name shown to users and recorded with submissions (``slurm``)
    name: str

    def require(self) -> None:
        """A one-line error unless the scheduler's commands are usable (checked before
        anything is written or submitted)."""

    def plan_jobs(self, study_dir: Path, study_name: str, request: JobRound
                  ) -> Sequence[BatchJob]:
        """The scripts of one submission (pure apart from reading the study folder's
        record to number them): one array per rank count of ``request.ranks`` and, with
        ``request.post_steps``, the follow-up job, its analysis split when asked (see
        :class:`JobRound`)."""

    def submit(self, study_dir: Path, jobs: Sequence[BatchJob]) -> list[dict]:
        """Write and submit ``jobs`` in order (a follow-up job after the arrays before
        it), recording each in the study folder; the new record entries."""

    def status(self, study_dir: Path, tolerant: bool = False) -> StudyStatus:
        """The poll: every case's manifest beside the state of its latest task, and every
        recorded job with its state (a job after the arrays also with ``active``)."""

    def cancel(self, study_dir: Path) -> list[str]:
        """Stop the study's queued and running jobs; their ids."""


class SubmitAndWait:
    """What makes a :class:`Scheduler` an :class:`Executor`, written once for every
    scheduler over its job verbs and :func:`wait_for`: :meth:`run_cases` submits the cases
    as arrays and waits for them, :meth:`analyse` submits the split analysis and waits for
    its merge. A scheduler class inherits it and sets ``poll_seconds`` (seconds between
    polls) and ``forget_polls`` (polls in a row in which the scheduler does not know a job
    it was given before the wait gives up on it: one that ended before the first poll,
    with no accounting)."""

    poll_seconds: float = 5.0
    forget_polls: int = 3

    def _wait(self: Scheduler, study_dir: Path, stop: threading.Event,
              pending: Callable[[StudyStatus], bool]) -> bool:
        """Poll every ``poll_seconds`` while ``pending(status)``; ``stop`` set: cancel the
        study's jobs once and go on waiting until they have ended. Whether it cancelled."""
        return wait_for(lambda: pending(self.status(study_dir)), stop, self.poll_seconds,
                        lambda: self.cancel(study_dir))

    def run_cases(self, study, cases: Sequence, monitor=None,
                  stop: threading.Event | None = None) -> bool:
        """Submit ``cases`` as job arrays (ranks from the allocation rank plan, each case
        in an allocation of its own; no follow-up job) and wait until none of them is
        queued or running; whether all of them are done. ``stop`` set: the arrays are
        cancelled (the runners write forced restarts, the cases end ``killed``) and the
        wait goes on until the scheduler has ended them. ``monitor`` is not fed: the
        engines run on other nodes (``ligwf status --executor NAME`` shows them)."""
        from ligwf.eligibility import eligible
        from ligwf.engine.plan import allocation_schedule, case_load

        stop = stop or threading.Event()
        cases = list(cases)
        if not cases:
            return True
        schedule = allocation_schedule([case_load(c.path.name, c.scaled) for c in cases])
        ranks = {c.index: schedule.ranks_of(c.path.name) for c in cases}
        indices = {c.index for c in cases}
        self.require()
        self.submit(study.path, self.plan_jobs(study.path, study.name,
                                               JobRound(tuple(indices), ranks=ranks)))
        self._wait(study.path, stop,
                   lambda st: any(c.queued for c in st.cases if c.index in indices))
        return eligible(cases).settled

    def analyse(self, study, tasks: int = 1,
                stop: threading.Event | None = None) -> dict | None:
        """The study's analysis as a job array of ``tasks`` shares and the merge job after
        it (what ``ligwf analyse --executor NAME --tasks N`` submits), waited for; the
        merged analysis record. ``stop`` set: both jobs are cancelled and None is returned
        once they have ended. SubmitError when the merge job ends without a record (its
        log, in the study's scheduler log folder, says why: a share that failed is named
        there with the command that re-runs it)."""
        from ligwf.analysis.outputs import new_token
        from ligwf.analysis.records.analysis_record import AnalysisRecord
        from ligwf.errors import SubmitError
        from ligwf.study import layout

        stop = stop or threading.Event()
        self.require()
        jobs = self.plan_jobs(study.path, study.name, JobRound(
            post_steps=("analyse",), analysis_tasks=max(1, tasks), token=new_token()))
        merge = str(self.submit(study.path, jobs)[-1]["job_id"])
        looks: list[str | None] = []         # the merge job's state at each poll
        ended_well = False

        def pending(st: StudyStatus) -> bool:
            nonlocal ended_well
            entry = next(j for j in st.jobs if str(j["job_id"]) == merge)
            looks.append(entry.get("state"))
            ended_well = bool(entry.get("completed"))
            if looks[-1] is not None:
                return bool(entry["active"])
            # unknown to the scheduler: waited for until so forget_polls + 1 polls in a row
            return looks[-self.forget_polls - 1:] != [None] * (self.forget_polls + 1)

        if self._wait(study.path, stop, pending):
            return None
        state = looks[-1]
        if state is None or not ended_well:
            raise SubmitError(f"the analysis merge job {merge} ended "
                              f"{state or 'unknown to ' + self.name}: its log in "
                              f"{study.path / layout.SLURM_LOG_DIR} says why")
        record = AnalysisRecord.read(study.analysis_dir)
        return record.data if record is not None else None

"""The pipeline on a batch scheduler: prepare, plan the ranks, write, submit.

``ligwf study --executor slurm`` (``ligwf slurm submit``) =
:func:`~ligwf.pipeline.prepare.prepare_workflow` (the same validation, rendering and
pre-flight as ``ligwf study``, before anything is written or submitted) +
:func:`plan_submission` + :func:`write_for_submit` + :meth:`Submission.submit`; ``ligwf
slurm resubmit`` = :func:`plan_resubmission` + :meth:`Resubmission.submit`; ``ligwf
analyse STUDY --executor slurm --tasks N`` = :func:`plan_split_analysis` +
:meth:`SplitAnalysis.submit`. The ranks of every case come from
the same planner as a local run (:func:`ligwf.engine.plan.allocation_schedule`: each case
in an allocation of its own, at most ``cores`` ranks if given), or ``--ntasks`` / the
site's fixed task count; the scheduler (:class:`ligwf.scheduler.Scheduler`) builds one
array per rank count and the follow-up job runs :data:`POSTPROCESS_COMMANDS`, the
post-processing of ``ligwf study``.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Sequence

from ligwf.engine.plan import Schedule, allocation_schedule, case_load
from ligwf.errors import SubmitError
from ligwf.pipeline.post import POSTPROCESS_COMMANDS
from ligwf.pipeline.prepare import Prepared, prepared_loads, write
from ligwf.eligibility import Eligible, eligible
from ligwf.scheduler import (BatchJob, CaseView, JobRound, Scheduler, active_tasks,
                             queued_tasks)
from ligwf.study.layout import is_study_folder
from ligwf.study.study import Study


def submission_schedule(loads, cores: int | None, ntasks: int | None) -> Schedule:
    """The ranks of every case on a scheduler: the rank plan (at most ``cores`` ranks a
    case), or every case on ``ntasks`` ranks (``--ntasks`` / the site's ntasks)."""
    fixed = (ntasks, "--ntasks") if ntasks is not None else None
    return allocation_schedule(loads, cores, fixed)


@dataclass(frozen=True)
class Submission:
    """What a submit will do: the study folder, the rank schedule and the scripts."""

    out: Path
    schedule: Schedule
    jobs: tuple[BatchJob, ...]

    @property
    def planned(self) -> bool:
        return self.schedule.planned

    def submit(self, scheduler: Scheduler) -> list[dict]:
        """Submit the scripts of a written study (:func:`write_for_submit`); the recorded
        entries."""
        return scheduler.submit(self.out, self.jobs)


def plan_submission(prepared: Prepared, out: Path, scheduler: Scheduler, cores: int | None,
                    ntasks: int | None, analysis: bool = True,
                    analysis_tasks: int = 1, post_steps: Sequence[str] | None = None,
                    study_round: int | None = None) -> Submission:
    """The schedule and scripts of a first submission of ``prepared`` into ``out`` (pure
    apart from reading an earlier submission record to number the scripts and drawing a
    staging token when the analysis is split over ``analysis_tasks`` array tasks).
    ``post_steps``: the follow-up job's commands instead of :data:`POSTPROCESS_COMMANDS`
    (a sequential study's next round, :mod:`ligwf.pipeline.submit_rounds`)."""
    schedule = submission_schedule(prepared_loads(prepared), cores, ntasks)
    ranks = None if not schedule.planned else {
        rc.case.index: schedule.ranks_of(rc.case.case_id) for rc in prepared.rendered}
    steps = (list(post_steps) if post_steps is not None
             else list(POSTPROCESS_COMMANDS) if analysis else [])
    jobs = scheduler.plan_jobs(out, prepared.workflow.name, JobRound(
        tuple(rc.case.index for rc in prepared.rendered), None, ranks, tuple(steps), cores,
        analysis_tasks, _token(analysis_tasks), study_round))
    return Submission(out, schedule, tuple(jobs))


def _token(analysis_tasks: int) -> str | None:
    """A fresh staging token for a split analysis (None for one analysis job)."""
    if analysis_tasks <= 1:
        return None
    from ligwf.analysis.outputs import new_token

    return new_token()


def write_for_submit(prepared: Prepared, submission: Submission, scheduler: Scheduler,
                     mesh_cache: Path | None = None, replace: bool = False) -> Study:
    """Check the scheduler's commands, refuse while an earlier submission of the study
    still runs, then write the study folder (:meth:`Submission.submit` submits it)."""
    scheduler.require()
    out = submission.out
    if is_study_folder(out):        # a study submitted before: none of its cases queued
        busy = active_tasks(scheduler.status(out).cases)
        if busy:
            raise SubmitError(f"{out} still has {len(busy)} queued or running case(s) "
                              f"({', '.join(c.job or '?' for c in busy[:5])}); wait, scancel "
                              f"them, or use 'ligwf {scheduler.name} resubmit'")
    return write(prepared, out, mesh_cache, replace)


@dataclass(frozen=True)
class Resubmission:
    """The cases a resubmit runs again, the ones still queued, and the scripts."""

    study_dir: Path
    cases: tuple[CaseView, ...]        # every case with its status
    indices: tuple[int, ...]          # the ones to run again
    busy: tuple[CaseView, ...]         # still queued or running: left alone
    jobs: tuple[BatchJob, ...]
    needs: Eligible                    # what each case needs (why it runs again or not)

    def submit(self, scheduler: Scheduler) -> list[dict]:
        return scheduler.submit(self.study_dir, self.jobs)


def plan_resubmission(study_dir: Path, scheduler: Scheduler, include_unstable: bool,
                      cores: int | None, planned: bool, recorded_cores: int | None = None,
                      analysis: bool = True, analysis_tasks: int = 1) -> Resubmission:
    """The cases :func:`~ligwf.eligibility.eligible` says must run (missing, failed,
    killed, their scene changed, or done with their production extended since;
    ``include_unstable``: unstable too) and whose task is not queued, with their scripts.
    ``planned``: a planned submission is planned again, on ``cores`` or else the cores it
    was planned on (``recorded_cores``); otherwise every case gets the site's fixed task
    count."""
    study = Study.open(study_dir)
    st = scheduler.status(study_dir)
    needs = eligible(study.cases, include_unstable, queued_tasks(st))
    indices = list(needs.indices)
    busy = active_tasks(st.cases)
    jobs: Sequence[BatchJob] = ()
    plan_cores = cores if cores is not None else recorded_cores
    if indices:
        steps = list(POSTPROCESS_COMMANDS) if analysis else []
        jobs = rerun_jobs(study, scheduler, indices, plan_cores, planned, steps,
                          analysis_tasks)
    return Resubmission(Path(study_dir), tuple(st.cases), tuple(indices), tuple(busy),
                        tuple(jobs), needs)


def rerun_jobs(study: Study, scheduler: Scheduler, indices: Sequence[int], cores: int | None,
               planned: bool, steps: Sequence[str], analysis_tasks: int = 1,
               study_round: int | None = None) -> Sequence[BatchJob]:
    """The scripts that run the cases ``indices`` of a written study (none: the follow-up
    job alone) and then ``steps``: ``planned``, their ranks from the rank plan on at most
    ``cores``; otherwise every case on the site's fixed task count."""
    again = [c for c in study.cases if c.index in set(indices)]
    ranks = None
    if planned and again:
        schedule = submission_schedule([case_load(c.path.name, c.scaled) for c in again],
                                       cores, None)
        ranks = {c.index: schedule.ranks_of(c.path.name) for c in again}
    return scheduler.plan_jobs(study.path, study.name, JobRound(
        tuple(indices), None, ranks, tuple(steps), cores, analysis_tasks,
        _token(analysis_tasks), study_round))


@dataclass(frozen=True)
class SplitAnalysis:
    """A written study's analysis as a scheduler's array of ``tasks`` shares staged under
    ``token`` and the job that merges them: the scripts."""

    study_dir: Path
    token: str
    tasks: int
    jobs: tuple[BatchJob, ...]

    def submit(self, scheduler: Scheduler) -> list[dict]:
        """Submit the array and the merge job after it; the recorded entries."""
        return scheduler.submit(self.study_dir, self.jobs)


def plan_split_analysis(study: Study, scheduler: Scheduler, tasks: int) -> SplitAnalysis:
    """The analysis of ``study`` split into ``tasks`` shares on ``scheduler`` (pure apart
    from drawing a fresh staging token): each array task computes one share (``ligwf
    analyse --part K/N``), the merge job writes the same tables as one analysis."""
    from ligwf.analysis.outputs import new_token

    token = new_token()
    jobs = scheduler.plan_jobs(study.path, study.path.name, JobRound(
        post_steps=("analyse",), analysis_tasks=tasks, token=token))
    return SplitAnalysis(study.path, token, tasks, tuple(jobs))

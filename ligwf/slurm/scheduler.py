"""Slurm as a :class:`ligwf.scheduler.Scheduler`: the pure builders of :mod:`ligwf.slurm.script`,
the parsers of :mod:`ligwf.slurm.parse` and the study-folder I/O of :mod:`ligwf.slurm.jobs`
behind the operations the pipeline asks of a scheduler (script building, submit, status,
cancel) and of any executor (run cases and wait for them), with the site settings
(:class:`ligwf.slurm.site.SlurmSite`) it builds the scripts from."""

from __future__ import annotations

import threading
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, ClassVar, Sequence

from ligwf.engine.plan import allocation_schedule, case_load
from ligwf.errors import SubmitError
from ligwf.eligibility import eligible
from ligwf.scheduler import JobRound, wait_for
from ligwf.slurm.jobs import (PlannedJob, Runner, StudyStatus, dry_run_text, next_round,
                              plan_analysis_array, plan_jobs, read_record, recorded_plan,
                              require_scheduler, run_command, study_status, submit_jobs)
from ligwf.slurm.parse import FINISHED_STATES
from ligwf.slurm.script import scancel_command
from ligwf.slurm.site import SlurmSite
from ligwf.study import layout


@dataclass(frozen=True)
class SlurmScheduler:
    """Slurm on the site ``site``; ``run`` runs its commands (sbatch, squeue, scontrol,
    scancel), replaced by a recorder in tests."""

    site: SlurmSite
    run: Runner = run_command
    name: ClassVar[str] = "slurm"
    #: seconds between looks at the queue while :meth:`run_cases` waits
    poll_seconds: float = 5.0
    #: looks in a row in which Slurm does not know a job it was given before the wait
    #: gives up on it (a job that ended before the first look, with no accounting)
    forget_polls: int = 3

    def require(self) -> None:
        require_scheduler()

    def plan_jobs(self, study_dir: Path, study_name: str, request: JobRound
                  ) -> list[PlannedJob]:
        return plan_jobs(study_dir, study_name, self.site, request)

    def plan_analysis(self, study_dir: Path, study_name: str, tasks: int, token: str
                      ) -> list[PlannedJob]:
        return plan_analysis_array(study_dir, study_name, self.site, tasks, token)

    def run_cases(self, study, cases: Sequence, monitor=None,
                  stop: threading.Event | None = None) -> bool:
        """Submit ``cases`` as job arrays (ranks from the allocation rank plan, each case
        in an allocation of its own; no follow-up job) and wait until none of them is
        queued or running; whether all of them are done. ``stop`` set: the arrays are
        cancelled (the runners write forced restarts, the cases end ``killed``) and the
        wait goes on until Slurm has ended them. ``monitor`` is not fed: the engines run
        on other nodes (``ligwf slurm status`` shows them)."""
        stop = stop or threading.Event()
        cases = list(cases)
        if not cases:
            return True
        schedule = allocation_schedule([case_load(c.path.name, c.scaled) for c in cases])
        ranks = {c.index: schedule.ranks_of(c.path.name) for c in cases}
        indices = {c.index for c in cases}
        self.require()
        jobs = self.plan_jobs(study.path, study.name, JobRound(
            tuple(indices), self.next_round(study.path), ranks))
        self.submit(study.path, jobs)
        self._wait(study.path, stop,
                   lambda st: any(c.queued for c in st.cases if c.index in indices))
        return eligible(cases).settled

    def _wait(self, study_dir: Path, stop: threading.Event,
              pending: Callable[[StudyStatus], bool]) -> bool:
        """Look at the queue every ``poll_seconds`` while ``pending(status)``; ``stop`` set:
        cancel the study's jobs once and go on waiting until Slurm has ended them.
        Whether it cancelled."""
        return wait_for(lambda: pending(self.status(study_dir)), stop, self.poll_seconds,
                        lambda: self.cancel(study_dir))

    def analyse(self, study, tasks: int = 1,
                stop: threading.Event | None = None) -> dict | None:
        """The study's analysis as a job array of ``tasks`` shares and the merge job after
        it (what ``ligwf analyse --slurm N`` submits), waited for; the merged analysis
        record. ``stop`` set: both jobs are cancelled and None is returned once Slurm has
        ended them. SubmitError when the merge job ends without a record (its log, in
        the study's Slurm log folder, says why: a share that failed is named there with
        the command that re-runs it)."""
        from ligwf.analysis.outputs import new_token
        from ligwf.analysis.records.analysis_record import AnalysisRecord

        stop = stop or threading.Event()
        self.require()
        jobs = self.plan_analysis(study.path, study.name, max(1, tasks), new_token())
        merge = str(self.submit(study.path, jobs)[-1]["job_id"])
        looks: list[str | None] = []         # the merge job's state at each look

        def pending(st: StudyStatus) -> bool:
            entry = next(j for j in st.jobs if str(j["job_id"]) == merge)
            looks.append(entry.get("state"))
            if looks[-1] is not None:
                return bool(entry["active"])
            # unknown to Slurm: waited for until it has been so forget_polls + 1 looks in a row
            return looks[-self.forget_polls - 1:] != [None] * (self.forget_polls + 1)

        if self._wait(study.path, stop, pending):
            return None
        state = looks[-1]
        if state is None or state.split()[0] != "COMPLETED":
            raise SubmitError(f"the analysis merge job {merge} ended "
                              f"{state or 'unknown to Slurm'}: its log in "
                              f"{study.path / layout.SLURM_LOG_DIR} says why")
        record = AnalysisRecord.read(study.analysis_dir)
        return record.data if record is not None else None

    def dry_run_text(self, jobs: Sequence[PlannedJob]) -> str:
        return dry_run_text(jobs)

    def submit(self, study_dir: Path, jobs: Sequence[PlannedJob]) -> list[dict]:
        return submit_jobs(study_dir, jobs, self.site, self.run)

    def status(self, study_dir: Path, tolerant: bool = False) -> StudyStatus:
        return study_status(study_dir, self.run, tolerant=tolerant)

    def cancel(self, study_dir: Path) -> list[str]:
        """``scancel`` every recorded job of the study that still has a queued or running
        task (a whole array at once) and a follow-up job that has not ended; their ids."""
        st = study_status(study_dir, self.run)
        ids = sorted({c.job.split("_")[0] for c in st.cases if c.queued and c.job})
        ids += [str(j["job_id"]) for j in st.jobs
                if j.get("kind") != "array" and j.get("state")
                and j["state"].split()[0] not in FINISHED_STATES]
        for job_id in ids:
            cmd = scancel_command(job_id)
            out = self.run(cmd)
            if out.returncode != 0:
                raise SubmitError(f"{' '.join(cmd)} exited {out.returncode}: "
                                  f"{(out.stderr or out.stdout).strip()}")
        return ids

    def next_round(self, study_dir: Path) -> int:
        return next_round(study_dir)

    def recorded(self, study_dir: Path) -> bool:
        return bool(read_record(study_dir))

    def recorded_plan(self, study_dir: Path) -> dict | None:
        """``{"cores": N or None}`` if the latest array took its ranks from the rank plan."""
        return recorded_plan(study_dir)

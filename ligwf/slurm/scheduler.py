"""Slurm as a :class:`ligwf.scheduler.Scheduler`: the pure builders of :mod:`ligwf.slurm.script`,
the parsers of :mod:`ligwf.slurm.parse` and the study-folder I/O of :mod:`ligwf.slurm.jobs`
behind the job verbs the pipeline asks of a scheduler (plan the scripts, submit, poll the
status, cancel), with the site settings (:class:`ligwf.slurm.site.SlurmSite`) it builds the
scripts from. Running cases and the analysis and waiting for them
(:class:`ligwf.scheduler.SubmitAndWait`) are written once for every scheduler."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import ClassVar, Sequence

from ligwf.errors import SubmitError
from ligwf.scheduler import JobRound, SubmitAndWait
from ligwf.slurm.jobs import (PlannedJob, Runner, StudyStatus, plan_jobs, recorded_plan,
                              require_scheduler, run_command, study_status, submit_jobs)
from ligwf.slurm.parse import FINISHED_STATES
from ligwf.slurm.script import scancel_command
from ligwf.slurm.site import SlurmSite


@dataclass(frozen=True)
class SlurmScheduler(SubmitAndWait):
    """Slurm on the site ``site``; ``run`` runs its commands (sbatch, squeue, scontrol,
    scancel), replaced by a recorder in tests."""

    site: SlurmSite
    run: Runner = run_command
    name: ClassVar[str] = "slurm"
    #: seconds between polls of the queue while :meth:`run_cases` / :meth:`analyse` wait
    poll_seconds: float = 5.0
    #: polls in a row in which Slurm does not know a job it was given before the wait
    #: gives up on it (a job that ended before the first poll, with no accounting)
    forget_polls: int = 3

    def require(self) -> None:
        require_scheduler()

    def plan_jobs(self, study_dir: Path, study_name: str, request: JobRound
                  ) -> list[PlannedJob]:
        return plan_jobs(study_dir, study_name, self.site, request)

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

    def recorded_plan(self, study_dir: Path) -> dict | None:
        """``{"cores": N or None}`` if the latest array took its ranks from the rank plan."""
        return recorded_plan(study_dir)

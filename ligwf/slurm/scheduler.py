"""Slurm as a :class:`ligwf.scheduler.Scheduler`: the pure builders of :mod:`ligwf.slurm.script`,
the parsers of :mod:`ligwf.slurm.parse` and the study-folder I/O of :mod:`ligwf.slurm.jobs`
behind the four operations the pipeline asks of a scheduler (script building, submit,
status, cancel), with the site settings (:class:`ligwf.slurm.site.SlurmSite`) it builds
the scripts from."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import ClassVar, Iterable, Mapping, Sequence

from ligwf.errors import SubmitError
from ligwf.slurm.jobs import (PlannedJob, Runner, StudyStatus, dry_run_text, next_round,
                              plan_jobs, read_record, recorded_plan, require_scheduler,
                              run_command, study_status, submit_jobs)
from ligwf.slurm.parse import FINISHED_STATES
from ligwf.slurm.script import scancel_command
from ligwf.slurm.site import SlurmSite


@dataclass(frozen=True)
class SlurmScheduler:
    """Slurm on the site ``site``; ``run`` runs its commands (sbatch, squeue, scontrol,
    scancel), replaced by a recorder in tests."""

    site: SlurmSite
    run: Runner = run_command
    name: ClassVar[str] = "slurm"

    def require(self) -> None:
        require_scheduler()

    def plan_jobs(self, study_dir: Path, study_name: str, indices: Iterable[int],
                  ranks: Mapping[int, int] | None, post_steps: Sequence[str], round_no: int,
                  plan_cores: int | None = None, analysis_tasks: int = 1,
                  token: str | None = None, study_round: int | None = None
                  ) -> list[PlannedJob]:
        return plan_jobs(study_dir, study_name, self.site, indices, post_steps, round_no, ranks,
                         plan_cores, analysis_tasks, token, study_round)

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

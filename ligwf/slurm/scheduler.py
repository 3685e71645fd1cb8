"""Slurm as a :class:`ligwf.scheduler.Scheduler`: the pure builders of :mod:`ligwf.slurm.script`,
the parsers of :mod:`ligwf.slurm.parse` and the study-folder I/O of :mod:`ligwf.slurm.jobs`
behind the operations the pipeline asks of a scheduler (script building, submit, status,
cancel) and of any executor (run cases and wait for them), with the site settings
(:class:`ligwf.slurm.site.SlurmSite`) it builds the scripts from."""

from __future__ import annotations

import threading
import time
from dataclasses import dataclass
from pathlib import Path
from typing import ClassVar, Iterable, Mapping, Sequence

from ligwf.engine.plan import allocation_schedule, case_load
from ligwf.errors import SubmitError
from ligwf.local import all_done
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
    #: seconds between looks at the queue while :meth:`run_cases` waits
    poll_seconds: float = 5.0

    def require(self) -> None:
        require_scheduler()

    def plan_jobs(self, study_dir: Path, study_name: str, indices: Iterable[int],
                  ranks: Mapping[int, int] | None, post_steps: Sequence[str], round_no: int,
                  plan_cores: int | None = None, analysis_tasks: int = 1,
                  token: str | None = None, study_round: int | None = None
                  ) -> list[PlannedJob]:
        return plan_jobs(study_dir, study_name, self.site, indices, post_steps, round_no, ranks,
                         plan_cores, analysis_tasks, token, study_round)

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
        jobs = self.plan_jobs(study.path, study.name, sorted(indices), ranks, [],
                              self.next_round(study.path))
        self.submit(study.path, jobs)
        cancelled = False
        while True:
            st = self.status(study.path)
            if not any(c.queued for c in st.cases if c.index in indices):
                break
            if stop.is_set() and not cancelled:
                self.cancel(study.path)
                cancelled = True
            time.sleep(self.poll_seconds)
        return all_done(cases)

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

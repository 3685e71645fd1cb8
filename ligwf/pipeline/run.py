"""The run stage of the pipeline: write a prepared study, schedule its cases, run them.

* ``ligwf run`` = :func:`~ligwf.pipeline.prepare.prepare_workflow` + :func:`start_run`
  (write the folders, schedule the cases) + :meth:`StudyRun.run`;
* ``ligwf run-case`` (a Slurm array task) = :func:`run_case_of` on one case of a written
  study, on ``--np`` or the allocation's ``SLURM_NTASKS`` ranks;
* ``ligwf study`` = the same as ``run``, then :func:`ligwf.pipeline.post.postprocess`.

How the cases run: by default the planner (:mod:`ligwf.engine.plan`) gives each case its
ranks and packs the cases onto the cores (:func:`study_schedule`); ``--np`` /
``--ensemble`` override it with their old meaning. What callers choose is only how things
run (ranks, ensembles, cores), never what is computed.
"""

from __future__ import annotations

import os
import signal
import threading
from dataclasses import dataclass
from pathlib import Path
from typing import Sequence

from ligwf.engine.launch import Monitor
from ligwf.engine.plan import Schedule, allocation_schedule, case_load, plan_study
from ligwf.engine.site import EngineConfig, EngineIdentity
from ligwf.errors import ConfigError, LigwfError
from ligwf.eligibility import eligible
from ligwf.executors import LOCAL, build_executor
from ligwf.local import LocalExecutor, RunSettings, study_schedule
from ligwf.pipeline.prepare import Prepared, prepared_loads, write
from ligwf.scheduler import Executor
from ligwf.study.case import CaseFolder
from ligwf.study.extension import extend_production
from ligwf.study.layout import OUTPUT_DIRS
from ligwf.study.paths import check_inside
from ligwf.study.study import Study


class Interrupted(LigwfError):
    """The run was stopped on request (Ctrl-C, SIGTERM): the engines wrote their forced
    restarts and the cases are ``killed`` (the same command resumes them); nothing after
    the run stage may run. ``exit_code`` is the shell's 128 + signal number."""

    def __init__(self, signum: int | None) -> None:
        self.signum = int(signum or signal.SIGINT)
        self.exit_code = 128 + self.signum
        super().__init__(f"interrupted by the user ({signal.Signals(self.signum).name}): "
                         "forced restarts written, cases marked killed; the same command "
                         "resumes them")


def run_study(study: Study, cases: Sequence[CaseFolder], executor: Executor,
              monitor: Monitor | None = None, stop: threading.Event | None = None) -> bool:
    """Run ``cases`` of ``study`` on ``executor`` (this machine: skipping finished ones,
    resuming killed ones, planned or as asked). Returns whether all of them are done.

    A stop on request (``stop`` set; the CLI's signal handler records the signal as
    ``stop.signum``) ends the engines with forced restarts and raises
    :class:`Interrupted`, so nothing after the run stage (analysis, report) runs.
    ConfigError, before any case is touched, when a case folder or its output folders are
    symbolic links or lead outside the study (the runner writes and cleans there)."""
    for case in cases:
        inside = [case.path] if case.path != study.path else []
        check_inside(study.path, inside + [case.path / sub for sub in OUTPUT_DIRS])
    stop = stop or threading.Event()
    done = executor.run_cases(study, cases, monitor, stop)
    if stop.is_set():
        raise Interrupted(getattr(stop, "signum", None))
    return done


@dataclass(frozen=True)
class StudyRun:
    """A written study about to run: its folder, the schedule of the cases still to run
    (what the CLI prints before the engines start), the executor that runs them (this
    machine, with its engine and run settings) and the engine as found (``identity``)."""

    study: Study
    schedule: Schedule
    executor: Executor
    identity: EngineIdentity

    def run(self, monitor: Monitor | None = None, stop: threading.Event | None = None) -> bool:
        """Run every case of the study (:func:`run_study`); whether all of them are done."""
        return run_study(self.study, self.study.cases, self.executor, monitor, stop)


def start_run(prepared: Prepared, out: Path, settings: RunSettings,
              mesh_cache: Path | None = None, replace: bool = False,
              extend_seconds: float = 0.0) -> StudyRun:
    """Write a prepared study (the pre-flight is behind it) and schedule the cases that
    are not finished. The site's engine is found first (executable, its library, version,
    the MPI launcher): one that is missing or cannot be loaded is refused before anything
    is written. ``extend_seconds``: every case's production that much longer than rendered
    (:func:`~ligwf.study.extension.extend_production`; done cases are continued)."""
    _, identity = site_engine()
    study = write(prepared, out, mesh_cache, replace)    # refuses another study's folder
    if extend_seconds > 0 and extend_production(study.cases, extend_seconds):
        study = Study.open(out)                          # the cases with their extensions
    return scheduled(study, build_executor(LOCAL, settings), identity)


def scheduled(study: Study, executor: Executor, identity: EngineIdentity) -> StudyRun:
    """A written study with the schedule of its cases still to run on ``executor``: this
    machine's (:func:`~ligwf.local.study_schedule`, its phases), or on any other executor
    one allocation per case (:func:`~ligwf.engine.plan.allocation_schedule`, what a
    scheduler's ``run_cases`` submits)."""
    if isinstance(executor, LocalExecutor):
        settings = executor.settings
        schedule = study_schedule(eligible(study.cases, settings.retry_unstable).to_run,
                                  settings)
    else:
        schedule = allocation_schedule([case_load(c.path.name, c.scaled)
                                        for c in eligible(study.cases).to_run])
    return StudyRun(study, schedule, executor, identity)


def site_engine() -> tuple[EngineConfig, EngineIdentity]:
    """The site's engine settings and the engine they name, checked: EngineNotFound (or
    ConfigError) when the executable, its library or the MPI launcher is not usable."""
    engine = EngineConfig.from_site()
    engine.mpirun_path()
    return engine, engine.identify()


def run_case_of(study: Study, case: CaseFolder, nprocs: int | None = None,
                retry_unstable: bool = False, monitor: Monitor | None = None,
                stop: threading.Event | None = None) -> bool:
    """Run one case of a written study (what a scheduler's array task does) on ``nprocs``
    ranks, default the allocation's ``SLURM_NTASKS``, else 1. Whether it is done.
    ConfigError (one line, nothing touched) when the case's scene record is not the one
    rendering wrote (its fields or its original block edited since: its run would be
    analysed as a skipped case). An edited input alone is run: the engine's run of it ends
    in its own verdict (failed, unstable), which is what a user who edits it asks for."""
    if (why := case.record_problem(check_hash=False)) is not None:
        raise ConfigError(f"{case.path}: not run: {why}")
    ranks = nprocs or int(os.environ.get("SLURM_NTASKS", "1"))
    site_engine()                   # refused before the case is locked or touched
    executor = build_executor(LOCAL, RunSettings(nprocs=ranks, retry_unstable=retry_unstable))
    return run_study(study, [case], executor, monitor, stop)


def planned_schedule(prepared: Prepared, settings: RunSettings) -> Schedule:
    """The rank plan of every prepared case on ``settings.cores`` cores: what ``ligwf
    run`` / ``study`` do without ``--np`` / ``--ensemble`` (``ligwf check`` prints it)."""
    return plan_study(prepared_loads(prepared), settings.cores)

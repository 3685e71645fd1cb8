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
from contextlib import ExitStack
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Iterable, Sequence

from ligwf.engine.ensemble import run_ensemble
from ligwf.engine.launch import Monitor, run_case, take_over
from ligwf.engine.cores import machine_cores
from ligwf.engine.plan import Phase, Schedule, case_load, override_schedule, plan_study
from ligwf.engine.resume import SKIP, plan_case
from ligwf.engine.site import EngineConfig, EngineIdentity
from ligwf.errors import ConfigError, LigwfError
from ligwf.pipeline.prepare import Prepared, prepared_loads, write
from ligwf.study.case import CaseFolder
from ligwf.study.manifest import DONE, case_busy, case_lock
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


#: Seconds between looks at cases another runner holds (see :func:`run_study`).
WAIT_SECONDS = 1.0


@dataclass(frozen=True)
class RunSettings:
    """How the run stage runs (not what it computes).

    ``nprocs`` None and no ``ensemble``: planned (ranks per case and phases from
    :func:`ligwf.engine.plan.plan_study` on ``cores`` cores); otherwise the override:
    every case on ``nprocs`` ranks (1 if None), one after the other or in one ensemble.
    """

    nprocs: int | None = 1          # MPI ranks per case; None: the planner decides
    ensemble: int = 0               # > 0: all cases in ONE mpirun of this many ranks
    retry_unstable: bool = False
    template_dirs: tuple[Path, ...] = ()
    cores: int = 1                  # cores a planned run fills
    cores_source: str = "given"     # where ``cores`` came from (engine.cores.available_cores)

    @property
    def planned(self) -> bool:
        return self.nprocs is None and not self.ensemble


def run_settings(nprocs: int | None = None, ensemble: int = 0, cores: int | None = None,
                 retry_unstable: bool = False,
                 template_dirs: Iterable[Path] = ()) -> RunSettings:
    """How ``ligwf run`` / ``study`` run: planned on the cores of this machine or
    allocation (``cores`` to say otherwise, :func:`ligwf.engine.cores.machine_cores`) unless
    ``nprocs`` or ``ensemble`` is given (``ensemble`` alone keeps groups of one rank)."""
    count, source = machine_cores(cores)
    if nprocs is None and ensemble:
        nprocs = 1
    return RunSettings(nprocs=nprocs, ensemble=ensemble, retry_unstable=retry_unstable,
                       template_dirs=tuple(template_dirs), cores=count, cores_source=source)


def all_done(cases: Iterable[CaseFolder]) -> bool:
    """Whether every case's manifest says done."""
    return all((m := c.manifest()) is not None and m.status == DONE for c in cases)


def cases_to_run(cases: Iterable[CaseFolder], retry_unstable: bool = False) -> list[CaseFolder]:
    """The cases a runner would start or resume now (not done, not unstable unless
    ``retry_unstable``, not held by a live runner)."""
    return [c for c in cases if plan_case(c, retry_unstable).action != SKIP]


def study_schedule(cases: Sequence[CaseFolder], settings: RunSettings) -> Schedule:
    """What :func:`run_study` does with ``cases`` (pass :func:`cases_to_run`): the planned
    schedule, or the one ``--np`` / ``--ensemble`` ask for."""
    loads = [case_load(c.path.name, c.scaled) for c in cases]
    if settings.planned:
        return plan_study(loads, settings.cores)
    return override_schedule(loads, settings.nprocs or 1, settings.ensemble, settings.cores)


def run_study(study: Study, cases: Sequence[CaseFolder], engine: EngineConfig,
              settings: RunSettings = RunSettings(), monitor: Monitor | None = None,
              stop: threading.Event | None = None) -> bool:
    """Run ``cases`` of ``study`` (skipping finished ones, resuming killed ones): planned
    (:func:`study_schedule`), one after the other, or as one MPI ensemble. Returns whether
    all of them are done.

    Several runners may work on one study: each case runs in one of them (a per-case
    lock, :func:`ligwf.study.manifest.case_lock`); a runner that has finished its share
    waits for the cases the others hold, so every runner returns once the study is done.
    (An explicit ``--ensemble`` takes no locks, as before.)

    A stop on request (``stop`` set; the CLI's signal handler records the signal as
    ``stop.signum``) ends the engines with forced restarts and raises
    :class:`Interrupted`, so nothing after the run stage (analysis, report) runs."""
    stop = stop or threading.Event()
    done = _run_cases(study, cases, engine, settings, monitor, stop)
    if stop.is_set():
        raise Interrupted(getattr(stop, "signum", None))
    return done


def _run_cases(study: Study, cases: Sequence[CaseFolder], engine: EngineConfig,
               settings: RunSettings, monitor: Monitor | None, stop: threading.Event) -> bool:
    if settings.ensemble:
        run_ensemble(study.path, list(cases), settings.ensemble, settings.nprocs or 1, engine,
                     retry_unstable=settings.retry_unstable, stop=stop, monitor=monitor)
        return all_done(cases)

    def one(case: CaseFolder, nprocs: int) -> None:
        run_case(case, nprocs, engine, monitor, stop, settings.retry_unstable,
                 settings.template_dirs)

    if settings.planned:
        schedule = study_schedule(cases_to_run(cases, settings.retry_unstable), settings)
        # every case's ranks (a case taken over below may not be in this runner's phases)
        ranks = {c.name: c.ranks for c in study_schedule(cases, settings).cases}
        by_name = {c.path.name: c for c in cases}
        for number, phase in enumerate(schedule.phases, 1):
            if stop.is_set():
                break
            members = [by_name[name] for name in phase.cases]
            if phase.ensemble:
                _ensemble_phase(study, members, phase, f"phase{number}-pid{os.getpid()}",
                                engine, settings, monitor, stop, one)
            else:
                for case in members:
                    if stop.is_set():
                        break
                    one(case, phase.ranks)
    else:
        ranks = {}
        for case in cases:
            if stop.is_set():
                break
            one(case, settings.nprocs or 1)
    # cases another `ligwf run` holds: wait for them, and take over any whose runner
    # stops before it is done (its lock goes with it)
    default = settings.nprocs or 1
    busy = [c for c in cases if case_busy(c.path)]
    while busy and not stop.wait(WAIT_SECONDS):
        for case in [c for c in busy if not case_busy(c.path)]:
            one(case, ranks.get(case.path.name, default))
        busy = [c for c in cases if case_busy(c.path)]
    return all_done(cases)


def _ensemble_phase(study: Study, members: list[CaseFolder], phase: Phase, label: str,
                    engine: EngineConfig, settings: RunSettings, monitor: Monitor | None,
                    stop: threading.Event, one: Callable[[CaseFolder, int], None]) -> None:
    """Run a planned phase as one MPI ensemble over the members this runner can lock
    (held for the whole launch, so a second runner leaves them alone); a single lockable
    member runs on its own under mpirun instead."""
    with ExitStack() as held:
        mine = [c for c in members if held.enter_context(case_lock(c.path))]
        for case in mine:
            take_over(case)         # engines and attempts a dead runner left behind
        if len(mine) > 1:
            groups = min(phase.groups, len(mine))
            run_ensemble(study.path, mine, groups * phase.ranks, phase.ranks, engine,
                         retry_unstable=settings.retry_unstable, stop=stop, monitor=monitor,
                         label=label)
            return
    for case in mine:               # lock released: run_case takes it again
        one(case, phase.ranks)


@dataclass(frozen=True)
class StudyRun:
    """A written study about to run: its folder, the schedule of the cases still to run
    (what the CLI prints before the engines start), the engine (as configured and as
    found: ``identity``) and the run settings."""

    study: Study
    schedule: Schedule
    engine: EngineConfig
    settings: RunSettings
    identity: EngineIdentity

    def run(self, monitor: Monitor | None = None, stop: threading.Event | None = None) -> bool:
        """Run every case of the study (:func:`run_study`); whether all of them are done."""
        return run_study(self.study, self.study.cases, self.engine, self.settings, monitor,
                         stop)


def start_run(prepared: Prepared, out: Path, settings: RunSettings,
              mesh_cache: Path | None = None) -> StudyRun:
    """Write a prepared study (the pre-flight is behind it) and schedule the cases that
    are not finished. The site's engine is found first (executable, its library, version,
    the MPI launcher): one that is missing or cannot be loaded is refused before anything
    is written."""
    engine, identity = site_engine()
    study = write(prepared, out, mesh_cache)
    schedule = study_schedule(cases_to_run(study.cases, settings.retry_unstable), settings)
    return StudyRun(study, schedule, engine, settings, identity)


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
    engine, _ = site_engine()       # refused before the case is locked or touched
    return run_study(study, [case], engine,
                     RunSettings(nprocs=ranks, retry_unstable=retry_unstable), monitor, stop)


def planned_schedule(prepared: Prepared, settings: RunSettings) -> Schedule:
    """The rank plan of every prepared case on ``settings.cores`` cores: what ``ligwf
    run`` / ``study`` do without ``--np`` / ``--ensemble`` (``ligwf check`` prints it)."""
    return plan_study(prepared_loads(prepared), settings.cores)

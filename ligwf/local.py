"""This machine (or this allocation) as an :class:`ligwf.scheduler.Executor`: the cases run
here, now, under the engine supervisors of :mod:`ligwf.engine`.

What the run does with the cases is decided by :class:`RunSettings`: by default the rank
planner (:mod:`ligwf.engine.plan`) gives each case its ranks and packs the single-rank
ones side by side into MPI ensembles, phase after phase (:func:`study_schedule`);
``--np`` / ``--ensemble`` override it with their old meaning. Several runners may work on
one study: each case runs in one of them (a per-case lock,
:func:`ligwf.study.manifest.case_lock`); a runner that has finished its share waits for the
cases the others hold and takes over any whose runner stops before it is done, so every
runner returns once the study is done.

The executor's view of a study (:meth:`LocalExecutor.status`) is every case's manifest
beside the runner process that holds it (``pid@host``), the local counterpart of a
scheduler's task; :meth:`LocalExecutor.cancel` sends those runners SIGTERM, which ends
their engines with forced restarts and marks the cases ``killed`` (the same command
resumes them), as ``scancel`` does to an array task.
"""

from __future__ import annotations

import dataclasses
import os
import signal
import subprocess
import sys
import threading
from contextlib import ExitStack
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable, ClassVar, Iterable, Sequence

from ligwf.engine.cores import machine_cores
from ligwf.engine.ensemble import run_ensemble
from ligwf.engine.launch import Monitor, run_case, take_over
from ligwf.engine.plan import CaseLoad, Phase, Schedule, case_load, override_schedule, plan_study
from ligwf.eligibility import eligible
from ligwf.engine.resume import plan_case
from ligwf.engine.site import EngineConfig
from ligwf.study import layout
from ligwf.study.case import CaseFolder
from ligwf.study.manifest import (MISSING, RUNNING, case_busy, case_lock, effective_status,
                                  runner_alive)
from ligwf.scheduler import wait_for
from ligwf.study.study import Study

#: Seconds between looks at cases another runner holds.
WAIT_SECONDS = 1.0
#: set in the environment of a local analysis share: the pid of the ligwf that started it
#: (the share ends when that process does: :func:`end_with_parent`)
SHARE_PARENT_ENV = "LIGWF_SHARE_PARENT"
#: prctl option: a signal this process gets when its parent ends (linux/prctl.h)
_PR_SET_PDEATHSIG = 1


def end_with_parent() -> None:
    """In a local analysis share (``SHARE_PARENT_ENV`` set): have the kernel send this
    process SIGTERM when the ligwf that started it ends, however it ends (a SIGKILLed
    ``ligwf analyse --tasks N`` leaves no share computing for nobody); a parent already
    gone ends it now. Nothing outside a share."""
    parent = os.environ.get(SHARE_PARENT_ENV)
    if parent is None:
        return
    import ctypes
    ctypes.CDLL(None, use_errno=True).prctl(_PR_SET_PDEATHSIG, signal.SIGTERM, 0, 0, 0)
    if str(os.getppid()) != parent:
        os.kill(os.getpid(), signal.SIGTERM)


@dataclass(frozen=True)
class RunSettings:
    """How the cases run here (not what they compute).

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


def study_schedule(cases: Sequence[CaseFolder], settings: RunSettings) -> Schedule:
    """What a run does with ``cases`` (pass :attr:`ligwf.eligibility.Eligible.to_run`): the
    planned schedule, or the one ``--np`` / ``--ensemble`` ask for."""
    loads = [_remaining(case_load(c.path.name, c.scaled), c, settings.retry_unstable)
             for c in cases]
    if settings.planned:
        return plan_study(loads, settings.cores)
    return override_schedule(loads, settings.nprocs or 1, settings.ensemble, settings.cores)


def _remaining(load: CaseLoad, case: CaseFolder, retry_unstable: bool) -> CaseLoad:
    """The load of what is left of a case: a killed or extended case continues from its
    newest own restart (:func:`~ligwf.engine.resume.plan_case`), so the planner prices
    the steps after that restart, not the whole run again."""
    plan = plan_case(case, retry_unstable)
    if plan.restart is None:
        return load
    left = load.steps - plan.restart.step
    return dataclasses.replace(load, steps=left) if 0 < left < load.steps else load


@dataclass(frozen=True)
class LocalCase:
    """One case as this machine sees it: its manifest status (or ``missing``) and, while a
    live runner holds it, that runner (``pid@host``: what a scheduler calls the task)."""

    index: int
    case_id: str
    manifest: str
    runner_pid: int | None = None       # the live runner holding it, on ``runner_host``
    runner_host: str = ""
    reason: str = ""

    @property
    def job(self) -> str | None:
        """The runner as ``pid@host`` (a scheduler's task id), None when none holds it."""
        return None if self.runner_pid is None else f"{self.runner_pid}@{self.runner_host}"

    @property
    def queued(self) -> bool:
        """A live runner has it (it will write its manifest itself)."""
        return self.runner_pid is not None


@dataclass(frozen=True)
class LocalStatus:
    """Every case of a study and the runners that hold some (no scheduler, no jobs)."""

    cases: list[LocalCase]
    jobs: list[dict] = field(default_factory=list)
    scheduler_error: str | None = None


@dataclass(frozen=True)
class LocalExecutor:
    """Runs cases on this machine (see the module docstring); ``engine`` None: the site's
    engine, found and checked on first use."""

    settings: RunSettings = RunSettings()
    engine: EngineConfig | None = None
    name: ClassVar[str] = "local"

    def require(self) -> None:
        """EngineNotFound (or ConfigError) unless the site's engine and its MPI launcher
        are usable: checked before anything is written."""
        self._engine().mpirun_path()

    def _engine(self) -> EngineConfig:
        return self.engine if self.engine is not None else EngineConfig.from_site()

    def run_cases(self, study: Study, cases: Sequence[CaseFolder],
                  monitor: Monitor | None = None,
                  stop: threading.Event | None = None) -> bool:
        """Run ``cases`` of ``study`` now (skipping finished ones, resuming killed ones):
        planned, one after the other, or as one MPI ensemble; returns whether all of them
        are done. ``stop`` set ends the engines with forced restarts (the cases are
        ``killed``, resumable) and returns."""
        stop = stop or threading.Event()
        engine = self._engine()
        settings = self.settings
        if settings.ensemble:
            run_ensemble(study.path, list(cases), settings.ensemble, settings.nprocs or 1,
                         engine, retry_unstable=settings.retry_unstable, stop=stop,
                         monitor=monitor)
            return eligible(cases).settled

        def one(case: CaseFolder, nprocs: int) -> None:
            run_case(case, nprocs, engine, monitor, stop, settings.retry_unstable,
                     settings.template_dirs)

        ranks: dict[str, int] = {}
        if settings.planned:
            schedule = study_schedule(eligible(cases, settings.retry_unstable).to_run,
                                      settings)
            # every case's ranks (a case taken over below may not be in this runner's phases)
            ranks = {c.name: c.ranks for c in study_schedule(cases, settings).cases}
            by_name = {c.path.name: c for c in cases}
            for number, phase in enumerate(schedule.phases, 1):
                if stop.is_set():
                    break
                members = [by_name[name] for name in phase.cases]
                if phase.ensemble:
                    self.ensemble_phase(study, members, phase,
                                         f"phase{number}-pid{os.getpid()}", engine, monitor,
                                         stop, one)
                else:
                    for case in members:
                        if stop.is_set():
                            break
                        one(case, phase.ranks)
        else:
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
        return eligible(cases).settled

    def ensemble_phase(self, study: Study, members: list[CaseFolder], phase: Phase,
                        label: str, engine: EngineConfig, monitor: Monitor | None,
                        stop: threading.Event,
                        one: Callable[[CaseFolder, int], None]) -> None:
        """Run a planned phase as one MPI ensemble over the members this runner can lock
        (held for the whole launch, so a second runner leaves them alone); a single
        lockable member runs on its own under mpirun instead."""
        with ExitStack() as held:
            mine = [c for c in members if held.enter_context(case_lock(c.path))]
            for case in mine:
                take_over(case)         # engines and attempts a dead runner left behind
            if len(mine) > 1:
                groups = min(phase.groups, len(mine))
                run_ensemble(study.path, mine, groups * phase.ranks, phase.ranks, engine,
                             retry_unstable=self.settings.retry_unstable, stop=stop,
                             monitor=monitor, label=label)
                return
        for case in mine:               # lock released: run_case takes it again
            one(case, phase.ranks)

    def analyse(self, study: Study, tasks: int = 1,
                stop: threading.Event | None = None) -> dict | None:
        """The study's analysis (its stored settings) into its analysis folder, here:
        ``tasks`` 1 in this process (frame-parallel when this process runs under mpirun);
        more, as that many processes of this interpreter each computing one share
        (``ligwf analyse --part K/N``), then merged in this one into the same bytes. A share
        that failed is named by the merge with the command that re-runs it; ``stop`` set
        ends the shares (SIGTERM) and returns None with nothing merged."""
        from ligwf.analysis.outputs import new_token
        from ligwf.analysis.runner import AnalysisOptions, analyse, merge_parts

        if tasks <= 1:
            return analyse(study.path, None, AnalysisOptions(), None)
        stop = stop or threading.Event()
        token = new_token()
        logs = study.path / layout.ANALYSIS_SHARE_LOG_DIR
        logs.mkdir(parents=True, exist_ok=True)
        procs = []
        env = {**os.environ, SHARE_PARENT_ENV: str(os.getpid())}
        try:
            for index in range(tasks):
                with open(logs / layout.analysis_share_log(token, index), "wb") as log:
                    procs.append(subprocess.Popen(
                        [sys.executable, "-m", "ligwf", "analyse", str(study.path), "--part",
                         f"{index}/{tasks}", "--token", token],
                        stdout=log, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL,
                        env=env))
            if wait_for(lambda: any(p.poll() is None for p in procs), stop, WAIT_SECONDS):
                return None
        finally:            # stopped, or an error here: no share computes on for nobody
            for p in procs:
                if p.poll() is None:
                    p.terminate()
            for p in procs:
                p.wait()
        return merge_parts(study.path, token, tasks, None, AnalysisOptions(),
                           rerun=f"{sys.executable} -m ligwf analyse {study.path} "
                                 f"--part {{index}}/{tasks} --token {token}")

    def status(self, study_dir: Path, tolerant: bool = False) -> LocalStatus:
        """Every case's manifest status beside the live runner holding it (if any)."""
        rows = []
        for c in Study.open(study_dir).cases:
            m = c.manifest()
            held = m is not None and m.status == RUNNING and runner_alive(m)
            rows.append(LocalCase(c.index, c.case_id,
                                  effective_status(m) if m is not None else MISSING,
                                  m.pid if held else None, m.host if held else "",
                                  m.reason if m is not None else ""))
        return LocalStatus(rows)

    def cancel(self, study_dir: Path) -> list[str]:
        """SIGTERM every live runner of this host holding a case of the study (its engines
        write forced restarts, its cases end ``killed``); the runners, as ``pid@host``."""
        sent = []
        runners = {(c.runner_pid, c.job) for c in self.status(study_dir).cases if c.queued}
        for pid, job in sorted(runners):
            try:
                os.kill(pid, signal.SIGTERM)
            except ProcessLookupError:
                continue
            sent.append(job)
        return sent

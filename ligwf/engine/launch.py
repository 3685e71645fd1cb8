"""Launch: run one case folder with the real engine under ``mpirun`` and watch it live.

The engine writes stdout+stderr straight into ``run.log`` in the case folder (no pipe for
ligwf to drain, so monitoring cannot stall the engine); ligwf tails that file every
``poll_seconds`` to update the progress display and to check health while it runs. A run
that turns unstable (nan, atom loss, energy blow-up) is stopped early: its outputs would
never be used.

Stopping is graceful: SIGTERM goes to the engine ranks (the children of ``mpirun``), not to
``mpirun`` itself -- ``mpirun`` would kill the ranks before LIGGGHTS writes its forced
restart ``restart_forced_liggghts_<step>.data`` (observed with OpenMPI 4.1).
"""

from __future__ import annotations

import os
import signal
import subprocess
import threading
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Protocol, Sequence

from ligwf.engine.attempt import begin_attempt, finish_attempt, restart_unreadable
from ligwf.engine.health import KILLED, atom_loss, kinetic_energy_blowup, log_errors, non_finite
from ligwf.engine.render import grid_vars
from ligwf.engine.resume import FRESH, RESUME, SKIP, Plan, discard_restart, input_for, plan_case
from ligwf.engine.site import EngineConfig
from ligwf.engine.thermo import LogTail, ThermoParser
from ligwf.study.case import CaseFolder
from ligwf.study.layout import SCREEN_FILE
from ligwf.study.manifest import Manifest

#: Seconds a stopped engine gets to write its forced restart before it is killed.
STOP_GRACE_SECONDS = 60.0


class Monitor(Protocol):
    """Receives live progress of the cases a runner works on (local runs and ensembles
    alike; :class:`ligwf.engine.progress.RichMonitor` draws it)."""

    def start(self, case_id: str, total_steps: int, from_step: int) -> None: ...
    def update(self, case_id: str, parser: ThermoParser) -> None: ...
    def end(self, case_id: str, manifest: Manifest | None, plan: Plan) -> None: ...


class NullMonitor:
    """A :class:`Monitor` that shows nothing (library use, tests, batch jobs)."""

    def start(self, case_id: str, total_steps: int, from_step: int) -> None:
        pass

    def update(self, case_id: str, parser: ThermoParser) -> None:
        pass

    def end(self, case_id: str, manifest: Manifest | None, plan: Plan) -> None:
        pass


@dataclass(frozen=True)
class LaunchResult:
    """How the engine process ended: exit code, wall seconds, whether ligwf stopped it."""

    exit_code: int | None
    wall_seconds: float
    killed: bool
    stopped_unstable: bool = False


def descendants(pid: int) -> list[int]:
    """Process ids below ``pid`` (children first), from /proc."""
    out: list[int] = []
    todo = [pid]
    while todo:
        p = todo.pop()
        try:
            tasks = os.listdir(f"/proc/{p}/task")
        except OSError:
            continue
        for t in tasks:
            try:
                with open(f"/proc/{p}/task/{t}/children") as fh:
                    kids = [int(x) for x in fh.read().split()]
            except OSError:
                continue
            out += kids
            todo += kids
    return out


def signal_engine(proc: subprocess.Popen, sig: int = signal.SIGTERM) -> None:
    """Send ``sig`` to the engine ranks below the launcher (or the launcher if none)."""
    kids = descendants(proc.pid)
    for pid in kids or [proc.pid]:
        try:
            os.kill(pid, sig)
        except ProcessLookupError:
            pass


def live_problem(parser: ThermoParser, particle_count: int | None = None) -> str | None:
    """A reason to stop a run now: an ERROR line, nan, atom loss (below ``particle_count``,
    see :func:`ligwf.engine.health.atom_loss`) or energy blow-up."""
    issues = (log_errors(parser.lines[-200:]) + non_finite(parser.rows[-50:])
              + atom_loss(parser.rows, particle_count) + kinetic_energy_blowup(parser.rows))
    issues = [i for i in issues if i.kind != "error"]  # errors end the engine by themselves
    return issues[0].message if issues else None


def launch(case_dir: Path, input_name: str, nprocs: int, engine: EngineConfig,
           case_id: str = "", monitor: Monitor | None = None,
           stop: threading.Event | None = None, poll_seconds: float = 0.5,
           stop_unstable: bool = True, particle_count: int | None = None,
           engine_args: Sequence[str] = ()) -> LaunchResult:
    """Run ``input_name`` in ``case_dir`` on ``nprocs`` ranks; stdout+stderr -> run.log.
    ``particle_count``: the count the scene asks for (the live atom-loss test needs it);
    ``engine_args``: further LIGGGHTS arguments (the processor grid)."""
    case_dir = Path(case_dir)
    cmd = engine.command(input_name, nprocs, extra=engine_args)
    screen = case_dir / SCREEN_FILE
    parser, tail = ThermoParser(), LogTail(screen)
    t0 = time.monotonic()
    with open(screen, "wb") as out:
        proc = subprocess.Popen(cmd, cwd=case_dir, stdout=out, stderr=subprocess.STDOUT,
                                stdin=subprocess.DEVNULL, start_new_session=True)
    killed = unstable = False
    stop_sent_at: float | None = None
    # a thread blocks in waitpid; this one sleeps on an event between polls. (Popen.wait
    # with a timeout polls waitpid with backoff, ~30 wake-ups a second, each of which
    # preempts one of the busy-polling MPI ranks on a fully used machine.)
    ended = threading.Event()
    threading.Thread(target=lambda: (proc.wait(), ended.set()), daemon=True,
                     name=f"wait-{case_id or proc.pid}").start()
    try:
        while not ended.wait(poll_seconds):
            for line in tail.read_lines():
                parser.feed(line)
            if monitor is not None:
                monitor.update(case_id, parser)
            if stop_sent_at is None:
                problem = live_problem(parser, particle_count) if stop_unstable else None
                if problem or (stop is not None and stop.is_set()):
                    unstable = bool(problem)
                    killed = not unstable
                    signal_engine(proc)
                    stop_sent_at = time.monotonic()
            elif time.monotonic() - stop_sent_at > STOP_GRACE_SECONDS:
                os.killpg(proc.pid, signal.SIGKILL)
    except BaseException:
        # ligwf itself is going down: never leave an orphaned engine behind
        if proc.poll() is None:
            signal_engine(proc)
            try:
                proc.wait(timeout=STOP_GRACE_SECONDS)
            except subprocess.TimeoutExpired:
                os.killpg(proc.pid, signal.SIGKILL)
        raise
    for line in tail.flush():
        parser.feed(line)
    if monitor is not None:
        monitor.update(case_id, parser)
    return LaunchResult(proc.returncode, time.monotonic() - t0, killed, unstable)


def run_case(case: CaseFolder, nprocs: int, engine: EngineConfig, monitor: Monitor | None = None,
             stop: threading.Event | None = None, retry_unstable: bool = False,
             template_dirs=(), poll_seconds: float = 0.5) -> Manifest | None:
    """Plan, launch and record one case (skip, fresh run or resume). Returns the manifest,
    or None when the case was skipped."""
    monitor = monitor or NullMonitor()
    plan = plan_case(case, retry_unstable)
    case_id = case.path.name
    if plan.action == SKIP:
        monitor.end(case_id, None, plan)
        return None
    grid = grid_vars(case.scaled, nprocs)
    while True:
        cmd = engine.command(input_for(plan), nprocs, extra=grid)
        manifest, attempt = begin_attempt(case, plan, nprocs, "mpirun", cmd, template_dirs)
        monitor.start(case_id, manifest.total_steps, attempt.from_step)
        result = launch(case.path, attempt.input, nprocs, engine, case_id, monitor, stop,
                        poll_seconds, particle_count=case.scaled.particle_count,
                        engine_args=grid)
        manifest = finish_attempt(case, manifest, attempt, result.exit_code,
                                  result.wall_seconds, killed=result.killed)
        if restart_unreadable(manifest, attempt) and plan.restart is not None:
            # a restart cut short by SIGKILL: set it aside and try the next one (or afresh)
            discard_restart(case.path, plan.restart)
            manifest.status = KILLED
            case.write_manifest(manifest)
            plan = plan_case(case, retry_unstable)
            if plan.action in (FRESH, RESUME):
                continue
        monitor.end(case_id, manifest, plan)
        return manifest

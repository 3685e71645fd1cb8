"""Launch: run one case folder with the real engine under ``mpirun`` and watch it live.

The engine writes stdout+stderr straight into ``run.log`` in the case folder (no pipe for
ligwf to drain, so monitoring cannot stall the engine); ligwf tails that file every
``poll_seconds`` to update the progress display and to check health while it runs. A run
that turns unstable (nan, atom loss, energy blow-up: the rule of the final assessment,
over the rows of every attempt) is stopped early: its outputs would never be used.

Stopping is graceful: SIGTERM goes to the engine ranks (the children of ``mpirun``), so
LIGGGHTS writes its forced restart ``restart_forced_liggghts_<step>.data``. The engine dies
with its runner (a watchdog, :func:`ligwf.engine.guard.watch`), and one runner at a time
works on a case (:func:`ligwf.study.manifest.case_lock`); engines a dead runner left
behind are stopped and the lost attempt recorded from its screen before the case resumes.
"""

from __future__ import annotations

import os
import signal
import subprocess
import threading
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Protocol, Sequence

from ligwf.engine.dump_hasher import DumpHasher
from ligwf.engine.attempt import (begin_attempt, close_lost_attempt, expectation,
                                  finish_attempt, history, merge_rows, restart_unreadable,
                                  stamp_restarts)
from ligwf.engine.restart_id import SETTLE_SECONDS, CaseIdentity, stamp
from ligwf.engine.guard import (STOP_GRACE_SECONDS, descendants, engine_env, engine_tree,
                                live_engines, release, stop_engines, watch)
from ligwf.engine.health import Expectation, physics_issues
from ligwf.engine.render import grid_vars
from ligwf.engine.resume import (FRESH, RESUME, SKIP, NextAttempt, Why, discard_restart,
                                 input_for, plan_case)
from ligwf.engine.site import EngineConfig
from ligwf.engine.thermo import LogTail, ThermoParser
from ligwf.fsio import NOT_WRITABLE, FolderNotWritable, not_writable
from ligwf.study.case import CaseFolder
from ligwf.study.layout import POST_DIR, SCREEN_FILE
from ligwf.study.manifest import KILLED, RUNNING, Manifest, Stop, case_lock, runner_alive
from ligwf.study.processes import EngineProcess
from ligwf.study.thermo_table import ThermoRow

class Monitor(Protocol):
    """Receives live progress of the cases a runner works on (local runs and ensembles
    alike; :class:`ligwf.engine.progress.RichMonitor` draws it)."""

    def start(self, case_id: str, total_steps: int, from_step: int) -> None: ...
    def update(self, case_id: str, parser: ThermoParser) -> None: ...
    def end(self, case_id: str, manifest: Manifest | None, plan: NextAttempt) -> None: ...


class NullMonitor:
    """A :class:`Monitor` that shows nothing (library use, tests, batch jobs)."""

    def start(self, case_id: str, total_steps: int, from_step: int) -> None:
        pass

    def update(self, case_id: str, parser: ThermoParser) -> None:
        pass

    def end(self, case_id: str, manifest: Manifest | None, plan: NextAttempt) -> None:
        pass


@dataclass(frozen=True)
class LaunchResult:
    """How the engine process ended: exit code, wall seconds, whether ligwf stopped it
    (``killed``: on request; ``problem``: the live check's reason, None if it did not)."""

    exit_code: int | None
    wall_seconds: float
    killed: bool
    problem: str | None = None


def signal_engine(proc: subprocess.Popen, sig: int = signal.SIGTERM) -> None:
    """Send ``sig`` to the engine ranks below the launcher (or the launcher if none)."""
    kids = descendants(proc.pid)
    for pid in kids or [proc.pid]:
        try:
            os.kill(pid, sig)
        except ProcessLookupError:
            pass


def stop_engine(proc: subprocess.Popen) -> None:
    """ligwf itself is going down: ask the engine ranks to write their restarts and stop
    (:func:`signal_engine`), and kill the launcher's process group after
    ``STOP_GRACE_SECONDS``, so no orphaned engine is left behind (local and ensemble runs)."""
    if proc.poll() is None:
        signal_engine(proc)
        try:
            proc.wait(timeout=STOP_GRACE_SECONDS)
        except subprocess.TimeoutExpired:
            os.killpg(proc.pid, signal.SIGKILL)


def live_problem(rows: Sequence[ThermoRow], expect: Expectation | None) -> str | None:
    """A reason to stop a run now: nan, atom loss or energy blow-up in the case's rows
    (earlier attempts included), by the rule of the final assessment."""
    issues = physics_issues(rows, expect)
    return issues[0].message if issues else None


def interrupted_reason(stop: threading.Event | None, steps_done: int, total_steps: int) -> str:
    """The reason of an attempt the user (or the scheduler) stopped: the stop event may
    carry the signal (``stop.signum``, set by the CLI's handler)."""
    sig = getattr(stop, "signum", None)
    name = f" ({signal.Signals(sig).name})" if sig else ""
    return f"interrupted by the user{name} at step {steps_done} of {total_steps}"


def launch(case_dir: Path, command: Sequence[str], case_id: str = "",
           monitor: Monitor | None = None, stop: threading.Event | None = None,
           poll_seconds: float = 0.5,
           judge: Callable[[ThermoParser], str | None] | None = None,
           on_engine: Callable[[list[EngineProcess]], None] | None = None,
           tick: Callable[[], None] | None = None) -> LaunchResult:
    """Run ``command`` in ``case_dir``; stdout+stderr -> run.log. ``judge``: the live
    health check (a reason to stop, or None); ``on_engine``: told the engine's processes
    once its ranks are up (the manifest records them); ``tick``: called every poll (the
    runner stamps new restarts)."""
    case_dir = Path(case_dir)
    screen = case_dir / SCREEN_FILE
    parser, tail = ThermoParser(), LogTail(screen)
    t0 = time.monotonic()
    with open(screen, "wb") as out:
        proc = subprocess.Popen(list(command), cwd=case_dir, stdout=out,
                                stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL,
                                env=engine_env(), start_new_session=True)
    watchdog = watch(proc, [case_dir])
    killed, problem, recorded = False, None, False
    stop_sent_at: float | None = None
    # a thread blocks in waitpid; this one sleeps on an event between polls. (Popen.wait
    # with a timeout polls waitpid with backoff, ~30 wake-ups a second, each of which
    # preempts one of the busy-polling MPI ranks on a fully used machine.)
    ended = threading.Event()
    threading.Thread(target=lambda: (proc.wait(), ended.set()), daemon=True,
                     name=f"wait-{case_id or proc.pid}").start()
    try:
        while not ended.wait(poll_seconds):
            if not recorded and on_engine is not None and descendants(proc.pid):
                on_engine(engine_tree(proc.pid))
                recorded = True
            for line in tail.read_lines():
                parser.feed(line)
            if monitor is not None:
                monitor.update(case_id, parser)
            if tick is not None:
                tick()
            if stop_sent_at is None:
                problem = judge(parser) if judge is not None else None
                if problem or (stop is not None and stop.is_set()):
                    killed = not problem
                    signal_engine(proc)
                    stop_sent_at = time.monotonic()
            elif time.monotonic() - stop_sent_at > STOP_GRACE_SECONDS:
                os.killpg(proc.pid, signal.SIGKILL)
    except BaseException:
        stop_engine(proc)   # ligwf itself is going down: never leave an orphaned engine behind
        raise
    finally:
        release(watchdog)
    for line in tail.flush():
        parser.feed(line)
    if monitor is not None:
        monitor.update(case_id, parser)
    return LaunchResult(proc.returncode, time.monotonic() - t0, killed, problem)


def take_over(case: CaseFolder) -> None:
    """Before a runner works on a case it holds the lock of: stop engines a dead runner
    left behind (forced restart written) and record that runner's lost attempt from its
    screen, so no rows and no wall time are lost."""
    m = case.manifest()
    if m is not None and runner_alive(m):
        return  # an ensemble worker (it takes no case lock): plan_case skips the case
    orphans = live_engines(case.path, m.engine_processes() if m else [])
    if orphans:
        asked = time.time()
        stop_engines(orphans)
        if m is not None and m.attempts:
            # what the orphans wrote once told to stop is theirs (a file dropped in
            # earlier is not stamped here; the dead runner's watchdog may stamp the rest)
            stamp(case.path, CaseIdentity.of(case), m.attempts[-1].number, asked)
        m = case.manifest()        # the stopped engine may have recorded its attempt
    if m is not None and m.status == RUNNING and m.attempts and not runner_alive(m):
        close_lost_attempt(case, m)


def run_case(case: CaseFolder, nprocs: int, engine: EngineConfig, monitor: Monitor | None = None,
             stop: threading.Event | None = None, retry_unstable: bool = False,
             template_dirs=(), poll_seconds: float = 0.5) -> Manifest | None:
    """Plan, launch and record one case (skip, fresh run or resume). Returns the manifest,
    or None when the case was skipped (done, unstable, or held by another runner).
    FolderNotWritable when the case folder is full or read-only."""
    monitor = monitor or NullMonitor()
    case_id = case.path.name
    try:
        with case_lock(case.path) as mine:
            if not mine:
                monitor.end(case_id, None, NextAttempt(SKIP, "running in another ligwf process",
                                                     why=Why.HELD))
                return None
            take_over(case)
            manifest = _run_locked(case, nprocs, engine, monitor, stop, retry_unstable,
                                   template_dirs, poll_seconds)
    except OSError as exc:
        if exc.errno in NOT_WRITABLE:   # e.g. removing old outputs on a read-only mount
            raise not_writable(exc, case.path) from exc
        raise
    if manifest is not None and manifest.stop is Stop.DISK_FULL:
        raise FolderNotWritable(f"{case.path}: {manifest.reason}")
    return manifest


def _run_locked(case: CaseFolder, nprocs: int, engine: EngineConfig, monitor: Monitor,
                stop: threading.Event | None, retry_unstable: bool, template_dirs,
                poll_seconds: float) -> Manifest | None:
    case_id = case.path.name
    plan = plan_case(case, retry_unstable)
    if plan.action == SKIP:
        monitor.end(case_id, None, plan)
        return None
    grid = grid_vars(case.scaled, nprocs)
    expect = expectation(case.scaled)
    identity = engine.identify()
    while True:
        cmd = engine.command(input_for(plan), nprocs, extra=grid)
        manifest, attempt = begin_attempt(case, plan, nprocs, "mpirun", cmd, template_dirs,
                                          identity)
        monitor.start(case_id, manifest.total_steps, attempt.from_step)
        before = history(case, manifest, attempt)

        def judge(parser: ThermoParser) -> str | None:
            return live_problem(merge_rows(before, parser.rows, attempt.from_step,
                                           case.scaled.numerics.dt), expect)

        def record(procs: list[EngineProcess]) -> None:
            manifest.engine = [p.to_dict() for p in procs]
            case.write_manifest(manifest)

        with DumpHasher(case.path / POST_DIR) as hasher:   # the done record hashes the rest
            result = launch(case.path, cmd, case_id, monitor, stop, poll_seconds, judge,
                            record, tick=lambda: stamp_restarts(case, attempt, SETTLE_SECONDS))
        manifest = finish_attempt(case, manifest, attempt, result.exit_code,
                                  result.wall_seconds, killed=result.killed,
                                  stop_problem=result.problem, digests=hasher.digests)
        if result.killed and manifest.status == KILLED:
            manifest.reason = interrupted_reason(stop, manifest.steps_done,
                                                 manifest.total_steps)
            manifest.stop = Stop.INTERRUPTED
            attempt.reason = manifest.reason
            case.write_manifest(manifest)
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

"""MPI ensembles: all cases and replicas inside one ``mpirun -np P``, supervised.

``run_ensemble`` starts ``mpirun -np P python -m ligwf.engine.ensemble_worker`` (see there: rank
groups, ctypes engine, dynamic claims) and watches it from outside MPI. An error inside
the LIGGGHTS library MPI_Aborts (or exits) the whole job, killing the other groups'
members mid-run. The supervisor is what makes that survivable:

* members that finished before the abort already have their manifest (written by their
  group leader) and ``claims/<i>.done``: nothing is lost;
* a member in flight whose screen carries an ``ERROR`` line is the culprit: it is recorded
  ``failed`` with that line (an unreadable restart is set aside instead, and the member
  resumes from an older one);
* the other members -- in flight, or stopped by ``mpirun``'s SIGTERM after a rank died
  (they write a forced restart, :mod:`ligwf.engine.ensemble_worker`) -- are ``killed``
  with their attempt recorded from its screen (steps, wall time), and the supervisor
  launches a new ``mpirun`` for the remaining work, where they continue from their newest
  own restart (:mod:`ligwf.engine.resume`, :mod:`ligwf.engine.restart_id`).

Ranks that outlive a killed ``mpirun`` are stopped (SIGTERM, then SIGKILL once their
attempt is recorded) before anything is settled. A stop on request (Ctrl-C, SIGTERM of
ligwf) ends every member ``killed``, "interrupted by the user", forced restarts written.
The supervisor stamps the members' new restarts with their identity while they run. A
member that finds its folder full stops the launch: FolderNotWritable, the others
resumable. A launch in which no member makes progress (no step gained, none finished)
marks its members ``failed`` with the launcher's output, so the loop always ends.
"""

from __future__ import annotations

import json
import os
import shutil
import signal
import socket
import subprocess
import sys
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path

from ligwf.engine.attempt import finish_attempt, restart_unreadable, stamp_restarts
from ligwf.engine.health import log_errors
from ligwf.engine.guard import RANK_NAMES, engine_env, engine_tree, release, watch
from ligwf.engine.launch import (Monitor, NullMonitor, interrupted_reason, signal_engine,
                                 stop_engine, take_over)
from ligwf.engine.restart_id import SETTLE_SECONDS
from ligwf.engine.resume import SKIP, RestartFile, discard_restart, plan_case
from ligwf.engine.site import EngineConfig, EngineIdentity
from ligwf.engine.thermo import LogTail, ThermoParser
from ligwf.errors import SimulationFailed
from ligwf.fsio import FolderNotWritable, atomic_write_json
from ligwf.study import layout
from ligwf.study.case import CaseFolder
from ligwf.study.manifest import FAILED, KILLED, Manifest, Stop, overwrite_manifest
from ligwf.study.processes import EngineProcess, process



def worker_command(engine: EngineConfig, nprocs: int, ens_dir: Path, group_size: int) -> list[str]:
    """``mpirun -np P <python> -m ligwf.engine.ensemble_worker ENS_DIR --group-size K``."""
    return engine.mpirun_prefix(nprocs) + [sys.executable, "-m", "ligwf.engine.ensemble_worker",
                                           str(ens_dir), "--group-size", str(group_size)]


def _claims(ens_dir: Path) -> dict[int, dict]:
    out = {}
    for p in (ens_dir / layout.ENSEMBLE_CLAIMS_DIR).glob(layout.ENSEMBLE_CLAIM_GLOB):
        try:
            out[int(p.stem)] = json.loads(p.read_text())
        except (ValueError, json.JSONDecodeError):
            pass  # being written right now; seen on the next poll
    return out


def _done(ens_dir: Path, pos: int) -> bool:
    return (ens_dir / layout.ENSEMBLE_CLAIMS_DIR / layout.ensemble_claim_done(pos)).exists()


def _settle_in_flight(case: CaseFolder, exit_code: int | None) -> Manifest | None:
    """Record a member that was running when the job ended, from its screen: the culprit
    (its screen has an ERROR line) is judged as usual; any other was stopped with the job
    and is ``killed`` (resumable), its attempt kept with the steps and wall time it ran."""
    m = case.manifest()
    if m is None or not m.attempts or m.attempts[-1].ended is not None:
        return m
    attempt = m.attempts[-1]
    screen = case.path / attempt.screen
    lines = screen.read_text(errors="replace").splitlines() if screen.exists() else []
    wall = max(0.0, (screen.stat().st_mtime if screen.exists() else time.time())
               - attempt.started_at)
    if log_errors(lines):
        m = finish_attempt(case, m, attempt, exit_code, wall)
        if restart_unreadable(m, attempt) and attempt.from_restart:
            # the engine could not read the restart (and its error aborted the job): set
            # it aside; the next launch resumes from an older one
            discard_restart(case.path, RestartFile(attempt.from_restart, attempt.from_step))
            m.status = KILLED
            m.reason = f"restart {attempt.from_restart} unreadable ({m.reason}); set aside"
            m.stop = Stop.RESTART_SET_ASIDE
            _record(case, m)
        return m
    return finish_attempt(case, m, attempt, None, wall, killed=True)


def _record(case: CaseFolder, m: Manifest) -> None:
    """Write a member's manifest; in place when a full disk leaves no room for the atomic
    copy (the reason then says so)."""
    try:
        case.write_manifest(m)
    except FolderNotWritable:
        overwrite_manifest(case.path, m)


def _job_end(launch_log: str, exit_code: int | None) -> str:
    """How the job ended, in words (mpirun's notice about a rank, else the exit code)."""
    for line in launch_log.splitlines():
        if "exited on signal" in line:
            return line.strip()
    return f"mpirun exit code {exit_code}"


def _stop_leftovers(ranks: list[EngineProcess], ens_dir: Path, grace: float = 20.0) -> None:
    """Ranks still running after ``mpirun`` ended (it was killed): SIGTERM (forced
    restart, the rank records its attempt and marks its claim done), then SIGKILL once
    their claims are done or after ``grace`` seconds (MPI_Finalize without mpirun would
    wait forever)."""
    alive = [r for r in ranks if r.alive()]
    if not alive:
        return
    for r in alive:
        try:
            os.kill(r.pid, signal.SIGTERM)
        except ProcessLookupError:
            pass
    deadline = time.monotonic() + grace
    while time.monotonic() < deadline:
        busy = {c.get("pid") for pos, c in _claims(ens_dir).items() if not _done(ens_dir, pos)}
        alive = [r for r in alive if r.alive()]
        if not alive or not any(r.pid in busy for r in alive):
            break
        time.sleep(0.2)
    for r in alive:
        if r.alive():
            try:
                os.kill(r.pid, signal.SIGKILL)
            except ProcessLookupError:
                pass
    t = time.monotonic()
    while any(r.alive() for r in alive) and time.monotonic() - t < 5:
        time.sleep(0.1)


def _key(case: CaseFolder) -> str:
    """How the queue and the claims name a case: its resolved folder."""
    return str(case.path.resolve())


@dataclass
class Launch:
    """One ``mpirun`` of an ensemble: its folder, the process, when it started, each
    member's steps before it, the ranks seen under it, and the claims whose end the
    monitor has been told (``shown``)."""

    ens_dir: Path
    proc: subprocess.Popen
    started: float
    before: dict[str, int]
    ranks: dict[int, EngineProcess] = field(default_factory=dict)
    shown: set[int] = field(default_factory=set)


def launch(ens_dir: Path, todo: list[CaseFolder], engine: EngineConfig, nprocs: int,
           group_size: int, retry_unstable: bool, runner: dict,
           identity: EngineIdentity) -> Launch:
    """Start one ``mpirun`` over the queue of ``todo`` in a fresh ``ens_dir`` (its queue
    names the members, the runner that supervises them and the engine library)."""
    if ens_dir.exists():
        shutil.rmtree(ens_dir)
    (ens_dir / layout.ENSEMBLE_CLAIMS_DIR).mkdir(parents=True)
    atomic_write_json(ens_dir / layout.ENSEMBLE_QUEUE, {"cases": [_key(c) for c in todo],
                                                        "retry_unstable": retry_unstable,
                                                        "runner": runner,
                                                        "engine": identity.to_dict()})
    before = {_key(c): (c.manifest().steps_done if c.manifest() else 0) for c in todo}
    cmd = worker_command(engine, nprocs, ens_dir, group_size)
    started = time.time()
    with open(ens_dir / layout.ENSEMBLE_LOG, "wb") as out:
        proc = subprocess.Popen(cmd, stdout=out, stderr=subprocess.STDOUT,
                                stdin=subprocess.DEVNULL, env=engine_env(),
                                start_new_session=True)
    return Launch(ens_dir, proc, started, before)


def poll(job: Launch, by_key: dict[str, CaseFolder], monitor: Monitor,
         stop: threading.Event, outcome: dict[str, str], poll_seconds: float = 0.5) -> None:
    """Watch a launch until ``mpirun`` ends: the members' screens to the monitor, their new
    restarts stamped, each finished member's status into ``outcome``; ``stop`` set: the job
    gets SIGTERM once (forced restarts). A watchdog stops the job if this runner dies; ligwf
    going down stops it first. Ranks that outlive ``mpirun`` are stopped afterwards."""
    tails: dict[int, tuple[LogTail, ThermoParser]] = {}
    ended: set[int] = set()
    proc, ens_dir = job.proc, job.ens_dir
    watchdog = watch(proc, [ens_dir])   # stops the job if this runner dies
    stop_sent = False
    try:
        while True:
            finished = proc.poll() is not None
            if not finished:
                for p in engine_tree(proc.pid):
                    if p.name in RANK_NAMES:
                        job.ranks.setdefault(p.pid, p)
            for pos, claim in _claims(ens_dir).items():
                case = by_key[claim["case"]]
                name = case.path.name
                m = case.manifest()
                if pos not in tails:
                    if m is None or not m.attempts:
                        continue
                    tails[pos] = (LogTail(case.screen), ThermoParser())
                    monitor.start(name, m.total_steps, m.attempts[-1].from_step)
                tail, parser = tails[pos]
                for line in tail.read_lines():
                    parser.feed(line)
                monitor.update(name, parser)
                if m is not None and m.attempts and m.attempts[-1].ended is None:
                    stamp_restarts(case, m.attempts[-1], SETTLE_SECONDS)
                if pos not in ended and _done(ens_dir, pos):
                    ended.add(pos)
                    if m is not None:
                        outcome[name] = m.status
                        if m.status != KILLED:      # a killed one is settled below
                            job.shown.add(pos)
                            monitor.end(name, m, plan_case(case))
            if finished:
                break
            if stop.is_set() and not stop_sent:
                signal_engine(proc)
                stop_sent = True
            time.sleep(poll_seconds)
    except BaseException:
        stop_engine(proc)   # ligwf itself is going down: the ranks write their restarts first
        raise
    finally:
        release(watchdog)
    _stop_leftovers(list(job.ranks.values()), ens_dir)   # mpirun killed under its ranks


def settle(job: Launch, by_key: dict[str, CaseFolder], monitor: Monitor,
           stop: threading.Event, outcome: dict[str, str]) -> tuple[set[str], set[str]]:
    """Record every member of an ended launch (:func:`_settle_in_flight`; a killed one
    gets why, by its stop kind) and return (the members it settled, the ones to launch
    again). SimulationFailed when the launch failed before any member started;
    FolderNotWritable when a member found its folder full; members of a launch in which
    none made progress are ``failed`` (so the launches end)."""
    ens_dir, proc = job.ens_dir, job.proc
    launch_log = (ens_dir / layout.ENSEMBLE_LOG).read_text(errors="replace")
    claims = _claims(ens_dir)
    how = _job_end(launch_log, proc.returncode)
    progressed, retry, full = False, set(), None
    for pos, claim in claims.items():
        case = by_key[claim["case"]]
        m = _settle_in_flight(case, proc.returncode)
        if m is None:
            continue
        if m.status == KILLED and m.attempts and m.attempts[-1].started_at >= job.started - 1:
            if m.stop is Stop.DISK_FULL:
                full = full or f"{case.path}: {m.reason}"
            elif stop.is_set():
                m.reason = interrupted_reason(stop, m.steps_done, m.total_steps)
                m.stop = Stop.INTERRUPTED
            elif m.stop not in (Stop.INCOMPLETE_RECORD, Stop.RESTART_SET_ASIDE):
                m.reason = (f"stopped when the ensemble job ended ({how}) at step "
                            f"{m.steps_done} of {m.total_steps}")
                m.stop = Stop.JOB_ENDED
            m.attempts[-1].reason = m.reason
            _record(case, m)
        outcome[case.path.name] = m.status
        if (m.status != KILLED or m.steps_done > job.before.get(_key(case), 0)
                or m.stop is Stop.RESTART_SET_ASIDE):   # a restart set aside is progress
            progressed = True
        if m.status == KILLED:
            retry.add(_key(case))
        if pos not in job.shown:
            monitor.end(case.path.name, m, plan_case(case))
    if not claims and proc.returncode:
        raise SimulationFailed(
            f"ensemble launch failed before any case started (exit {proc.returncode})",
            exit_code=proc.returncode, run_dir=str(ens_dir), log_tail=launch_log[-2000:])
    if full is not None:
        raise FolderNotWritable(full)
    if not progressed and retry and not stop.is_set():
        for key in retry:
            case = by_key[key]
            m = case.manifest()
            if m is not None:
                m.status = FAILED
                m.stop = Stop.NO_PROGRESS
                m.reason = (f"ensemble job ended ({how}) with no member making progress "
                            f"and no ERROR line; see {ens_dir / layout.ENSEMBLE_LOG}")
                _record(case, m)
                outcome[case.path.name] = FAILED
                monitor.end(case.path.name, m, plan_case(case))
        retry = set()
    return {c["case"] for c in claims.values()}, retry


def run_ensemble(study: Path, cases: list[CaseFolder], nprocs: int, group_size: int,
                 engine: EngineConfig, retry_unstable: bool = False,
                 stop: threading.Event | None = None, monitor: Monitor | None = None,
                 poll_seconds: float = 0.5, max_launches: int | None = None,
                 label: str = "launch") -> dict[str, str]:
    """Run ``cases`` in MPI ensembles of ``nprocs`` ranks, groups of ``group_size``;
    ``monitor`` gets the same live progress as for local runs. Each launch is
    :func:`launch`, :func:`poll`, :func:`settle`; launch ``n`` works in
    ``.ensemble/<label>-<n>`` (a planned run gives each phase its own label), and the
    members a launch did not finish go into the next one.

    Returns ``{case folder name: status}`` for the cases worked on. FolderNotWritable
    when a member found its folder full (the others were stopped and are resumable).
    """
    if group_size < 1 or nprocs % group_size:
        raise SimulationFailed(f"--ensemble {nprocs} cannot be split into groups of --np "
                               f"{group_size}")
    stop = stop or threading.Event()
    monitor = monitor or NullMonitor()
    identity = engine.identify()    # the library the ranks load: the named executable's
    for case in cases:
        take_over(case)     # a dead runner's engines and attempts (a no-op when there are none)
    todo = [c for c in cases if plan_case(c, retry_unstable).action != SKIP]
    by_key = {_key(c): c for c in todo}
    outcome: dict[str, str] = {}
    root = Path(study) / layout.ENSEMBLE_DIR
    launches = 0
    limit = max_launches or (2 * len(todo) + 2)
    me = process(os.getpid())
    runner = {"host": socket.gethostname(), "pid": os.getpid(),
              "start": me.start if me is not None else None}
    while todo and not stop.is_set() and launches < limit:
        launches += 1
        job = launch(root / layout.ensemble_launch_dir(label, launches), todo, engine, nprocs,
                     group_size, retry_unstable, runner, identity)
        poll(job, by_key, monitor, stop, outcome, poll_seconds)
        settled, retry = settle(job, by_key, monitor, stop, outcome)
        todo = [c for c in todo if _key(c) not in settled or _key(c) in retry]
    return outcome

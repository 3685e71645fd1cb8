"""MPI ensembles: all cases and replicas inside one ``mpirun -np P``, supervised.

``run_ensemble`` starts ``mpirun -np P python -m ligwf.engine.ensemble_worker`` (see there: rank
groups, ctypes engine, dynamic claims) and watches it from outside MPI. An error inside
the LIGGGHTS library MPI_Aborts (or exits) the whole job, killing the other groups'
members mid-run. The supervisor is what makes that survivable:

* members that finished before the abort already have their manifest (written by their
  group leader) and ``claims/<i>.done``: nothing is lost;
* a member in flight whose screen carries an ``ERROR`` line is the culprit: it is recorded
  ``failed`` with that line;
* the other members in flight are innocent victims: they are marked ``killed`` and the
  supervisor launches a new ``mpirun`` for the remaining work, where they continue from
  their newest restart file (:mod:`ligwf.engine.resume`).

A launch that makes no progress at all (no member finished, no culprit found) marks its
in-flight members ``failed`` with the launcher's output, so the loop always ends.
"""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
import threading
import time
from pathlib import Path

from ligwf.engine.attempt import finish_attempt
from ligwf.engine.ensemble_worker import CLAIMS_DIR, QUEUE_FILE
from ligwf.engine.health import FAILED, KILLED, log_errors
from ligwf.engine.guard import engine_env, release, watch
from ligwf.engine.launch import Monitor, NullMonitor, signal_engine
from ligwf.engine.resume import SKIP, plan_case
from ligwf.engine.site import EngineConfig
from ligwf.engine.thermo import LogTail, ThermoParser
from ligwf.errors import SimulationFailed
from ligwf.fsio import atomic_write_json
from ligwf.study.case import CaseFolder
from ligwf.study.manifest import Manifest

ENSEMBLE_DIR = ".ensemble"


def worker_command(engine: EngineConfig, nprocs: int, ens_dir: Path, group_size: int) -> list[str]:
    """``mpirun -np P <python> -m ligwf.engine.ensemble_worker ENS_DIR --group-size K``."""
    return engine.mpirun_prefix(nprocs) + [sys.executable, "-m", "ligwf.engine.ensemble_worker",
                                           str(ens_dir), "--group-size", str(group_size)]


def _claims(ens_dir: Path) -> dict[int, dict]:
    out = {}
    for p in (ens_dir / CLAIMS_DIR).glob("*.json"):
        try:
            out[int(p.stem)] = json.loads(p.read_text())
        except (ValueError, json.JSONDecodeError):
            pass  # being written right now; seen on the next poll
    return out


def _done(ens_dir: Path, pos: int) -> bool:
    return (ens_dir / CLAIMS_DIR / f"{pos}.done").exists()


def _settle_in_flight(case: CaseFolder, exit_code: int | None, wall: float) -> Manifest | None:
    """Record a member that was running when the job ended: culprit or victim."""
    m = case.manifest()
    if m is None or not m.attempts:
        return None
    attempt = m.attempts[-1]
    screen = case.path / attempt.screen
    lines = screen.read_text(errors="replace").splitlines() if screen.exists() else []
    if log_errors(lines):
        return finish_attempt(case, m, attempt, exit_code, wall)
    m.status, m.reason = KILLED, "stopped when another ensemble member aborted the job"
    case.write_manifest(m)
    return m


def _key(case: CaseFolder) -> str:
    """How the queue and the claims name a case: its resolved folder."""
    return str(case.path.resolve())


def run_ensemble(study: Path, cases: list[CaseFolder], nprocs: int, group_size: int,
                 engine: EngineConfig, retry_unstable: bool = False,
                 stop: threading.Event | None = None, monitor: Monitor | None = None,
                 poll_seconds: float = 0.5, max_launches: int | None = None,
                 label: str = "launch") -> dict[str, str]:
    """Run ``cases`` in MPI ensembles of ``nprocs`` ranks, groups of ``group_size``;
    ``monitor`` gets the same live progress as for local runs. Launch ``n`` works in
    ``.ensemble/<label>-<n>`` (a planned run gives each phase its own label).

    Returns ``{case folder name: status}`` for the cases worked on.
    """
    if group_size < 1 or nprocs % group_size:
        raise SimulationFailed(f"--ensemble {nprocs} cannot be split into groups of --np "
                               f"{group_size}")
    stop = stop or threading.Event()
    monitor = monitor or NullMonitor()
    todo = [c for c in cases if plan_case(c, retry_unstable).action != SKIP]
    by_key = {_key(c): c for c in todo}
    outcome: dict[str, str] = {}
    root = Path(study) / ENSEMBLE_DIR
    launches = 0
    limit = max_launches or (2 * len(todo) + 2)
    while todo and not stop.is_set() and launches < limit:
        launches += 1
        ens_dir = root / f"{label}-{launches}"
        if ens_dir.exists():
            shutil.rmtree(ens_dir)
        (ens_dir / CLAIMS_DIR).mkdir(parents=True)
        atomic_write_json(ens_dir / QUEUE_FILE, {"cases": [_key(c) for c in todo],
                                                 "retry_unstable": retry_unstable})
        cmd = worker_command(engine, nprocs, ens_dir, group_size)
        t0 = time.monotonic()
        tails: dict[int, tuple[LogTail, ThermoParser]] = {}
        ended: set[int] = set()
        with open(ens_dir / "launch.log", "wb") as out:
            proc = subprocess.Popen(cmd, stdout=out, stderr=subprocess.STDOUT,
                                    stdin=subprocess.DEVNULL, env=engine_env(),
                                    start_new_session=True)
        watchdog = watch(proc)   # stops the job if this runner dies
        stop_sent = False
        while True:
            finished = proc.poll() is not None
            for pos, claim in _claims(ens_dir).items():
                case = by_key[claim["case"]]
                name = case.path.name
                if pos not in tails:
                    m = case.manifest()
                    if m is None or not m.attempts:
                        continue
                    tails[pos] = (LogTail(case.screen), ThermoParser())
                    monitor.start(name, m.total_steps, m.attempts[-1].from_step)
                tail, parser = tails[pos]
                for line in tail.read_lines():
                    parser.feed(line)
                monitor.update(name, parser)
                if pos not in ended and _done(ens_dir, pos):
                    ended.add(pos)
                    m = case.manifest()
                    if m is not None:
                        outcome[name] = m.status
                        monitor.end(name, m, plan_case(case))
            if finished:
                break
            if stop.is_set() and not stop_sent:
                signal_engine(proc)
                stop_sent = True
            time.sleep(poll_seconds)
        release(watchdog)
        wall = time.monotonic() - t0
        launch_log = (ens_dir / "launch.log").read_text(errors="replace")
        claims = _claims(ens_dir)
        progressed = bool(ended)
        victims: list[CaseFolder] = []
        for pos, claim in claims.items():
            if pos in ended or _done(ens_dir, pos):
                continue
            case = by_key[claim["case"]]
            m = _settle_in_flight(case, proc.returncode, wall)
            if m is None:
                continue
            outcome[case.path.name] = m.status
            if m.status == KILLED:
                victims.append(case)
            else:
                progressed = True
                monitor.end(case.path.name, m, plan_case(case))
        if not claims and proc.returncode:
            raise SimulationFailed(
                f"ensemble launch failed before any case started (exit {proc.returncode})",
                exit_code=proc.returncode, run_dir=str(ens_dir), log_tail=launch_log[-2000:])
        if not progressed and victims and not stop.is_set():
            for case in victims:
                m = case.manifest()
                if m is not None:
                    m.status = FAILED
                    m.reason = (f"ensemble job ended (exit {proc.returncode}) with no member "
                                f"finished and no ERROR line; see {ens_dir / 'launch.log'}")
                    case.write_manifest(m)
                    outcome[case.path.name] = FAILED
                    monitor.end(case.path.name, m, plan_case(case))
        settled = {c["case"] for c in claims.values()}
        retried = {_key(v) for v in victims} if progressed else set()
        todo = [c for c in todo if _key(c) not in settled or _key(c) in retried]
    return outcome

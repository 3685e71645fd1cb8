"""Engine processes: they die with their runner, are recorded, and are found again later.

A runner that is SIGKILLed (or crashes) cannot stop its engine, and ``mpirun`` runs in a
session of its own (a Ctrl-C in the terminal must not reach the ranks before ligwf asks
them to write a restart). Two guards make sure no engine keeps writing a case folder
nobody watches:

* :func:`watch` starts a watchdog process next to every launch. It blocks reading a pipe
  whose only writer is the runner; when the runner dies, however it dies, the pipe closes
  and the watchdog stops the engine like ligwf would (:func:`stop_engines`: SIGTERM to the
  ranks, so LIGGGHTS writes its forced restart in ~0.1 s). Relying on ``mpirun`` instead
  (``prctl(PR_SET_PDEATHSIG)``) was measured unreliable with OpenMPI 4.1.4: on SIGTERM it
  sometimes exits at once and its ranks die ~1 s later without a restart, sometimes it
  sends SIGCONT, waits ``odls_base_sigkill_timeout``, then SIGTERM, then SIGKILL.
* :func:`live_engines` finds engine processes still running in a case folder (the ones the
  manifest recorded, told apart from a recycled pid by their start time from
  ``/proc/<pid>/stat``, plus any ``liggghts`` / ``mpirun`` / ``orted`` whose working folder
  is the case), and :func:`stop_engines` stops them before a later run resumes the case.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

from ligwf.study.processes import EngineProcess, process

#: the process name an MPI-ensemble rank gives itself (``python -m
#: ligwf.engine.ensemble_worker`` sets it with prctl, so it can be found like ``liggghts``)
ENSEMBLE_RANK_NAME = "ligwf-ensemble"
#: process names of the engine's ranks (they write the forced restart on SIGTERM)
RANK_NAMES = ("liggghts", ENSEMBLE_RANK_NAME)
#: process names of an engine run (``orted`` only appears on multi-node launches)
ENGINE_NAMES = RANK_NAMES + ("mpirun", "orterun", "orted", "prterun")
#: seconds a stopped engine gets to write its forced restart before it is killed
STOP_GRACE_SECONDS = 60.0

#: seconds OpenMPI's mpirun waits between SIGCONT, SIGTERM and SIGKILL to its ranks
MPI_KILL_DELAY = 3


def engine_env() -> dict[str, str]:
    """Environment of an engine launch: the caller's, with OpenMPI's kill delay raised to
    :data:`MPI_KILL_DELAY` unless the site set it (other MPIs ignore the variable)."""
    env = dict(os.environ)
    env.setdefault("OMPI_MCA_odls_base_sigkill_timeout", str(MPI_KILL_DELAY))
    return env


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


def engine_tree(pid: int) -> list[EngineProcess]:
    """The launcher ``pid`` and every process below it, with start times."""
    found = (process(p) for p in [pid, *descendants(pid)])
    return [p for p in found if p is not None]


def watch(launcher: subprocess.Popen, case_dirs=()) -> subprocess.Popen:
    """Start the watchdog of an engine launch (see the module docstring); the runner
    calls :func:`release` when the engine has ended. ``case_dirs``: the case folders the
    launch works on (an ensemble folder stands for the cases it claimed); when the
    watchdog stops the engine of a dead runner it gives their new restarts their
    identity sidecars (:mod:`ligwf.engine.restart_id`)."""
    root = process(launcher.pid)
    return subprocess.Popen([sys.executable, "-m", "ligwf.engine.watchdog", str(launcher.pid),
                             str(root.start if root else 0), *map(str, case_dirs)],
                            stdin=subprocess.PIPE, stdout=subprocess.DEVNULL,
                            stderr=subprocess.DEVNULL, start_new_session=True)


#: what a runner writes to its watchdog before closing the pipe: "released, not dead"
RELEASED = b"released\n"


def release(watchdog: subprocess.Popen) -> None:
    """Tell a watchdog its engine ended under the runner's eyes (it then exits)."""
    if watchdog.stdin is not None:
        try:
            watchdog.stdin.write(RELEASED)
            watchdog.stdin.close()
        except (BrokenPipeError, OSError):
            pass
    try:
        watchdog.wait(timeout=10)
    except subprocess.TimeoutExpired:
        watchdog.kill()


def _cwd_matches(pid: int, folder: Path) -> bool:
    try:
        return Path(os.readlink(f"/proc/{pid}/cwd")) == folder
    except OSError:
        return False


def live_engines(case_dir: Path, recorded: list[EngineProcess] = ()) -> list[EngineProcess]:
    """Engine processes running now for a case folder: ``recorded`` ones still alive, and
    any engine-named process whose working folder is the case (ranks first)."""
    folder = Path(case_dir).resolve()
    found = {p.pid: p for p in recorded if p.alive()}
    for entry in os.listdir("/proc"):
        if entry.isdigit() and int(entry) not in found and int(entry) != os.getpid():
            p = process(int(entry))
            if p is not None and p.name in ENGINE_NAMES and _cwd_matches(p.pid, folder):
                found[p.pid] = p
    return sorted(found.values(), key=lambda p: p.name not in RANK_NAMES)


def _signal(procs: list[EngineProcess], sig: int) -> None:
    for p in procs:
        if p.alive():
            try:
                os.kill(p.pid, sig)
            except ProcessLookupError:
                pass


def stop_engines(procs: list[EngineProcess], grace: float = STOP_GRACE_SECONDS) -> bool:
    """Stop engine processes of a case: SIGTERM to the ranks (LIGGGHTS writes a forced
    restart), then to the launchers, SIGKILL after ``grace`` seconds. Returns whether a
    SIGKILL was needed."""
    ranks = [p for p in procs if p.name in RANK_NAMES]
    _signal(ranks or procs, signal.SIGTERM)
    deadline = time.monotonic() + grace
    while any(p.alive() for p in ranks) and time.monotonic() < deadline:
        time.sleep(0.2)
    _signal(procs, signal.SIGTERM)
    while any(p.alive() for p in procs) and time.monotonic() < deadline:
        time.sleep(0.2)
    left = [p for p in procs if p.alive()]
    _signal(left, signal.SIGKILL)
    return bool(left)

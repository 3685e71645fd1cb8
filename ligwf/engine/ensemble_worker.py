"""The MPI side of an ensemble: ``python -m ligwf.engine.ensemble_worker ENS_DIR --group-size K``.

Started by :mod:`ligwf.engine.ensemble` as ONE ``mpirun -np P``. The ranks split into P/K groups
(``comm.Split``); each group runs one case at a time in the LIGGGHTS shared library
(the ``libliggghts`` the named executable links to, as the supervisor found it and wrote
into the queue; LAMMPS C API through ctypes) on its sub-communicator. Assignment is
dynamic and needs no master rank: a group leader claims the next case of ``queue.json``
by creating ``claims/<index>.json`` with O_EXCL (only one creator can win), broadcasts it to
its group, and takes the next when the case is done.

Each finished case is judged and recorded by the leader right away (same manifest and
health checks as a local run, :mod:`ligwf.engine.attempt`), and ``claims/<index>.done`` is
written, so the results of finished members survive when another member's engine error
MPI_Aborts the whole job; the supervisor then sorts out the members that were in flight.

Stopping: the ranks install LIGGGHTS' own SIGINT/SIGTERM handler (what the ``liggghts``
executable's ``main`` does; a library user gets none), so a SIGTERM from the supervisor or
from ``mpirun`` (when another rank died) makes the engine write
``restart_forced_liggghts_<step>.data`` and end its run; the leader records the attempt
(``killed``, resumable) and the group claims nothing more. A resumed member whose restart
the engine cannot read sets that restart aside and resumes from the next older one (as a
local run does). The manifest names the supervisor as the case's runner (its lock holder)
and this rank as its engine process; the rank calls itself
:data:`ligwf.engine.guard.ENSEMBLE_RANK_NAME` so a later runner finds it like ``liggghts``.
"""

from __future__ import annotations

import argparse
import ctypes
import json
import os
import signal
import sys
import time
from pathlib import Path

from ligwf.engine.attempt import begin_attempt, finish_attempt, restart_unreadable
from ligwf.engine.dump_hasher import DumpHasher
from ligwf.engine.guard import ENSEMBLE_RANK_NAME
from ligwf.engine.liggghts import Liggghts
from ligwf.engine.site import EngineIdentity
from ligwf.fsio import atomic_write_json
from ligwf.engine.resume import FRESH, RESUME, SKIP, discard_restart, input_for, plan_case
from ligwf.study.case import CaseFolder
from ligwf.study import layout
from ligwf.study.layout import POST_DIR
from ligwf.study.manifest import KILLED, Stop
from ligwf.study.processes import process

_libc = ctypes.CDLL(None)


def run_file(engine: Liggghts, comm, case: CaseFolder, input_name: str) -> None:
    """Run ``input_name`` in the case folder on the mpi4py communicator ``comm``.

    The engine's screen is the process's stdout, pointed at the case's screen file on
    the group leader and line-buffered (:func:`line_buffered_stdout`): an Error::one
    ends in MPI_Abort, which drops whatever a fully buffered ``-screen FILE`` still
    held -- including the ERROR line that names the culprit.
    """
    from mpi4py import MPI

    args = [b"liggghts", b"-log", b"log.liggghts"]
    argv = (ctypes.c_char_p * len(args))(*args)
    handle = ctypes.c_void_p()
    comm_ptr = ctypes.c_void_p.from_address(MPI._addressof(comm))
    cwd = os.getcwd()
    saved = None
    _libc.fflush(None)
    if comm.rank == 0:
        saved = os.dup(1)
        fd = os.open(case.screen, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o666)
        os.dup2(fd, 1)
        os.close(fd)
    os.chdir(case.path)
    try:
        engine.lib.lammps_open(len(args), argv, comm_ptr, ctypes.byref(handle))
        engine.lib.lammps_file(handle, input_name.encode())
        engine.lib.lammps_close(handle)
    finally:
        _libc.fflush(None)
        os.chdir(cwd)
        if saved is not None:
            os.dup2(saved, 1)
            os.close(saved)


_HANDLER = "_ZN9LAMMPS_NS13SignalHandler11int_handlerEi"
_QUIT = "_ZN9LAMMPS_NS13SignalHandler12request_quitE"


def install_engine_signals(engine: Liggghts) -> None:
    """SIGINT and SIGTERM to LIGGGHTS' handler (forced restart at the next step, then the
    run ends), as the ``liggghts`` executable installs them; and name the process."""
    _libc.prctl(15, ENSEMBLE_RANK_NAME.encode(), 0, 0, 0)   # 15 = PR_SET_NAME
    _libc.signal.argtypes = [ctypes.c_int, ctypes.c_void_p]
    _libc.signal.restype = ctypes.c_void_p
    handler = ctypes.cast(getattr(engine.lib, _HANDLER), ctypes.c_void_p)
    for sig in (signal.SIGINT, signal.SIGTERM):
        _libc.signal(int(sig), handler)


def quit_requested(engine: Liggghts) -> bool:
    """Whether this rank has been asked to stop (LIGGGHTS' flag, set by its handler)."""
    return bool(ctypes.c_bool.in_dll(engine.lib, _QUIT).value)


def line_buffered_stdout() -> None:
    """Make C stdout line-buffered (must run before anything is written to it)."""
    stdout = ctypes.c_void_p.in_dll(_libc, "stdout")
    _libc.setvbuf(stdout, None, 1, 0)  # 1 = _IOLBF


def _record_runner(case: CaseFolder, manifest, runner: dict, me) -> None:
    """The supervisor is the case's runner (it holds the case lock and outlives this
    launch); this rank is its engine process."""
    if runner.get("pid"):
        manifest.host = runner.get("host", manifest.host)
        manifest.pid, manifest.pid_start = int(runner["pid"]), runner.get("start")
    manifest.engine = [me.to_dict()] if me is not None else []
    case.write_manifest(manifest)


def claim_next(ens_dir: Path, cases: list[str], record: dict) -> tuple[int, str] | None:
    """Atomically claim the first unclaimed case: (queue position, case folder) or None."""
    claims = ens_dir / layout.ENSEMBLE_CLAIMS_DIR
    for pos, case in enumerate(cases):
        path = claims / layout.ensemble_claim(pos)
        try:
            fd = os.open(path, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o666)
        except FileExistsError:
            continue
        with os.fdopen(fd, "w") as fh:
            json.dump({**record, "case": case, "claimed": time.time()}, fh)
        return pos, case
    return None


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m ligwf.engine.ensemble_worker")
    parser.add_argument("ens_dir", type=Path)
    parser.add_argument("--group-size", type=int, default=1)
    args = parser.parse_args(argv)

    line_buffered_stdout()
    from mpi4py import MPI

    world = MPI.COMM_WORLD
    k = args.group_size
    if k < 1 or world.size % k:
        if world.rank == 0:
            print(f"ensemble: {world.size} ranks cannot form groups of {k}", file=sys.stderr)
        return 2
    group = world.rank // k
    sub = world.Split(group, world.rank)
    ranks = list(range(group * k, group * k + k))
    queue = json.loads((args.ens_dir / layout.ENSEMBLE_QUEUE).read_text())
    runner = queue.get("runner", {})
    identity = EngineIdentity.from_dict(queue["engine"])
    engine = Liggghts(identity.library)     # the library of the executable the user named
    mapped = Liggghts.mapped()
    if mapped != {os.path.realpath(identity.library)}:
        print(f"ensemble: engine library {identity.library} asked for, {sorted(mapped)} "
              "loaded", file=sys.stderr)
        return 2
    install_engine_signals(engine)
    engine.warm_up_vtk()
    world.Barrier()
    me = process(os.getpid())
    stop_claiming = False
    while True:
        job = None
        if sub.rank == 0 and not stop_claiming and not quit_requested(engine):
            while True:
                claim = claim_next(args.ens_dir, queue["cases"],
                                   {"group": group, "world_ranks": ranks, "pid": os.getpid()})
                if claim is None:
                    break
                pos, case_path = claim
                case = CaseFolder.open(case_path)
                plan = plan_case(case, queue.get("retry_unstable", False))
                if plan.action == SKIP:
                    atomic_write_json(args.ens_dir / layout.ENSEMBLE_CLAIMS_DIR
                                      / layout.ensemble_claim_done(pos), {"skipped": True})
                    continue
                job = (pos, case_path, plan)
                break
        job = sub.bcast(job, root=0)
        if job is None:
            break
        pos, case_path, plan = job
        case = CaseFolder.open(case_path)
        while True:
            if sub.rank == 0:
                manifest, attempt = begin_attempt(case, plan, k, "ensemble",
                                                  [f"ensemble group {group}", input_for(plan)],
                                                  engine=identity)
                _record_runner(case, manifest, runner, me)
            t0 = time.monotonic()
            # the group's rank 0 hashes the dumps while the engine runs (the done record
            # then hashes only the last ones: ligwf.engine.dump_hasher)
            hasher = DumpHasher(case.path / POST_DIR).__enter__() if sub.rank == 0 else None
            try:
                run_file(engine, sub, case, input_for(plan))
                sub.Barrier()
            finally:
                if hasher is not None:
                    hasher.close()
            again = None
            if sub.rank == 0:
                quit = quit_requested(engine)
                manifest = finish_attempt(case, manifest, attempt, 0, time.monotonic() - t0,
                                          killed=quit, digests=hasher.digests)
                if (not quit and plan.restart is not None
                        and restart_unreadable(manifest, attempt)):
                    # a restart the engine could not read: set it aside, take the next one
                    discard_restart(case.path, plan.restart)
                    manifest.status = KILLED
                    case.write_manifest(manifest)
                    plan = plan_case(case, queue.get("retry_unstable", False))
                    again = plan if plan.action in (FRESH, RESUME) else None
                if again is None:
                    atomic_write_json(args.ens_dir / layout.ENSEMBLE_CLAIMS_DIR
                                      / layout.ensemble_claim_done(pos),
                                      {"group": group, "quit": quit})
                stop_claiming = quit or manifest.stop is Stop.DISK_FULL
            again = sub.bcast(again, root=0)
            if again is None:
                break
            plan = again
    sub.Free()
    return 0


if __name__ == "__main__":
    sys.exit(main())

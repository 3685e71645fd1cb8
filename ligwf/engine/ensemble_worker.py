"""The MPI side of an ensemble: ``python -m ligwf.engine.ensemble_worker ENS_DIR --group-size K``.

Started by :mod:`ligwf.engine.ensemble` as ONE ``mpirun -np P``. The ranks split into P/K groups
(``comm.Split``); each group runs one case at a time in the LIGGGHTS shared library
(``libliggghts.so.3``, LAMMPS C API through ctypes) on its sub-communicator. Assignment is
dynamic and needs no master rank: a group leader claims the next case of ``queue.json``
by creating ``claims/<index>.json`` with O_EXCL (only one creator can win), broadcasts it to
its group, and takes the next when the case is done.

Each finished case is judged and recorded by the leader right away (same manifest and
health checks as a local run, :mod:`ligwf.engine.attempt`), and ``claims/<index>.done`` is
written, so the results of finished members survive when another member's engine error
MPI_Aborts the whole job; the supervisor then sorts out the members that were in flight.
"""

from __future__ import annotations

import argparse
import ctypes
import json
import os
import sys
import time
from pathlib import Path

from ligwf.engine.attempt import begin_attempt, finish_attempt
from ligwf.engine.liggghts import Liggghts
from ligwf.fsio import atomic_write_json
from ligwf.engine.resume import SKIP, input_for, plan_case
from ligwf.study.case import CaseFolder

QUEUE_FILE = "queue.json"
_libc = ctypes.CDLL(None)
CLAIMS_DIR = "claims"


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
        fd = os.open(case.screen, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o644)
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


def line_buffered_stdout() -> None:
    """Make C stdout line-buffered (must run before anything is written to it)."""
    stdout = ctypes.c_void_p.in_dll(_libc, "stdout")
    _libc.setvbuf(stdout, None, 1, 0)  # 1 = _IOLBF


def claim_next(ens_dir: Path, cases: list[str], record: dict) -> tuple[int, str] | None:
    """Atomically claim the first unclaimed case: (queue position, case folder) or None."""
    claims = ens_dir / CLAIMS_DIR
    for pos, case in enumerate(cases):
        path = claims / f"{pos}.json"
        try:
            fd = os.open(path, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o644)
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
    queue = json.loads((args.ens_dir / QUEUE_FILE).read_text())
    engine = Liggghts()
    engine.warm_up_vtk()
    world.Barrier()
    while True:
        job = None
        if sub.rank == 0:
            while True:
                claim = claim_next(args.ens_dir, queue["cases"],
                                   {"group": group, "world_ranks": ranks, "pid": os.getpid()})
                if claim is None:
                    break
                pos, case_path = claim
                case = CaseFolder.open(case_path)
                plan = plan_case(case, queue.get("retry_unstable", False))
                if plan.action == SKIP:
                    atomic_write_json(args.ens_dir / CLAIMS_DIR / f"{pos}.done", {"skipped": True})
                    continue
                manifest, attempt = begin_attempt(case, plan, k, "ensemble",
                                                  [f"ensemble group {group}", input_for(plan)])
                job = (pos, case_path, attempt.input)
                break
        job = sub.bcast(job, root=0)
        if job is None:
            break
        pos, case_path, input_name = job
        case = CaseFolder.open(case_path)
        t0 = time.monotonic()
        run_file(engine, sub, case, input_name)
        sub.Barrier()
        if sub.rank == 0:
            finish_attempt(case, manifest, attempt, 0, time.monotonic() - t0)
            atomic_write_json(args.ens_dir / CLAIMS_DIR / f"{pos}.done", {"group": group})
    sub.Free()
    return 0


if __name__ == "__main__":
    sys.exit(main())

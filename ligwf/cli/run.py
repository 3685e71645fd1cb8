"""Command line of the run stage: ``ligwf run``, ``ligwf run-case``, ``ligwf status``.

``run`` prepares a workflow into a study folder (identical cases are rewritten byte for
byte, so their outputs stay) and runs every case that is not finished. By default the rank
planner (:mod:`ligwf.engine.plan`) decides: ranks per case from its particle count and the
axial slab rule, single-rank cases side by side in one MPI ensemble, bigger ones on several
ranks, longest first, on the cores of this machine or allocation (``--cores`` to say
otherwise); the plan is printed before the run. ``--np K`` runs every case on K ranks one
after the other, ``--ensemble P`` all of them in one ``mpirun -np P`` (groups of ``--np``,
default 1), as before. Running the same command again resumes (see
:mod:`ligwf.engine.resume`).
``run-case`` runs case number I of a rendered study folder with the same runner (what a
Slurm array task calls).
"""

from __future__ import annotations

import argparse
import os
from pathlib import Path

from ligwf.cli.common import (add_cores_arg, add_mesh_cache, add_workflow_args, console,
                              folder_to_write, plan_table, prepare_from_args, rank_count,
                              stop_on_signals)
from ligwf.engine.plan import machine_cores
from ligwf.engine.progress import RichMonitor, summary_table
from ligwf.engine.site import EngineConfig
from ligwf.study.pipeline import RunSettings, cases_to_run, run_study, study_schedule, write
from ligwf.study.study import Study


def run_settings(args: argparse.Namespace, cores: int = 1) -> RunSettings:
    """The run settings of ``args``: planned on ``cores`` cores unless ``--np`` or
    ``--ensemble`` was given (``--ensemble`` alone keeps groups of one rank)."""
    ensemble = getattr(args, "ensemble", 0)
    nprocs = args.np if args.np is not None else (1 if ensemble else None)
    return RunSettings(nprocs=nprocs, ensemble=ensemble, retry_unstable=args.retry_unstable,
                       template_dirs=tuple(getattr(args, "templates", ())), cores=cores)


def prepare_and_run(args: argparse.Namespace) -> tuple[Study, bool]:
    """Prepare (pre-flight first), write, show the rank plan and run a workflow with live
    progress; returns the study and whether every case is done (``run`` and ``study``)."""
    prepared = prepare_from_args(args)
    cores, source = machine_cores(args.cores)
    settings = run_settings(args, cores)
    engine = EngineConfig.from_site()   # a bad site setting is refused before writing
    study = write(prepared, args.out, args.mesh_cache)
    schedule = study_schedule(cases_to_run(study.cases, settings.retry_unstable), settings)
    title = (f"rank plan for {cores} core(s) ({source})" if settings.planned
             else "ranks as asked (--np / --ensemble)")
    console.print(plan_table(schedule, title))
    with stop_on_signals() as stop, RichMonitor(console) as monitor:
        done = run_study(study, study.cases, engine, settings, monitor, stop)
    console.print(summary_table(study.cases, f"{study.name}: {args.out}"))
    return study, done


def cmd_run(args: argparse.Namespace) -> int:
    return 0 if prepare_and_run(args)[1] else 1


def cmd_run_case(args: argparse.Namespace) -> int:
    study = Study.open(args.study)
    case = study.case(args.index)
    args.np = args.np or int(os.environ.get("SLURM_NTASKS", "1"))
    with stop_on_signals() as stop, RichMonitor(console) as monitor:
        done = run_study(study, [case], EngineConfig.from_site(), run_settings(args), monitor,
                         stop)
    console.print(summary_table([case], f"case {args.index}"))
    return 0 if done else 1


def cmd_status(args: argparse.Namespace) -> int:
    study = Study.open(args.study)
    console.print(summary_table(study.cases, f"{args.study}: {len(study.cases)} case(s)"))
    return 0


def add_run_args(p: argparse.ArgumentParser) -> None:
    """The options of the run stage (``run`` and ``study``)."""
    p.add_argument("--out", type=folder_to_write, required=True, help="study folder")
    p.add_argument("--np", type=rank_count, default=None,
                   help="MPI ranks for every case, one case after the other (default: the "
                   "rank plan, see 'ligwf check')")
    p.add_argument("--ensemble", type=rank_count, default=0, metavar="P",
                   help="run all cases in ONE mpirun -np P, P/np cases at a time (np "
                   "default 1; overrides the rank plan)")
    add_cores_arg(p)
    p.add_argument("--retry-unstable", action="store_true",
                   help="also re-run cases found unstable before")
    add_mesh_cache(p)


def register(subparsers) -> None:
    """Add ``run``, ``run-case`` and ``status`` to the ligwf command line."""
    p = subparsers.add_parser("run", help="render and run every case with the real engine "
                              "(resumes: finished cases are skipped)")
    add_workflow_args(p)
    add_run_args(p)
    p.set_defaults(func=cmd_run)

    p = subparsers.add_parser("run-case", help="run case number I of a rendered study folder "
                              "(Slurm array tasks call this)")
    p.add_argument("study", type=Path, help="rendered study folder")
    p.add_argument("--index", type=int, required=True, help="case index in the study")
    p.add_argument("--np", type=rank_count, default=0,
                   help="MPI ranks (default $SLURM_NTASKS, else 1)")
    p.add_argument("--retry-unstable", action="store_true")
    p.set_defaults(func=cmd_run_case)

    p = subparsers.add_parser("status", help="list the cases of a study folder and their state")
    p.add_argument("study", type=Path, help="study folder")
    p.set_defaults(func=cmd_status)

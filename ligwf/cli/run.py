"""Command line of the run stage: ``ligwf run``, ``ligwf run-case``, ``ligwf status``.

``run`` prepares a workflow into a study folder (identical cases are rewritten byte for
byte, so their outputs stay) and runs every case that is not finished: one after the other
under ``mpirun -np K``, or all together in one ``mpirun -np P`` allocation with
``--ensemble P``. Running the same command again resumes (see :mod:`ligwf.engine.resume`).
``run-case`` runs case number I of a rendered study folder with the same runner (what a
Slurm array task calls).
"""

from __future__ import annotations

import argparse
import os
from pathlib import Path

from ligwf.cli.common import (add_mesh_cache, add_workflow_args, console, folder_to_write,
                              positive_int, prepare_from_args, stop_on_signals)
from ligwf.engine.progress import RichMonitor, summary_table
from ligwf.engine.site import EngineConfig
from ligwf.study.pipeline import RunSettings, run_study, write
from ligwf.study.study import Study


def run_settings(args: argparse.Namespace) -> RunSettings:
    return RunSettings(nprocs=args.np, ensemble=getattr(args, "ensemble", 0),
                       retry_unstable=args.retry_unstable,
                       template_dirs=tuple(getattr(args, "templates", ())))


def prepare_and_run(args: argparse.Namespace) -> tuple[Study, bool]:
    """Prepare (pre-flight first), write and run a workflow with live progress; returns
    the study and whether every case is done (``run`` and ``study``)."""
    prepared = prepare_from_args(args)
    study = write(prepared, args.out, args.mesh_cache)
    with stop_on_signals() as stop, RichMonitor(console) as monitor:
        done = run_study(study, study.cases, EngineConfig.from_site(), run_settings(args),
                         monitor, stop)
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
    p.add_argument("--np", type=positive_int, default=1, help="MPI ranks per case (default 1)")
    p.add_argument("--ensemble", type=positive_int, default=0, metavar="P",
                   help="run all cases in ONE mpirun -np P, P/np cases at a time")
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
    p.add_argument("--np", type=positive_int, default=0,
                   help="MPI ranks (default $SLURM_NTASKS, else 1)")
    p.add_argument("--retry-unstable", action="store_true")
    p.set_defaults(func=cmd_run_case)

    p = subparsers.add_parser("status", help="list the cases of a study folder and their state")
    p.add_argument("study", type=Path, help="study folder")
    p.set_defaults(func=cmd_status)

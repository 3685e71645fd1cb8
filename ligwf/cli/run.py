"""Command line of the run stage: ``ligwf run``, ``ligwf run-case``, ``ligwf status``.

``run`` renders a workflow into a study folder (identical cases are rewritten byte for byte,
so their outputs stay) and runs every case that is not finished: one after the other under
``mpirun -np K``, or all together in one ``mpirun -np P`` allocation with ``--ensemble P``.
Running the same command again resumes (see :mod:`ligwf.engine.resume`). ``run-case`` runs case
number I of a rendered study folder with the same runner (what a Slurm array task calls).
"""

from __future__ import annotations

import argparse
import json
import os
import signal
import sys
import threading
from contextlib import contextmanager
from pathlib import Path
from typing import Iterator

from rich.console import Console

from ligwf.study.prepare import STUDY_FILE, render_workflow, write_study
from ligwf.cli.stability import preflight_or_refuse
from ligwf.engine.site import EngineConfig
from ligwf.errors import ConfigError
from ligwf.engine.health import DONE
from ligwf.engine.launch import run_case
from ligwf.engine.manifest import read_manifest
from ligwf.engine.progress import RichMonitor, summary_table
from ligwf.scene.workflow import load_workflow

console = Console(width=None if sys.stdout.isatty() else 160)


@contextmanager
def stop_on_signals() -> Iterator[threading.Event]:
    """An event set by SIGTERM / SIGINT, so a runner stops its engines gracefully
    (forced restart written, case marked ``killed``) instead of dying mid-write."""
    stop = threading.Event()
    previous = {}

    def handler(signum, frame):  # noqa: ARG001 - signal handler signature
        stop.set()

    for sig in (signal.SIGTERM, signal.SIGINT):
        previous[sig] = signal.signal(sig, handler)
    try:
        yield stop
    finally:
        for sig, old in previous.items():
            signal.signal(sig, old)


def study_case_dirs(study: Path) -> list[Path]:
    """Case folders of a rendered study, in case-index order."""
    path = Path(study) / STUDY_FILE
    if not path.is_file():
        raise ConfigError(f"{study} is not a rendered study folder (no {STUDY_FILE})")
    cases = json.loads(path.read_text())["cases"]
    return [Path(study) / c["case_id"] for c in sorted(cases, key=lambda c: c["index"])]


def all_done(case_dirs: list[Path]) -> bool:
    ms = [read_manifest(d) for d in case_dirs]
    return all(m is not None and m.status == DONE for m in ms)


def run_cases(case_dirs: list[Path], nprocs: int, engine: EngineConfig, stop: threading.Event,
              retry_unstable: bool = False, template_dirs=()) -> None:
    """Run cases one after the other, each under ``mpirun -np nprocs``, with live bars."""
    with RichMonitor(console) as monitor:
        for d in case_dirs:
            if stop.is_set():
                break
            run_case(d, nprocs, engine, monitor, stop, retry_unstable, template_dirs)


def cmd_run(args: argparse.Namespace) -> int:
    wf = load_workflow(args.workflow, args.overrides)
    rendered = render_workflow(wf, args.templates)
    preflight_or_refuse(rendered, args.allow_unstable)  # ligwf.scene.stability: refuse before writing
    case_dirs = write_study(wf, rendered, args.out, args.mesh_cache)
    engine = EngineConfig.from_site()
    with stop_on_signals() as stop:
        if args.ensemble:
            from ligwf.engine.ensemble import run_ensemble
            run_ensemble(Path(args.out), case_dirs, args.ensemble, args.np, engine,
                         retry_unstable=args.retry_unstable, stop=stop, console=console)
        else:
            run_cases(case_dirs, args.np, engine, stop, args.retry_unstable, args.templates)
    console.print(summary_table(case_dirs, f"{wf.name}: {args.out}"))
    return 0 if all_done(case_dirs) else 1


def cmd_run_case(args: argparse.Namespace) -> int:
    dirs = study_case_dirs(args.study)
    if not 0 <= args.index < len(dirs):
        raise ConfigError(f"--index {args.index}: the study has cases 0..{len(dirs) - 1}")
    nprocs = args.np or int(os.environ.get("SLURM_NTASKS", "1"))
    case_dir = dirs[args.index]
    with stop_on_signals() as stop:
        run_cases([case_dir], nprocs, EngineConfig.from_site(), stop, args.retry_unstable)
    console.print(summary_table([case_dir], f"case {args.index}"))
    return 0 if all_done([case_dir]) else 1


def cmd_status(args: argparse.Namespace) -> int:
    dirs = study_case_dirs(args.study)
    console.print(summary_table(dirs, f"{args.study}: {len(dirs)} case(s)"))
    return 0


def register(subparsers) -> None:
    """Add ``run``, ``run-case`` and ``status`` to the ligwf command line."""
    from ligwf.cli.main import add_workflow_args

    p = subparsers.add_parser("run", help="render and run every case with the real engine "
                              "(resumes: finished cases are skipped)")
    add_workflow_args(p)
    p.add_argument("--out", type=Path, required=True, help="study folder")
    p.add_argument("--np", type=int, default=1, help="MPI ranks per case (default 1)")
    p.add_argument("--ensemble", type=int, default=0, metavar="P",
                   help="run all cases in ONE mpirun -np P, P/np cases at a time")
    p.add_argument("--retry-unstable", action="store_true",
                   help="also re-run cases found unstable before")
    p.add_argument("--mesh-cache", type=Path, default=None,
                   help="mesh cache folder (default $LIGWF_MESH_CACHE or ./meshes)")
    p.set_defaults(func=cmd_run)

    p = subparsers.add_parser("run-case", help="run case number I of a rendered study folder "
                              "(Slurm array tasks call this)")
    p.add_argument("study", type=Path, help="rendered study folder (with study.json)")
    p.add_argument("--index", type=int, required=True, help="case index in study.json")
    p.add_argument("--np", type=int, default=0,
                   help="MPI ranks (default $SLURM_NTASKS, else 1)")
    p.add_argument("--retry-unstable", action="store_true")
    p.set_defaults(func=cmd_run_case)

    p = subparsers.add_parser("status", help="list the cases of a study folder and their state")
    p.add_argument("study", type=Path, help="study folder")
    p.set_defaults(func=cmd_status)

"""``ligwf report STUDY`` and ``ligwf study WORKFLOW`` (run + analyse + report).

``study`` is the one reproducible command of a CG study: it renders and runs every case
(resuming what is already done), identifies granules and GSDs, computes the flow metrics
and writes the report folder, even when some cases failed (they are listed, not used).
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

from rich.console import Console

console = Console()


def cmd_report(args: argparse.Namespace) -> int:
    from ligwf.report.write import write_report

    out = write_report(args.study, args.out, snapshots=not args.no_snapshots,
                       steady_after=args.steady_after)
    console.print(f"report: {out / 'summary.md'} and {out / 'index.html'}")
    return 0


def _discard_frames(study: Path, steady_after: float) -> int:
    """Frames of the start-up part of production, left out of the GSD like the flow stage."""
    from ligwf.analysis.dumps import discover_frames
    from ligwf.cli.run import study_case_dirs

    counts = [len(discover_frames(d)) for d in study_case_dirs(study) if (d / "post").is_dir()]
    counts = [c for c in counts if c]
    return math.floor(steady_after * min(counts)) if counts else 0


def cmd_study(args: argparse.Namespace) -> int:
    from ligwf.analysis.runner import AnalysisOptions, analyse
    from ligwf.cli.run import cmd_run
    from ligwf.report.write import write_report

    run_status = cmd_run(args)
    analyse(args.out, options=AnalysisOptions(discard_frames=_discard_frames(args.out,
                                                                             args.steady_after)))
    out = write_report(args.out, None, snapshots=not args.no_snapshots,
                       steady_after=args.steady_after)
    console.print(f"report: {out / 'summary.md'} and {out / 'index.html'}")
    return run_status


def _report_options(p: argparse.ArgumentParser) -> None:
    p.add_argument("--steady-after", type=float, default=0.25, metavar="FRACTION",
                   help="leave this fraction of the production time out as start-up "
                   "(default 0.25)")
    p.add_argument("--no-snapshots", action="store_true",
                   help="skip the pyvista snapshots (the slowest figures)")


def register(subparsers) -> None:
    """Add ``report`` and ``study``."""
    from ligwf.cli.main import add_workflow_args

    p = subparsers.add_parser("report", help="tables, figures and ParaView files of a finished study")
    p.add_argument("study", type=Path, help="study folder (study.json)")
    p.add_argument("--out", type=Path, default=None, help="report folder (default STUDY/report)")
    _report_options(p)
    p.set_defaults(func=cmd_report)

    p = subparsers.add_parser("study", help="run + analyse + report a workflow in one command")
    add_workflow_args(p)
    p.add_argument("--out", type=Path, required=True, help="study folder")
    p.add_argument("--np", type=int, default=1, help="MPI ranks per case (default 1)")
    p.add_argument("--ensemble", type=int, default=0, metavar="P",
                   help="run all cases in ONE mpirun -np P (see ligwf run)")
    p.add_argument("--retry-unstable", action="store_true")
    p.add_argument("--mesh-cache", type=Path, default=None)
    _report_options(p)
    p.set_defaults(func=cmd_study)

"""``ligwf report STUDY`` and ``ligwf study WORKFLOW`` (run + analyse + report).

``study`` is the one reproducible command of a CG study: it prepares (pre-flight first),
renders and runs every case (resuming what is already done), then post-processes the
study with its stored analysis settings (:func:`ligwf.study.pipeline.postprocess`: the
granule analysis, then the flow metrics and the report folder), even when some cases
failed (they are listed, not used).
"""

from __future__ import annotations

import argparse
from pathlib import Path

from ligwf.cli.common import add_workflow_args, console, err_console
from ligwf.cli.run import add_run_args, prepare_and_run
from ligwf.study.pipeline import postprocess, report_study
from ligwf.study.study import Study


def _print_report(study_dir: Path, out: Path) -> None:
    """Where the report is, and on stderr how much it lists as not used."""
    from ligwf.report.problems import study_problems

    console.print(f"report: {out / 'summary.md'} and {out / 'index.html'}")
    p = study_problems(Study.open(study_dir))
    if p.count:
        err_console.print(f"[yellow]ligwf: warning:[/] the report lists {len(p.cases)} skipped "
                          f"case(s), {len(p.frames)} skipped or missing frame(s) and "
                          f"{len(p.outputs)} analysis output problem(s) (see summary.md)",
                          highlight=False)


def cmd_report(args: argparse.Namespace) -> int:
    _print_report(args.study, report_study(args.study, args.out, snapshots=not args.no_snapshots))
    return 0


def cmd_study(args: argparse.Namespace) -> int:
    study, done = prepare_and_run(args)
    _, out = postprocess(study.path, snapshots=not args.no_snapshots)
    _print_report(study.path, out)
    return 0 if done else 1


def _add_snapshots(p: argparse.ArgumentParser) -> None:
    p.add_argument("--no-snapshots", action="store_true",
                   help="skip the pyvista snapshots (the slowest figures)")


def register(subparsers) -> None:
    """Add ``report`` and ``study``."""
    p = subparsers.add_parser("report", help="flow metrics, tables, figures and ParaView files "
                              "of a finished study (steady window from its analysis settings)")
    p.add_argument("study", type=Path, help="study folder")
    p.add_argument("--out", type=Path, default=None, help="report folder (default STUDY/report)")
    _add_snapshots(p)
    p.set_defaults(func=cmd_report)

    p = subparsers.add_parser("study", help="run + analyse + report a workflow in one command")
    add_workflow_args(p)
    add_run_args(p)
    _add_snapshots(p)
    p.set_defaults(func=cmd_study)

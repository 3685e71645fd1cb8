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

from ligwf.cli.common import add_workflow_args, console
from ligwf.cli.run import add_run_args, prepare_and_run
from ligwf.study.pipeline import postprocess, report_study


def _print_report(out: Path) -> None:
    console.print(f"report: {out / 'summary.md'} and {out / 'index.html'}")


def cmd_report(args: argparse.Namespace) -> int:
    _print_report(report_study(args.study, args.out, snapshots=not args.no_snapshots))
    return 0


def cmd_study(args: argparse.Namespace) -> int:
    study, done = prepare_and_run(args)
    _, out = postprocess(study.path, snapshots=not args.no_snapshots)
    _print_report(out)
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

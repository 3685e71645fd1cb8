"""``ligwf study WORKFLOW``: run + analyse + report in one command.

``study`` is the one reproducible command of a CG study: it prepares (pre-flight first),
renders and runs every case (resuming what is already done), then post-processes the
study with its stored analysis settings (:func:`ligwf.pipeline.post.postprocess`: the
granule analysis, then the flow metrics and the report folder), even when some cases
failed (they are listed, not used). The chain is :mod:`ligwf.pipeline`; this module parses
and prints.
"""

from __future__ import annotations

import argparse

from ligwf.cli.common import add_workflow_args
from ligwf.cli.report import add_snapshots, print_report
from ligwf.cli.run import add_run_args, run_with_progress, start_from_args
from ligwf.pipeline.post import postprocess


def cmd_study(args: argparse.Namespace) -> int:
    run = start_from_args(args)
    done = run_with_progress(run, args)
    _, out = postprocess(run.study.path, snapshots=not args.no_snapshots)
    print_report(run.study.path, out)
    return 0 if done else 1


def register(subparsers) -> None:
    """Add ``study``."""
    p = subparsers.add_parser("study", help="run + analyse + report a workflow in one command")
    add_workflow_args(p)
    add_run_args(p)
    add_snapshots(p)
    p.set_defaults(func=cmd_study)

"""``ligwf study WORKFLOW``: run + analyse + report in one command.

``study`` is the one reproducible command of a CG study: it prepares (pre-flight first),
renders and runs every case (resuming what is already done), then post-processes the
study with its stored analysis settings (:func:`ligwf.pipeline.post.postprocess`: the
granule analysis, then the flow metrics and the report folder), even when some cases
failed (they are listed, not used). With ``--until-decided`` it goes on in rounds
(:mod:`ligwf.pipeline.rounds`): after each look it extends the runs or adds the replicas
that decide the cheapest level that can still pass, until it is decided, the looks
(``--max-looks``) are spent or the cap (``--max-core-hours``) is reached; WORKFLOW may
then also be a study folder (its stored workflow is used), on any executor. ``--executor`` picks what runs
it (:mod:`ligwf.executors`): ``local`` (the default) runs it here and now; a batch
scheduler (``--executor slurm``, also spelt ``ligwf slurm submit``) writes the study and
submits it with its post-processing, or its first round and the follow-up job that takes
each look, and returns. The chain is :mod:`ligwf.pipeline`; this module parses and prints.
"""

from __future__ import annotations

import argparse

from ligwf.cli.common import (add_until_decided_args, add_workflow_args, console,
                              prepare_from_args, stop_on_signals)
from ligwf.cli.executors import SUBMIT_STUDY, add_executor_arg, checked_executor
from ligwf.cli.report import add_snapshots, print_report, show_look
from ligwf.cli.slurm import add_site_args
from ligwf.cli.run import add_run_args, run_with_progress, start_from_args
from ligwf.engine.progress import RichMonitor, summary_table
from ligwf.errors import ConfigError
from ligwf.pipeline.post import postprocess
from ligwf.pipeline.rounds import RoundPlan, until_decided
from ligwf.executors import LOCAL, build_executor
from ligwf.local import run_settings
from ligwf.pipeline.run import StudyRun
from ligwf.study.layout import REPORT_DIR


def cmd_study(args: argparse.Namespace) -> int:
    name = checked_executor(args)       # before anything is read or written
    if name != LOCAL:
        return SUBMIT_STUDY[name](args)
    if args.until_decided:
        return cmd_until_decided(args)
    run = start_from_args(args)
    done = run_with_progress(run, args)
    _, out = postprocess(run.study.path, run.executor, snapshots=not args.no_snapshots)
    print_report(run.study.path, out)
    return 0 if done else 1


def cmd_until_decided(args: argparse.Namespace) -> int:
    if args.extend_production:
        raise ConfigError(f"--extend-production = {args.extend_production:g}: not with "
                          "--until-decided (its rounds choose the production); run "
                          "'ligwf study' without it first")
    prepared = prepare_from_args(args)      # WORKFLOW, or a study folder's stored one
    settings = run_settings(args.np, args.ensemble, args.cores, args.retry_unstable,
                            args.templates)

    def run_round(run: StudyRun) -> bool:
        with stop_on_signals() as stop, RichMonitor(console) as monitor:
            done = run.run(monitor, stop)
        console.print(summary_table(run.study.cases, f"{run.study.name}: {args.out}"))
        return done

    rounds = until_decided(prepared, args.out, build_executor(LOCAL, settings),
                           RoundPlan(args.max_looks, args.max_core_hours, args.every_level),
                           run_round,
                           show_look, args.mesh_cache, snapshots=not args.no_snapshots,
                           replace=args.replace)
    if not rounds.stopped:
        console.print("some cases did not finish (see the table): the same command resumes "
                      "them and goes on with the rounds")
        return 1
    print_report(args.out, args.out / REPORT_DIR)
    return 0


def register(subparsers) -> None:
    """Add ``study``."""
    p = subparsers.add_parser("study", help="run + analyse + report a workflow in one command")
    add_workflow_args(p)
    add_executor_arg(p, "the cases and the post-processing")
    add_run_args(p, cores_help="local: cores the rank plan fills (default: the tasks of the "
                 "Slurm allocation this runs in, else the CPUs this process may use); on a "
                 "scheduler: most ranks the rank plan gives one case (default: no limit "
                 "besides the slab rule and particles per rank)")
    add_snapshots(p)
    add_until_decided_args(p)
    add_site_args(p.add_argument_group("with --executor slurm (as 'ligwf slurm submit')"),
                  cores=False)
    p.set_defaults(func=cmd_study)

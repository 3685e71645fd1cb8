"""``ligwf study WORKFLOW``: run + analyse + report in one command.

``study`` is the one reproducible command of a CG study: it prepares (pre-flight first),
renders and runs every case (resuming what is already done), then post-processes the
study with its stored analysis settings (:func:`ligwf.pipeline.post.postprocess`: the
granule analysis, then the flow metrics and the report folder), even when some cases
failed (they are listed, not used). With ``--until-decided`` it goes on in rounds
(:mod:`ligwf.pipeline.rounds`): after each look it extends the runs or adds the replicas
that decide the cheapest level that can still pass, until it is decided, the looks
(``--max-looks``) are spent or the cap (``--max-core-hours``) is reached; WORKFLOW may
then also be a study folder (its stored workflow is used). The chain is
:mod:`ligwf.pipeline`; this module parses and prints.
"""

from __future__ import annotations

import argparse
import math
from functools import partial

from rich.table import Table

from ligwf.cli.common import (add_workflow_args, console, grouped_warnings, number_in,
                              positive_int, prepare_from_args, print_warning, stop_on_signals)
from ligwf.cli.report import add_snapshots, print_report
from ligwf.cli.run import add_run_args, run_with_progress, start_from_args
from ligwf.engine.progress import RichMonitor, summary_table
from ligwf.errors import ConfigError
from ligwf.pipeline.post import postprocess
from ligwf.pipeline.rounds import RoundPlan, prepare_study_folder, until_decided
from ligwf.local import LocalExecutor, run_settings
from ligwf.pipeline.run import StudyRun
from ligwf.report.rounds import look_line
from ligwf.study.layout import REPORT_DIR, is_study_folder
from ligwf.study.rounds import Look, Rounds


def cmd_study(args: argparse.Namespace) -> int:
    if args.until_decided:
        return cmd_until_decided(args)
    run = start_from_args(args)
    done = run_with_progress(run, args)
    _, out = postprocess(run.study.path, run.executor, snapshots=not args.no_snapshots)
    print_report(run.study.path, out)
    return 0 if done else 1


def show_look(look: Look, rounds: Rounds) -> None:
    """A look on the terminal: every interval against its budget, the half-width beside
    the previous look's (the intervals shrinking), then what the next round does."""
    before = {(c["condition"], c["criterion"]): c for x in rounds.looks
              if x.number == look.number - 1 for c in x.criteria}
    table = Table(title=f"look {look.number} of at most {rounds.max_looks}", box=None)
    for col in ("condition", "criterion", "state", "value [interval]", "half-width",
                "previous", "budget"):
        table.add_column(col)
    for c in look.criteria:
        lo, hi = c.get("lo"), c.get("hi")
        half = 0.5 * (hi - lo) if lo is not None and hi is not None and math.isfinite(lo) \
            and math.isfinite(hi) else math.nan
        p = before.get((c["condition"], c["criterion"]))
        prev = (0.5 * (p["hi"] - p["lo"]) if p and p.get("lo") is not None
                and p.get("hi") is not None else math.nan)
        band = (f"{c['value']:.3g} [{lo:.3g}, {hi:.3g}]" if math.isfinite(half)
                else f"{c.get('value', math.nan):.3g}")
        table.add_row(c["condition"], c["label"], c["state"], band,
                      f"{half:.3g}" if math.isfinite(half) else "–",
                      f"{prev:.3g}" if math.isfinite(prev) else "–",
                      f"{c.get('budget', math.nan):.3g}")
    console.print(table)
    console.print(look_line(look), highlight=False, soft_wrap=True)


def cmd_until_decided(args: argparse.Namespace) -> int:
    if args.extend_production:
        raise ConfigError(f"--extend-production = {args.extend_production:g}: not with "
                          "--until-decided (its rounds choose the production); run "
                          "'ligwf study' without it first")
    if is_study_folder(args.workflow):
        prepared = prepare_study_folder(args.workflow, args.overrides, args.templates,
                                        args.allow_unstable)
        for line in grouped_warnings(prepared.warnings,
                                     [rc.case.case_id for rc in prepared.rendered]):
            print_warning(line)
    else:
        prepared = prepare_from_args(args)
    settings = run_settings(args.np, args.ensemble, args.cores, args.retry_unstable,
                            args.templates)

    def run_round(run: StudyRun) -> bool:
        with stop_on_signals() as stop, RichMonitor(console) as monitor:
            done = run.run(monitor, stop)
        console.print(summary_table(run.study.cases, f"{run.study.name}: {args.out}"))
        return done

    rounds = until_decided(prepared, args.out, LocalExecutor(settings),
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
    add_run_args(p)
    add_snapshots(p)
    p.add_argument("--until-decided", action="store_true",
                   help="go on in rounds (longer production or more replicas, the cheapest "
                   "that decides) until the cheapest level that can still pass is decided; "
                   "WORKFLOW may be a study folder")
    p.add_argument("--max-looks", type=partial(positive_int, unit="looks"), default=3,
                   help="with --until-decided: looks at most (each tests at 0.05 / looks; "
                   "default 3)")
    p.add_argument("--max-core-hours", type=number_in(1e-6, 1e9, "core-h"), default=None,
                   metavar="H", help="with --until-decided: stop before a round would take "
                   "the study's runs past H core-hours")
    p.add_argument("--every-level", action="store_true",
                   help="with --until-decided: the rounds work on the undecided criteria of "
                   "every CG level (a ladder: each level's error decided), not only on the "
                   "cheapest level that can still pass")
    p.set_defaults(func=cmd_study)

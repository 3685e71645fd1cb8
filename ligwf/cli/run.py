"""Command line of the run stage: ``ligwf run``, ``ligwf run-case``, ``ligwf status``,
``ligwf cancel``.

``run`` prepares a workflow into a study folder (identical cases are rewritten byte for
byte, so their outputs stay) and runs every case that is not finished. By default the rank
planner (:mod:`ligwf.engine.plan`) decides: ranks per case from its particle count and the
axial slab rule, single-rank cases side by side in one MPI ensemble, bigger ones on several
ranks, longest first, on the cores of this machine or allocation (``--cores`` to say
otherwise); the plan is printed before the run. ``--np K`` runs every case on K ranks one
after the other, ``--ensemble P`` all of them in one ``mpirun -np P`` (groups of ``--np``,
default 1), as before. Running the same command again resumes (see
:mod:`ligwf.engine.resume`). The chain is :mod:`ligwf.pipeline.run`; this module parses
and prints.
``run-case`` runs case number I of a rendered study folder with the same runner (what a
Slurm array task calls).
"""

from __future__ import annotations

import argparse
from pathlib import Path

from ligwf.cli.common import (add_cores_arg, add_mesh_cache, add_replace_arg,
                              add_workflow_args, console, number_in,
                              folder_to_write, plan_table, prepare_from_args,
                              print_warning, rank_count, stop_on_signals)
from ligwf.engine.progress import RichMonitor, summary_table
from ligwf.cli.executors import CANCEL, SHOW_STATUS, add_executor_arg
from ligwf.eligibility import HELD, analysis_due, eligible
from ligwf.executors import LOCAL, build_executor, executor_kind
from ligwf.local import run_settings
from ligwf.pipeline.run import StudyRun, run_case_of, start_run
from ligwf.scheduler import queued_tasks
from ligwf.study.study import Study


def start_from_args(args: argparse.Namespace) -> StudyRun:
    """Prepare (pre-flight first), write and schedule the workflow of ``args``, and print
    the rank plan (``run`` and ``study``)."""
    prepared = prepare_from_args(args)
    settings = run_settings(args.np, args.ensemble, args.cores, args.retry_unstable,
                            args.templates)
    run = start_run(prepared, args.out, settings, args.mesh_cache, args.replace,
                    args.extend_production)
    title = (f"rank plan for {settings.cores} core(s) ({settings.cores_source})"
             if settings.planned else "ranks as asked (--np / --ensemble)")
    console.print(plan_table(run.schedule, title))
    console.print(run.identity.describe(), highlight=False, soft_wrap=True)
    for c in run.study.cases:
        if c.extension_steps:
            console.print(f"{c.path.name}: production {c.extension_steps * c.scaled.numerics.dt:.3g} s "
                          f"longer than rendered ({c.scaled.numerics.run_steps} production steps)",
                          highlight=False, soft_wrap=True)
    for line in elsewhere(run.study.cases, settings.retry_unstable):
        console.print(line, highlight=False, soft_wrap=True)
    for line in skipped_restarts(run.study.cases, settings.retry_unstable):
        print_warning(line)
    return run


def elsewhere(cases, retry_unstable: bool) -> list[str]:
    """The cases another live ligwf process is running (left to it, not in the plan)."""
    return [f"{t.case.path.name}: {t.reason}: left to that runner"
            for t in eligible(cases, retry_unstable).tasks if t.need is HELD]


def skipped_restarts(cases, retry_unstable: bool) -> list[str]:
    """The restart files a case to be resumed or extended does not use (unreadable: killed
    while writing or a full disk; or not its own: another case's, edited, past its
    recorded progress), each with what the case does instead: said here, one line each,
    and recorded in its manifest's issues by the runner (:class:`ligwf.engine.resume.NextAttempt`)."""
    from ligwf.engine.resume import SKIP, plan_case

    out = []
    for c in cases:
        plan = plan_case(c, retry_unstable)
        if plan.action != SKIP:
            out += [f"{c.path.name}: {line}" for line in plan.skipped]
    return out


def run_with_progress(run: StudyRun, args: argparse.Namespace) -> bool:
    """Run a started study with live progress, then print its case table."""
    with stop_on_signals() as stop, RichMonitor(console) as monitor:
        done = run.run(monitor, stop)
    console.print(summary_table(run.study.cases, f"{run.study.name}: {args.out}"))
    return done


def cmd_run(args: argparse.Namespace) -> int:
    return 0 if run_with_progress(start_from_args(args), args) else 1


def cmd_run_case(args: argparse.Namespace) -> int:
    study = Study.open(args.study)
    case = study.case(args.index)
    with stop_on_signals() as stop, RichMonitor(console) as monitor:
        done = run_case_of(study, case, args.np, args.retry_unstable, monitor, stop)
    console.print(summary_table([case], f"case {args.index}"))
    return 0 if done else 1


def cmd_status(args: argparse.Namespace) -> int:
    if (name := executor_kind(args.executor).name) != LOCAL:
        return SHOW_STATUS[name](args.study)
    study = Study.open(args.study)
    console.print(summary_table(study.cases, f"{args.study}: {len(study.cases)} case(s)"))
    for case in study.cases:             # an edited record: its results are not used
        if (why := case.record_problem(check_hash=False)) is not None:
            print_warning(f"{case.case_id}: {why}")
    st = build_executor(LOCAL).status(args.study)
    held = [c for c in st.cases if c.queued]
    for runner in sorted({c.job for c in held}):
        names = [c.case_id for c in held if c.job == runner]
        console.print(f"running in ligwf process {runner}: {', '.join(names)}",
                      highlight=False, soft_wrap=True)
    for line in needs_lines(study, queued_tasks(st)):
        console.print(line, highlight=False, soft_wrap=True)
    return 0


def needs_lines(study: Study, queued: dict[int, str]) -> list[str]:
    """What each case that is not done needs next (:func:`ligwf.eligibility.eligible`: the
    same word ``ligwf status --executor slurm`` shows, and what the same run command does
    with it; ``queued``: the cases a runner holds) and whether the analysis is due."""
    lines = [f"{t.case.case_id}: next {t.need} ({t.reason})"
             for t in eligible(study.cases, queued=queued).not_done]
    why = analysis_due(study)
    return lines + [f"analysis due: {why}" if why else
                    "analysis: holds for the study (its record, cases, dumps, settings)"]


def cmd_cancel(args: argparse.Namespace) -> int:
    """SIGTERM the live runners of a study on this machine (the local executor's cancel);
    another executor's cancel with ``--executor``."""
    if (name := executor_kind(args.executor).name) != LOCAL:
        return CANCEL[name](args.study)
    Study.open(args.study)          # a folder that is no study: one line, nothing sent
    sent = build_executor(LOCAL).cancel(args.study)
    if not sent:
        console.print(f"{args.study}: no live ligwf runner on this machine holds a case",
                      highlight=False)
        return 0
    console.print(f"sent SIGTERM to the ligwf runner(s) {', '.join(sent)}: their engines write "
                  "forced restarts and the cases end killed; the same run command resumes "
                  "them", highlight=False, soft_wrap=True)
    return 0


def add_run_args(p: argparse.ArgumentParser, cores_help: str | None = None) -> None:
    """The options of the run stage (``run`` and ``study``; ``cores_help``: what
    ``--cores`` means there)."""
    p.add_argument("--out", type=folder_to_write, required=True, help="study folder")
    p.add_argument("--np", type=rank_count, default=None,
                   help="MPI ranks for every case, one case after the other (default: the "
                   "rank plan, see 'ligwf check')")
    p.add_argument("--ensemble", type=rank_count, default=0, metavar="P",
                   help="run all cases in ONE mpirun -np P, P/np cases at a time (np "
                   "default 1; overrides the rank plan)")
    add_cores_arg(p, cores_help)
    p.add_argument("--retry-unstable", action="store_true",
                   help="also re-run cases found unstable before")
    add_mesh_cache(p)
    add_replace_arg(p)
    p.add_argument("--extend-production", type=number_in(0, 1e4, "s"), default=0.0,
                   metavar="S", help="every case's production S seconds longer than the "
                   "workflow's run_time, done cases continued from their restarts (the fix "
                   "the verdict names for runs too short to show a steady state); repeating "
                   "it changes nothing")


def register(subparsers) -> None:
    """Add ``run``, ``run-case``, ``status`` and ``cancel`` to the ligwf command line."""
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
    add_executor_arg(p, "the cases: whose view is shown beside the manifests")
    p.set_defaults(func=cmd_status)

    p = subparsers.add_parser("cancel", help="stop the ligwf runners of a study folder on this "
                              "machine (SIGTERM: forced restarts, cases killed; the same run "
                              "command resumes them)")
    p.add_argument("study", type=Path, help="study folder")
    add_executor_arg(p, "the cases: what is stopped")
    p.set_defaults(func=cmd_cancel)

"""``ligwf slurm submit | status | resubmit | cancel``: run a study as Slurm job arrays.

``submit`` prepares the workflow exactly as ``ligwf study`` does -- validation, rendering
and the stability pre-flight (``--allow-unstable`` overrides it) before anything is
written or submitted -- writes the same folders, one array script with one task per case
(each runs ``ligwf run-case STUDY --index I``, the local runner with its manifests, health
checks and resume) plus an analysis job that depends on the array (``afterany``) and runs
the same post-processing as ``ligwf study`` (:data:`ligwf.pipeline.post.POSTPROCESS_COMMANDS`,
with the analysis settings stored in the study), and submits both. Each case's ranks
(``--ntasks`` of its array task) come from the rank plan (:mod:`ligwf.engine.plan`: particle
count and axial slab rule, at most ``--cores`` if given): one array per rank count, the
analysis job after all of them; ``--ntasks`` or the site's ``ntasks`` put every case on that
many ranks in one array, as before. With ``--cores-per-node`` (or the site's
``cores_per_node``) a planned case also asks for ceil(ranks / cores per node) nodes. The
plan is printed (:mod:`ligwf.slurm.walltime`): per case (replicas alike share a row) its
particles, steps, ranks and what bound them, nodes, the estimated wall time against
``--time``, with a warning for each case the estimate says would outlive its ``--time``.
``--dry-run`` prints the plan, what it assumed about the site (MPI launcher, cores per node,
partition limits: :mod:`ligwf.slurm.assumptions`), the scripts and the sbatch commands and
writes nothing.
``status`` joins the runner's manifests with squeue/scontrol and says what each case needs
next (:func:`ligwf.eligibility.eligible`) and whether the analysis is due; ``resubmit``
submits new arrays with exactly the cases that need running -- missing, failed, killed,
re-rendered, or done with their production extended since (a planned submission is
planned again); ``cancel`` scancels the study's queued and running jobs (the runners write
forced restarts, so ``resubmit`` resumes them). The chain is :mod:`ligwf.pipeline.submit`
over :class:`ligwf.slurm.scheduler.SlurmScheduler`; this module parses and prints.
"""

from __future__ import annotations

import argparse
import json
import shlex
from dataclasses import asdict
from functools import partial
from pathlib import Path

from rich.console import Group
from rich.markup import escape
from rich.table import Table
from rich.text import Text

from ligwf.cli.common import (add_cores_arg, add_mesh_cache, add_replace_arg,
                              add_until_decided_args, add_workflow_args, case_table,
                              console, duration, err_console, folder_to_write, positive_int,
                              prepare_from_args, print_warning, rank_count)
from ligwf.cli.report import add_snapshots
from ligwf.cli.slurm_rounds import (NEXT_ROUND_HELP, add_next_round_args, dry_run_note,
                                    follow_up_of, next_round, print_submitted,
                                    resubmit_rounds, submit_until_decided)
from ligwf.eligibility import EXTEND, analysis_due, eligible
from ligwf.engine.plan import RankPlan
from ligwf.engine.progress import shown_reason
from ligwf.engine.site import EngineConfig
from ligwf.errors import ConfigError
from ligwf.pipeline.prepare import prepared_loads
from ligwf.pipeline.submit import (plan_resubmission, plan_split_analysis, plan_submission,
                                   write_for_submit)
from ligwf.slurm.assumptions import site_assumptions
from ligwf.slurm.walltime import (PlanRow, estimate_basis, hours_minutes, over_time_warning,
                                plan_rows, slab_note, slurm_time_seconds)
from ligwf.pipeline.submit_rounds import NEXT_ROUND, is_sequential
from ligwf.executors import build_executor, executor_kind, study_executor
from ligwf.slurm.jobs import PlannedJob, dry_run_text, read_record, study_status
from ligwf.slurm.site import SlurmSite, load_slurm_site, ntasks_configured
from ligwf.scheduler import queued_tasks
from ligwf.study import layout
from ligwf.study.ownership import other_study
from ligwf.study.study import Study


#: this module's executor in the registry (:mod:`ligwf.executors`)
SLURM = "slurm"


def add_site_args(p: argparse.ArgumentParser, cores: bool = True) -> None:
    """The Slurm site options (``cores``: with ``--cores``, which ``ligwf study`` has of
    its own)."""
    p.add_argument("--partition", help="Slurm partition (default: site setting)")
    p.add_argument("--account", help="Slurm account (default: site setting)")
    p.add_argument("--time", help="wall time per case, e.g. 02:00:00 (default: site setting)")
    p.add_argument("--ntasks", type=rank_count,
                   help="MPI ranks for every case (default: site setting, else the rank plan)")
    if cores:
        add_cores_arg(p, "most ranks the rank plan gives one case, e.g. a node's cores "
                      "(default: no limit besides the slab rule and particles per rank)")
    p.add_argument("--cores-per-node", type=partial(positive_int, unit="cores"), metavar="N",
                   help="cores of one node: a planned case asks for ceil(ranks / N) nodes "
                   "(default: site setting, else unknown and Slurm places the ranks)")
    p.add_argument("--max-concurrent", type=positive_int, metavar="K",
                   help="at most K cases at once (--array=...%%K)")
    p.add_argument("--no-analysis", action="store_true",
                   help="do not submit the dependent analysis job")
    p.add_argument("--analysis-tasks", type=positive_int, default=1, metavar="N",
                   help="split the analysis over an array of N tasks after the cases, merged "
                   "by a job that then writes the report: the tables of one analysis job "
                   "(default 1: one job; for big studies, see 'ligwf analyse --executor slurm')")
    p.add_argument("--dry-run", action="store_true",
                   help="print the scripts and sbatch commands; submit and write nothing")


def site_from_args(args: argparse.Namespace, base: SlurmSite) -> SlurmSite:
    return base.with_overrides(partition=args.partition, account=args.account, time=args.time,
                               ntasks=args.ntasks, max_concurrent=args.max_concurrent,
                               cores_per_node=args.cores_per_node)


def _warn(lines: list[str]) -> None:
    for line in lines:
        print_warning(line)


def plan_caption(plans: tuple[RankPlan, ...], jobs: list[PlannedJob], rows: tuple[PlanRow, ...],
                 site: SlurmSite) -> list[str]:
    """How the arrays split the cases, where the nodes come from, the slab limits and the
    estimated total cost."""
    lines = [f"{job.script_path.name}: {len(job.indices)} case(s), --ntasks="
             f"{job.site.ntasks if job.site else '?'}"
             + (f", --nodes={job.nodes}" if job.nodes is not None else "")
             for job in jobs if job.kind == "array"]
    planned = any(job.planned for job in jobs)
    if site.cores_per_node is None:
        lines.append("nodes ?: cores per node unknown (give --cores-per-node N or the site's "
                     "slurm cores_per_node); the scripts ask for --ntasks only")
    elif planned:
        lines.append(f"nodes = ceil(ranks / {site.cores_per_node} cores per node), asked for "
                     "with --nodes")
    else:
        lines.append(f"nodes = ceil(ranks / {site.cores_per_node} cores per node), not asked "
                     "for: on --ntasks / site ntasks the scripts ask for --ntasks only")
    lines += [slab_note(row) for row in rows if row.slab_bound] + estimate_basis(rows)
    if any(len(row.cases) > 1 for row in rows):
        lines.append("'+N more': N more replicas of that CG level and rule, same load and plan")
    core_hours = sum(p.ranks * p.estimated_seconds for p in plans) / 3600
    longest = max((p.estimated_seconds for p in plans), default=0.0)
    lines.append(f"estimated {core_hours:.3g} core-hours in all, longest case "
                 f"~{duration(longest)} (rates measured on a 2-core machine: "
                 "ligwf.engine.plan; --time is per case)")
    if site.time is None:
        lines.append("no --time (nor site time): the partition's default limit applies")
    return lines


def slurm_plan_table(rows: tuple[PlanRow, ...], title: str, time: str | None,
                     notes: list[str]) -> Group:
    """The Slurm plan: per row its case(s), load, ranks and their bound, nodes, estimated
    wall time and the ``--time`` each array task asks for; ``notes`` below, one a line.
    (The first four columns are those of ``ligwf check``'s rank plan.)"""
    limit = slurm_time_seconds(time)
    table = Table(title=title)
    for col in ("case", "particle-steps", "ranks", "limited by", "nodes", "est. wall (h:mm)",
                "--time", "particles", "steps"):
        table.add_column(col, justify="left" if col in ("case", "limited by") else "right")
    for row in rows:
        table.add_row(row.label, f"{row.load.particle_steps:.3g}", str(row.ranks), row.bound,
                      "?" if row.nodes is None else str(row.nodes),
                      hours_minutes(row.estimated_seconds),
                      (time or "-") + (" (too short)" if row.exceeds(limit) else ""),
                      f"{row.load.particles:,}", f"{row.load.steps:,}")
    return Group(table, *(Text(line) for line in notes))


def cmd_submit(args: argparse.Namespace) -> int:
    """``ligwf study --executor slurm`` (``ligwf slurm submit``): write the study and submit
    it (round 1 of a study ``--until-decided``), or with ``--dry-run`` show what would be."""
    prepared = prepare_from_args(args)      # pre-flight before anything is written
    wf, rendered = prepared.workflow, prepared.rendered
    site = site_from_args(args, load_slurm_site())
    scheduler = build_executor(SLURM, site)
    fixed = args.ntasks is not None or ntasks_configured()   # every case on site.ntasks ranks
    rounds = follow_up_of(args, not fixed, args.cores)      # None: no --until-decided
    submission = plan_submission(prepared, args.out.resolve(), scheduler, args.cores,
                                 site.ntasks if fixed else None, not args.no_analysis,
                                 args.analysis_tasks, rounds.steps if rounds else None,
                                 1 if rounds else None)
    plans, jobs = submission.schedule.cases, list(submission.jobs)
    title = ("rank plan" + (f" (at most {args.cores} per case)" if args.cores else "")
             if submission.planned else "ranks as asked (--ntasks / site ntasks)")
    groups = [(rc.scaled.cg, rc.scaled.rule) for rc in rendered]    # replicas share a row
    rows = plan_rows(prepared_loads(prepared), plans, groups, site.cores_per_node)
    plan_view = slurm_plan_table(rows, title, site.time, plan_caption(plans, jobs, rows, site))
    limit = slurm_time_seconds(site.time)
    over_time = [over_time_warning(row, site.time) for row in rows if row.exceeds(limit)]
    if args.dry_run:
        if not args.replace and (why := other_study(submission.out, wf.name, wf.raw)):
            raise ConfigError(why)          # what the submission would refuse
        console.print(case_table(prepared, f"{wf.name}: {len(rendered)} case(s) (dry run)"))
        console.print(plan_view)
        _warn(over_time)
        engine = EngineConfig.from_site()
        print("\n".join(site_assumptions(site, jobs, shlex.join([engine.mpirun,
                                                                  *engine.mpirun_args]))))
        print(dry_run_text(jobs))
        if rounds:
            print(dry_run_note(args, submission.out))
        return 0
    write_for_submit(prepared, submission, scheduler, args.mesh_cache, args.replace)
    console.print(case_table(prepared, f"{wf.name}: {len(rendered)} case(s) -> {submission.out}"))
    console.print(plan_view)
    _warn(over_time)
    if rounds:      # the rounds record first, then round 1 (or what an earlier study asks)
        return submit_until_decided(args, prepared, submission.out, scheduler, rounds)
    print_submitted(submission.submit(scheduler))
    return 0


def submit_analysis(args: argparse.Namespace, count: int) -> int:
    """``ligwf analyse STUDY --executor slurm --tasks N`` (``--slurm N``): plan (and unless
    ``--dry-run`` submit) the analysis array of ``count`` shares and its merge job; returns
    once they are submitted (the token and the logs printed)."""
    scheduler = build_executor(SLURM)
    split = plan_split_analysis(Study.open(args.run_dir), scheduler, count)
    if args.dry_run:
        print(dry_run_text(list(split.jobs)))
        return 0
    scheduler.require()
    entries = split.submit(scheduler)
    array, merge = entries[0]["job_id"], entries[-1]["job_id"]
    print(f"submitted analysis array {array} ({count} task(s)) and merge job {merge} "
          f"(token {split.token}); logs in {split.study_dir / layout.SLURM_LOG_DIR}")
    return 0


def status_table(study_dir: Path) -> tuple[Table, dict]:
    """Each case's manifest, its latest task and what it needs next
    (:func:`ligwf.eligibility.eligible`, what a resubmit runs: unknown while Slurm cannot
    be asked), and why the analysis is due (None: it holds)."""
    st = study_status(study_dir, tolerant=True)
    study = Study.open(study_dir)
    needs = ({} if st.scheduler_error else
             {t.case.index: t.need.value for t in eligible(study.cases,
                                                           queued=queued_tasks(st)).tasks})
    table = Table(title=f"{study_dir}")
    for col in ("index", "case", "manifest", "next", "slurm task", "slurm state", "reason"):
        table.add_column(col)
    counts: dict[str, int] = {}
    for c in st.cases:
        counts[c.manifest] = counts.get(c.manifest, 0) + 1
        table.add_row(str(c.index), c.case_id, c.manifest, needs.get(c.index, "?"),
                      c.job or "-", c.slurm_state or "-",
                      shown_reason(c.manifest, c.reason)[:60])
    data = {"cases": [{**asdict(c), "next": needs.get(c.index)} for c in st.cases],
            "jobs": st.jobs, "counts": counts, "scheduler_error": st.scheduler_error,
            "analysis_due": analysis_due(study)}
    return table, data


def cmd_status(args: argparse.Namespace) -> int:
    return show_status(args.study_dir, args.json)       # = ligwf status --executor slurm


def show_status(study_dir: Path, as_json: bool = False) -> int:
    """Each case's manifest, its Slurm task and what it needs next, the follow-up jobs,
    the counts and whether the analysis is due (``as_json``: all of it as JSON)."""
    table, data = status_table(study_dir)
    if as_json:
        print(json.dumps(data, indent=2, default=str))
        return 0
    console.print(table)
    if data["scheduler_error"]:
        err_console.print(f"[yellow]Slurm not reachable, manifests only:[/] "
                          f"{escape(str(data['scheduler_error']))}", highlight=False)
    for job in data["jobs"]:
        if job["kind"] != "array":
            console.print(f"{job['kind']} job {job['job_id']} (after {job.get('after')}): "
                          f"{job.get('state') or 'finished/forgotten by Slurm'}")
    console.print(", ".join(f"{n} {s}" for s, n in sorted(data["counts"].items())))
    console.print(f"analysis due: {data['analysis_due']}" if data["analysis_due"]
                  else "analysis: holds for the study (its record, cases, dumps, settings)",
                  highlight=False, soft_wrap=True)
    return 0


def cmd_resubmit(args: argparse.Namespace) -> int:
    study_dir: Path = args.study_dir.resolve()
    base = executor_kind(SLURM).recorded(study_dir)
    scheduler = build_executor(SLURM, site_from_args(args, base))
    # a planned submission is planned again (same core limit unless --cores says otherwise)
    plan = scheduler.recorded_plan(study_dir) if args.ntasks is None else None
    if is_sequential(read_record(study_dir)):
        return resubmit_rounds(study_dir, scheduler, read_record(study_dir), plan is not None,
                               args.cores if args.cores is not None else (plan or {}).get(
                                   "cores"), args.include_unstable, args.dry_run)
    again = plan_resubmission(study_dir, scheduler, args.include_unstable, args.cores,
                              planned=plan is not None, recorded_cores=(plan or {}).get("cores"),
                              analysis=not args.no_analysis,
                              analysis_tasks=args.analysis_tasks)
    if again.busy:
        console.print(f"{len(again.busy)} case(s) still queued or running, not resubmitted: "
                      + ", ".join(c.job or "?" for c in again.busy))
    if not again.indices:
        console.print("nothing to resubmit: every case is done, unstable or still queued")
        return 0
    console.print(f"resubmitting {len(again.indices)} case(s): "
                  + ", ".join(f"{c.index} {c.case_id} ({c.manifest}"
                              + (", production extended)" if again.needs.of(c.index).need
                                 is EXTEND else ")")
                              for c in again.cases if c.index in again.indices))
    if args.dry_run:
        print(dry_run_text(list(again.jobs)))
        return 0
    print_submitted(again.submit(scheduler))
    return 0


def cmd_next_round(args: argparse.Namespace) -> int:
    study_dir: Path = args.study_dir.resolve()
    scheduler = study_executor(SLURM, study_dir)
    plan = scheduler.recorded_plan(study_dir)
    return next_round(args, study_dir, scheduler, plan is not None, (plan or {}).get("cores"))


def cmd_cancel(args: argparse.Namespace) -> int:
    return cancel_study(args.study_dir)                 # = ligwf cancel --executor slurm


def cancel_study(study: Path) -> int:
    """scancel the study's queued and running jobs and say which (the cases resume on
    ``resubmit``)."""
    study_dir = Path(study).resolve()
    ids = study_executor(SLURM, study_dir).cancel(study_dir)
    if not ids:
        console.print("nothing to cancel: no job of this study is queued or running")
        return 0
    console.print(f"cancelled job(s) {', '.join(ids)}: running cases write their forced "
                  f"restarts and are marked killed; 'ligwf slurm resubmit {study}' "
                  "resumes them")
    return 0


#: what ``resubmit`` does, for its help (``ligwf resubmit`` and ``ligwf slurm resubmit``)
RESUBMIT_HELP = ("submit a new array with exactly the cases that are missing, failed, killed "
                 "or extended")


def add_resubmit_args(p) -> None:
    """The options of ``resubmit`` besides STUDY (``p``: a parser or an argument group)."""
    p.add_argument("--include-unstable", action="store_true",
                   help="also rerun cases the health checks marked unstable")
    add_site_args(p)


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add ``ligwf slurm submit|status|resubmit|cancel`` to the top-level parser."""
    slurm = subparsers.add_parser("slurm", help="run a study as Slurm job arrays")
    sub = slurm.add_subparsers(dest="slurm_command", required=True)

    p = sub.add_parser("submit", help="render all cases and submit them as one job array "
                                      "plus a dependent analysis job")
    add_workflow_args(p)
    p.add_argument("--out", type=folder_to_write, required=True, help="study folder to write")
    add_mesh_cache(p)
    add_replace_arg(p)
    add_site_args(p)
    add_until_decided_args(p)
    add_snapshots(p)
    p.set_defaults(func=cmd_submit, executor=SLURM)    # = ligwf study --executor slurm

    p = sub.add_parser("status", help="cases with their manifest and Slurm state")
    p.add_argument("study_dir", type=Path, help="study folder")
    p.add_argument("--json", action="store_true", help="print JSON instead of a table")
    p.set_defaults(func=cmd_status)

    p = sub.add_parser("resubmit", help=RESUBMIT_HELP)
    p.add_argument("study_dir", type=Path, help="study folder")
    add_resubmit_args(p)
    p.set_defaults(func=cmd_resubmit)      # = ligwf resubmit --executor slurm

    p = sub.add_parser("cancel", help="scancel the study's queued and running jobs (the "
                                      "cases resume on 'ligwf slurm resubmit')")
    p.add_argument("study_dir", type=Path, help="study folder")
    p.set_defaults(func=cmd_cancel)

    add_next_round_args(sub.add_parser(NEXT_ROUND, help=NEXT_ROUND_HELP), add_mesh_cache
                        ).set_defaults(func=cmd_next_round)     # = ligwf next-round --executor slurm

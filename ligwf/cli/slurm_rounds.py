"""``ligwf slurm submit --until-decided`` and ``ligwf slurm next-round``: a sequential
study (``ligwf study --until-decided``) as Slurm arrays, one dependent round at a time.

``submit --until-decided`` writes the study and its rounds record and submits round 1
with a follow-up job running ``ligwf slurm next-round STUDY`` instead of the plain
analysis job; that job analyses, reports and takes the look, then writes and submits the
next round with another follow-up job of its kind, until the study stops (final report).
``resubmit`` on such a study submits what keeps it going (the cases of the round that did
not finish, with a follow-up; or the follow-up job alone when a look is due and no job
will take it). The chain is :mod:`ligwf.pipeline.submit_rounds`; this module parses and
prints.
"""

from __future__ import annotations

import argparse
import dataclasses
import os
from pathlib import Path

from ligwf.cli.common import console, grouped_warnings, print_warning
from ligwf.cli.report import add_snapshots, print_report, show_look
from ligwf.errors import ConfigError
from ligwf.pipeline.prepare import Prepared
from ligwf.pipeline.rounds import (INCOMPLETE, STOPPED, RoundPlan, prepare_study_folder,
                                   start_rounds)
from ligwf.pipeline.submit_rounds import (NEXT_ROUND, FollowUp, Moved, keep_going, progress,
                                          recorded_steps)
from ligwf.scheduler import Scheduler
from ligwf.study.layout import REPORT_DIR, ROUNDS_FILE
from ligwf.study.rounds import read_rounds

#: how long a follow-up job waits for case tasks Slurm still shows (a task that has just
#: ended may still be completing), seconds
SETTLE_SECONDS = 60.0


#: what ``next-round`` does, for its help (``ligwf next-round`` and ``ligwf slurm next-round``)
NEXT_ROUND_HELP = ("the follow-up job of a study submitted --until-decided: analyse, report "
                   "and take the look, then submit the next round (or write the final "
                   "report); safe to run again")


def add_next_round_args(p: argparse.ArgumentParser, add_mesh_cache) -> argparse.ArgumentParser:
    """The follow-up job's arguments (STUDY and the options the first submission had)."""
    p.add_argument("study_dir", type=Path, help="study folder")
    p.add_argument("--templates", action="append", default=[], type=Path, metavar="DIR",
                   help="user template folder the study was written with (repeatable)")
    p.add_argument("--allow-unstable", action="store_true",
                   help="as given to the first submission (renders added replicas)")
    add_mesh_cache(p)
    add_snapshots(p)
    return p


def follow_up_of(args: argparse.Namespace, planned: bool, cores: int | None) -> FollowUp | None:
    """The follow-up settings of ``submit --until-decided`` (None without it); refuses the
    options a sequential study cannot keep."""
    if not args.until_decided:
        return None
    if args.no_analysis:
        raise ConfigError("--no-analysis: a study --until-decided takes its looks in the "
                          "follow-up job after each round; drop one of the two")
    if args.analysis_tasks != 1:
        raise ConfigError(f"--analysis-tasks = {args.analysis_tasks}: with --until-decided "
                          "the follow-up job analyses the study itself (allowed: 1)")
    return FollowUp("slurm", planned, cores, not args.no_snapshots,
                    tuple(Path(t).resolve() for t in args.templates), args.allow_unstable,
                    mesh_cache=args.mesh_cache)


def dry_run_note(args: argparse.Namespace, out: Path) -> str:
    taken = len(read_rounds(out).looks)
    if taken:
        return (f"--until-decided: {out} has {taken} look(s) already: without --dry-run the "
                "command goes on from its records (the next round, or what keeps it going), "
                "not from round 1 as shown")
    return (f"--until-decided: this is round 1; its follow-up job ('ligwf slurm {NEXT_ROUND} "
            f"{out}') analyses, reports and takes look 1, then plans and submits each later "
            f"round itself (at most {args.max_looks} looks"
            + (f", {args.max_core_hours:g} core-h" if args.max_core_hours else "") + ")")


def print_submitted(entries) -> None:
    for e in entries:
        dep = f" (after {e['after']})" if e.get("after") else ""
        console.print(f"submitted {e['kind']} job {e['job_id']}{dep}: {e['script']}")


def print_moved(moved: Moved) -> None:
    for look in moved.looks:
        console.print(f"look {look.number} taken", highlight=False)
    console.print(moved.note, highlight=False, soft_wrap=True)
    print_submitted(moved.submitted)


def submit_until_decided(args: argparse.Namespace, prepared: Prepared, out: Path,
                         scheduler: Scheduler, how: FollowUp) -> int:
    """After the study is written: its rounds record, then what its state asks for (round
    1 on a new study)."""
    start_rounds(out, RoundPlan(args.max_looks, args.max_core_hours, args.every_level))
    print_moved(keep_going(out, scheduler, how, prepared=lambda: prepared))
    return 0


def next_round(args: argparse.Namespace, study_dir: Path, scheduler: Scheduler,
               planned: bool, cores: int | None) -> int:
    """``ligwf slurm next-round``: 1 when the round did not finish (no look taken). A
    study with no rounds record (never run ``--until-decided``) is refused in one line
    before anything is written or submitted: its first round would be submitted."""
    if not (study_dir / ROUNDS_FILE).is_file():
        raise ConfigError(f"{study_dir}: no rounds record ({ROUNDS_FILE}): next-round is the "
                          "follow-up job of a study run --until-decided; 'ligwf resubmit "
                          "STUDY --executor slurm' runs what a plain study still needs")
    how = FollowUp("slurm", planned, cores, not args.no_snapshots,
                   tuple(Path(t).resolve() for t in args.templates), args.allow_unstable,
                   mesh_cache=args.mesh_cache)

    def prepared() -> Prepared:
        ready = prepare_study_folder(study_dir, (), how.template_dirs, how.allow_unstable)
        for line in grouped_warnings(ready.warnings, [rc.case.case_id for rc in ready.rendered]):
            print_warning(line)
        return ready

    own = os.environ.get("SLURM_JOB_ID")
    moved = keep_going(study_dir, scheduler, how, prepared, take_looks=True, show=show_look,
                       wait_seconds=SETTLE_SECONDS if own else 0.0, own_job=own)
    print_moved(moved)
    if moved.progress.state == STOPPED:
        print_report(study_dir, study_dir / REPORT_DIR)
    return 1 if moved.progress.state == INCOMPLETE else 0


def resubmit_rounds(study_dir: Path, scheduler: Scheduler, jobs: list[dict], planned: bool,
                    cores: int | None, include_unstable: bool, dry_run: bool) -> int:
    """``ligwf slurm resubmit`` on a sequential study: what keeps it going."""
    steps = recorded_steps(jobs)
    how = dataclasses.replace(FollowUp.from_steps(steps, planned, cores),
                              retry_unstable=include_unstable)
    if dry_run:
        p = progress(study_dir, scheduler, include_unstable)
        console.print(f"sequential study: {p.looks} look(s) taken, round {p.round} "
                      f"{p.state}" + (f"; would submit case(s) {list(p.unfinished)}"
                                      if p.unfinished else ""), highlight=False)
        return 0
    print_moved(keep_going(study_dir, scheduler, how))
    return 0

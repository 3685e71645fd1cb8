"""The command line's face of the executor registry (:mod:`ligwf.executors`): ``--executor
NAME`` on ``ligwf study``, ``analyse``, ``status``, ``cancel``, ``resubmit`` and
``next-round``, the options that set one executor's settings (refused in one line with
another), and what a batch scheduler's sub-commands do for them (``ligwf study --executor
slurm`` is ``ligwf slurm submit``, ``ligwf analyse --executor slurm --tasks N`` is ``ligwf
analyse --slurm N``, ``ligwf status|cancel|resubmit|next-round --executor slurm`` are
``ligwf slurm status|cancel|resubmit|next-round``: the same code). ``resubmit`` and
``next-round`` (this module's own commands) hand a study to a batch scheduler again; on
this machine the command that ran a study resumes it, which their refusal says.
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Callable, Mapping

from ligwf.cli import slurm
from ligwf.cli.common import add_mesh_cache
from ligwf.cli.slurm_rounds import NEXT_ROUND_HELP, add_next_round_args
from ligwf.pipeline.submit_rounds import NEXT_ROUND
from ligwf.errors import ConfigError
from ligwf.executors import EXECUTORS, LOCAL, executor_kind

#: the options of ``ligwf study`` that set one executor's settings: argparse dest ->
#: (executor, the option, its value when not given)
STUDY_OPTIONS: Mapping[str, tuple[str, str, object]] = {
    "np": (LOCAL, "--np", None), "ensemble": (LOCAL, "--ensemble", 0),
    "retry_unstable": (LOCAL, "--retry-unstable", False),
    "extend_production": (LOCAL, "--extend-production", 0.0),
    **{dest: (slurm.SLURM, flag, unset) for dest, flag, unset in (
        ("partition", "--partition", None), ("account", "--account", None),
        ("time", "--time", None), ("ntasks", "--ntasks", None),
        ("cores_per_node", "--cores-per-node", None),
        ("max_concurrent", "--max-concurrent", None), ("no_analysis", "--no-analysis", False),
        ("analysis_tasks", "--analysis-tasks", 1), ("dry_run", "--dry-run", False))},
}

#: executor -> what ``ligwf study --executor NAME`` does (a batch scheduler: write the
#: study and submit it); the local executor runs it here (:mod:`ligwf.cli.study`)
SUBMIT_STUDY: Mapping[str, Callable[[argparse.Namespace], int]] = {
    slurm.SLURM: slurm.cmd_submit}
#: executor -> what ``ligwf analyse STUDY --executor NAME --tasks N`` does on a batch
#: scheduler (submit the shares and their merge); the local executor runs them here
SUBMIT_ANALYSIS: Mapping[str, Callable[[argparse.Namespace, int], int]] = {
    slurm.SLURM: slurm.submit_analysis}


#: executor -> what ``ligwf status STUDY --executor NAME`` shows (``ligwf slurm status``)
SHOW_STATUS: Mapping[str, Callable[[Path], int]] = {slurm.SLURM: slurm.show_status}
#: executor -> what ``ligwf cancel STUDY --executor NAME`` does (``ligwf slurm cancel``)
CANCEL: Mapping[str, Callable[[Path], int]] = {slurm.SLURM: slurm.cancel_study}
#: batch scheduler -> what ``ligwf resubmit STUDY --executor NAME`` does (``ligwf slurm
#: resubmit``: the cases that need running again, or what keeps a sequential study going)
RESUBMIT: Mapping[str, Callable[[argparse.Namespace], int]] = {
    slurm.SLURM: slurm.cmd_resubmit}
#: batch scheduler -> what ``ligwf next-round STUDY --executor NAME`` does (``ligwf slurm
#: next-round``, the follow-up job of a sequential study)
FOLLOW_UP: Mapping[str, Callable[[argparse.Namespace], int]] = {
    slurm.SLURM: slurm.cmd_next_round}
#: on this machine, what does the work of ``resubmit`` / ``next-round`` (their refusal)
LOCAL_WAY = {
    "resubmit": "on this machine the command that ran the study resumes what is not done "
                "('ligwf study WORKFLOW --out STUDY', or 'ligwf study STUDY --out STUDY "
                "--until-decided')",
    NEXT_ROUND: "on this machine 'ligwf study STUDY --out STUDY --until-decided' takes the "
                "looks and runs the rounds"}


def add_executor_arg(p: argparse.ArgumentParser, what: str) -> None:
    """``--executor NAME`` (default ``local``); ``what`` says what it does for the command."""
    names = "; ".join(f"{name}: {executor_kind(name).summary}" for name in EXECUTORS)
    p.add_argument("--executor", default=LOCAL, metavar="NAME",
                   help=f"what runs {what} ({names}; default {LOCAL})")


def checked_executor(args: argparse.Namespace,
                     options: Mapping[str, tuple[str, str, object]] = STUDY_OPTIONS) -> str:
    """The executor ``args`` name, checked before anything is read or written: an unknown
    name, or an option of another executor given, is refused in one line."""
    name = executor_kind(args.executor).name
    for dest, (owner, flag, unset) in options.items():
        if owner != name and getattr(args, dest, unset) != unset:
            raise ConfigError(f"{flag}: an option of --executor {owner}, not of --executor "
                              f"{name}")
    return name


def on_scheduler(command: str, table: Mapping[str, Callable[[argparse.Namespace], int]]
                 ) -> Callable[[argparse.Namespace], int]:
    """``ligwf COMMAND STUDY --executor NAME``: ``table``'s function for NAME; the local
    executor (the default) or another without one is refused in one line that says what
    does the work there."""
    def run(args: argparse.Namespace) -> int:
        name = executor_kind(args.executor).name
        if name not in table:
            raise ConfigError(f"--executor = {name!r}: ligwf {command} hands a study to a "
                              f"batch scheduler again (allowed: {', '.join(table)}); "
                              + LOCAL_WAY[command])
        return table[name](args)
    return run


def register(subparsers) -> None:
    """Add ``resubmit`` and ``next-round`` (``ligwf slurm resubmit|next-round`` with
    ``--executor``)."""
    p = subparsers.add_parser("resubmit", help=slurm.RESUBMIT_HELP + " (a batch scheduler)")
    p.add_argument("study_dir", type=Path, help="study folder")
    add_executor_arg(p, "the cases again")
    slurm.add_resubmit_args(p.add_argument_group(
        "with --executor slurm (as 'ligwf slurm resubmit')"))
    p.set_defaults(func=on_scheduler("resubmit", RESUBMIT))

    p = add_next_round_args(subparsers.add_parser(NEXT_ROUND, help=NEXT_ROUND_HELP),
                            add_mesh_cache)
    add_executor_arg(p, "the next round")
    p.set_defaults(func=on_scheduler(NEXT_ROUND, FOLLOW_UP))

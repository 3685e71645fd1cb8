"""``ligwf analyse RUN_DIR``: granules, GSD and ParaView series of a study or one case.

The science settings (steady window, bond criterion, GSD binning and bootstrap) are the
study's own (the workflow's ``analysis:`` block, stored in the study folder; defaults for
a case folder run by hand): change them with ``--set analysis.KEY=VALUE`` on the workflow.
The options here only say how the analysis runs.

Runs serially, or frame-parallel under MPI: ``mpirun -np P ligwf analyse RUN_DIR`` gives
each of the P ranks a contiguous share of the (case, frame) tasks; the outputs are
identical to the serial run. ``--tasks N`` splits the study's analysis into N shares
(each ``--part K/N``, one partial output each) merged (``--merge N``) into the same
tables, on the executor ``--executor`` names: locally N processes side by side, merged
here; on Slurm (``--executor slurm``, also spelt ``--slurm N``) an array of N tasks and a
job that merges them, and the command returns once they are submitted. A share that
failed is named by the merge, with the command that re-runs it.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from ligwf.cli.common import folder_to_write, stop_on_signals
from ligwf.cli.executors import SUBMIT_ANALYSIS, add_executor_arg
from ligwf.errors import ConfigError, LigwfError
from ligwf.executors import LOCAL


def register(subparsers) -> None:
    """Add the ``analyse`` sub-command."""
    p = subparsers.add_parser(
        "analyse", help="identify granules, compute GSDs and compare CG levels (MPI-parallel)",
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("run_dir", type=Path, help="study folder or one case folder")
    p.add_argument("--out", type=folder_to_write, default=None,
                   help="output folder (default: the study's analysis folder)")
    p.add_argument("--reference", action="store_true",
                   help="use the networkx reference implementation (slow) instead of the compiled fast path")
    p.add_argument("--no-vtu", action="store_true", help="do not write the .pvd/.vtu series")
    p.add_argument("--louvain", action="store_true",
                   help="add Louvain communities (bridge-force weighted) to the .vtu files")
    p.add_argument("--no-manifest-check", action="store_true",
                   help="analyse cases without a `done` manifest too (e.g. run by hand)")
    add_executor_arg(p, "the shares of --tasks")
    p.add_argument("--tasks", type=int, metavar="N", default=1,
                   help="split the study's analysis into N shares run side by side and merged "
                   "into the same tables (default 1)")
    split = p.add_mutually_exclusive_group()
    split.add_argument("--slurm", type=int, metavar="N", default=None,
                       help="= --executor slurm --tasks N: submit the analysis as a Slurm array "
                       "of N tasks and a merge job")
    split.add_argument("--part", metavar="K/N", default=None,
                       help="compute share K of N and write it as a partial output (one share "
                            "of --tasks; needs --token)")
    split.add_argument("--merge", type=int, metavar="N", default=None,
                       help="merge the N partial outputs of --token into the outputs")
    p.add_argument("--token", default=None,
                   help="the split analysis' token (a batch scheduler's --tasks prints it; "
                   "--part / --merge)")
    p.add_argument("--dry-run", action="store_true",
                   help="on a batch scheduler: print the scripts and submit commands, submit "
                   "nothing")
    p.set_defaults(func=cmd_analyse)


def cmd_analyse(args: argparse.Namespace) -> int:
    from ligwf.analysis.runner import AnalysisOptions, mpi_comm
    from ligwf.pipeline.post import analyse_study
    from ligwf.study.study import Study

    options = AnalysisOptions(implementation="reference" if args.reference else "fast",
                              write_vtu=not args.no_vtu, louvain=args.louvain,
                              require_manifest=not args.no_manifest_check)
    if args.slurm is not None:          # the old spelling of --executor slurm --tasks N
        args.executor, args.tasks = "slurm", args.slurm
    if args.part is not None or args.merge is not None:
        return cmd_split(args, options)
    if args.executor != LOCAL or args.tasks != 1:
        return cmd_shares(args)
    if args.token is not None or args.dry_run:
        raise ConfigError("--token and --dry-run belong to --tasks on a batch scheduler / "
                          "--part / --merge")
    comm = mpi_comm()
    try:
        record = analyse_study(args.run_dir, args.out, options, comm)
    except LigwfError as exc:          # a refusal: one line (every rank got here or is done)
        if comm is None:
            raise
        print(f"ligwf: {type(exc).__name__}: {exc}", file=sys.stderr)
        return 2
    except BaseException:
        if comm is not None:            # one failing rank must not leave the others waiting
            import traceback

            traceback.print_exc()
            comm.Abort(1)
        raise
    if record is None:
        return 0
    out = args.out or Study.open(args.run_dir).analysis_dir
    print_record(record, out)
    return 0


def cmd_shares(args: argparse.Namespace) -> int:
    """``--tasks N`` on ``--executor``: a batch scheduler submits the shares and their merge
    job (:data:`~ligwf.cli.executors.SUBMIT_ANALYSIS`); locally the local executor runs
    them side by side and merges them here."""
    from ligwf.analysis import parts
    from ligwf.executors import build_executor, executor_kind
    from ligwf.pipeline.run import Interrupted
    from ligwf.study.study import Study

    name = executor_kind(args.executor).name
    count = parts.check_count(args.tasks, "--tasks")
    if args.out is not None or args.reference or args.no_vtu or args.louvain \
            or args.no_manifest_check:
        raise ConfigError(f"--executor {name} --tasks {count} runs the study's own analysis "
                          "into its analysis folder: --out, --reference, --no-vtu, --louvain "
                          "and --no-manifest-check are for one local process")
    if args.token is not None:
        raise ConfigError("--token: --tasks makes its own token")
    if name != LOCAL:
        return SUBMIT_ANALYSIS[name](args, count)
    if args.dry_run:
        raise ConfigError("--dry-run: the local executor runs the shares now (a batch "
                          "scheduler's --executor shows what it would submit)")
    study = Study.open(args.run_dir)
    with stop_on_signals() as stop:
        record = build_executor(LOCAL).analyse(study, count, stop)
    if record is None:
        raise Interrupted(getattr(stop, "signum", None))
    print_record(record, study.analysis_dir)
    return 0


def cmd_split(args: argparse.Namespace, options) -> int:
    """``--part K/N`` (one share), ``--merge N``."""
    from ligwf.analysis import parts
    from ligwf.analysis.runner import analyse_part, merge_parts
    from ligwf.local import end_with_parent
    from ligwf.study.study import Study

    if args.executor != LOCAL or args.tasks != 1:
        raise ConfigError(f"--{'part' if args.part else 'merge'}: one share or the merge, "
                          "here; not with --executor / --tasks (they run the shares)")
    if args.dry_run:
        raise ConfigError("--dry-run belongs to --tasks on a batch scheduler")
    if args.token is None:
        raise ConfigError(f"--{'part' if args.part else 'merge'} needs --token (the token "
                          "`ligwf analyse --slurm` printed)")
    token = parts.check_token(args.token)
    if args.part is not None:
        end_with_parent()               # a share of a local analysis ends with its ligwf
        index, count = parts.parse_part(args.part)
        path = analyse_part(args.run_dir, token, index, count, args.out, options)
        print(f"analysis task {index} of {count}: partial output {path}")
        return 0
    count = parts.check_count(args.merge, "--merge")
    record = merge_parts(args.run_dir, token, count, args.out, options)
    print_record(record, args.out or Study.open(args.run_dir).analysis_dir)
    return 0


def print_record(record: dict, out: Path) -> None:
    """What was analysed (stdout) and what was skipped, with reasons (stderr)."""
    analysed = sum(c["analysed"] for c in record["cases"])
    print(f"analysed {analysed} frame(s) of {len(record['cases'])} case(s) -> {out}")
    for s in record.get("granules_absent", []):
        print(f"granules not analysed for {s['case_id']}: {s['reason']} (its flow metrics "
              "are)")
    for s in record["skipped_cases"]:
        print(f"skipped case {s['case_id']}: {s['reason']}", file=sys.stderr)
    for s in record["skipped_frames"]:
        print(f"{s.get('kind', 'skipped')} frame {s['case_id']} step {s['step']}: {s['reason']}",
              file=sys.stderr)

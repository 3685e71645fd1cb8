"""``ligwf analyse RUN_DIR``: granules, GSD and ParaView series of a study or one case.

The science settings (steady window, bond criterion, GSD binning and bootstrap) are the
study's own (the workflow's ``analysis:`` block, stored in the study folder; defaults for
a case folder run by hand): change them with ``--set analysis.KEY=VALUE`` on the workflow.
The options here only say how the analysis runs.

Runs serially, or frame-parallel under MPI: ``mpirun -np P ligwf analyse RUN_DIR`` gives
each of the P ranks a contiguous share of the (case, frame) tasks; the outputs are
identical to the serial run. For big studies, ``--slurm N`` submits the same shares as a
Slurm array of N tasks (each ``--part K/N``, one partial output each) and a job that
merges them (``--merge N``) into the same tables; a task that failed is named by the
merge, with the command that re-runs it.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from ligwf.cli.common import folder_to_write
from ligwf.errors import ConfigError, LigwfError
from ligwf.study import layout


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
    split = p.add_mutually_exclusive_group()
    split.add_argument("--slurm", type=int, metavar="N", default=None,
                       help="submit the analysis as a Slurm array of N tasks and a merge job")
    split.add_argument("--part", metavar="K/N", default=None,
                       help="compute share K of N and write it as a partial output (an array "
                            "task of --slurm; needs --token)")
    split.add_argument("--merge", type=int, metavar="N", default=None,
                       help="merge the N partial outputs of --token into the outputs")
    p.add_argument("--token", default=None,
                   help="the split analysis' token (--slurm prints it; --part / --merge)")
    p.add_argument("--dry-run", action="store_true",
                   help="with --slurm: print the scripts and sbatch commands, submit nothing")
    p.set_defaults(func=cmd_analyse)


def cmd_analyse(args: argparse.Namespace) -> int:
    from ligwf.analysis.runner import AnalysisOptions, mpi_comm
    from ligwf.pipeline.post import analyse_study
    from ligwf.study.study import Study

    options = AnalysisOptions(implementation="reference" if args.reference else "fast",
                              write_vtu=not args.no_vtu, louvain=args.louvain,
                              require_manifest=not args.no_manifest_check)
    if args.slurm is not None or args.part is not None or args.merge is not None:
        return cmd_split(args, options)
    if args.token is not None or args.dry_run:
        raise ConfigError("--token and --dry-run belong to --slurm / --part / --merge")
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


def cmd_split(args: argparse.Namespace, options) -> int:
    """``--slurm N`` (submit), ``--part K/N`` (one array task), ``--merge N``."""
    from ligwf.analysis import parts
    from ligwf.analysis.runner import analyse_part, merge_parts
    from ligwf.local import end_with_parent
    from ligwf.study.study import Study

    if args.slurm is not None:
        if args.token is not None:
            raise ConfigError("--token: --slurm makes its own token")
        return submit_split(args, parts.check_count(args.slurm))
    if args.dry_run:
        raise ConfigError("--dry-run belongs to --slurm")
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


def submit_split(args: argparse.Namespace, count: int) -> int:
    """Plan (and unless ``--dry-run`` submit) the analysis array and its merge job."""
    from ligwf.analysis.outputs import new_token
    from ligwf.slurm.scheduler import SlurmScheduler
    from ligwf.slurm.site import load_slurm_site
    from ligwf.study.study import Study

    if args.out is not None or args.reference or args.no_vtu or args.louvain \
            or args.no_manifest_check:
        raise ConfigError("--slurm runs the study's own analysis into its analysis folder: "
                          "--out, --reference, --no-vtu, --louvain and --no-manifest-check "
                          "are for a local run")
    study = Study.open(args.run_dir)
    token = new_token()
    scheduler = SlurmScheduler(load_slurm_site())
    planned = scheduler.plan_analysis(study.path, study.path.name, count, token)
    if args.dry_run:
        print(scheduler.dry_run_text(planned))
        return 0
    scheduler.require()
    entries = scheduler.submit(study.path, planned)
    array, merge = entries[0]["job_id"], entries[-1]["job_id"]
    print(f"submitted analysis array {array} ({count} task(s)) and merge job {merge} "
          f"(token {token}); logs in {study.path / layout.SLURM_LOG_DIR}")
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

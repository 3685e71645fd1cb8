"""``ligwf analyse RUN_DIR``: granules, GSD and ParaView series of a study or one case.

The science settings (steady window, bond criterion, GSD binning and bootstrap) are the
study's own (the workflow's ``analysis:`` block, stored in the study folder; defaults for
a case folder run by hand): change them with ``--set analysis.KEY=VALUE`` on the workflow.
The options here only say how the analysis runs.

Runs serially, or frame-parallel under MPI: ``mpirun -np P ligwf analyse RUN_DIR`` deals
(case, frame) tasks to the P ranks; the outputs are identical to the serial run.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from ligwf.errors import LigwfError


def register(subparsers) -> None:
    """Add the ``analyse`` sub-command."""
    p = subparsers.add_parser(
        "analyse", help="identify granules, compute GSDs and compare CG levels (MPI-parallel)",
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("run_dir", type=Path, help="study folder or one case folder")
    p.add_argument("--out", type=Path, default=None,
                   help="output folder (default: the study's analysis folder)")
    p.add_argument("--reference", action="store_true",
                   help="use the networkx reference implementation (slow) instead of the compiled fast path")
    p.add_argument("--no-vtu", action="store_true", help="do not write the .pvd/.vtu series")
    p.add_argument("--louvain", action="store_true",
                   help="add Louvain communities (bridge-force weighted) to the .vtu files")
    p.add_argument("--no-manifest-check", action="store_true",
                   help="analyse cases without a `done` manifest too (e.g. run by hand)")
    p.set_defaults(func=cmd_analyse)


def cmd_analyse(args: argparse.Namespace) -> int:
    from ligwf.analysis.runner import AnalysisOptions, _mpi_comm
    from ligwf.pipeline.post import analyse_study
    from ligwf.study.study import Study

    options = AnalysisOptions(implementation="reference" if args.reference else "fast",
                              write_vtu=not args.no_vtu, louvain=args.louvain,
                              require_manifest=not args.no_manifest_check)
    comm = _mpi_comm()
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

"""``ligwf analyse RUN_DIR``: granules, GSD and ParaView series of a study or one case.

Runs serially, or frame-parallel under MPI: ``mpirun -np P ligwf analyse RUN_DIR`` deals
(case, frame) tasks to the P ranks; the outputs are identical to the serial run.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from ligwf.errors import ConfigError


def register(subparsers) -> None:
    """Add the ``analyse`` sub-command."""
    p = subparsers.add_parser(
        "analyse", help="identify granules, compute GSDs and compare CG levels (MPI-parallel)",
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("run_dir", type=Path, help="study folder (study.json) or one case folder")
    p.add_argument("--out", type=Path, default=None, help="output folder (default RUN_DIR/analysis)")
    p.add_argument("--min-bridge-force", type=float, default=0.0, metavar="N",
                   help="a bond needs a bridge force above this, N (default 0: any unbroken bridge)")
    p.add_argument("--max-velocity-angle", type=float, default=30.0, metavar="DEG",
                   help="a bond needs partners' velocities within this angle, deg (default 30)")
    p.add_argument("--min-particles", type=int, default=10,
                   help="CG granules with fewer particles are below the size limit (default 10)")
    p.add_argument("--bins-per-decade", type=int, default=5)
    p.add_argument("--bootstrap", type=int, default=1000, help="bootstrap draws (default 1000)")
    p.add_argument("--seed", type=int, default=12345, help="bootstrap seed")
    p.add_argument("--discard-frames", type=int, default=0,
                   help="leave the first N frames of each case out of the GSD (start-up)")
    p.add_argument("--reference", action="store_true",
                   help="use the networkx reference implementation (slow) instead of the compiled fast path")
    p.add_argument("--no-vtu", action="store_true", help="do not write the .pvd/.vtu series")
    p.add_argument("--louvain", action="store_true",
                   help="add Louvain communities (bridge-force weighted) to the .vtu files")
    p.add_argument("--no-manifest-check", action="store_true",
                   help="analyse cases without a `done` manifest too (e.g. run by hand)")
    p.set_defaults(func=cmd_analyse)


def cmd_analyse(args: argparse.Namespace) -> int:
    from ligwf.analysis.runner import AnalysisOptions, _mpi_comm, analyse
    from ligwf.analysis.granules import BondCriterion
    from ligwf.analysis.gsd import GsdSettings

    try:
        options = AnalysisOptions(
            criterion=BondCriterion(args.min_bridge_force, args.max_velocity_angle),
            gsd=GsdSettings(args.bins_per_decade, args.min_particles, args.bootstrap, 0.95,
                            args.seed),
            implementation="reference" if args.reference else "fast",
            discard_frames=args.discard_frames, write_vtu=not args.no_vtu, louvain=args.louvain,
            require_manifest=not args.no_manifest_check)
    except ValueError as exc:
        raise ConfigError(str(exc)) from None
    comm = _mpi_comm()
    try:
        record = analyse(args.run_dir, args.out, options, comm)
    except BaseException:
        if comm is not None:            # one failing rank must not leave the others waiting
            import traceback

            traceback.print_exc()
            comm.Abort(1)
        raise
    if record is None:
        return 0
    out = args.out or args.run_dir / "analysis"
    analysed = sum(c["analysed"] for c in record["cases"])
    print(f"analysed {analysed} frame(s) of {len(record['cases'])} case(s) -> {out}")
    for s in record["skipped_cases"]:
        print(f"skipped case {s['case_id']}: {s['reason']}", file=sys.stderr)
    for s in record["skipped_frames"]:
        print(f"skipped frame {s['case_id']} step {s['step']}: {s['reason']}", file=sys.stderr)
    return 0

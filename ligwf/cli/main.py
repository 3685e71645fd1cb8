"""Command line: ``ligwf render``, ``ligwf check`` and every stage's sub-commands.

Every command validates the whole workflow, renders every case in memory and runs the
stability pre-flight before it writes anything (:func:`ligwf.pipeline.prepare.prepare_workflow`),
so a bad value is reported with its field and allowed range and nothing is left half-done.
The CLI only parses arguments and prints: the pipeline is :mod:`ligwf.pipeline`.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from ligwf import __version__
from ligwf.cli import (analyse, analyse_dumps, calibrate, executors, report, run, schema,
                       slurm, stability, study)
from ligwf.cli.common import (Parser, add_cores_arg, add_mesh_cache, add_replace_arg,
                              add_workflow_args,
                              case_table, console, err_console, folder_to_write, plan_table,
                              prepare_from_args)
from ligwf.errors import LigwfError
from ligwf.scene.regime import granulation_warning, original_numbers, regime_numbers
from rich.markup import escape
from rich.table import Table
from ligwf.fsio import NOT_WRITABLE, not_writable
from ligwf.pipeline.prepare import write
from ligwf.local import run_settings
from ligwf.pipeline.run import Interrupted, planned_schedule, site_engine
from ligwf.study.case import granules_absent

#: Modules that add their stage's sub-commands: each has ``register(subparsers)``.
COMMAND_MODULES = (run, slurm, executors, analyse, analyse_dumps, stability, report, study,
                   schema, calibrate)


def cmd_check(args: argparse.Namespace) -> int:
    prepared = prepare_from_args(args)
    wf = prepared.workflow
    console.print(case_table(prepared, f"{wf.name}: {len(prepared.rendered)} case(s), valid"))
    for line in analysis_lines(prepared):
        console.print(line, highlight=False, soft_wrap=True)
    settings = run_settings(cores=args.cores)
    schedule = planned_schedule(prepared, settings)
    console.print(plan_table(schedule, f"rank plan for {settings.cores} core(s) "
                             f"({settings.cores_source}): what "
                             "'ligwf run' / 'ligwf study' do without --np / --ensemble"))
    console.print(regime_table(prepared))
    console.print(grains_table(prepared))
    warnings = [g.warning for g in level_grains(prepared)] + [strip_problem(prepared)]
    for w in filter(None, warnings):
        err_console.print(f"[yellow]ligwf: warning:[/] {escape(w)}", highlight=False,
                          soft_wrap=True)
    for line in size_relation_lines(prepared):
        console.print(line, highlight=False, soft_wrap=True)
    try:
        console.print(site_engine()[1].describe(), highlight=False, soft_wrap=True)
    except LigwfError as exc:   # check writes nothing: the run would refuse, say so here
        err_console.print(f"[yellow]ligwf: warning:[/] engine not usable here: "
                          f"{escape(str(exc))} ('ligwf run' refuses it)", highlight=False)
    return 0


def regime_table(prepared) -> Table:
    """Dimensionless numbers of every case: its own particles and the CG1 originals
    (:mod:`ligwf.scene.regime`), and whether the regime map expects granules there."""
    table = Table(title="regime (St_v viscous Stokes, Bo_g granular Bond, Ca capillary, Fr "
                  "Froude; CG1: the original particles)")
    for col in ("case", "St_v", "Bo_g", "Ca", "Fr", "St_v CG1", "Bo_g CG1", "granules expected"):
        table.add_column(col, justify="left" if col == "case" else "right")
    for rc in prepared.rendered:
        own, cg1 = regime_numbers(rc.scaled), original_numbers(rc.case)
        control = any(k == "control" for k, _ in rc.case.varied)
        closest = "closest point" in granulation_warning(cg1)
        verdict = "control" if control else "closest (unproven)" if closest else "no"
        table.add_row(rc.case.case_id, *(f"{own[k]:.3g}" for k in
                                         ("stokes_viscous", "bond_granular", "capillary", "froude")),
                      f"{cg1['stokes_viscous']:.3g}", f"{cg1['bond_granular']:.3g}", verdict)
    return table


def level_grains(prepared) -> list:
    """The drum's lengths in grains of each CG level of the study (its first scene)."""
    from ligwf.scene.grains import grains

    if not prepared.rendered:
        return []
    scene = prepared.rendered[0].case.scene
    return [grains(scene, cg) for cg in sorted({rc.case.cg for rc in prepared.rendered})]


def strip_problem(prepared) -> str | None:
    """Whether the study's one surface resolution leaves its bed too few strips."""
    from ligwf.scene.grains import scaled_mean_diameter, strip_warning, study_strip

    if not prepared.rendered:
        return None
    strip = study_strip([scaled_mean_diameter(rc.scaled) for rc in prepared.rendered],
                        prepared.workflow.analysis.surface_strip)
    return strip_warning(prepared.rendered[0].case.scene, strip)


def grains_table(prepared) -> Table:
    """Lifter height, periodic slice and bed depth counted in grains of each CG level."""
    table = Table(title="the drum in grains of each CG level (ligwf.scene.grains; the "
                  "report adds the measured flowing layer)")
    for col in ("CG", "diameter [mm]", "lifter height", "slice length", "bed depth"):
        table.add_column(col, justify="right")
    for g in level_grains(prepared):
        table.add_row(f"{g.cg:g}", f"{g.diameter * 1e3:.3g}", f"{g.lifter:.2g}",
                      f"{g.slice:.3g}", f"{g.bed_depth:.3g}")
    return table


def size_relation_lines(prepared) -> list[str]:
    """What the size relation (:mod:`ligwf.inference.size_relation`) expects of each Weber
    level's angle of repose on this drum, before a core-hour is spent."""
    from ligwf.inference.reference import size_ratio
    from ligwf.inference.size_relation import SLOPE_DEG, expected_excess

    levels = sorted({(rc.case.cg, str(rc.case.rule.value)) for rc in prepared.rendered
                     if rc.case.cg > 1.0})
    if not levels:
        return []
    ratio = size_ratio(prepared.rendered[0].case.scene.model_dump(mode="json"))
    lines = [f"size relation (angle of repose, Weber: {SLOPE_DEG:g} deg x (n - 1) d / D, "
             f"docs/results/extrapolation; d / D = {ratio:.3g} here):"]
    for cg in sorted({n for n, rule in levels if rule == "weber"}):
        lines.append(f"  {expected_excess(cg, ratio).text}")
    if any(rule == "bond" for _, rule in levels):
        lines.append("  Bond: no size relation (its cohesion grows with n: on the committed "
                     "flow beds, the we_vs_bo drum and the demo, its CG2 lies 7.6-7.9 deg "
                     "above CG1: docs/results/extrapolation/size_relation.csv)")
    return lines


def analysis_lines(prepared) -> list[str]:
    """What `ligwf study` will and will not analyse, case by case, before anything runs."""
    absent = {rc.case.case_id: why for rc in prepared.rendered
              if (why := granules_absent(rc.scaled)) is not None}
    from ligwf.analysis.granules.definitions import describe
    from ligwf.report.verdict_text import budget_line

    wf = prepared.workflow
    lines = [f"analysis: flow metrics (angle of repose, rigid-block share, velocity profile, "
             f"flowing layer) for all {len(prepared.rendered)} case(s)"]
    granules = f"granules ({describe(wf.analysis)}), GSD and kinetics"
    budget = [f"verdict budget (accept: block): {budget_line(wf.accept.model_dump())}"]
    if not absent:
        return lines + [f"analysis: {granules} for every case"] + budget
    if len(absent) == len(prepared.rendered) and len(set(absent.values())) == 1:
        return lines + [f"analysis: NO granules, GSD or kinetics: "
                        f"{next(iter(absent.values()))}"] + budget
    return lines + [f"analysis: no granules, GSD or kinetics for {cid}: {why}"
                    for cid, why in absent.items()] + budget


def cmd_render(args: argparse.Namespace) -> int:
    prepared = prepare_from_args(args)
    write(prepared, args.out, args.mesh_cache, args.replace)
    wf = prepared.workflow
    console.print(case_table(prepared, f"{wf.name}: {len(prepared.rendered)} case(s) -> {args.out}"))
    return 0


def build_parser() -> argparse.ArgumentParser:
    parser = Parser(
        prog="ligwf", description="Coarse-grained LIGGGHTS studies of wet rotating drums.")
    parser.add_argument("--version", action="version", version=f"ligwf {__version__}")
    sub = parser.add_subparsers(dest="command", required=True)

    p = sub.add_parser("check", help="validate a workflow, render it in memory and show the "
                       "rank plan (writes nothing)")
    add_workflow_args(p)
    add_cores_arg(p)
    p.set_defaults(func=cmd_check)

    p = sub.add_parser("render", help="write one folder per case (input, mesh, scene record)")
    add_workflow_args(p)
    p.add_argument("--out", type=folder_to_write, required=True, help="study folder to write")
    add_mesh_cache(p)
    add_replace_arg(p)
    p.set_defaults(func=cmd_render)

    for module in COMMAND_MODULES:
        module.register(sub)
    parser.set_defaults(root_parser=parser)     # `ligwf schema --cli` documents this parser
    return parser


def os_error_text(exc: Exception) -> str:
    """An OSError in words, without Python's ``[Errno N]`` prefix: what went wrong and on
    which file(s) (any other error: its own text)."""
    if not getattr(exc, "strerror", None):
        return str(exc)
    files = [str(f) for f in (exc.filename, exc.filename2) if f is not None]
    return exc.strerror + (f": {' -> '.join(files)}" if files else "")


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
    except SystemExit as exc:          # --help, --version, or a refused argument
        return int(exc.code or 0)
    try:
        return int(args.func(args) or 0)
    except OSError as exc:  # a stage writing into a full or read-only folder: one line
        exc = not_writable(exc, Path.cwd()) if exc.errno in NOT_WRITABLE else exc
        err_console.print(f"[bold red]ligwf: {type(exc).__name__}:[/] "
                          f"{escape(os_error_text(exc))}", highlight=False)
        return 2
    except Interrupted as exc:         # Ctrl-C / SIGTERM: 130 / 143, as a shell would
        err_console.print(f"[bold red]ligwf: {type(exc).__name__}:[/] {escape(str(exc))}",
                          highlight=False)
        return exc.exit_code
    except LigwfError as exc:
        err_console.print(f"[bold red]ligwf: {type(exc).__name__}:[/] {escape(str(exc))}",
                          highlight=False)
        return 2


if __name__ == "__main__":
    sys.exit(main())

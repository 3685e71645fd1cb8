"""Command line: ``ligwf render``, ``ligwf check`` (and the later stages' commands).

Every command validates the whole workflow and renders every case in memory before it
writes anything, so a bad value is reported with its field and allowed range and nothing
is left half-done.
"""

from __future__ import annotations

import argparse
import importlib
import sys
from pathlib import Path

from rich.console import Console
from rich.table import Table

from ligwf import __version__
from ligwf.study.prepare import render_workflow, write_study
from ligwf.cli.stability import add_allow_unstable, preflight_or_refuse
from ligwf.errors import LigwfError
from ligwf.scene.workflow import load_workflow

console = Console(width=None if sys.stdout.isatty() else 160)
err_console = Console(stderr=True, soft_wrap=True)


def case_table(rendered, title: str) -> Table:
    """Table of cases: CG level, rule, replica, particle count, dt, steps."""
    table = Table(title=title)
    for col in ("case", "CG", "rule", "rep", "particles", "dt [s]", "dt/t_R", "steps",
                "particle-steps"):
        table.add_column(col, justify="right" if col not in ("case", "rule") else "left")
    for rc in rendered:
        s = rc.scaled
        table.add_row(rc.case.case_id, f"{s.cg:g}", s.rule, str(s.replica),
                      f"{s.particle_count:,}", f"{s.dt:.3g}", f"{s.dt_rayleigh_fraction:.3g}",
                      f"{s.total_steps:,}", f"{s.particle_count * s.total_steps:.3g}")
    return table


def add_workflow_args(p: argparse.ArgumentParser) -> None:
    p.add_argument("workflow", type=Path, help="workflow YAML file")
    p.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE",
                   help="override a workflow value, e.g. scene.drum.lifters.count=12 (repeatable)")
    p.add_argument("--templates", action="append", default=[], type=Path, metavar="DIR",
                   help="user template folder searched before ligwf's own (repeatable)")
    add_allow_unstable(p)


def cmd_check(args: argparse.Namespace) -> int:
    wf = load_workflow(args.workflow, args.overrides)
    rendered = render_workflow(wf, args.templates)
    preflight_or_refuse(rendered, args.allow_unstable)
    console.print(case_table(rendered, f"{wf.name}: {len(rendered)} case(s), valid"))
    return 0


def cmd_render(args: argparse.Namespace) -> int:
    wf = load_workflow(args.workflow, args.overrides)
    rendered = render_workflow(wf, args.templates)
    preflight_or_refuse(rendered, args.allow_unstable)
    write_study(wf, rendered, args.out, args.mesh_cache)
    console.print(case_table(rendered, f"{wf.name}: {len(rendered)} case(s) -> {args.out}"))
    return 0


#: Modules that add their stage's sub-commands: each has ``register(subparsers)``.
#: (One module per stage keeps this file small and the stages independent.)
COMMAND_MODULES: tuple[str, ...] = ("ligwf.cli.run", "ligwf.cli.slurm", "ligwf.cli.analyse",
                                     "ligwf.cli.stability", "ligwf.cli.report")


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="ligwf", description="Coarse-grained LIGGGHTS studies of wet rotating drums.")
    parser.add_argument("--version", action="version", version=f"ligwf {__version__}")
    sub = parser.add_subparsers(dest="command", required=True)

    p = sub.add_parser("check", help="validate a workflow and render it in memory (writes nothing)")
    add_workflow_args(p)
    p.set_defaults(func=cmd_check)

    p = sub.add_parser("render", help="write one folder per case (input, mesh, scene.json)")
    add_workflow_args(p)
    p.add_argument("--out", type=Path, required=True, help="study folder to write")
    p.add_argument("--mesh-cache", type=Path, default=None,
                   help="mesh cache folder (default $LIGWF_MESH_CACHE or ./meshes)")
    p.set_defaults(func=cmd_render)

    for name in COMMAND_MODULES:
        importlib.import_module(name).register(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.func(args) or 0)
    except LigwfError as exc:
        err_console.print(f"[bold red]ligwf: {type(exc).__name__}:[/] {exc}", highlight=False)
        return 2


if __name__ == "__main__":
    sys.exit(main())
